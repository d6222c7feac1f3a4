//! Agreement between two solutions of the same problem, and solving one
//! given-friction subproblem (a fixed g) with any registered solver.

use anyhow::{Result, bail};
use contactlab_solvers::{Observer, Solution};
use serde::Serialize;

use crate::coulomb::continuation::LevelCount;
use crate::coulomb::driver::with_step;
use crate::mechanics::discretization::Discretization;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;

/// Differences of a solution from a reference, each relative to the
/// reference's largest value (max) or its Euclidean norm (l2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Agreement {
    /// Nodal displacements of both bodies.
    pub displacement_max: f64,
    pub displacement_l2: f64,
    /// Contact pressure.
    pub pressure_max: f64,
    pub pressure_l2: f64,
    /// Friction traction (relative to the largest pressure when the
    /// reference has no friction).
    pub traction_max: f64,
    pub traction_l2: f64,
    /// (J(v) − J(v_ref)) / |J(v_ref)| for the objective J of paper (10).
    pub objective_gap: f64,
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, |m, d| if d.is_nan() { f64::NAN } else { m.max(d) })
}

fn l2(a: &[f64]) -> f64 {
    a.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn max_abs(a: &[f64]) -> f64 {
    a.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

fn rel(num: f64, den: f64) -> f64 {
    if den > 0.0 { num / den } else { num }
}

/// How far `s` is from `reference`, both solutions of `d.problem`.
pub fn agreement(d: &Discretization, s: &Solution, reference: &Solution) -> Agreement {
    let flat =
        |sol: &Solution| -> Vec<f64> { d.displacements(&sol.v).into_iter().flatten().collect() };
    let (u, u_ref) = (flat(s), flat(reference));
    let du: Vec<f64> = u.iter().zip(&u_ref).map(|(a, b)| a - b).collect();
    let dp: Vec<f64> = s
        .pressure
        .iter()
        .zip(&reference.pressure)
        .map(|(a, b)| a - b)
        .collect();
    let dq: Vec<f64> = s
        .friction_traction
        .iter()
        .zip(&reference.friction_traction)
        .map(|(a, b)| a - b)
        .collect();
    let p_max = max_abs(&reference.pressure);
    let q_max = max_abs(&reference.friction_traction).max(
        if max_abs(&reference.friction_traction) == 0.0 {
            p_max
        } else {
            0.0
        },
    );
    let q_l2 = if l2(&reference.friction_traction) > 0.0 {
        l2(&reference.friction_traction)
    } else {
        l2(&reference.pressure)
    };
    let j = d.problem.objective(&s.v);
    let j_ref = d.problem.objective(&reference.v);
    Agreement {
        displacement_max: rel(max_abs(&du), max_abs(&u_ref)),
        displacement_l2: rel(l2(&du), l2(&u_ref)),
        pressure_max: rel(max_diff(&s.pressure, &reference.pressure), p_max),
        pressure_l2: rel(l2(&dp), l2(&reference.pressure)),
        traction_max: rel(max_abs(&dq), q_max),
        traction_l2: rel(l2(&dq), q_l2),
        objective_gap: rel(j - j_ref, j_ref.abs()),
    }
}

/// One given-friction subproblem (bound `g` on the finest level's contact
/// nodes) solved by a registered solver, the way it solves inside the
/// Coulomb fixed point: by continuation over the scene's levels if it
/// warm-starts, otherwise on the finest level.
pub fn solve_given_friction(
    scene: &Scene,
    settings: &Settings,
    solver: &str,
    g: &[f64],
    observer: &mut dyn Observer,
) -> Result<(Discretization, Solution, Vec<LevelCount>)> {
    let (solution, mut finest, counts, _) = with_step(scene, settings, solver, |step, _| {
        step.solve_step(g, observer)
    })?;
    let counts = counts.unwrap_or_else(|| {
        vec![LevelCount {
            h: finest.h(),
            visits: 1,
            uzawa: solution.iterations.outer,
            sweeps: solution.iterations.inner,
            seconds: solution.timing.total(),
        }]
    });
    finest.problem.set_friction_bound(g)?;
    Ok((finest, solution, counts))
}

/// Which problem a comparison row is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// One given-friction subproblem, g from the oracle's Coulomb solution.
    GivenFriction,
    /// The whole Coulomb problem (fixed point around the solver).
    Coulomb,
}

impl Mode {
    pub fn as_str(self) -> &'static str {
        match self {
            Mode::GivenFriction => "given_friction",
            Mode::Coulomb => "coulomb",
        }
    }
}

