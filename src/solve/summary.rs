//! `summary.json` of `contactlab solve`: a view of one [`Outcome`] with
//! the scene, the settings and the contact zone.

use contactlab_solvers::{ContactProblem, Friction, Solution, Status};
use serde::Serialize;

use crate::certificate::{BoundReport, Certificate, SOLVE_BOUND_MAX_UNKNOWNS, bound_room};
use crate::coulomb::continuation::LevelCount;
use crate::coulomb::fixed_point::{Ending, FrictionIteration};
use crate::mechanics::scene::Scene;
use crate::settings::CertificateSettings;
use crate::settings::Settings;
use crate::solve::{Outcome, Solved};

/// `summary.json`.
#[derive(Debug, Serialize)]
pub struct Summary {
    /// The whole scene: material, loads (normal and tangential), friction,
    /// mesh levels.
    pub scene: Scene,
    /// The commit of contactlab that produced it (the binary's).
    pub git_commit: String,
    pub problem: String,
    pub h: String,
    pub solver: String,
    pub plane: String,
    pub friction_coefficient: f64,
    pub friction_iterations: usize,
    /// The certified status: `converged` only if the solver claimed it and
    /// the certificate passed.
    pub status: Status,
    /// The solver's own claim, beside it.
    pub solver_status: Status,
    /// How the fixed point ended (`direct` for a Coulomb solver).
    pub outcome: Ending,
    pub detail: String,
    /// Every condition of the Coulomb law at g = 𝓕p, in the problem's scales.
    pub certificate: Certificate,
    /// Which condition fails or is worst, in words.
    pub certificate_summary: String,
    /// An upper bound on the answer's error from the duality gap
    /// ([`crate::certificate::error_bound`]), or why there is none.
    pub error_bound: BoundReport,
    pub separated_intervals: Vec<[f64; 2]>,
    pub separated_fraction: f64,
    pub separation_tolerance: f64,
    pub max_pressure: f64,
    pub total_contact_force: f64,
    pub total_applied_load: f64,
    pub objective: f64,
    /// The solver's work: outer iterations (interior-point, Uzawa or Newton,
    /// over all friction iterations) and inner ones (sweeps).
    pub iterations_outer: usize,
    pub iterations_inner: usize,
    /// Seconds of the whole solve, its set-up (building, factorizing) and
    /// the rest.
    pub seconds: f64,
    pub seconds_setup: f64,
    pub seconds_solve: f64,
    pub history: Vec<FrictionIteration>,
    pub levels: Vec<LevelCount>,
    /// Every setting, resolved.
    pub settings: serde_json::Value,
}

impl Summary {
    /// The summary of `solved` on `scene` at `settings`; `git_commit` is
    /// the provenance the command attaches.
    /// `error_bound` is the answer's ([`answer_bound`]), computed by the
    /// caller: a summary is a view, and the bound takes factorizations.
    pub fn of(
        solved: &Solved,
        scene: &Scene,
        settings: &Settings,
        error_bound: BoundReport,
        git_commit: String,
    ) -> Self {
        let o: &Outcome = &solved.outcome;
        let s = &o.solution;
        let d = &solved.finest;
        let total_contact_force = d.problem.total_contact_force(&s.pressure);
        let separation = solved.separation();
        Summary {
            scene: scene.clone(),
            git_commit,
            problem: scene.name.clone(),
            h: d.h().to_string(),
            solver: o.solver.name.to_string(),
            plane: scene.material.plane.to_string(),
            friction_coefficient: scene.friction,
            friction_iterations: o.friction_iterations(),
            status: o.status,
            solver_status: o.claim,
            outcome: o.ending(),
            detail: o.detail.clone(),
            certificate: o.certificate,
            certificate_summary: o.certificate.summary(),
            error_bound,
            separated_intervals: separation.intervals,
            separated_fraction: separation.fraction,
            separation_tolerance: separation.tolerance,
            max_pressure: s.pressure.iter().fold(f64::NEG_INFINITY, |m, p| m.max(*p)),
            total_contact_force,
            total_applied_load: d.total_load,
            objective: solved.objective(),
            iterations_outer: o.work.outer,
            iterations_inner: o.work.inner,
            seconds: o.timing.total(),
            seconds_setup: o.timing.setup,
            seconds_solve: o.timing.solve,
            history: o
                .fixed_point
                .as_ref()
                .map(|fp| fp.history.clone())
                .unwrap_or_default(),
            levels: o.levels.clone(),
            settings: settings.resolved(),
        }
    }
}

/// The error bound of the answer (issue 51), on meshes where it costs
/// about what the solve does (up to `certificate.bound_max_unknowns`,
/// by default [`SOLVE_BOUND_MAX_UNKNOWNS`]) and its factors fit in half
/// the memory that is free.
pub fn answer_bound(solved: &Solved, settings: &CertificateSettings) -> BoundReport {
    bound_within_limit(
        &solved.finest.problem,
        Friction::Coulomb,
        &solved.outcome.solution,
        settings,
    )
    .with_contraction(solved.outcome.contraction_for_estimate())
}

/// The bound of `s` under `friction` if the problem has at most
/// `certificate.bound_max_unknowns` unknowns (else why not): the one gate
/// of `solve` and of every trial.
pub fn bound_within_limit(
    problem: &ContactProblem,
    friction: Friction<'_>,
    s: &Solution,
    settings: &CertificateSettings,
) -> BoundReport {
    if !settings.bounds(problem.n()) {
        return BoundReport::skipped(too_large_to_bound(problem.n(), settings));
    }
    BoundReport::of_solution(problem, friction, s, bound_room())
}

/// Why an answer of `n` unknowns gets no bound, and the way to one.
pub fn too_large_to_bound(n: usize, settings: &CertificateSettings) -> String {
    format!(
        "{n} unknowns, more than certificate.bound_max_unknowns = {} (default {SOLVE_BOUND_MAX_UNKNOWNS}, h = 1/512); raise it with --set certificate.bound_max_unknowns=N, or `certify` an answer written by `solve --out`",
        settings.bound_max_unknowns
    )
}
