//! Coulomb friction by successive approximations (MPP), paper (9):
//! g⁰ = 0, solve the given-friction problem with g^m, set g^{m+1} = 𝓕 p(u^m),
//! stop when max_i |g^{m+1}_i − g^m_i| is below the tolerance. Whether this
//! converges in theory is an open question (the paper says so), so every
//! step is recorded and the way it ended is an [`Outcome`].

use std::time::Instant;

use contactlab_solvers::settings::{Kind, Knob, Stopping, Validate, check_tree, to_tree};
use contactlab_solvers::{
    ContactProblem, Control, Iterations, Observer, Progress, STOPPED_AT_NEED, Solution, Status,
};
use serde::{Deserialize, Serialize};

pub use super::single_level::SingleLevel;

/// The stage name of the fixed point's progress events (residual max|Δg|).
pub const STAGE: &str = "friction";

/// The default forcing factor: a step is asked for a pressure accurate to
/// 0.3 of the last relative change of g, so that steps whose g is far from
/// the fixed point are not solved to 1e-10. The answer's accuracy does not
/// depend on it: the fixed point ends only on a step solved to its own ε
/// (see [`friction_fixed_point`]); the forcing trades friction steps for
/// work per step, and 0.3 keeps the perturbed map contracting (the paper's
/// problems contract by about 0.1 per step). Measured with `tnnmg
/// --schedule nested`, problem 1, single runs: 110 → 61 iterations (1.14 →
/// 0.60 s) at 1/256 and 140 → 77 (19.4 → 11.8 s) at 1/1024 against 1e-3;
/// 0.1 took 74 and 94 (0.74 s, 14.2 s); problems 1-3 and all three
/// schedules certified at 1/256.
pub const DEFAULT_FORCING: f64 = 0.3;

/// Settings of the fixed point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CoulombSettings {
    /// How `epsilon` is read (set from the harness's stopping mode).
    pub stopping: Stopping,
    /// Stop when max_i |g^{m+1}_i − g^m_i| ≤ ε·𝓕·P (relative: 𝓕 the largest
    /// coefficient, P the problem's pressure scale) or ≤ ε (paper).
    pub epsilon: f64,
    /// Cap on given-friction solves.
    pub max_iterations: usize,
    /// Stop as not contracting when max|Δg| has not fallen over this many
    /// iterations (0: never).
    pub stall_window: usize,
    /// The forcing factor η of the inexact fixed point: step m + 1 asks its
    /// solver for a relative accuracy η·max|Δg^m|/(𝓕P) when that is looser
    /// than the solver's own tolerance ([`Start::accuracy`]; 0: never).
    pub forcing: f64,
    /// The nested schedule's ε on the levels below the finest, read as
    /// `epsilon` is; the larger of the two is used there. A coarse level's
    /// answer is only the next level's start, and nested iteration (full
    /// multigrid) needs each level solved to about its discretization
    /// error, not beyond ([`DEFAULT_COARSE_EPSILON`]). Without friction,
    /// where the fixed point is one solve and asks no accuracy, it is the
    /// accuracy those levels' solves are asked for ([`Start::accuracy`]).
    ///
    /// [`Start::accuracy`]: contactlab_solvers::Start
    pub coarse_epsilon: f64,
}

/// The coarse levels' default ε of the nested schedule (relative). The
/// first step on a finer level changes g by about the discretization gap
/// between the two meshes: 3.0e-2·𝓕P from 1/256 to 1/512 and 1.7e-2·𝓕P
/// from 1/512 to 1/1024 on problem 1, so 1e-3 leaves the start a tenth of
/// that gap from the coarse fixed point. Measured with `tnnmg --schedule
/// nested`, problem 1 at 1/1024, single runs: the coarse levels' friction
/// steps fell from 7 to 2-3 each and the solve from 11.1 to 9.2 s, with
/// the same 7 steps on the finest and the same certified answer (max
/// pressure equal to 12 digits); 1e-2 did no better (9.1 s).
pub const DEFAULT_COARSE_EPSILON: f64 = 1e-3;