/// One solver on one problem, against the oracle's solution of the same problem.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CompareRow {
    pub problem: String,
    pub h: String,
    pub mode: Mode,
    pub solver: String,
    pub status: String,
    pub friction_iterations: usize,
    pub outer: usize,
    pub inner: usize,
    pub agreement: Agreement,
    pub separated: Vec<[f64; 2]>,
    pub separated_fraction: f64,
    /// The certificate (given-friction law at g for the subproblem rows,
    /// the Coulomb law at g = 𝓕p for the Coulomb rows).
    pub certificate: crate::certificate::Certificate,
    /// Minimum wall-clock seconds of the solver's work over the timed runs.
    pub seconds: f64,
    /// Convergence history of the first run (for charts).
    #[serde(skip)]
    pub history: Vec<contactlab_solvers::Progress>,
    /// The first run's solution (for profiles).
    #[serde(skip)]
    pub solution: Solution,
}

/// The oracle's Coulomb solution of a scene, which every comparison is
/// measured against, and its g (the operating point of the subproblem).
pub const ORACLE: &str = "clarabel";

/// Runs every solver in `solvers` on the given-friction subproblem (g from
/// the oracle's Coulomb solution) and on the whole Coulomb problem, and
/// measures each against the oracle. Times are the minimum over `repeats`
/// runs after the first one (a warm-up that also gives the accuracy figures);
/// the oracle's first runs are the reference solves themselves.
pub fn compare(
    scene: &Scene,
    settings: &Settings,
    solvers: &[&str],
    repeats: usize,
    mut tick: impl FnMut(&str),
) -> Result<Vec<CompareRow>> {
    use contactlab_solvers::{History, Law, Silent, registry};

    use crate::certificate::certify;

    use crate::coulomb::driver::{Run, solve_scene};
    use crate::mechanics::contact_zone::separation_of;

    // Coulomb rows keep their convergence history (for the charts).
    let mut stages = vec![crate::coulomb::fixed_point::STAGE];
    for e in registry::SOLVERS {
        stages.extend(e.stages.iter().filter(|s| s.history).map(|s| s.name));
    }
    let coulomb_history = || History::of(&stages);
    let mut oracle_history = coulomb_history();
    let oracle = solve_scene(scene, settings, ORACLE, &mut oracle_history)?;
    if !oracle.coulomb.status.is_converged() {
        bail!(
            "the oracle did not converge on {}: {}",
            scene.name,
            oracle.coulomb.detail
        );
    }
    tick(ORACLE);
    let g = oracle.coulomb.g.clone();
    let (d, reference, _) = solve_given_friction(scene, settings, ORACLE, &g, &mut Silent)?;
    tick(ORACLE);
    let mut rows = Vec::new();
    for &solver in solvers {
        // The subproblem with the oracle's g.
        let first = if solver == ORACLE {
            reference.clone()
        } else {
            let (_, s, _) = solve_given_friction(scene, settings, solver, &g, &mut Silent)?;
            tick(solver);
            s
        };
        let mut best: Option<f64> = None;
        for _ in 0..repeats {
            let t = solve_given_friction(scene, settings, solver, &g, &mut Silent)?
                .1
                .timing
                .total();
            best = Some(best.map_or(t, |b| b.min(t)));
            tick(solver);
        }
        let separation = separation_of(&d, &first);
        rows.push(CompareRow {
            problem: scene.name.clone(),
            h: d.h().to_string(),
            mode: Mode::GivenFriction,
            solver: solver.to_string(),
            status: first.status.to_string(),
            friction_iterations: 0,
            outer: first.iterations.outer,
            inner: first.iterations.inner,
            agreement: agreement(&d, &first, &reference),
            separated: separation.intervals,
            separated_fraction: separation.fraction,
            certificate: certify(
                &d.problem,
                Law::GivenFriction,
                &first.v,
                &first.pressure,
                &first.friction_traction,
                settings.certificate.tolerance,
            ),
            seconds: best.unwrap_or(first.timing.total()),
            history: Vec::new(),
            solution: first,
        });
        // The whole Coulomb problem.
        let fresh: Run;
        let (run, history) = if solver == ORACLE {
            (&oracle, oracle_history.events.clone())
        } else {
            let mut history = coulomb_history();
            fresh = solve_scene(scene, settings, solver, &mut history)?;
            tick(solver);
            (&fresh, history.events)
        };
        let mut best: Option<f64> = None;
        for _ in 0..repeats {
            let t = solve_scene(scene, settings, solver, &mut Silent)?
                .coulomb
                .seconds;
            best = Some(best.map_or(t, |b| b.min(t)));
            tick(solver);
        }
        let total = run.coulomb.total_iterations();
        rows.push(CompareRow {
            problem: scene.name.clone(),
            h: d.h().to_string(),
            mode: Mode::Coulomb,
            solver: solver.to_string(),
            status: run.coulomb.status.to_string(),
            friction_iterations: run.coulomb.history.len(),
            outer: total.outer,
            inner: total.inner,
            agreement: agreement(
                &oracle.discretization,
                &run.coulomb.solution,
                &oracle.coulomb.solution,
            ),
            separated: run.separation.intervals.clone(),
            separated_fraction: run.separation.fraction,
            certificate: run.certificate,
            seconds: best.unwrap_or(run.coulomb.seconds),
            history,
            solution: run.coulomb.solution.clone(),
        });
    }
    Ok(rows)
}

