//! The stability map: each method across stress conditions, every run
//! classified as converged, slow, stalled, diverged, wrong or refused, with
//! the reason.
//!
//! Classification (stated so it can be checked):
//! - refused: the problem has no solution: condition (13) fails (our check),
//!   or a solver reports the problem unbounded or infeasible;
//! - diverged: a NaN or infinity, a numerical breakdown, or a friction fixed
//!   point whose max|Δg| grows (contraction factor > 1);
//! - stalled: stopped by an iteration cap or time limit, reduced accuracy, or
//!   a fixed point that stopped contracting without growing;
//! - wrong: converged by its own test, but the solver-independent KKT
//!   residual exceeds 1e-4 or the pressure differs from the oracle's by more
//!   than 1e-3 of its largest value (about what moves the separation zone by
//!   a node at h = 1/64); where the oracle does not finish within its budget
//!   (the finest meshes) the exact Newton solution is the reference;
//! - slow: converged and right, but its work exceeds 10 times that of the
//!   same method at its default settings on the same problem and mesh
//!   (sweeps for the relaxation, interior-point iterations for Clarabel,
//!   friction iterations for the fixed point);
//! - converged: everything else.

use std::time::Instant;

use anyhow::Result;
use contactlab_solvers::{Law, Silent, Smoothing, Status};
use serde_json::Value;

use crate::certificate::certify;
use crate::coulomb::budget::Budget;
use serde::Serialize;

use crate::coulomb::driver::{Run, solve_scene, solver_entry};
use crate::io::charts::{Chart, Series};
use crate::io::output::{csv_bytes, fixed};
use crate::mechanics::discretization::Discretization;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::{Scene, Traction};
use crate::settings::Settings;
use crate::study::compare::agreement;

/// KKT residual above which a converged run is wrong.
pub const WRONG_KKT: f64 = 1e-4;
/// Pressure difference from the oracle above which a converged run is wrong.
pub const WRONG_PRESSURE: f64 = 1e-3;
/// Work beyond this many times the default run's is slow.
pub const SLOW_FACTOR: f64 = 10.0;

/// The classes of the map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Class {
    Converged,
    Slow,
    Stalled,
    Diverged,
    Wrong,
    Refused,
}

impl Class {
    pub const ALL: [Class; 6] = [
        Class::Converged,
        Class::Slow,
        Class::Stalled,
        Class::Diverged,
        Class::Wrong,
        Class::Refused,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            Class::Converged => "converged",
            Class::Slow => "slow",
            Class::Stalled => "stalled",
            Class::Diverged => "diverged",
            Class::Wrong => "wrong",
            Class::Refused => "refused",
        }
    }
}

/// One run of the map.
#[derive(Clone, Debug, Serialize)]
pub struct StabilityRow {
    pub group: &'static str,
    pub method: String,
    pub problem: String,
    pub h: String,
    pub condition: String,
    /// The varied quantity, for charts.
    pub value: f64,
    pub class: Class,
    pub reason: String,
    pub status: String,
    pub friction_iterations: usize,
    pub outer: usize,
    pub inner: usize,
    /// Contraction factor of the friction fixed point at its last step.
    pub contraction: Option<f64>,
    pub kkt: f64,
    pub pressure_error: f64,
    pub seconds: f64,
}

/// What the map runs.
#[derive(Clone, Debug, Serialize)]
pub struct StabilitySpec {
    /// Mesh of the parameter groups (r, ε, smoothing, proximal, load).
    pub h: MeshSize,
    /// Mesh of the friction-coefficient scan and of Clarabel's tolerances.
    pub h_friction: MeshSize,
    /// Meshes of the mesh group (relaxation and Clarabel, frictionless).
    pub meshes: Vec<MeshSize>,
    /// Time budget of one given-friction solve in the mesh group, seconds.
    pub mesh_time_limit: f64,
    /// Time budget of one given-friction solve elsewhere, seconds.
    pub time_limit: f64,
    pub r_values: Vec<f64>,
    pub epsilon_values: Vec<f64>,
    pub smoothing_values: Vec<Smoothing>,
    pub friction_values: Vec<f64>,
    /// Inner solvers of the friction scan (each gives its own limit: a
    /// failure of the inner solver also ends the fixed point).
    pub friction_solvers: Vec<&'static str>,
    /// Bisection steps for the largest friction coefficient that converges.
    pub bisection_steps: usize,
    /// |total vertical load| values approaching 0 (problem 1 is 20).
    pub load_totals: Vec<f64>,
    pub clarabel_tolerances: Vec<f64>,
}

impl StabilitySpec {
    /// The map `reproduce` runs.
    pub fn standard() -> Self {
        let k = |k| MeshSize::from_level(k).expect("in range");
        Self {
            h: k(4),
            h_friction: k(4),
            meshes: vec![k(4), k(5), k(6), k(7), k(8)],
            mesh_time_limit: 20.0,
            time_limit: 10.0,
            r_values: [-8, -6, -4, -2, 0, 2, 4, 6, 8, 10]
                .iter()
                .map(|&e| 10f64.powi(e))
                .collect(),
            epsilon_values: (2..=10).map(|e| 10f64.powi(-e)).collect(),
            smoothing_values: std::iter::once(Smoothing::Exact)
                .chain([2, 4, 6, 8, 10, 12].iter().map(|&e| Smoothing::Huber {
                    delta: 10f64.powi(-e),
                }))
                .collect(),
            friction_values: vec![0.0, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 64.0],
            friction_solvers: vec!["newton", "clarabel"],
            bisection_steps: 5,
            load_totals: vec![20.0, 2.0, 0.2, 2e-2, 2e-3, 2e-4, 2e-6],
            clarabel_tolerances: vec![1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14],
        }
    }

