//! Parameter sweeps. One factor at a time around the paper's settings:
//! - `r`, `epsilon`, `smoothing`, `schedule`: the whole Coulomb problem with
//!   the paper's solver (relaxation), errors against a tight oracle solution;
//! - `tolerance`: every registered solver through its own accuracy knob on
//!   the given-friction subproblem at the oracle's g (the work-precision
//!   diagram: no outer loop blurs the comparison).
//!
//! Every planned run gives a row, converged or not: the status says which.

use anyhow::Result;
use contactlab_solvers::registry;
use contactlab_solvers::{Silent, Smoothing};
use rayon::prelude::*;
use serde::Serialize;
use serde_json::Value;

use crate::coulomb::continuation::Schedule;
use crate::coulomb::driver::{Run, solve_scene};
use crate::mechanics::discretization::Discretization;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::compare::{Agreement, Mode, ORACLE, agreement, solve_given_friction};
use contactlab_solvers::Solution;

/// What a sweep varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Factor {
    /// Penalty r of the modified Lagrangian.
    R,
    /// The paper's ε (Coulomb, Uzawa and sweep thresholds together).
    Epsilon,
    /// Huber width δ of |s|, and the exact minimizer.
    Smoothing,
    /// Continuation schedule.
    Schedule,
    /// Each solver's own tolerance, on the given-friction subproblem.
    Tolerance,
}

impl Factor {
    pub fn as_str(self) -> &'static str {
        match self {
            Factor::R => "r",
            Factor::Epsilon => "epsilon",
            Factor::Smoothing => "smoothing",
            Factor::Schedule => "schedule",
            Factor::Tolerance => "tolerance",
        }
    }
}

/// What to sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepSpec {
    /// Scenes to sweep (their own levels are replaced by 1/8 ... each mesh).
    pub scenes: Vec<Scene>,
    pub meshes: Vec<MeshSize>,
    pub factors: Vec<Factor>,
    pub r_values: Vec<f64>,
    pub epsilon_values: Vec<f64>,
    pub smoothing_values: Vec<Smoothing>,
    pub schedules: Vec<Schedule>,
    /// Solvers of the tolerance factor (default: all registered).
    pub solvers: Vec<&'static str>,
    /// Wall-clock budget of one given-friction solve, seconds.
    pub time_limit: f64,
    /// Run in parallel (then times are not recorded: they would not compare).
    pub parallel: bool,
    /// Extra timed runs of each tolerance-factor run (short given-friction
    /// solves); their time is the minimum over all runs.
    pub repeats: usize,
    /// Take every k-th value of each solver's tolerance list (1: all).
    pub tolerance_stride: usize,
}

impl Default for SweepSpec {
    fn default() -> Self {
        Self {
            scenes: vec![Scene::paper_problem(1).expect("built in")],
            meshes: vec![MeshSize::from_level(5).expect("in range")],
            factors: vec![
                Factor::R,
                Factor::Epsilon,
                Factor::Smoothing,
                Factor::Schedule,
                Factor::Tolerance,
            ],
            r_values: (0..=14).map(|k| 10f64.powi(k)).collect(),
            epsilon_values: (2..=8).map(|k| 10f64.powi(-k)).collect(),
            smoothing_values: std::iter::once(Smoothing::Exact)
                .chain((6..=12).step_by(2).map(|k| Smoothing::Huber {
                    delta: 10f64.powi(-k),
                }))
                .collect(),
            schedules: vec![Schedule::Revisit, Schedule::FinestOnly],
            solvers: registry::names(),
            time_limit: 30.0,
            parallel: false,
            repeats: 2,
            tolerance_stride: 1,
        }
    }
}

/// One planned run.
#[derive(Clone, Debug)]
pub struct PlannedRun {
    /// Index of the scene in the spec.
    pub scene: usize,
    pub problem: String,
    pub h: MeshSize,
    pub factor: Factor,
    pub mode: Mode,
    pub solver: &'static str,
    /// The varied value as text (a number, `exact`, a schedule).
    pub value: String,
    pub settings: Settings,
}