impl Default for CoulombSettings {
    fn default() -> Self {
        Self::defaults(Stopping::Relative)
    }
}

impl CoulombSettings {
    /// The paper's ε = 1e-4 (absolute), or its relative counterpart 1e-7:
    /// the fixed point's stopping error, about ε·𝓕P·q/(1 − q) for a
    /// contraction factor q, stays ten times below the certificate's default
    /// tolerance 1e-5 for q ≤ 0.9, while a tighter ε (1e-8 was measured)
    /// falls under the noise of the inner solvers' own answers (Clarabel's
    /// fixed point then stalls near max|Δg| = 1e-7·P at 𝓕 = 2).
    pub fn defaults(stopping: Stopping) -> Self {
        Self {
            stopping,
            epsilon: match stopping {
                Stopping::Paper => 1e-4,
                Stopping::Relative => 1e-7,
            },
            max_iterations: 50,
            stall_window: 5,
            forcing: DEFAULT_FORCING,
            coarse_epsilon: match stopping {
                // The paper solves no coarse level to an ε of its own.
                Stopping::Paper => 1e-4,
                Stopping::Relative => DEFAULT_COARSE_EPSILON,
            },
        }
    }

    /// The threshold on max|Δg| for `problem`.
    pub fn tolerance(&self, problem: &ContactProblem) -> f64 {
        match self.stopping {
            Stopping::Paper => self.epsilon,
            Stopping::Relative => {
                let coefficient = problem
                    .contacts()
                    .iter()
                    .fold(0.0f64, |m, c| m.max(c.coefficient));
                self.epsilon * coefficient * problem.scales().pressure
            }
        }
    }
}

/// The fixed point's settings as knobs (`coulomb.NAME`): what they do and
/// the values they take; their defaults are [`CoulombSettings::defaults`].
pub const KNOBS: &[Knob] = &[
    Knob {
        name: "epsilon",
        fields: &["epsilon"],
        help: "the friction tolerance: stop when max|Δg| ≤ ε·𝓕·P (relative) or ≤ ε (paper)",
        kind: Kind::Positive,
    },
    Knob {
        name: "max_iterations",
        fields: &["max_iterations"],
        help: "cap on friction iterations (given-friction solves)",
        kind: Kind::Count,
    },
    Knob {
        name: "forcing",
        fields: &["forcing"],
        help: "inexact fixed point: ask each given-friction solve for an accuracy of its pressure of forcing·max|Δg|/(𝓕P) of the previous step, relative to P, when looser than its own tolerance (solvers that read it: tnnmg); the fixed point still ends only on a step asked for its own ε or better; in [0, 1), as an inexact iteration's forcing terms must be (Dembo, Eisenstat & Steihaug 1982); 0: never",
        kind: Kind::Fraction,
    },
    Knob {
        name: "coarse_epsilon",
        fields: &["coarse_epsilon"],
        help: "nested schedule: the friction tolerance on the levels below the finest, read as epsilon is (the larger of the two is used there); their answers only start the next level; without friction, the accuracy of the pressure their solves are asked for (solvers that read it: tnnmg)",
        kind: Kind::Positive,
    },
    Knob {
        name: "stall_window",
        fields: &["stall_window"],
        help: "stop as not contracting when max|Δg| has not fallen over this many iterations (0: never)",
        kind: Kind::Whole,
    },
];

/// The fixed point's settings tree in a stopping mode.
pub fn default_tree(stopping: Stopping) -> serde_json::Value {
    to_tree(&CoulombSettings::defaults(stopping))
}

impl Validate for CoulombSettings {
    fn validate(&self) -> Result<(), String> {
        check_tree("coulomb", KNOBS, default_tree, &to_tree(self))
    }
}