    /// A small map for tests (seconds).
    pub fn quick() -> Self {
        let k = |k| MeshSize::from_level(k).expect("in range");
        Self {
            h: k(3),
            h_friction: k(4),
            meshes: vec![k(3), k(4)],
            mesh_time_limit: 10.0,
            time_limit: 0.5,
            r_values: vec![1e-8, 1e7],
            epsilon_values: vec![1e-6, 1e-15],
            smoothing_values: vec![Smoothing::Exact, Smoothing::Huber { delta: 1e-2 }],
            friction_values: vec![0.0, 0.5, 16.0],
            friction_solvers: vec!["newton", "clarabel"],
            bisection_steps: 2,
            load_totals: vec![20.0, 2e-4],
            clarabel_tolerances: vec![1e-4, 1e-10, 1e-14],
        }
    }
}

/// The outcome of one run before classification.
struct Outcome {
    status: Status,
    detail: String,
    friction_iterations: usize,
    outer: usize,
    inner: usize,
    contraction: Option<f64>,
    /// Mean contraction over the last iterations (for divergence).
    trend: Option<f64>,
    kkt: f64,
    pressure_error: f64,
    seconds: f64,
}

impl Outcome {
    fn from_run(run: &Run, reference: Option<&Run>, seconds: f64) -> Self {
        let total = run.coulomb.total_iterations();
        let history = &run.coulomb.history;
        let last: Vec<f64> = history
            .iter()
            .rev()
            .take(4)
            .filter_map(|h| h.contraction)
            .collect();
        let trend = (!last.is_empty())
            .then(|| last.iter().map(|q| q.ln()).sum::<f64>() / last.len() as f64)
            .map(f64::exp);
        let pressure_error = reference
            .map(|r| {
                agreement(
                    &r.discretization,
                    &run.coulomb.solution,
                    &r.coulomb.solution,
                )
                .pressure_max
            })
            .unwrap_or(f64::NAN);
        Self {
            status: run.coulomb.status,
            detail: run.coulomb.detail.clone(),
            friction_iterations: history.len(),
            outer: total.outer,
            inner: total.inner,
            contraction: history.last().and_then(|h| h.contraction),
            trend,
            kkt: run.certificate.residual(),
            pressure_error,
            seconds,
        }
    }
}

/// Work of a run for the slow test: sweeps if it has any, else outer iterations.
fn work(o: &Outcome) -> f64 {
    if o.inner > 0 {
        o.inner as f64
    } else {
        o.outer as f64
    }
}

fn classify(o: &Outcome, budget: Option<f64>, friction_budget: Option<usize>) -> (Class, String) {
    match o.status {
        Status::Unbounded | Status::Infeasible => (
            Class::Refused,
            format!("the solver reports {}: {}", o.status, o.detail),
        ),
        Status::NonFinite | Status::NumericalError => (Class::Diverged, o.detail.clone()),
        Status::InsufficientProgress if o.detail.contains("not contracting") => match o.trend {
            Some(q) if q > 1.0 => (
                Class::Diverged,
                format!("{} (contraction factor {q:.2} > 1)", o.detail),
            ),
            _ => (Class::Stalled, o.detail.clone()),
        },
        Status::Converged => {
            if o.kkt > WRONG_KKT {
                (
                    Class::Wrong,
                    format!(
                        "converged by its own test but KKT residual {:.1e} > {WRONG_KKT:e}",
                        o.kkt
                    ),
                )
            } else if o.pressure_error > WRONG_PRESSURE {
                (
                    Class::Wrong,
                    format!(
                        "converged by its own test but pressure differs from the oracle by {:.1e} > {WRONG_PRESSURE:e}",
                        o.pressure_error
                    ),
                )
            } else if let Some(b) = budget.filter(|&b| work(o) > SLOW_FACTOR * b) {
                (
                    Class::Slow,
                    format!(
                        "work {:.0} > {SLOW_FACTOR} × {b:.0} of the default run",
                        work(o)
                    ),
                )
            } else if let Some(b) =
                friction_budget.filter(|&b| o.friction_iterations as f64 > SLOW_FACTOR * b as f64)
            {
                (
                    Class::Slow,
                    format!(
                        "{} friction iterations > {SLOW_FACTOR} × {b} of the paper's 𝓕",
                        o.friction_iterations
                    ),
                )
            } else {
                (Class::Converged, o.detail.clone())
            }
        }
        _ => (Class::Stalled, format!("{}: {}", o.status, o.detail)),
    }
}

fn row(
    group: &'static str,
    method: &str,
    scene: &Scene,
    condition: String,
    value: f64,
    o: &Outcome,
    class: (Class, String),
) -> StabilityRow {
    StabilityRow {
        group,
        method: method.to_string(),
        problem: scene.name.clone(),
        h: scene.finest().to_string(),
        condition,
        value,
        class: class.0,
        reason: class.1,
        status: o.status.to_string(),
        friction_iterations: o.friction_iterations,
        outer: o.outer,
        inner: o.inner,
        contraction: o.contraction,
        kkt: o.kkt,
        pressure_error: o.pressure_error,
        seconds: o.seconds,
    }
}