/// One row of `sweep.csv`.
#[derive(Clone, Debug, Serialize)]
pub struct SweepRow {
    /// The scene's name.
    pub problem: String,
    pub h: String,
    pub factor: &'static str,
    pub mode: &'static str,
    pub solver: String,
    pub value: String,
    pub r: f64,
    pub epsilon: f64,
    pub smoothing: String,
    pub schedule: String,
    pub status: String,
    pub converged: bool,
    pub friction_iterations: usize,
    pub outer: usize,
    pub inner: usize,
    pub agreement: Agreement,
    pub kkt: f64,
    pub separated_fraction: f64,
    /// Seconds of solver work (None in parallel sweeps).
    pub seconds: Option<f64>,
}

/// Expands a spec into runs.
pub fn plan(spec: &SweepSpec, base: &Settings) -> Vec<PlannedRun> {
    let mut runs = Vec::new();
    let set =
        |s: &mut Settings, path: &str, v: Value| s.set(path, v).expect("a registered setting");
    for (index, scene) in spec.scenes.iter().enumerate() {
        for &h in &spec.meshes {
            let mut push = |factor, mode, solver, value: String, settings: Settings| {
                runs.push(PlannedRun {
                    scene: index,
                    problem: scene.name.clone(),
                    h,
                    factor,
                    mode,
                    solver,
                    value,
                    settings,
                })
            };
            for &factor in &spec.factors {
                match factor {
                    Factor::R => {
                        for &r in &spec.r_values {
                            let mut s = base.clone();
                            set(&mut s, "relaxation.r", Value::from(r));
                            push(factor, Mode::Coulomb, "relaxation", format!("{r:e}"), s);
                        }
                    }
                    Factor::Epsilon => {
                        for &e in &spec.epsilon_values {
                            let mut s = base.clone();
                            s.set_epsilon(e).expect("registered settings");
                            push(factor, Mode::Coulomb, "relaxation", format!("{e:e}"), s);
                        }
                    }
                    Factor::Smoothing => {
                        for &sm in &spec.smoothing_values {
                            let mut s = base.clone();
                            set(
                                &mut s,
                                "relaxation.smoothing",
                                serde_json::to_value(sm).expect("a tree"),
                            );
                            push(factor, Mode::Coulomb, "relaxation", sm.label(), s);
                        }
                    }
                    Factor::Schedule => {
                        for &sc in &spec.schedules {
                            let mut s = base.clone();
                            s.schedule = sc;
                            push(factor, Mode::Coulomb, "relaxation", sc.to_string(), s);
                        }
                    }
                    Factor::Tolerance => {
                        for &name in &spec.solvers {
                            let Some(entry) = registry::by_name(name) else {
                                continue;
                            };
                            for &t in entry
                                .accuracy
                                .values
                                .iter()
                                .step_by(spec.tolerance_stride.max(1))
                            {
                                let mut s = base.clone();
                                let path = format!("{}.{}", entry.name, entry.accuracy.knob);
                                set(&mut s, &path, Value::from(t));
                                push(factor, Mode::GivenFriction, entry.name, format!("{t:e}"), s);
                            }
                        }
                    }
                }
            }
        }
    }
    runs
}

/// The references of one (scene, h): the most accurate Coulomb solution
/// available and its given-friction subproblem, and how far the oracle is
/// from it.
pub struct Reference {
    pub scene: Scene,
    /// The solver that produced the reference (`newton` unless it failed).
    pub solver: &'static str,
    pub coulomb: Run,
    pub g: Vec<f64>,
    pub subproblem: (Discretization, Solution),
    /// Max pressure difference of the oracle's subproblem solution from the
    /// reference (relative): the oracle's own accuracy.
    pub oracle_pressure_error: f64,
}

/// Fixed-point tolerance of the reference Coulomb solution.
pub const REFERENCE_COULOMB_EPSILON: f64 = 1e-9;