/// One way of solving the given-friction subproblem for a bound g on the
/// finest level's contact nodes (one level, or mesh continuation).
pub trait GivenFrictionStep {
    /// The finest level's problem (its coefficients and scales).
    fn problem(&self) -> &ContactProblem;
    /// Solves with friction bound `g`, to the relative `accuracy` if the
    /// caller needs less than the solver's own tolerance ([`Start::accuracy`]).
    fn solve_step(
        &mut self,
        g: &[f64],
        accuracy: Option<f64>,
        observer: &mut dyn Observer,
    ) -> Solution;
    /// Takes back the last solution once the fixed point has read it: the
    /// start of the next step, held without a copy (a copy of v was 17 MB
    /// of tnnmg's peak at h = 1/1024). A caller that does not hand it back
    /// gets a next step started afresh.
    fn keep(&mut self, _solution: Solution) {}
    /// Tightens the solver's own tolerance one step ([`Solver::tighten`]),
    /// saying what changed; None: it cannot.
    ///
    /// [`Solver::tighten`]: contactlab_solvers::Solver::tighten
    fn tighten(&mut self) -> Option<String> {
        None
    }
    /// The first bound g⁰ of the fixed point, when the step can do better
    /// than g⁰ = 0 (the nested schedule: the Coulomb problem solved on the
    /// coarser meshes first); None: g⁰ = 0.
    fn initial_bound(
        &mut self,
        _settings: &CoulombSettings,
        _observer: &mut dyn Observer,
    ) -> Option<Vec<f64>> {
        None
    }
}

/// The fixed point's first bound g⁰ when no step gives a better one:
/// g⁰ = 0, the frictionless problem, unless a rigid mode moves slips
/// alone (a body free sideways). Friction alone holds that mode, and the
/// given-friction problem at g = 0 has no solution under a tangential
/// load; g⁰ = 𝓕 P, the bound of the mean pressure P = N/L, carries what
/// every later bound 𝓕p carries (Σ w p = N by the force balance), so each
/// step is solvable when the Coulomb problem is (|Q| < 𝓕N).
pub fn first_bound(problem: &ContactProblem) -> Vec<f64> {
    let contacts = problem.contacts();
    let held_by_friction = problem
        .rigid_modes()
        .iter()
        .any(|z| !contactlab_solvers::problem::moves_a_jump(z, contacts));
    let p = if held_by_friction {
        problem.scales().pressure
    } else {
        0.0
    };
    contacts.iter().map(|c| c.coefficient * p).collect()
}

/// g_i = 𝓕_i p_i⁺ for the problem's coefficients: the bound of paper (9).
pub fn bound_of(problem: &ContactProblem, pressure: &[f64]) -> Vec<f64> {
    problem
        .contacts()
        .iter()
        .zip(pressure)
        .map(|(c, p)| c.coefficient * p.max(0.0))
        .collect()
}

/// How the fixed point ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ending {
    /// max|Δg| reached the tolerance.
    Converged,
    /// max|Δg| did not fall over the stall window.
    NotContracting,
    /// The iteration cap came first.
    IterationCap,
    /// A given-friction solve did not converge (its status says how).
    InnerFailed,
    /// The new bound was not finite.
    NonFinite,
    /// The harness stopped it (a budget).
    Stopped,
    /// No fixed point: a solver of the Coulomb problem itself.
    Direct,
}

impl Ending {
    pub fn as_str(self) -> &'static str {
        match self {
            Ending::Converged => "converged",
            Ending::NotContracting => "not_contracting",
            Ending::IterationCap => "iteration_cap",
            Ending::InnerFailed => "inner_failed",
            Ending::NonFinite => "non_finite",
            Ending::Stopped => "stopped",
            Ending::Direct => "direct",
        }
    }
}

/// One step of the fixed point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrictionIteration {
    /// 1-based.
    pub iteration: usize,
    /// max_i |g^{m+1}_i − g^m_i| after this step.
    pub change: f64,
    /// change / previous change (the observed contraction factor).
    pub contraction: Option<f64>,
    pub status: Status,
    pub iterations: Iterations,
    /// Wall-clock seconds of this step, and the part the solver spent setting up.
    pub seconds: f64,
    pub setup_seconds: f64,
}