fn timed(
    scene: &Scene,
    settings: &Settings,
    solver: &str,
    seconds: Option<f64>,
) -> Result<(Run, f64)> {
    let t = Instant::now();
    let entry = solver_entry(solver)?;
    let run = solve_scene(
        scene,
        settings,
        solver,
        &mut Budget::new(entry, None, seconds, &mut Silent),
    )?;
    Ok((run, t.elapsed().as_secs_f64()))
}

fn problem(n: u32, h: MeshSize) -> Result<Scene> {
    let mut s = Scene::paper_problem(n)?;
    s.set_finest(h);
    Ok(s)
}

fn budgeted(base: &Settings, _seconds: f64) -> Settings {
    base.clone()
}

fn set(s: &mut Settings, path: &str, value: Value) {
    s.set(path, value).expect("a registered setting");
}

/// Runs the whole map. `log` receives one line per group.
pub fn stability(
    spec: &StabilitySpec,
    base: &Settings,
    log: &dyn Fn(&str),
) -> Result<(Vec<StabilityRow>, Vec<FrictionTrace>)> {
    let mut rows = Vec::new();
    let settings = budgeted(base, spec.time_limit);
    let p1 = problem(1, spec.h)?;
    let oracle = solve_scene(&p1, base, "clarabel", &mut Silent)?;
    let (default_relax, t) = timed(&p1, &settings, "relaxation", Some(spec.time_limit))?;
    let default_work = work(&Outcome::from_run(&default_relax, Some(&oracle), t));
    let relax = |group: &'static str,
                 condition: String,
                 value: f64,
                 s: &Settings,
                 rows: &mut Vec<StabilityRow>,
                 method: &str|
     -> Result<()> {
        let (run, t) = timed(&p1, s, "relaxation", Some(spec.time_limit))?;
        let o = Outcome::from_run(&run, Some(&oracle), t);
        let c = classify(&o, Some(default_work), None);
        rows.push(row(group, method, &p1, condition, value, &o, c));
        Ok(())
    };

    log("relaxation with and without the proximal term");
    for r in [1e7, 1e-1] {
        for rho in [1.0, 0.0] {
            let mut s = settings.clone();
            set(&mut s, "relaxation.r", Value::from(r));
            set(&mut s, "relaxation.proximal", Value::from(rho));
            relax(
                "proximal",
                format!("r = {r:e}, ρ = {rho}"),
                r,
                &s,
                &mut rows,
                &format!("relaxation ρ = {rho}"),
            )?;
        }
    }
    log("penalty r");
    for &r in &spec.r_values {
        let mut s = settings.clone();
        set(&mut s, "relaxation.r", Value::from(r));
        relax("r", format!("r = {r:e}"), r, &s, &mut rows, "relaxation")?;
    }
    log("smoothing of |s|");
    for &sm in &spec.smoothing_values {
        let mut s = settings.clone();
        set(
            &mut s,
            "relaxation.smoothing",
            serde_json::to_value(sm).expect("a tree"),
        );
        let value = match sm {
            Smoothing::Exact => f64::NAN,
            Smoothing::Huber { delta } => delta,
        };
        relax("smoothing", sm.label(), value, &s, &mut rows, "relaxation")?;
    }
    log("tolerance ε");
    for &e in &spec.epsilon_values {
        let mut s = settings.clone();
        s.set_epsilon(e).expect("registered settings");
        relax(
            "epsilon",
            format!("ε = {e:e}"),
            e,
            &s,
            &mut rows,
            "relaxation",
        )?;
    }

    log("friction coefficient (fixed point around the oracle)");
    let mut traces = Vec::new();
    friction_group(spec, base, &mut rows, &mut traces)?;
    log("loads approaching condition (13)");
    load_group(spec, &settings, base, &mut rows)?;
    log("fine meshes");
    mesh_group(spec, base, &mut rows, log)?;
    log("Clarabel's tolerances and equilibration");
    clarabel_group(spec, base, &mut rows)?;
    Ok((rows, traces))
}

/// max|Δg| per friction iteration of one friction-coefficient run.
#[derive(Clone, Debug, Serialize)]
pub struct FrictionTrace {
    pub problem: String,
    pub friction: f64,
    pub changes: Vec<f64>,
    pub contractions: Vec<Option<f64>>,
    pub converged: bool,
}