/// The reference: the exact solver (`newton`, tolerance 1e-12, residuals
/// ~1e-13) where it converges, cross-checked against the oracle; the oracle
/// itself otherwise. Errors are then resolved below the oracle's own ~1e-8.
pub fn reference(scene: &Scene, h: MeshSize, base: &Settings) -> Result<Reference> {
    let mut scene = scene.clone();
    scene.set_finest(h);
    let mut s = base.clone();
    s.set("coulomb.epsilon", Value::from(REFERENCE_COULOMB_EPSILON))
        .expect("a setting");
    s.set("newton.tolerance", Value::from(1e-12))
        .expect("a setting");
    let exact = solve_scene(&scene, &s, "newton", &mut Silent)?;
    let (solver, coulomb) = if exact.coulomb.status.is_converged() {
        ("newton", exact)
    } else {
        s.set("coulomb.epsilon", Value::from(1e-6))
            .expect("a setting");
        (ORACLE, solve_scene(&scene, &s, ORACLE, &mut Silent)?)
    };
    if !coulomb.coulomb.status.is_converged() {
        anyhow::bail!(
            "the reference ({solver}) did not converge on {} at h = {h}: {}",
            scene.name,
            coulomb.coulomb.detail
        );
    }
    let g = coulomb.coulomb.g.clone();
    let (d, sol, _) = solve_given_friction(&scene, &s, solver, &g, &mut Silent)?;
    let (_, oracle, _) = solve_given_friction(&scene, base, ORACLE, &g, &mut Silent)?;
    let oracle_pressure_error = agreement(&d, &oracle, &sol).pressure_max;
    Ok(Reference {
        scene,
        solver,
        coulomb,
        g,
        subproblem: (d, sol),
        oracle_pressure_error,
    })
}

/// Runs one planned run against its reference.
pub fn run_one(
    run: &PlannedRun,
    reference: &Reference,
    timed: bool,
    repeats: usize,
    time_limit: f64,
) -> Result<SweepRow> {
    let entry = crate::coulomb::driver::solver_entry(run.solver)?;
    let budget = || crate::coulomb::budget::Budget::silent(entry, None, Some(time_limit));
    let (
        status,
        converged,
        friction_iterations,
        outer,
        inner,
        agree,
        kkt,
        separated_fraction,
        seconds,
    ) = match run.mode {
        Mode::Coulomb => {
            let out = solve_scene(&reference.scene, &run.settings, run.solver, &mut budget())?;
            let total = out.coulomb.total_iterations();
            let agree = agreement(
                &reference.coulomb.discretization,
                &out.coulomb.solution,
                &reference.coulomb.coulomb.solution,
            );
            (
                out.status,
                out.status.is_converged(),
                out.coulomb.history.len(),
                total.outer,
                total.inner,
                agree,
                out.certificate.residual(),
                out.separation.fraction,
                out.coulomb.seconds,
            )
        }
        Mode::GivenFriction => {
            let (d, s, _) = solve_given_friction(
                &reference.scene,
                &run.settings,
                run.solver,
                &reference.g,
                &mut budget(),
            )?;
            let mut seconds = s.timing.total();
            if timed {
                for _ in 0..repeats {
                    let (_, again, _) = solve_given_friction(
                        &reference.scene,
                        &run.settings,
                        run.solver,
                        &reference.g,
                        &mut Silent,
                    )?;
                    seconds = seconds.min(again.timing.total());
                }
            }
            let agree = agreement(&d, &s, &reference.subproblem.1);
            let certificate = crate::certificate::certify(
                &d.problem,
                contactlab_solvers::Law::GivenFriction,
                &s.v,
                &s.pressure,
                &s.friction_traction,
                run.settings.certificate.tolerance,
            );
            let kkt = certificate.residual();
            let status = certificate.verdict(s.status);
            let fraction = crate::mechanics::contact_zone::separation_of(&d, &s).fraction;
            (
                status,
                status.is_converged(),
                0,
                s.iterations.outer,
                s.iterations.inner,
                agree,
                kkt,
                fraction,
                seconds,
            )
        }
    };
    Ok(SweepRow {
        problem: run.problem.clone(),
        h: run.h.to_string(),
        factor: run.factor.as_str(),
        mode: run.mode.as_str(),
        solver: run.solver.to_string(),
        value: run.value.clone(),
        r: setting_number(&run.settings, "relaxation.r"),
        epsilon: setting_number(&run.settings, "relaxation.epsilon"),
        smoothing: run
            .settings
            .get("relaxation.smoothing")
            .and_then(|v| serde_json::from_value::<Smoothing>(v).ok())
            .map(|s| s.label())
            .unwrap_or_default(),
        schedule: run.settings.schedule.to_string(),
        status: status.to_string(),
        converged,
        friction_iterations,
        outer,
        inner,
        agreement: agree,
        kkt,
        separated_fraction,
        seconds: timed.then_some(seconds),
    })
}

