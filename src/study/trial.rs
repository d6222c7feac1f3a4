//! The one record every study produces: a trial, one solver on one problem
//! under one setting, with its certified status beside the solver's claim,
//! its counts, its certificate, and its agreement with the study's
//! reference. Accuracy columns are deterministic; times live apart, in
//! [`TrialTiming`].

use contactlab_solvers::registry::Entry;
use contactlab_solvers::{Law, Status};
use serde::{Deserialize, Serialize};

use crate::certificate::Certificate;
use crate::coulomb::fixed_point::Ending;
use crate::io::csv::{fixed, fixed_opt};
use crate::mechanics::scene::Scene;
use crate::settings::Settings;

/// A planned trial.
#[derive(Clone)]
pub struct TrialSpec {
    /// The study and the group within it (a sweep's knob, a stability group).
    pub study: &'static str,
    pub group: String,
    /// The scene, its levels ending at the trial's mesh.
    pub scene: Scene,
    pub solver: &'static Entry,
    pub law: Law,
    /// The setting varied, as `path = value`, if any.
    pub knob: Option<(String, String)>,
    pub settings: Settings,
    /// Stop after this much work (events of the solver's work stage).
    pub work: Option<usize>,
    /// Stop after this many seconds (only in studies whose results are
    /// times: a wall-clock stop makes a result depend on the machine).
    pub seconds: Option<f64>,
    /// Whether condition (13) is checked first (false: the stability map's
    /// look at what a solver does with a problem that has no solution; one
    /// given-friction solve with g = 0).
    pub check_solvable: bool,
    /// Extra runs for the time (their minimum or median is reported).
    pub repeats: usize,
}

impl TrialSpec {
    /// A trial of `solver` on `scene` under `law` with `settings`.
    pub fn new(
        study: &'static str,
        group: impl Into<String>,
        scene: &Scene,
        solver: &'static Entry,
        law: Law,
        settings: &Settings,
    ) -> Self {
        Self {
            study,
            group: group.into(),
            scene: scene.clone(),
            solver,
            law,
            knob: None,
            settings: settings.clone(),
            work: None,
            seconds: None,
            check_solvable: true,
            repeats: 0,
        }
    }

    /// The same trial with `path` set to `value` (as the command line writes it).
    pub fn varying(mut self, path: &str, value: &str) -> anyhow::Result<Self> {
        self.settings
            .set_text(path, value)
            .map_err(anyhow::Error::msg)?;
        self.knob = Some((path.to_string(), value.to_string()));
        Ok(self)
    }

    /// The same trial with the paper's ε set for every loop that uses one
    /// (the fixed point's and every solver knob named `epsilon`, as
    /// `--epsilon` does); recorded as the knob `epsilon`.
    pub fn varying_epsilon(mut self, epsilon: f64) -> anyhow::Result<Self> {
        self.settings
            .set_epsilon(epsilon)
            .map_err(anyhow::Error::msg)?;
        self.knob = Some(("epsilon".to_string(), format!("{epsilon:e}")));
        Ok(self)
    }

    /// The same trial stopped after `work` events of the solver's work stage.
    pub fn with_work(mut self, work: Option<usize>) -> Self {
        self.work = work;
        self
    }

    /// The same trial stopped after `seconds` of wall-clock time.
    pub fn with_seconds(mut self, seconds: Option<f64>) -> Self {
        self.seconds = seconds;
        self
    }

    /// The same trial without the check of condition (13), on the
    /// given-friction subproblem (where a solver can say "unbounded"
    /// without a fixed point around it) if the solver solves it, else on
    /// the Coulomb problem.
    pub fn unchecked(mut self) -> Self {
        self.check_solvable = false;
        self.law = if self.solver.solves(Law::GivenFriction) {
            Law::GivenFriction
        } else {
            Law::Coulomb
        };
        self
    }

    pub fn with_repeats(mut self, repeats: usize) -> Self {
        self.repeats = repeats;
        self
    }
}