/// Columns of `compare.csv` (accuracy; deterministic).
pub const COMPARE_COLUMNS: [&str; 26] = [
    "problem",
    "h",
    "mode",
    "solver",
    "status",
    "friction_iterations",
    "outer_iterations",
    "inner_iterations",
    "displacement_max",
    "displacement_l2",
    "pressure_max",
    "pressure_l2",
    "traction_max",
    "traction_l2",
    "objective_gap",
    "separated",
    "separated_fraction",
    "certificate",
    "nonpenetration",
    "pressure_sign",
    "complementarity",
    "friction_bound",
    "stick",
    "slip_direction",
    "stationarity",
    "force_balance",
];

/// Columns of `compare_timing.csv`.
pub const COMPARE_TIMING_COLUMNS: [&str; 5] = ["problem", "h", "mode", "solver", "seconds_min"];

/// Formats separated intervals as `[a;b] [c;d]` (no commas, for CSV).
pub fn intervals_text(intervals: &[[f64; 2]]) -> String {
    intervals
        .iter()
        .map(|[a, b]| format!("[{a:.4};{b:.4}]"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The accuracy rows as CSV fields.
pub fn compare_records(rows: &[CompareRow]) -> Vec<Vec<String>> {
    use crate::io::output::fixed;
    rows.iter()
        .map(|r| {
            let a = &r.agreement;
            let q = &r.certificate;
            vec![
                r.problem.clone(),
                r.h.clone(),
                r.mode.as_str().to_string(),
                r.solver.clone(),
                r.status.clone(),
                r.friction_iterations.to_string(),
                r.outer.to_string(),
                r.inner.to_string(),
                fixed(a.displacement_max),
                fixed(a.displacement_l2),
                fixed(a.pressure_max),
                fixed(a.pressure_l2),
                fixed(a.traction_max),
                fixed(a.traction_l2),
                fixed(a.objective_gap),
                intervals_text(&r.separated),
                format!("{:.6}", r.separated_fraction),
                fixed(q.residual()),
                fixed(q.nonpenetration),
                fixed(q.pressure_sign),
                fixed(q.complementarity),
                fixed(q.friction_bound),
                fixed(q.stick),
                fixed(q.slip_direction),
                fixed(q.stationarity),
                fixed(q.force_balance),
            ]
        })
        .collect()
}

/// The timing rows as CSV fields.
pub fn timing_records(rows: &[CompareRow]) -> Vec<Vec<String>> {
    rows.iter()
        .map(|r| {
            vec![
                r.problem.clone(),
                r.h.clone(),
                r.mode.as_str().to_string(),
                r.solver.clone(),
                format!("{:.6}", r.seconds),
            ]
        })
        .collect()
}

/// A Markdown table of the comparison.
pub fn compare_markdown(rows: &[CompareRow]) -> String {
    let mut out = String::from(
        "| problem | h | mode | solver | status | Δu max | Δp max | Δq max | separated | certificate | iterations | time (s) |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let iterations = match (r.friction_iterations, r.inner) {
            (0, 0) => format!("{}", r.outer),
            (0, i) => format!("{} / {}", r.outer, i),
            (f, 0) => format!("{f}: {}", r.outer),
            (f, i) => format!("{f}: {} / {}", r.outer, i),
        };
        let sep = if r.separated.is_empty() {
            "none".to_string()
        } else {
            r.separated
                .iter()
                .map(|[a, b]| format!("[{a:.3}, {b:.3}]"))
                .collect::<Vec<_>>()
                .join(" ")
        };
        out += &format!(
            "| {} | {} | {} | {} | {} | {:.1e} | {:.1e} | {:.1e} | {} ({:.1}%) | {:.1e} | {} | {:.3} |\n",
            r.problem,
            r.h,
            r.mode.as_str(),
            r.solver,
            r.status,
            r.agreement.displacement_max,
            r.agreement.pressure_max,
            r.agreement.traction_max,
            sep,
            100.0 * r.separated_fraction,
            r.certificate.residual(),
            iterations,
            r.seconds
        );
    }
    out + "\nΔ: max difference from the oracle (clarabel) relative to its largest value. Iterations: \
           [friction iterations:] outer (interior-point, Uzawa or Newton) [/ sweeps]. Time: minimum over the timed runs.\n"
}