fn setting_number(settings: &Settings, path: &str) -> f64 {
    settings
        .get(path)
        .and_then(|v| v.as_f64())
        .unwrap_or(f64::NAN)
}

/// Which reference a sweep measured against, per scene and mesh.
#[derive(Clone, Debug, Serialize)]
pub struct ReferenceInfo {
    pub problem: String,
    pub h: String,
    pub solver: &'static str,
    /// The oracle's max pressure difference from it (its own accuracy).
    pub oracle_pressure_error: f64,
}

/// Runs a sweep; `tick` is called after every run (for a progress bar).
pub fn sweep(
    spec: &SweepSpec,
    base: &Settings,
    tick: &(dyn Fn(&PlannedRun) + Sync),
) -> Result<(Vec<SweepRow>, Vec<ReferenceInfo>)> {
    let runs = plan(spec, base);
    let mut references = Vec::new();
    for (index, scene) in spec.scenes.iter().enumerate() {
        for &h in &spec.meshes {
            references.push(((index, h), reference(scene, h, base)?));
        }
    }
    let find = |run: &PlannedRun| {
        &references
            .iter()
            .find(|((p, h), _)| *p == run.scene && *h == run.h)
            .expect("a reference per problem and mesh")
            .1
    };
    let one = |run: &PlannedRun| {
        let row = run_one(
            run,
            find(run),
            !spec.parallel,
            spec.repeats,
            spec.time_limit,
        );
        tick(run);
        row
    };
    let rows: Result<Vec<SweepRow>> = if spec.parallel {
        runs.par_iter().map(one).collect()
    } else {
        runs.iter().map(one).collect()
    };
    let info = references
        .iter()
        .map(|((_, h), r)| ReferenceInfo {
            problem: r.scene.name.clone(),
            h: h.to_string(),
            solver: r.solver,
            oracle_pressure_error: r.oracle_pressure_error,
        })
        .collect();
    Ok((rows?, info))
}

/// Columns of `sweep.csv` (accuracy and counts; deterministic).
pub const SWEEP_COLUMNS: [&str; 24] = [
    "run",
    "problem",
    "h",
    "factor",
    "mode",
    "solver",
    "value",
    "r",
    "epsilon",
    "smoothing",
    "schedule",
    "status",
    "converged",
    "friction_iterations",
    "outer_iterations",
    "inner_iterations",
    "displacement_max",
    "displacement_l2",
    "pressure_max",
    "pressure_l2",
    "traction_max",
    "objective_gap",
    "kkt",
    "separated_fraction",
];

/// Columns of `sweep_timing.csv` (run = the row of `sweep.csv`).
pub const SWEEP_TIMING_COLUMNS: [&str; 5] = ["run", "factor", "solver", "value", "seconds"];

/// Rows as CSV fields.
pub fn sweep_records(rows: &[SweepRow]) -> Vec<Vec<String>> {
    use crate::io::output::fixed;
    rows.iter()
        .enumerate()
        .map(|(i, r)| {
            vec![
                i.to_string(),
                r.problem.clone(),
                r.h.clone(),
                r.factor.to_string(),
                r.mode.to_string(),
                r.solver.clone(),
                r.value.clone(),
                format!("{:e}", r.r),
                format!("{:e}", r.epsilon),
                r.smoothing.clone(),
                r.schedule.clone(),
                r.status.clone(),
                r.converged.to_string(),
                r.friction_iterations.to_string(),
                r.outer.to_string(),
                r.inner.to_string(),
                fixed(r.agreement.displacement_max),
                fixed(r.agreement.displacement_l2),
                fixed(r.agreement.pressure_max),
                fixed(r.agreement.pressure_l2),
                fixed(r.agreement.traction_max),
                fixed(r.agreement.objective_gap),
                fixed(r.kkt),
                format!("{:.6}", r.separated_fraction),
            ]
        })
        .collect()
}

/// Timing rows as CSV fields (empty seconds where not timed).
pub fn sweep_timing_records(rows: &[SweepRow]) -> Vec<Vec<String>> {
    rows.iter()
        .enumerate()
        .map(|(i, r)| {
            vec![
                i.to_string(),
                r.factor.to_string(),
                r.solver.clone(),
                r.value.clone(),
                r.seconds.map(|s| format!("{s:.6}")).unwrap_or_default(),
            ]
        })
        .collect()
}