fn friction_group(
    spec: &StabilitySpec,
    base: &Settings,
    rows: &mut Vec<StabilityRow>,
    traces: &mut Vec<FrictionTrace>,
) -> Result<()> {
    let mut s = base.clone();
    set(&mut s, "coulomb.max_iterations", Value::from(200u64));
    for &inner in &spec.friction_solvers {
        let method = format!("fixed point ({inner} inside)");
        for n in [1, 2, 3] {
            let scene = problem(n, spec.h_friction)?;
            let mut default_iterations = None;
            let mut attempt = |f: f64,
                               rows: &mut Vec<StabilityRow>,
                               traces: &mut Vec<FrictionTrace>,
                               bisect: bool|
             -> Result<bool> {
                let mut sc = scene.clone();
                sc.friction = f;
                let (run, t) = timed(&sc, &s, inner, None)?;
                let o = Outcome::from_run(&run, None, t);
                if (f - 0.5).abs() < 1e-12 {
                    default_iterations = Some(o.friction_iterations);
                }
                let mut c = classify(&o, None, default_iterations.or(Some(7)));
                if o.detail.contains("given-friction step") {
                    c.1 = format!("the inner solver failed, not the fixed point: {}", c.1);
                }
                let ok = run.coulomb.status.is_converged();
                rows.push(row(
                    "friction",
                    &method,
                    &sc,
                    format!("𝓕 = {f}{}", if bisect { " (bisection)" } else { "" }),
                    f,
                    &o,
                    c,
                ));
                traces.push(FrictionTrace {
                    problem: format!("{}, {inner}", sc.name),
                    friction: f,
                    changes: run.coulomb.history.iter().map(|h| h.change).collect(),
                    contractions: run.coulomb.history.iter().map(|h| h.contraction).collect(),
                    converged: ok,
                });
                Ok(ok)
            };
            let mut last_ok: Option<f64> = None;
            let mut first_bad: Option<f64> = None;
            for &f in &spec.friction_values {
                let ok = attempt(f, rows, traces, false)?;
                if first_bad.is_none() {
                    if ok {
                        last_ok = Some(f);
                    } else {
                        first_bad = Some(f);
                    }
                }
            }
            if let (Some(mut lo), Some(mut hi)) = (last_ok, first_bad) {
                for _ in 0..spec.bisection_steps {
                    let mid = 0.5 * (lo + hi);
                    if attempt(mid, rows, traces, true)? {
                        lo = mid
                    } else {
                        hi = mid
                    }
                }
            }
        }
    }
    Ok(())
}

/// Problem 1 plus an upward traction on [2/3, 1] so that the total
/// vertical load is −`total` (negative total: the load lifts the body).
fn lifted_problem(total: f64, h: MeshSize) -> Result<Scene> {
    let mut s = problem(1, h)?;
    let up = 3.0 * (20.0 - total);
    if up != 0.0 {
        s.loads.push(Traction {
            from: 2.0 / 3.0,
            to: 1.0,
            p2: up,
        });
    }
    s.name = format!("problem 1, total load −{total:e}");
    Ok(s)
}

fn load_group(
    spec: &StabilitySpec,
    settings: &Settings,
    base: &Settings,
    rows: &mut Vec<StabilityRow>,
) -> Result<()> {
    for &total in &spec.load_totals {
        let scene = lifted_problem(total, spec.h)?;
        let reference = solve_scene(&scene, base, "clarabel", &mut Silent)
            .ok()
            .filter(|r| r.coulomb.status.is_converged());
        for solver in contactlab_solvers::registry::names() {
            let (run, t) = timed(&scene, settings, solver, Some(spec.time_limit))?;
            let o = Outcome::from_run(&run, reference.as_ref().filter(|_| solver != "clarabel"), t);
            let c = classify(&o, None, None);
            rows.push(row(
                "load",
                solver,
                &scene,
                format!("total vertical load −{total:e}"),
                total,
                &o,
                c,
            ));
        }
    }
    // Loads that violate condition (13): refused, and what happens without the check.
    for total in [0.0, -2.0] {
        let scene = lifted_problem(total, spec.h)?;
        let refused = scene
            .validate()
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        for solver in ["clarabel", "relaxation"] {
            let o = Outcome {
                status: Status::NotRun,
                detail: refused.clone(),
                friction_iterations: 0,
                outer: 0,
                inner: 0,
                contraction: None,
                trend: None,
                kkt: f64::NAN,
                pressure_error: f64::NAN,
                seconds: 0.0,
            };
            rows.push(row(
                "load",
                solver,
                &scene,
                format!("total vertical load {:+e} (violates (13))", 0.0 - total),
                total.abs().max(1e-12),
                &o,
                (Class::Refused, refused.clone()),
            ));
            // Bypassing the check: one given-friction solve (g = 0) on the assembled problem.
            let d = Discretization::new_unchecked(&scene, spec.h)?;
            let entry = solver_entry(solver)?;
            let mut solver_box = settings.build(entry).map_err(anyhow::Error::msg)?;
            let t = Instant::now();
            let sol = solver_box.solve(
                &d.problem,
                Law::GivenFriction,
                None,
                &mut Budget::new(entry, None, Some(spec.time_limit), &mut Silent),
            );
            let r = certify(
                &d.problem,
                Law::GivenFriction,
                &sol.v,
                &sol.pressure,
                &sol.friction_traction,
                settings.certificate.tolerance,
            );
            let o = Outcome {
                status: sol.status,
                detail: sol.detail.clone(),
                friction_iterations: 1,
                outer: sol.iterations.outer,
                inner: sol.iterations.inner,
                contraction: None,
                trend: None,
                kkt: r.residual(),
                pressure_error: f64::NAN,
                seconds: t.elapsed().as_secs_f64(),
            };
            let mut c = classify(&o, None, None);
            if c.0 == Class::Converged && total == 0.0 {
                // A zero total load: lifting the upper body costs nothing, so
                // minimizers exist (the bodies apart) but are not unique.
                c.1 = format!(
                    "{} (zero total load: a minimizer with the bodies apart, its height arbitrary)",
                    c.1
                );
            }
            rows.push(row(
                "load",
                &format!("{solver} (check (13) bypassed)"),
                &scene,
                format!("total vertical load {:+e}, no check", 0.0 - total),
                total.abs().max(1e-12),
                &o,
                c,
            ));
        }
    }
    Ok(())
}

