//! The one record every study produces: a trial, one solver on one problem
//! under one setting, with its certified status beside the solver's claim,
//! its counts, its certificate, and its agreement with the study's
//! reference. In memory a [`Trial`] is typed (the mesh, the solver's entry,
//! the varied setting, the outcome's statuses, counts and certificate, the
//! separated intervals, the study's class); it becomes text only when
//! written, as a [`TrialRow`]. Accuracy columns are deterministic; times
//! live apart, in [`TrialTiming`].

use contactlab_solvers::registry::Entry;
use contactlab_solvers::{Law, Status, Stopping};
use serde::{Deserialize, Serialize};

use crate::certificate::{BoundReport, Certificate, Condition, ErrorBound};
use crate::coulomb::fixed_point::Ending;
use crate::io::csv::{fixed, fixed_opt};
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::agreement::Agreement;
use crate::study::class::Class;
pub use crate::study::class::WRONG_PRESSURE;

/// The ending of a diagnostic that is a time (kept out of the trial
/// rows: they are compared between runs).
pub const SECONDS_SUFFIX: &str = "_seconds";

/// A setting a trial varies: its path (`relaxation.r`, `epsilon`, or a
/// study's own name for what it varies, such as `friction`) and its value
/// as the command line writes it (`1e-3`, `exact`).
#[derive(Clone, Debug, PartialEq)]
pub struct Setting {
    pub path: String,
    pub value: String,
    /// The value as a number, when it is one.
    pub number: Option<f64>,
}