/// One trial's accuracy record (one row of a study's trials CSV).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Trial {
    pub study: String,
    pub group: String,
    pub scene: String,
    pub h: String,
    pub solver: String,
    pub law: Law,
    /// The setting varied and its value (empty when none).
    pub knob: String,
    pub value: String,
    pub stopping: String,
    /// The certified status: the solver's claim, or `inaccurate` when a
    /// claim of convergence fails the certificate.
    pub status: Status,
    /// The solver's own claim.
    pub solver_status: Status,
    /// How the fixed point ended (`direct` for a solver of the Coulomb
    /// problem, `not_applicable` on the given-friction subproblem).
    pub outcome: TrialOutcome,
    /// The conditions that fail the certificate, worst first (`;`-separated).
    pub failing: String,
    pub friction_iterations: usize,
    pub outer_iterations: usize,
    pub inner_iterations: usize,
    /// Events of the solver's work stage.
    pub work: usize,
    /// The fixed point's last observed contraction factor.
    #[serde(serialize_with = "fixed_opt")]
    pub contraction: Option<f64>,
    /// The certificate's measure (largest violation) and its tolerance.
    #[serde(serialize_with = "fixed")]
    pub certificate: f64,
    #[serde(serialize_with = "fixed")]
    pub certificate_tolerance: f64,
    #[serde(serialize_with = "fixed")]
    pub nonpenetration: f64,
    #[serde(serialize_with = "fixed")]
    pub pressure_sign: f64,
    #[serde(serialize_with = "fixed")]
    pub complementarity: f64,
    #[serde(serialize_with = "fixed")]
    pub friction_bound: f64,
    #[serde(serialize_with = "fixed")]
    pub stick: f64,
    #[serde(serialize_with = "fixed")]
    pub slip_direction: f64,
    #[serde(serialize_with = "fixed")]
    pub stationarity: f64,
    #[serde(serialize_with = "fixed")]
    pub force_balance: f64,
    /// The solver whose answer is the reference (empty: none).
    pub reference: String,
    /// Differences from the reference, relative to its largest value.
    #[serde(serialize_with = "fixed_opt")]
    pub displacement_error: Option<f64>,
    #[serde(serialize_with = "fixed_opt")]
    pub pressure_error: Option<f64>,
    #[serde(serialize_with = "fixed_opt")]
    pub traction_error: Option<f64>,
    /// (J − J_ref)/|J_ref| for the objective of paper (10).
    #[serde(serialize_with = "fixed_opt")]
    pub objective_gap: Option<f64>,
    /// Separated intervals of Γ_K (`[a;b] [c;d]`) and their fraction.
    pub separated: String,
    #[serde(serialize_with = "fixed")]
    pub separated_fraction: f64,
    pub detail: String,
    /// What the solver reports beyond its counts (`name=value;...`, e.g. the
    /// condition number of its final Newton matrix).
    pub diagnostics: String,
    /// A study's verdict on the trial (the stability map's class), and why;
    /// empty where a study does not classify.
    pub class: String,
    pub reason: String,
}

/// The fixed point's outcome, or why there is none.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TrialOutcome {
    Converged,
    NotContracting,
    IterationCap,
    InnerFailed,
    NonFinite,
    Stopped,
    Direct,
    /// A given-friction trial: no fixed point.
    NotApplicable,
}

impl From<Ending> for TrialOutcome {
    fn from(o: Ending) -> Self {
        match o {
            Ending::Converged => TrialOutcome::Converged,
            Ending::NotContracting => TrialOutcome::NotContracting,
            Ending::IterationCap => TrialOutcome::IterationCap,
            Ending::InnerFailed => TrialOutcome::InnerFailed,
            Ending::NonFinite => TrialOutcome::NonFinite,
            Ending::Stopped => TrialOutcome::Stopped,
            Ending::Direct => TrialOutcome::Direct,
        }
    }
}

impl Trial {
    /// The certificate's columns.
    pub fn set_certificate(&mut self, c: &Certificate) {
        self.certificate = c.residual();
        self.certificate_tolerance = c.tolerance;
        self.nonpenetration = c.nonpenetration;
        self.pressure_sign = c.pressure_sign;
        self.complementarity = c.complementarity;
        self.friction_bound = c.friction_bound;
        self.stick = c.stick;
        self.slip_direction = c.slip_direction;
        self.stationarity = c.stationarity;
        self.force_balance = c.force_balance;
        self.failing = c
            .failing()
            .iter()
            .map(|f| f.as_str())
            .collect::<Vec<_>>()
            .join(";");
    }

    /// Whether the certified status is converged.
    pub fn certified(&self) -> bool {
        self.status.is_converged()
    }
}

impl Trial {
    /// A trial that was not run, with the reason (e.g. condition (13) fails):
    /// the spec's columns, infinite violations, no counts.
    pub fn not_run(spec: &TrialSpec, status: Status, detail: String) -> Self {
        let (knob, value) = spec.knob.clone().unwrap_or_default();
        let inf = f64::INFINITY;
        Trial {
            study: spec.study.into(),
            group: spec.group.clone(),
            scene: spec.scene.name.clone(),
            h: spec.scene.finest().to_string(),
            solver: spec.solver.name.into(),
            law: spec.law,
            knob,
            value,
            stopping: spec.settings.stopping.as_str().into(),
            status,
            solver_status: status,
            outcome: TrialOutcome::NotApplicable,
            failing: String::new(),
            friction_iterations: 0,
            outer_iterations: 0,
            inner_iterations: 0,
            work: 0,
            contraction: None,
            certificate: inf,
            certificate_tolerance: spec.settings.certificate.tolerance,
            nonpenetration: inf,
            pressure_sign: inf,
            complementarity: inf,
            friction_bound: inf,
            stick: inf,
            slip_direction: inf,
            stationarity: inf,
            force_balance: inf,
            reference: String::new(),
            displacement_error: None,
            pressure_error: None,
            traction_error: None,
            objective_gap: None,
            separated: String::new(),
            separated_fraction: 0.0,
            detail,
            diagnostics: String::new(),
            class: String::new(),
            reason: String::new(),
        }
    }
}

/// One trial's times (seconds of solver work, excluding assembly).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrialTiming {
    /// The row of the trial in the study's trials CSV.
    pub trial: usize,
    pub scene: String,
    pub h: String,
    pub solver: String,
    pub law: Law,
    pub knob: String,
    pub value: String,
    pub runs: usize,
    #[serde(serialize_with = "fixed")]
    pub seconds_min: f64,
    #[serde(serialize_with = "fixed")]
    pub seconds_median: f64,
    #[serde(serialize_with = "fixed")]
    pub seconds_setup: f64,
}