fn mesh_group(
    spec: &StabilitySpec,
    base: &Settings,
    rows: &mut Vec<StabilityRow>,
    log: &dyn Fn(&str),
) -> Result<()> {
    let settings = budgeted(base, spec.mesh_time_limit);
    for &h in &spec.meshes {
        let mut scene = problem(1, h)?;
        scene.friction = 0.0;
        log(&format!("  h = {h}"));
        let oracle = timed(&scene, &settings, "clarabel", Some(spec.mesh_time_limit))?;
        // The reference: the oracle, or the exact solver where the oracle did
        // not finish within its budget.
        let exact = solve_scene(&scene, base, "newton", &mut Silent)?;
        let reference = if oracle.0.coulomb.status.is_converged() {
            &oracle.0
        } else {
            &exact
        };
        {
            let o = Outcome::from_run(&oracle.0, None, oracle.1);
            let c = classify(&o, None, None);
            rows.push(row(
                "mesh",
                "clarabel",
                &scene,
                format!("h = {h}, frictionless"),
                h.divisions() as f64,
                &o,
                c,
            ));
        }
        for solver in contactlab_solvers::registry::names()
            .into_iter()
            .filter(|s| !["clarabel", "relaxation"].contains(s))
        {
            let (run, t) = timed(&scene, &settings, solver, Some(spec.mesh_time_limit))?;
            let o = Outcome::from_run(&run, Some(reference), t);
            let c = classify(&o, None, None);
            rows.push(row(
                "mesh",
                solver,
                &scene,
                format!("h = {h}, frictionless"),
                h.divisions() as f64,
                &o,
                c,
            ));
        }
        let (run, t) = timed(&scene, &settings, "relaxation", Some(spec.mesh_time_limit))?;
        let o = Outcome::from_run(&run, Some(reference), t);
        let finest_sweeps = run.levels.last().map(|l| l.sweeps).unwrap_or(0);
        let c = classify(&o, None, None);
        let mut r = row(
            "mesh",
            "relaxation",
            &scene,
            format!("h = {h}, frictionless"),
            h.divisions() as f64,
            &o,
            c,
        );
        r.reason = format!("{}; {finest_sweeps} sweeps on the finest level", r.reason);
        rows.push(r);
    }
    Ok(())
}

fn clarabel_group(
    spec: &StabilitySpec,
    base: &Settings,
    rows: &mut Vec<StabilityRow>,
) -> Result<()> {
    for n in [1, 2] {
        let scene = problem(n, spec.h_friction)?;
        let reference = solve_scene(&scene, base, "clarabel", &mut Silent)?;
        let default_ipm = reference.coulomb.total_iterations().outer as f64;
        for equilibrate in [true, false] {
            for &tol in &spec.clarabel_tolerances {
                let mut s = budgeted(base, spec.time_limit);
                set(&mut s, "clarabel.tol", Value::from(tol));
                set(&mut s, "clarabel.equilibrate", Value::from(equilibrate));
                let (run, t) = timed(&scene, &s, "clarabel", Some(spec.time_limit))?;
                let o = Outcome::from_run(&run, Some(&reference), t);
                let c = classify(&o, Some(default_ipm), None);
                let method = if equilibrate {
                    "clarabel"
                } else {
                    "clarabel, no equilibration"
                };
                rows.push(row(
                    "clarabel",
                    method,
                    &scene,
                    format!("tolerance {tol:e}"),
                    tol,
                    &o,
                    c,
                ));
            }
        }
        // Without our scaling of the unknowns.
        let mut s = budgeted(base, spec.time_limit);
        set(&mut s, "clarabel.scale_unknowns", Value::from(false));
        let (run, t) = timed(&scene, &s, "clarabel", Some(spec.time_limit))?;
        let o = Outcome::from_run(&run, Some(&reference), t);
        let c = classify(&o, Some(default_ipm), None);
        rows.push(row(
            "clarabel",
            "clarabel, unscaled unknowns",
            &scene,
            "tolerance 1e-10, unscaled".into(),
            1e-10,
            &o,
            c,
        ));
    }
    Ok(())
}

/// Columns of `stability.csv`.
pub const STABILITY_COLUMNS: [&str; 16] = [
    "group",
    "method",
    "problem",
    "h",
    "condition",
    "class",
    "reason",
    "status",
    "friction_iterations",
    "outer_iterations",
    "inner_iterations",
    "contraction",
    "kkt",
    "pressure_error",
    "value",
    "seconds",
];

pub fn stability_csv(rows: &[StabilityRow]) -> Result<Vec<u8>> {
    csv_bytes(
        &STABILITY_COLUMNS,
        rows.iter().map(|r| {
            vec![
                r.group.to_string(),
                r.method.clone(),
                r.problem.clone(),
                r.h.clone(),
                r.condition.clone(),
                r.class.as_str().to_string(),
                r.reason.clone(),
                r.status.clone(),
                r.friction_iterations.to_string(),
                r.outer.to_string(),
                r.inner.to_string(),
                r.contraction.map(fixed).unwrap_or_default(),
                fixed(r.kkt),
                fixed(r.pressure_error),
                fixed(r.value),
                format!("{:.3}", r.seconds),
            ]
        }),
    )
}

/// `stability_friction.csv`: max|Δg| and contraction per friction iteration.
pub fn friction_trace_csv(traces: &[FrictionTrace]) -> Result<Vec<u8>> {
    csv_bytes(
        &[
            "problem",
            "friction_coefficient",
            "iteration",
            "change",
            "contraction",
            "converged",
        ],
        traces.iter().flat_map(|t| {
            t.changes
                .iter()
                .zip(&t.contractions)
                .enumerate()
                .map(move |(i, (c, q))| {
                    vec![
                        t.problem.clone(),
                        t.friction.to_string(),
                        (i + 1).to_string(),
                        fixed(*c),
                        q.map(fixed).unwrap_or_default(),
                        t.converged.to_string(),
                    ]
                })
        }),
    )
}