impl Setting {
    pub fn new(path: &str, value: &str) -> Self {
        Self {
            path: path.to_string(),
            value: value.to_string(),
            number: value.trim().parse().ok(),
        }
    }
}

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
    /// The setting varied, if any.
    pub setting: Option<Setting>,
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
    /// Whether it is measured against its scene's reference (false: its
    /// certificate alone says how accurate it is, where earning a reference
    /// would cost more than the trials themselves).
    pub against_reference: bool,
    /// Extra runs for the time (their minimum or median is reported).
    pub repeats: usize,
    /// Whether its answer's error bound is computed beside its certificate
    /// (false: a study none of whose views reads it, `bench`, where at
    /// h = 1/256 the bound took longer than a fast solve).
    pub bounded: bool,
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
            setting: None,
            settings: settings.clone(),
            work: None,
            seconds: None,
            check_solvable: true,
            against_reference: true,
            repeats: 0,
            bounded: true,
        }
    }

    /// The same trial with `path` set to `value` (as the command line writes it).
    pub fn varying(mut self, path: &str, value: &str) -> anyhow::Result<Self> {
        self.settings
            .set_text(path, value)
            .map_err(anyhow::Error::msg)?;
        self.setting = Some(Setting::new(path, value));
        Ok(self)
    }

    /// The same trial with the paper's ε set for every loop that uses one
    /// (the fixed point's and every solver knob named `epsilon`, as
    /// `--epsilon` does); recorded as the knob `epsilon`.
    pub fn varying_epsilon(mut self, epsilon: f64) -> anyhow::Result<Self> {
        self.settings
            .set_epsilon(epsilon)
            .map_err(anyhow::Error::msg)?;
        self.setting = Some(Setting::new("epsilon", &format!("{epsilon:e}")));
        Ok(self)
    }

    /// The same trial measured by its certificate alone, against no
    /// reference.
    pub fn without_reference(mut self) -> Self {
        self.against_reference = false;
        self
    }

    /// Whether the trial asks for its scene's reference.
    pub fn wants_reference(&self) -> bool {
        self.check_solvable && self.against_reference
    }

    /// The same trial without its error bound (see [`TrialSpec::bounded`]).
    pub fn unbounded(mut self) -> Self {
        self.bounded = false;
        self
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

/// One trial, typed: what was run and what came of it.
#[derive(Clone, Debug)]
pub struct Trial {
    pub study: &'static str,
    pub group: String,
    pub scene: String,
    pub h: MeshSize,
    pub solver: &'static Entry,
    pub law: Law,
    pub setting: Option<Setting>,
    pub stopping: Stopping,
    /// The certified status: the solver's claim, or `inaccurate` when a
    /// claim of convergence fails the certificate.
    pub status: Status,
    /// The solver's own claim.
    pub solver_status: Status,
    /// How the fixed point ended (`direct` for a solver of the Coulomb
    /// problem, `not_applicable` on the given-friction subproblem).
    pub outcome: TrialOutcome,
    pub friction_iterations: usize,
    pub outer_iterations: usize,
    pub inner_iterations: usize,
    /// Events of the solver's work stage.
    pub work: usize,
    /// The fixed point's last observed contraction factor.
    pub contraction: Option<f64>,
    /// The certificate of its answer (none for a trial not run), and the
    /// tolerance it is held to.
    pub certificate: Option<Certificate>,
    pub tolerance: f64,
    /// The solver whose answer is the reference, and the differences from it.
    pub reference: Option<&'static str>,
    pub agreement: Option<Agreement>,
    /// The certificate's error bound (issue 51) and what it bounds, or why
    /// there is none (none at all: not asked, e.g. a trial not run).
    pub bound: Option<BoundReport>,
    /// Separated intervals of Γ_K and their fraction.
    pub separated: Vec<[f64; 2]>,
    pub separated_fraction: f64,
    /// The scene's total vertical load on the upper body (condition (13):
    /// negative).
    pub total_load: f64,
    pub detail: String,
    /// What the solver reports beyond its counts (e.g. the condition
    /// number of its final Newton matrix).
    pub diagnostics: Vec<(&'static str, f64)>,
    /// A study's verdict on the trial (the stability map's class), and why.
    pub class: Option<Class>,
    pub reason: String,
}

impl Trial {
    /// Whether the certified status is converged.
    pub fn certified(&self) -> bool {
        self.status.is_converged()
    }

    /// The largest violation of the certificate (infinite without one).
    pub fn residual(&self) -> f64 {
        self.certificate.map_or(f64::INFINITY, |c| c.residual())
    }

    /// The conditions that fail the certificate, worst first (none without
    /// one: nothing was checked).
    pub fn failing(&self) -> Vec<Condition> {
        self.certificate.map(|c| c.failing()).unwrap_or_default()
    }

    /// The maximum pressure difference from the reference, if there was one.
    pub fn pressure_error(&self) -> Option<f64> {
        self.agreement.map(|a| a.pressure_max)
    }

    /// The maximum displacement difference from the reference.
    pub fn displacement_error(&self) -> Option<f64> {
        self.agreement.map(|a| a.displacement_max)
    }

    /// The error bound, if one was computed.
    pub fn error_bound(&self) -> Option<ErrorBound> {
        self.bound.as_ref().and_then(|b| b.bound)
    }

    /// The varied setting's path and value (`"", ""` when none).
    pub fn knob(&self) -> (&str, &str) {
        self.setting
            .as_ref()
            .map_or(("", ""), |s| (s.path.as_str(), s.value.as_str()))
    }

    /// A trial that was not run, with the reason (e.g. condition (13) fails):
    /// the spec's columns, infinite violations, no counts.
    pub fn not_run(spec: &TrialSpec, status: Status, detail: String) -> Self {
        Trial {
            study: spec.study,
            group: spec.group.clone(),
            scene: spec.scene.name.clone(),
            h: spec.scene.finest(),
            solver: spec.solver,
            law: spec.law,
            setting: spec.setting.clone(),
            stopping: spec.settings.stopping,
            status,
            solver_status: status,
            outcome: TrialOutcome::NotApplicable,
            friction_iterations: 0,
            outer_iterations: 0,
            inner_iterations: 0,
            work: 0,
            contraction: None,
            certificate: None,
            tolerance: spec.settings.certificate.tolerance,
            reference: None,
            agreement: None,
            bound: None,
            separated: Vec::new(),
            separated_fraction: 0.0,
            total_load: spec.scene.total_vertical_load(),
            detail,
            diagnostics: Vec::new(),
            class: None,
            reason: String::new(),
        }
    }

    /// The trial as a row of text, as written.
    pub fn row(&self) -> TrialRow {
        let (knob, value) = self.knob();
        let c = self
            .certificate
            .unwrap_or_else(|| Certificate::not_run(self.law, self.tolerance));
        let a = self.agreement;
        TrialRow {
            study: self.study.into(),
            group: self.group.clone(),
            scene: self.scene.clone(),
            h: self.h.to_string(),
            solver: self.solver.name.into(),
            law: self.law,
            knob: knob.into(),
            value: value.into(),
            stopping: self.stopping.as_str().into(),
            status: self.status,
            solver_status: self.solver_status,
            outcome: self.outcome,
            failing: self
                .failing()
                .iter()
                .map(|f| f.as_str())
                .collect::<Vec<_>>()
                .join(";"),
            friction_iterations: self.friction_iterations,
            outer_iterations: self.outer_iterations,
            inner_iterations: self.inner_iterations,
            work: self.work,
            contraction: self.contraction,
            certificate: self.residual(),
            certificate_tolerance: self.tolerance,
            nonpenetration: c.nonpenetration,
            pressure_sign: c.pressure_sign,
            complementarity: c.complementarity,
            friction_bound: c.friction_bound,
            stick: c.stick,
            slip_direction: c.slip_direction,
            stationarity: c.stationarity,
            force_balance: c.force_balance,
            reference: self.reference.unwrap_or_default().into(),
            displacement_error: a.map(|a| a.displacement_max),
            pressure_error: a.map(|a| a.pressure_max),
            traction_error: a.map(|a| a.traction_max),
            objective_gap: a.map(|a| a.objective_gap),
            energy_error: a.map(|a| a.energy),
            bound_displacement: self.error_bound().map(|b| b.displacement),
            bound_pressure: self.error_bound().map(|b| b.pressure),
            estimate_displacement: self
                .bound
                .as_ref()
                .and_then(|b| b.fixed_point)
                .map(|e| e.displacement),
            estimate_pressure: self
                .bound
                .as_ref()
                .and_then(|b| b.fixed_point)
                .map(|e| e.pressure),
            bound_kind: match &self.bound {
                Some(BoundReport { bound: Some(b), .. }) => b.kind.tag().into(),
                Some(BoundReport {
                    not_computed: Some(why),
                    ..
                }) => format!("none: {why}"),
                _ => String::new(),
            },
            separated: intervals_text(&self.separated),
            separated_fraction: self.separated_fraction,
            detail: self.detail.clone(),
            // Seconds (a solver's phases) are timings: not in the columns
            // that a rerun reproduces.
            diagnostics: self
                .diagnostics
                .iter()
                .filter(|(k, _)| !k.ends_with(SECONDS_SUFFIX))
                .map(|(k, v)| format!("{k}={v:e}"))
                .collect::<Vec<_>>()
                .join(";"),
            class: self.class.map(|c| c.as_str()).unwrap_or_default().into(),
            reason: self.reason.clone(),
        }
    }
}

/// Separated intervals as `[a;b] [c;d]` (no commas, for CSV).
pub fn intervals_text(intervals: &[[f64; 2]]) -> String {
    intervals
        .iter()
        .map(|[a, b]| format!("[{a:.4};{b:.4}]"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// One trial's accuracy record as written (one row of a study's trials CSV).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrialRow {
    pub study: String,
    pub group: String,
    pub scene: String,
    pub h: String,
    pub solver: String,
    pub law: Law,
    /// The setting varied and its value (empty when none).
    pub knob: String,
    #[serde(serialize_with = "crate::io::csv::setting_value")]
    pub value: String,
    pub stopping: String,
    pub status: Status,
    pub solver_status: Status,
    pub outcome: TrialOutcome,
    /// The conditions that fail the certificate, worst first (`;`-separated).
    pub failing: String,
    pub friction_iterations: usize,
    pub outer_iterations: usize,
    pub inner_iterations: usize,
    pub work: usize,
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
    /// ‖v − v_ref‖_A over √K·U (the energy seminorm the bound bounds).
    #[serde(serialize_with = "fixed_opt")]
    pub energy_error: Option<f64>,
    /// The error bound (issue 51): ‖v − v*‖_A over √K·U, and max|p − p*|
    /// over P; what it bounds (`rigorous`, `at-own-bound` for a Coulomb
    /// answer: the given-friction solution at its own g = 𝓕p), or `none:`
    /// and why not.
    #[serde(serialize_with = "fixed_opt")]
    pub bound_displacement: Option<f64>,
    #[serde(serialize_with = "fixed_opt")]
    pub bound_pressure: Option<f64>,
    /// A Coulomb answer of a fixed point: the whole error, the bound at
    /// its own g over (1 − k) for the observed contraction factor k (an
    /// estimate; `FixedPointEstimate`).
    #[serde(serialize_with = "fixed_opt")]
    pub estimate_displacement: Option<f64>,
    #[serde(serialize_with = "fixed_opt")]
    pub estimate_pressure: Option<f64>,
    pub bound_kind: String,
    /// Separated intervals of Γ_K (`[a;b] [c;d]`) and their fraction.
    pub separated: String,
    #[serde(serialize_with = "fixed")]
    pub separated_fraction: f64,
    pub detail: String,
    pub diagnostics: String,
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
    #[serde(serialize_with = "crate::io::csv::setting_value")]
    pub value: String,
    /// The timed runs: those after the first, warm-up run, or that one
    /// run when the trial has no repeats.
    pub runs: usize,
    #[serde(serialize_with = "fixed")]
    pub seconds_min: f64,
    #[serde(serialize_with = "fixed")]
    pub seconds_median: f64,
    #[serde(serialize_with = "fixed")]
    pub seconds_setup: f64,
}