/// The outcome of the fixed point.
#[derive(Clone, Debug)]
pub struct CoulombSolution {
    /// The last given-friction solution (for the bound `g`).
    pub solution: Solution,
    /// The bound the last solution was computed with.
    pub g: Vec<f64>,
    pub history: Vec<FrictionIteration>,
    /// The solver's claim: converged only if every step converged and the
    /// fixed point reached its tolerance.
    pub status: Status,
    pub ending: Ending,
    pub detail: String,
    pub seconds: f64,
}

impl CoulombSolution {
    /// Inner iterations summed over all friction steps.
    pub fn total_iterations(&self) -> Iterations {
        self.history
            .iter()
            .fold(Iterations::default(), |a, h| Iterations {
                outer: a.outer + h.iterations.outer,
                inner: a.inner + h.iterations.inner,
            })
    }
}

/// Successive approximations (9): g^{m+1}_i = 𝓕_i p_i(u^m) with the
/// coefficients of the step's problem.
pub fn friction_fixed_point(
    step: &mut dyn GivenFrictionStep,
    settings: &CoulombSettings,
    observer: &mut dyn Observer,
) -> CoulombSolution {
    friction_fixed_point_accepting(step, settings, observer, &|_, _| true)
}

/// [`friction_fixed_point`] whose convergence must also pass `accept` on
/// the step's problem (the
/// harness's certificate of the answer, code the fixed point does not
/// share): a converged step that `accept` rejects tightens the solver
/// ([`GivenFrictionStep::tighten`]) and the fixed point goes on from it;
/// a solver that cannot tighten ends it as converged, and the certificate
/// then says what it says.
pub fn friction_fixed_point_accepting(
    step: &mut dyn GivenFrictionStep,
    settings: &CoulombSettings,
    observer: &mut dyn Observer,
    accept: &dyn Fn(&ContactProblem, &Solution) -> bool,
) -> CoulombSolution {
    let start = Instant::now();
    let tolerance = settings.tolerance(step.problem());
    let coefficient: Vec<f64> = step
        .problem()
        .contacts()
        .iter()
        .map(|c| c.coefficient)
        .collect();
    let mut g = step
        .initial_bound(settings, observer)
        .filter(|g| g.len() == coefficient.len())
        .unwrap_or_else(|| first_bound(step.problem()));
    let mut history: Vec<FrictionIteration> = Vec::new();
    let mut last_change: Option<f64> = None;
    // The stall test looks back only to the last tightening of the solver
    // (its steps before it were at another accuracy), and what was
    // tightened goes into the detail.
    let mut stall_from = 0;
    let tightened: std::cell::RefCell<Vec<String>> = Default::default();
    // The relative change of g is max|Δg| over 𝓕P.
    let bound_scale =
        coefficient.iter().fold(0.0f64, |m, c| m.max(*c)) * step.problem().scales().pressure;
    for m in 1..=settings.max_iterations {
        let t = Instant::now();
        // The first step, from g = 0, is as far from the fixed point as g
        // itself (relative change 1).
        let accuracy = (settings.forcing > 0.0 && bound_scale > 0.0)
            .then(|| settings.forcing * last_change.map_or(1.0, |c| c / bound_scale));
        let solution = step.solve_step(&g, accuracy, observer);
        let g_next: Vec<f64> = solution
            .pressure
            .iter()
            .zip(&coefficient)
            .map(|(p, f)| f * p.max(0.0))
            .collect();
        let change = g_next
            .iter()
            .zip(&g)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f64, |c, d| if d.is_nan() { f64::NAN } else { c.max(d) });
        history.push(FrictionIteration {
            iteration: m,
            change,
            contraction: last_change.filter(|c| *c > 0.0).map(|c| change / c),
            status: solution.status,
            iterations: solution.iterations,
            seconds: t.elapsed().as_secs_f64(),
            setup_seconds: solution.timing.setup,
        });
        let control = observer.observe(&Progress {
            stage: STAGE,
            iteration: m,
            residual: change,
            seconds: start.elapsed().as_secs_f64(),
        });
        let finish = |status, ending, detail: String, solution: Solution, g: Vec<f64>, history| {
            let tightened = tightened.borrow();
            let detail = if tightened.is_empty() {
                detail
            } else {
                format!(
                    "{detail} (the solver tightened: {})",
                    tightened.join(", then ")
                )
            };
            CoulombSolution {
                solution,
                g,
                history,
                status,
                ending,
                detail,
                seconds: start.elapsed().as_secs_f64(),
            }
        };
        if !solution.status.is_converged() {
            // A solver that declines the problem (not run) says why, and
            // that is the whole of it: no step was taken.
            let detail = if solution.status == Status::NotRun {
                solution.detail.clone()
            } else {
                format!(
                    "given-friction step {m} did not converge: {}",
                    solution.detail
                )
            };
            return finish(
                solution.status,
                Ending::InnerFailed,
                detail,
                solution,
                g,
                history,
            );
        }
        if !change.is_finite() {
            let detail = format!("friction step {m}: the new friction bound is not finite");
            return finish(
                Status::NonFinite,
                Ending::NonFinite,
                detail,
                solution,
                g,
                history,
            );
        }
        // A change between solves, the last of which stopped at a need
        // looser than the stop's own accuracy, proves nothing at that
        // accuracy: two loose solves can stop alike short of p(g) (seen
        // with the forcing 0.1, revisit schedule, problem 3 at 1/32:
        // max|Δg| = 1e-12 with the pressure 2e-6·P off). Such a step goes
        // on, and its successor is asked for forcing·change, below the
        // stop's accuracy. Solvers that ignore the need are never loose.
        let inexact = solution
            .diagnostics
            .iter()
            .any(|&(name, need)| name == STOPPED_AT_NEED && need * bound_scale > tolerance);
        let mut converged = change <= tolerance && !inexact;
        if converged
            && !accept(step.problem(), &solution)
            && let Some(what) = step.tighten()
        {
            tightened
                .borrow_mut()
                .push(format!("{what} at step {m}, its answer rejected"));
            stall_from = m;
            converged = false;
        }
        if converged {
            let detail =
                format!("max|Δg| = {change:.3e} ≤ {tolerance:.3e} after {m} friction iterations");
            return finish(
                Status::Converged,
                Ending::Converged,
                detail,
                solution,
                g,
                history,
            );
        }
        if let Control::Stop(status) = control {
            let detail = format!("stopped by the harness after {m} friction iterations");
            return finish(status, Ending::Stopped, detail, solution, g, history);
        }
        // A past step whose change met the tolerance without ending the
        // fixed point was a loose one: its change proved nothing, and is
        // no baseline of the stall test either.
        let w = settings.stall_window;
        let baseline = (w > 0 && m > stall_from + w)
            .then(|| history[m - 1 - w].change)
            .filter(|&c| c > tolerance);
        if let Some(before) = baseline.filter(|&c| change >= c) {
            // A stall at the noise of the solves: a solver that can solve
            // more accurately does so, and the fixed point goes on.
            if let Some(what) = step.tighten() {
                tightened
                    .borrow_mut()
                    .push(format!("{what} at step {m}, the fixed point stalled"));
                stall_from = m;
            } else {
                let detail = format!(
                    "the fixed point is not contracting: max|Δg| went from {before:.3e} to {change:.3e} over the last {w} friction iterations"
                );
                return finish(
                    Status::InsufficientProgress,
                    Ending::NotContracting,
                    detail,
                    solution,
                    g,
                    history,
                );
            }
        }
        if m == settings.max_iterations {
            let detail = format!(
                "friction iteration cap {m} reached with max|Δg| = {change:.3e} > {tolerance:.3e}"
            );
            return finish(
                Status::MaxIterations,
                Ending::IterationCap,
                detail,
                solution,
                g,
                history,
            );
        }
        step.keep(solution);
        g = g_next;
        last_change = Some(change);
    }
    unreachable!("max_iterations ≥ 1 is validated")
}

#[cfg(test)]
#[path = "fixed_point_tests.rs"]
mod tests;