/// Per problem and inner solver: the largest friction coefficient whose
/// fixed point converged and the smallest larger one that did not (if any).
pub fn largest_converging_friction(
    rows: &[StabilityRow],
) -> Vec<(String, String, f64, Option<f64>)> {
    let mut keys: Vec<(String, String)> = rows
        .iter()
        .filter(|r| r.group == "friction")
        .map(|r| (r.problem.clone(), r.method.clone()))
        .collect();
    keys.sort();
    keys.dedup();
    keys.into_iter()
        .map(|(p, m)| {
            let runs: Vec<&StabilityRow> = rows
                .iter()
                .filter(|r| r.group == "friction" && r.problem == p && r.method == m)
                .collect();
            let ok = runs
                .iter()
                .filter(|r| matches!(r.class, Class::Converged | Class::Slow))
                .map(|r| r.value)
                .fold(f64::NEG_INFINITY, f64::max);
            let bad = runs
                .iter()
                .filter(|r| !matches!(r.class, Class::Converged | Class::Slow) && r.value > ok)
                .map(|r| r.value)
                .fold(f64::INFINITY, f64::min);
            (p, m, ok, bad.is_finite().then_some(bad))
        })
        .collect()
}

/// A Markdown summary: counts per group and class, every run that did not
/// simply converge with its reason, and the friction limits.
pub fn summary_markdown(rows: &[StabilityRow]) -> String {
    let mut groups: Vec<&str> = rows.iter().map(|r| r.group).collect();
    groups.dedup();
    let mut s = String::from("| group | ");
    s += &Class::ALL
        .iter()
        .map(|c| c.as_str())
        .collect::<Vec<_>>()
        .join(" | ");
    s += " |\n|---|";
    s += &"---|".repeat(Class::ALL.len());
    s += "\n";
    for g in &groups {
        s += &format!("| {g} |");
        for c in Class::ALL {
            s += &format!(
                " {} |",
                rows.iter()
                    .filter(|r| r.group == *g && r.class == c)
                    .count()
            );
        }
        s += "\n";
    }
    s += "\n| group | method | problem | h | condition | class | reason |\n|---|---|---|---|---|---|---|\n";
    for r in rows.iter().filter(|r| r.class != Class::Converged) {
        let reason: String = r.reason.chars().take(220).collect();
        s += &format!(
            "| {} | {} | {} | {} | {} | **{}** | {} |\n",
            r.group,
            r.method,
            r.problem,
            r.h,
            r.condition,
            r.class.as_str(),
            reason.replace('|', "/")
        );
    }
    s
}

/// Charts of the map: work against the varied value, one series per class.
pub fn stability_charts(rows: &[StabilityRow], traces: &[FrictionTrace]) -> Vec<(String, Chart)> {
    let mut out = Vec::new();
    let by_class = |group: &str, y: fn(&StabilityRow) -> f64| -> Vec<Series> {
        Class::ALL
            .iter()
            .filter_map(|&c| {
                let pts: Vec<(f64, f64)> = rows
                    .iter()
                    .filter(|r| r.group == group && r.class == c)
                    .map(|r| (r.value, y(r)))
                    .collect();
                (!pts.is_empty()).then(|| Series::line(c.as_str(), pts).scatter())
            })
            .collect()
    };
    let sweeps = |r: &StabilityRow| r.inner.max(1) as f64;
    for (group, x, log_x, title) in [
        (
            "r",
            "penalty r",
            true,
            "Stability: relaxation against the penalty r",
        ),
        ("epsilon", "ε", true, "Stability: relaxation against ε"),
        (
            "smoothing",
            "Huber width δ (exact minimizer not drawn)",
            true,
            "Stability: relaxation against the smoothing of |s|",
        ),
    ] {
        out.push((
            format!("stability_{group}"),
            Chart {
                title: title.into(),
                x_label: x.into(),
                y_label: "relaxation sweeps (count)".into(),
                log_x,
                log_y: true,
                series: by_class(group, sweeps),
                legend: Default::default(),
            },
        ));
    }
    out.push((
        "stability_load".into(),
        Chart {
            title: "Stability: total vertical load approaching 0 (condition (13))".into(),
            x_label: "|total vertical load| [force]".into(),
            y_label: "KKT residual".into(),
            log_x: true,
            log_y: true,
            series: by_class("load", |r| r.kkt),
            legend: Default::default(),
        },
    ));
    // Contraction of the fixed point against 𝓕, one series per problem.
    let mut problems: Vec<String> = traces.iter().map(|t| t.problem.clone()).collect();
    problems.dedup();
    let mut series: Vec<Series> = problems
        .iter()
        .filter(|p| {
            traces
                .iter()
                .any(|t| &&t.problem == p && t.friction > 0.0 && t.changes.len() >= 5)
        })
        .map(|p| {
            let mut pts: Vec<(f64, f64)> = traces
                .iter()
                .filter(|t| &t.problem == p && t.friction > 0.0 && t.changes.len() >= 5)
                .filter_map(|t| {
                    let q: Vec<f64> = t
                        .contractions
                        .iter()
                        .rev()
                        .take(3)
                        .filter_map(|q| *q)
                        .filter(|q| *q > 0.0)
                        .collect();
                    (!q.is_empty()).then(|| {
                        (
                            t.friction,
                            (q.iter().map(|x| x.ln()).sum::<f64>() / q.len() as f64).exp(),
                        )
                    })
                })
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            Series::line(p.clone(), pts).with_markers()
        })
        .collect();
    let fs: Vec<f64> = traces
        .iter()
        .map(|t| t.friction)
        .filter(|f| *f > 0.0)
        .collect();
    if let (Some(lo), Some(hi)) = (
        fs.iter().copied().reduce(f64::min),
        fs.iter().copied().reduce(f64::max),
    ) {
        series.push(Series::line("contraction factor 1", vec![(lo, 1.0), (hi, 1.0)]).dashed());
    }
    out.push((
        "stability_friction".into(),
        Chart {
            title: "Coulomb fixed point: contraction factor against 𝓕".into(),
            x_label: "friction coefficient 𝓕".into(),
            y_label: "contraction max|Δg| ratio (last steps, geometric mean; runs of ≥ 5 steps)"
                .into(),
            log_x: true,
            log_y: true,
            series,
            legend: crate::io::charts::Legend::LowerRight,
        },
    ));
    // Mesh: sweeps on the finest level against 1/h, per method, with the fitted slope.
    let mut series = Vec::new();
    for method in contactlab_solvers::registry::names() {
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.group == "mesh" && r.method == method && r.class != Class::Stalled)
            .map(|r| (r.value, r.seconds.max(1e-6)))
            .collect();
        let slope = fit_slope(&pts);
        series.push(
            Series::line(
                format!(
                    "{method} (slope {})",
                    slope
                        .map(|s| format!("{s:.2}"))
                        .unwrap_or_else(|| "n/a".into())
                ),
                pts,
            )
            .with_markers(),
        );
        let stalled: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.group == "mesh" && r.method == method && r.class == Class::Stalled)
            .map(|r| (r.value, r.seconds.max(1e-6)))
            .collect();
        if !stalled.is_empty() {
            series.push(
                Series::line(format!("{method}: stopped at its time budget"), stalled).scatter(),
            );
        }
    }
    out.push((
        "stability_mesh".into(),
        Chart {
            title: "Stability: frictionless problem 1 on finer meshes".into(),
            x_label: "1/h".into(),
            y_label: "time [s]".into(),
            log_x: true,
            log_y: true,
            series,
            legend: crate::io::charts::Legend::UpperLeft,
        },
    ));
    out
}

/// Least-squares slope of log y against log x.
pub fn fit_slope(points: &[(f64, f64)]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// The README's section on the map: a paragraph per failure mode the data
/// show (and only those), each listing the conditions that trigger it.
pub fn readme_section(rows: &[StabilityRow]) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let list = |group: &str, class: Class| -> Vec<String> {
        rows.iter()
            .filter(|r| r.group == group && r.class == class)
            .map(|r| format!("{} ({})", r.condition, r.method))
            .collect()
    };
    let r_stalled = list("r", Class::Stalled);
    let r_slow = list("r", Class::Slow);
    if !r_stalled.is_empty() || !r_slow.is_empty() {
        let mut parts = Vec::new();
        if !r_stalled.is_empty() {
            parts.push(format!("stalled at {}", r_stalled.join(", ")));
        }
        if !r_slow.is_empty() {
            parts.push(format!("slow at {}", r_slow.join(", ")));
        }
        let _ = writeln!(
            s,
            "- **Penalty r too small**: {}. With l = 0 at the start the first Uzawa step lets the upper body sink by \
             about (load)/r, and Gauss-Seidel moves that rigid mode only through the penalty stiffness (≈ r) against \
             an elastic stiffness ≈ E: the smaller r, the more sweeps.",
            parts.join("; ")
        );
    }
    let r_ok = rows
        .iter()
        .filter(|r| r.group == "r" && r.class == Class::Converged)
        .map(|r| r.value)
        .fold(f64::NEG_INFINITY, f64::max);
    if r_ok.is_finite() {
        let _ = writeln!(
            s,
            "- **Penalty r large**: no failure up to r = {r_ok:e}: the penalty is minimized exactly along each jump \
             coordinate (never added to a matrix), so round-off does not grow with r."
        );
    }
    let prox: Vec<&StabilityRow> = rows.iter().filter(|r| r.group == "proximal").collect();
    if !prox.is_empty() {
        let pairs: Vec<String> = prox
            .iter()
            .map(|r| format!("{}: {} sweeps, {}", r.condition, r.inner, r.class.as_str()))
            .collect();
        let _ = writeln!(
            s,
            "- **Proximal term**: {}. Removing the paper's L2 term changes nothing measurable: the penalty already makes \
             each Uzawa subproblem coercive in the rigid mode, and the L2 term (entries ~h²) is tiny beside the \
             stiffness (~E).",
            pairs.join("; ")
        );
    }
    let smooth_wrong = list("smoothing", Class::Wrong);
    if !smooth_wrong.is_empty() {
        let _ = writeln!(
            s,
            "- **Coarse smoothing of |s|**: wrong at {}: the Huber traction −g·s/δ stays below its bound for slips \
             smaller than δ, so slipping nodes with small slip are treated as partly sticking (slip residual).",
            smooth_wrong.join(", ")
        );
    }
    let eps_wrong = list("epsilon", Class::Wrong);
    if !eps_wrong.is_empty() {
        let _ = writeln!(
            s,
            "- **Loose ε**: wrong at {}: the paper's tests bound changes per iteration, not errors, and the error is a \
             few times ε.",
            eps_wrong.join(", ")
        );
    }
    for (p, m, ok, bad) in largest_converging_friction(rows) {
        let _ = writeln!(
            s,
            "- **Friction coefficient, {p}, {m}**: the fixed point converges up to 𝓕 = {ok}{}.",
            match bad {
                Some(b) => format!(" and fails from 𝓕 = {b}"),
                None => " (no failure among the coefficients tried)".into(),
            }
        );
    }
    let fixed_fail: Vec<&StabilityRow> = rows
        .iter()
        .filter(|r| r.group == "friction" && !matches!(r.class, Class::Converged | Class::Slow))
        .collect();
    if !fixed_fail.is_empty() {
        let inner = fixed_fail
            .iter()
            .filter(|r| r.reason.contains("inner solver failed"))
            .count();
        let mut sticky: Vec<String> = rows
            .iter()
            .filter(|r| r.group == "friction")
            .map(|r| r.problem.clone())
            .filter(|p| {
                rows.iter()
                    .filter(|r| r.group == "friction" && &r.problem == p && r.value > 0.0)
                    .all(|r| r.class == Class::Converged && r.friction_iterations <= 3)
            })
            .collect();
        sticky.dedup();
        if !sticky.is_empty() {
            let _ = writeln!(
                s,
                "  On {} the fixed point stops within three steps for every 𝓕 tried: everything sticks, the map g ↦ 𝓕p \
                 is then locally constant, and there is no contraction factor to draw.",
                sticky.join(", ")
            );
        }
        let _ = writeln!(
            s,
            "  The contraction factor of max|Δg| grows with 𝓕 (chart below) until it reaches 1; past that the fixed point \
             stalls or diverges. {} of the {} failures are the inner solver's (it stopped at reduced accuracy), which \
             ends the fixed point too: problems 1 and 2 are the same problem up to a factor 2 (homogeneity), so any \
             difference between their limits is the inner solver's.",
            inner,
            fixed_fail.len()
        );
    }
    let load_wrong = list("load", Class::Wrong);
    if !load_wrong.is_empty() {
        let _ = writeln!(
            s,
            "- **Total load near zero**: wrong at {}: ε is an absolute tolerance on the multiplier l, whose size shrinks \
             with the load, so the relative error grows as the total falls (the oracle stays accurate).",
            load_wrong.join(", ")
        );
    }
    let refused: Vec<String> = rows
        .iter()
        .filter(|r| {
            r.group == "load" && r.class == Class::Refused && !r.method.contains("bypassed")
        })
        .map(|r| format!("{} ({})", r.condition, r.method))
        .collect();
    if !refused.is_empty() {
        let _ = writeln!(
            s,
            "- **Condition (13) violated**: refused with a one-line error: {}.",
            refused.join(", ")
        );
    }
    let bypass: Vec<String> = rows
        .iter()
        .filter(|r| r.group == "load" && r.method.contains("bypassed"))
        .map(|r| format!("{} → {} ({})", r.method, r.class.as_str(), r.status))
        .collect();
    if !bypass.is_empty() {
        let _ = writeln!(
            s,
            "  Without our check: {}. An upward total is unbounded (Clarabel says so; the relaxation keeps lifting the \
             body until its budget); a zero total has minimizers with the bodies apart at an arbitrary height.",
            bypass.join("; ")
        );
    }
    let mesh: Vec<&StabilityRow> = rows.iter().filter(|r| r.group == "mesh").collect();
    if !mesh.is_empty() {
        let line = |m: &str| -> String {
            mesh.iter()
                .filter(|r| r.method == m)
                .map(|r| format!("1/{}: {:.2} s, {}", r.value, r.seconds, r.class.as_str()))
                .collect::<Vec<_>>()
                .join("; ")
        };
        let perr: Vec<String> = mesh
            .iter()
            .filter(|r| r.method == "relaxation" && r.pressure_error.is_finite())
            .map(|r| format!("{:.1e} at 1/{}", r.pressure_error, r.value))
            .collect();
        let _ = writeln!(
            s,
            "- **Fine meshes** (frictionless problem 1): relaxation {}; Clarabel {}. The relaxation's pressure error grows \
             as h falls ({}): its sweeps stop at max|Δv| ≤ 1e-4·ε·h while Gauss-Seidel contracts by about 1 − c·h² per \
             sweep, so the error left is ~1e-4·ε/(c·h).",
            line("relaxation"),
            line("clarabel"),
            perr.join(", ")
        );
    }
    let clar: Vec<String> = rows
        .iter()
        .filter(|r| r.group == "clarabel" && r.class != Class::Converged)
        .map(|r| {
            format!(
                "{} on {} ({}, {})",
                r.condition,
                r.problem,
                r.method,
                r.class.as_str()
            )
        })
        .collect();
    if !clar.is_empty() {
        let _ = writeln!(
            s,
            "- **Clarabel's tolerances**: {}. Loose tolerances leave the multipliers inaccurate although Clarabel reports \
             Solved; without equilibration or without our scaling of the unknowns the multiplier noise exceeds ε/𝓕 and \
             the fixed point stops contracting; 1e-14 ends at reduced accuracy.",
            clar.join("; ")
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_of_a_power_law() {
        let pts: Vec<(f64, f64)> = [8.0, 16.0, 32.0]
            .iter()
            .map(|&x: &f64| (x, 3.0 * x.powf(2.5)))
            .collect();
        assert!((fit_slope(&pts).unwrap() - 2.5).abs() < 1e-12);
    }
}
