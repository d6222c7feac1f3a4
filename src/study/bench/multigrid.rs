//! The multigrid goals of the benchmark: TNNMG's iteration counts from
//! zero on the given-friction subproblem, the whole Coulomb problem at the
//! finest large mesh by TNNMG with the nested schedule (time and peak
//! memory in a fresh process, against the best factorization), the paper's
//! method with `relaxation.inner = multigrid` at a certified accuracy, and
//! TNNMG's pressures against semismooth Newton's. Each is measured once:
//! counts and agreements do not vary between runs, and the times are
//! single cold solves, as the large meshes' are.

use anyhow::Result;
// The given bound of the iteration counts is the sweep kernel's own.
use contactlab_solvers::multigrid::BOUND_OF_SCALE;
use contactlab_solvers::{Friction, Silent, registry};
use serde::Serialize;
use serde_json::json;

use crate::certificate::certify_solution;
use crate::coulomb::continuation::Schedule;
use crate::mechanics::discretization::Discretization;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::solve::{solve_scene, solver_entry};
use crate::study::bench::exact_bound::{self, ExactBound};
use crate::study::bench::goals::Goal;
use crate::study::bench::memory::{MemoryUse, available_memory_kb, measure_in_fresh_process};
use crate::study::bench::{BenchSpec, PerfRow};

/// The registered multigrid solver of the given-friction subproblem.
pub const SOLVER: &str = "tnnmg";

/// KiB in a GiB.
const GIB_KB: f64 = 1024.0 * 1024.0;

/// The iteration bound of the goal, from zero to a certified 1e-8.
pub const ITERATION_GOAL: usize = 30;

/// The certificate's tolerance of the iteration counts.
const COUNT_TOLERANCE: f64 = 1e-8;

/// What was measured.
#[derive(Clone, Debug, Default, Serialize)]
pub struct MultigridRows {
    /// (h, iterations, certified) from zero on the given-friction problem.
    pub iterations: Vec<(MeshSize, usize, bool)>,
    /// The whole Coulomb problem, nested schedule, each run in a fresh
    /// process: the run of median time, with the largest peak of the runs.
    pub coulomb: Vec<MemoryUse>,
    /// The same on the meshes only the multigrid solver runs on.
    pub finest: Vec<MemoryUse>,
    /// Those of them not run, and why (too little memory here).
    pub skipped: Vec<(MeshSize, String)>,
    /// The multigrid-only meshes this run planned: a goal on a mesh it did
    /// not is the long run's, not a shortfall.
    pub planned: Vec<MeshSize>,
    /// The whole Coulomb problem on the finest of the large meshes with
    /// `tnnmg.threads = 1` (the sequential method), as `coulomb`, its runs
    /// in alternation with those of `coulomb` on that mesh.
    pub one_thread: Option<MemoryUse>,
    /// The paper's method with multigrid inside: (h, seconds, status).
    pub paper: Option<(MeshSize, f64, String)>,
    /// max|p − p_Newton| / P of the Coulomb answers: (h, gap).
    pub agreement: Vec<(MeshSize, f64)>,
    /// The friction fixed point against TNNMG at the exact bound, on the
    /// large meshes.
    pub exact_bound: Vec<ExactBound>,
    /// Fresh-process runs of each large mesh's measurement (the spec's
    /// [`BenchSpec::fresh_runs`]).
    pub runs: usize,
}

/// The meshes of each measurement for a benchmark spec: every mesh of the
/// spec and its large ones for the counts; the large ones (the finest mesh
/// without) for the Coulomb problem; the finest of those for the paper's
/// method; 1/64 and 1/256 (those the spec has) for the agreement.
fn meshes(spec: &BenchSpec) -> (Vec<MeshSize>, Vec<MeshSize>, MeshSize, Vec<MeshSize>) {
    let all: Vec<MeshSize> = spec
        .meshes
        .iter()
        .chain(&spec.large)
        .copied()
        .filter(|h| h.level() >= 4)
        .collect();
    let finest = *spec.meshes.last().expect("a benchmark has meshes");
    let large = if spec.large.is_empty() {
        vec![finest]
    } else {
        spec.large.clone()
    };
    let at = |k: u32| {
        MeshSize::from_level(k)
            .ok()
            .filter(|h| spec.meshes.contains(h))
    };
    let paper = *large.last().expect("one mesh at least");
    let agreement = [at(6), at(8)].into_iter().flatten().collect();
    (all, large, paper, agreement)
}

/// Fresh-process runs of the whole Coulomb problem on the large meshes in
/// the long run (1/2048, at 40 s a run, runs once): one run moved by a
/// third from one `bench` to the next (1/1024: 5.9 s, 4.2 s, 2.9 s). The
/// main job's runs once ([`BenchSpec::fresh_runs`]).
pub const COULOMB_RUNS: usize = 3;

/// "median of 3 runs, each in a fresh process" or "one run, in a fresh
/// process".
fn runs_text(runs: usize) -> String {
    match runs {
        1 => "one run, in a fresh process".to_string(),
        n => format!("median of {n} runs, each in a fresh process"),
    }
}

/// The setting of the sequential runs.
const ONE_THREAD: &str = "tnnmg.threads=1";

/// The run of median time (the slower of the middle two when even), with
/// the largest peak of all and the worst status: a status that is not
/// converged in any run is the measurement's.
fn median_run(mut uses: Vec<MemoryUse>) -> Option<MemoryUse> {
    uses.sort_by(|a, b| a.seconds.total_cmp(&b.seconds));
    let peak = uses.iter().map(|u| u.peak_kb).max()?;
    let failed = uses
        .iter()
        .find(|u| u.status != "converged")
        .map(|u| u.status.clone());
    let mut used = uses.swap_remove(uses.len() / 2);
    used.peak_kb = peak;
    if let Some(status) = failed {
        used.status = status;
    }
    Some(used)
}

/// Runs the measurements (none if no multigrid solver is registered).
pub fn measure(spec: &BenchSpec, log: &dyn Fn(&str)) -> Result<MultigridRows> {
    let mut out = MultigridRows::default();
    if registry::by_name(SOLVER).is_none() {
        return Ok(out);
    }
    let (counts, large, paper, agreement) = meshes(spec);
    out.planned = spec.multigrid_only.clone();
    out.runs = spec.fresh_runs.max(1);
    for h in counts {
        log(&format!("{SOLVER} from zero at h = {h}"));
        out.iterations.push(count_from_zero(spec.problem, h)?);
    }
    let schedule = solver_entry(SOLVER)?.schedule;
    for (&h, finest) in large
        .iter()
        .map(|h| (h, false))
        .chain(spec.multigrid_only.iter().map(|h| (h, true)))
    {
        let runs = if finest { 1 } else { out.runs };
        if let Some(why) = finest
            .then(|| too_large(&out.finest, h, available_memory_kb()?))
            .flatten()
        {
            log(&format!("{SOLVER} at h = {h} not run: {why}"));
            out.skipped.push((h, why));
            continue;
        }
        // On the last large mesh the one-thread runs alternate with these:
        // this host's speed drifts by a third within an hour, and the
        // speed-up is a ratio of the two medians.
        let sequential_too = Some(&h) == large.last() && !finest;
        let (mut uses, mut sequential) = (Vec::new(), Vec::new());
        let fresh = |what: &str, set: &[&str], into: &mut Vec<MemoryUse>, run: usize| {
            log(&format!(
                "{SOLVER} {what} at h = {h} (fresh process, run {run} of {runs})"
            ));
            match measure_in_fresh_process(spec.problem, h, SOLVER, schedule, set) {
                Ok(used) => into.push(used),
                Err(e) => log(&format!("not measured: {e:#}")),
            }
        };
        for run in 1..=runs {
            fresh("on the Coulomb problem", &[], &mut uses, run);
            if sequential_too {
                fresh("on one thread", &[ONE_THREAD], &mut sequential, run);
            }
        }
        if sequential_too {
            out.one_thread = median_run(sequential);
        }
        match median_run(uses) {
            Some(used) if finest => out.finest.push(used),
            Some(used) => out.coulomb.push(used),
            None => {}
        }
    }
    log(&format!("the paper's method with multigrid at h = {paper}"));
    let scene = Scene::paper_problem_to(spec.problem, paper)?;
    let mut settings = Settings::default();
    settings
        .set("relaxation.inner", json!("multigrid"))
        .map_err(anyhow::Error::msg)?;
    settings
        .set("relaxation.target", json!(1e-6))
        .map_err(anyhow::Error::msg)?;
    let entry = solver_entry("relaxation")?;
    let solved = solve_scene(&scene, Friction::Coulomb, entry, &settings, &mut Silent)?;
    let o = &solved.outcome;
    let schedule = settings.schedule_of(entry);
    out.paper = Some((
        paper,
        o.timing.total(),
        format!("{}, {schedule} schedule", o.status),
    ));
    for h in agreement {
        log(&format!("{SOLVER} against newton-coulomb at h = {h}"));
        out.agreement.push((h, agreement_at(spec.problem, h)?));
    }
    for &h in &large {
        log(&format!(
            "{SOLVER}: the friction fixed point against the exact bound at h = {h}"
        ));
        out.exact_bound
            .extend(exact_bound::measure(spec.problem, h)?);
    }
    Ok(out)
}

/// Why a mesh finer than those measured would not fit here, if it would
/// not: its estimate, four times the unknowns of the mesh before it at
/// that mesh's peak per unknown, with a tenth to spare, against the memory
/// `available_kb` this machine has available now (1/4096 took 3.9 GiB,
/// 1/8192 15.3 GiB).
fn too_large(done: &[MemoryUse], h: MeshSize, available_kb: u64) -> Option<String> {
    let before = done.iter().find(|u| u.h.level() + 1 == h.level())?;
    let need = 4.0 * before.peak_kb as f64 * 1.1;
    let available = available_kb as f64;
    (need > available).then(|| {
        format!(
            "it would need about {:.0} GiB (four times {}'s peak), and {:.0} GiB are available",
            need / GIB_KB,
            before.h,
            available / GIB_KB
        )
    })
}

/// TNNMG from zero on the given-friction subproblem at `h` (one level):
/// its iterations to a change of 1e-11·U, and whether the answer passes the
/// certificate at 1e-8.
fn count_from_zero(problem: u32, h: MeshSize) -> Result<(MeshSize, usize, bool)> {
    let scene = Scene::paper_problem_to(problem, h)?;
    let d = Discretization::new(&scene, h)?;
    let p = &d.problem;
    let g = vec![BOUND_OF_SCALE * scene.friction * p.scales().pressure; p.contacts().len()];
    let mut settings = Settings::default();
    settings
        .set("tnnmg.tolerance", json!(1e-11))
        .map_err(anyhow::Error::msg)?;
    let mut solver = settings
        .build(solver_entry(SOLVER)?)
        .map_err(anyhow::Error::msg)?;
    let s = solver.solve(p, Friction::Given(&g), None, &mut Silent);
    let certified = certify_solution(p, Friction::Given(&g), &s, COUNT_TOLERANCE).passed();
    Ok((h, s.iterations.outer, certified && s.status.is_converged()))
}

/// max|p − p_N|/P between TNNMG in the nested fixed point (tolerance
/// 1e-12, ε = 1e-11; at 1e-13 the change per iteration stalls at rounding
/// at 1/256) and newton-coulomb at its defaults, both certified
/// (NaN if either is not).
fn agreement_at(problem: u32, h: MeshSize) -> Result<f64> {
    let scene = Scene::paper_problem_to(problem, h)?;
    let run = |solver: &str, settings: &Settings| -> Result<Option<(Vec<f64>, f64)>> {
        let solved = solve_scene(
            &scene,
            Friction::Coulomb,
            solver_entry(solver)?,
            settings,
            &mut Silent,
        )?;
        let o = solved.outcome;
        let scale = solved.finest.problem.scales().pressure;
        Ok(o.status
            .is_converged()
            .then_some((o.solution.pressure, scale)))
    };
    let (Some((mg, scale)), Some((newton, _))) = (
        run(SOLVER, &tight_settings()?)?,
        run("newton-coulomb", &Settings::default())?,
    ) else {
        return Ok(f64::NAN);
    };
    Ok(largest_gap(&mg, &newton) / scale)
}

/// TNNMG in the nested fixed point far tighter than its defaults
/// (tolerance 1e-12, ε = 1e-11): the reference answers of the agreement
/// goal and of the exact-bound comparison.
pub(crate) fn tight_settings() -> Result<Settings> {
    let mut tight = Settings::default();
    tight.schedule = Some(Schedule::Nested);
    tight
        .set("tnnmg.tolerance", json!(1e-12))
        .map_err(anyhow::Error::msg)?;
    tight
        .set("coulomb.epsilon", json!(1e-11))
        .map_err(anyhow::Error::msg)?;
    Ok(tight)
}

/// max_i |a_i − b_i|.
pub(crate) fn largest_gap(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

/// Issue 50's goals: the default solve at most this × the best
/// factorization; at most this many work units; at least this speed-up
/// from one thread to the machine's; the peak at 1/4096; 1/8192 within
/// memory and time; the paper's method with multigrid inside at 1/1024.
const DEFAULT_GOAL: f64 = 0.3;
const WORK_UNITS_GOAL: f64 = 30.0;
const THREADS_GOAL: f64 = 1.7;
const PEAK_GOAL_LEVEL: u32 = 12;
const PEAK_GOAL_GIB: f64 = 4.0;
const FINEST_GOAL_LEVEL: u32 = 13;
const FINEST_GOAL_GIB: f64 = 16.0;
const FINEST_GOAL_SECONDS: f64 = 120.0;
const PAPER_GOAL_SECONDS: f64 = 15.0;

/// The whole Coulomb problem in work units (its seconds over one product
/// A·v with the finest level's A, timed in the same process before and
/// after the solve, [`MemoryUse::product_seconds`]), by phase:
/// the solver's own phases, and the rest (the friction fixed point's
/// updates, the continuation's transfers, the harness).
fn work_units_goal(used: &MemoryUse) -> Goal {
    let goal = format!(
        "whole Coulomb problem {} at h = {} in work units (its seconds ÷ one product A·v with the problem's A, same process): at most {WORK_UNITS_GOAL}",
        used.solver, used.h
    );
    let Some(unit) = used.product_seconds.filter(|&u| u > 0.0) else {
        return Goal {
            goal,
            measured: "the product was not timed".into(),
            pass: Some(false),
        };
    };
    let total = used.seconds / unit;
    let solver_total = used
        .phases
        .iter()
        .find(|(k, _)| k == contactlab_solvers::multigrid::TOTAL_SECONDS)
        .map(|(_, s)| *s);
    let mut parts: Vec<String> = used
        .phases
        .iter()
        .filter(|(k, _)| k != contactlab_solvers::multigrid::TOTAL_SECONDS)
        .map(|(k, s)| {
            let name = k
                .trim_start_matches(&format!("{}_", used.solver))
                .trim_end_matches(crate::study::trial::SECONDS_SUFFIX)
                .replace('_', " ");
            format!("{name} {:.0}", s / unit)
        })
        .collect();
    if let Some(inside) = solver_total {
        parts.push(format!(
            "friction updates, transfers and the rest {:.0}",
            (used.seconds - inside) / unit
        ));
    }
    // The product's medians before and after the solve, when both were
    // timed: how far the machine's speed moved while it ran.
    let sides = used.product_sides.map_or(String::new(), |(before, after)| {
        format!(
            ", the median of {} products: {:.2} ms before the solve, {:.2} ms after",
            2 * crate::study::bench::memory::PRODUCTS,
            before * 1e3,
            after * 1e3
        )
    });
    Goal {
        goal,
        measured: format!(
            "{total:.0} work units ({:.2} s ÷ {:.2} ms{sides}): {} ({})",
            used.seconds,
            unit * 1e3,
            parts.join(", "),
            used.status
        ),
        pass: Some(used.status == "converged" && total <= WORK_UNITS_GOAL),
    }
}

/// A goal on the multigrid-only mesh of `level`: its run judged by
/// `within`, or why it was not run.
fn finest_goal(
    m: &MultigridRows,
    level: u32,
    within: impl Fn(&MemoryUse) -> Result<(), String>,
    goal: &str,
) -> Goal {
    let describe = |u: &MemoryUse| {
        format!(
            "{}: {:.1} s, peak {:.2} GiB, {}",
            u.h,
            u.seconds,
            u.peak_kb as f64 / GIB_KB,
            u.status
        )
    };
    let coarser: Vec<String> = m
        .finest
        .iter()
        .filter(|u| u.h.level() < level)
        .map(describe)
        .collect();
    let (measured, pass) = match MeshSize::from_level(level) {
        Err(e) => (format!("refused: {e}"), Some(false)),
        Ok(h) => match (
            m.finest.iter().find(|u| u.h == h),
            m.skipped.iter().find(|(s, _)| *s == h),
        ) {
            (Some(u), _) => {
                let verdict = within(u);
                (
                    format!(
                        "{}{}",
                        describe(u),
                        verdict
                            .as_ref()
                            .err()
                            .map_or(String::new(), |w| format!(" ({w})"))
                    ),
                    Some(u.status == "converged" && verdict.is_ok()),
                )
            }
            (None, Some((_, why))) => (format!("{h} not run: {why}"), Some(false)),
            (None, None) if !m.planned.contains(&h) => (
                format!("{h} not in this run (the long run's: `reproduce --long`)"),
                None,
            ),
            (None, None) => (format!("{h} not measured"), Some(false)),
        },
    };
    let before = if coarser.is_empty() {
        String::new()
    } else {
        format!(" (coarser: {})", coarser.join("; "))
    };
    Goal {
        goal: goal.into(),
        measured: format!("{measured}{before}"),
        pass,
    }
}

/// The best factorization's median seconds at `h` in `rows`.
pub(crate) fn factorization(rows: &[PerfRow], h: MeshSize) -> Option<f64> {
    rows.iter()
        .find(|r| r.what == "factorization" && r.h == h.to_string())
        .map(|r| r.median_seconds)
}

/// The goals of issue 28, checked against one run.
pub fn goals(m: &MultigridRows, rows: &[PerfRow]) -> Vec<Goal> {
    let mut out = Vec::new();
    if !m.iterations.is_empty() {
        let list: Vec<String> = m
            .iterations
            .iter()
            .map(|(h, k, ok)| format!("{h}: {k}{}", if *ok { "" } else { " (not certified)" }))
            .collect();
        out.push(Goal {
            goal: format!(
                "{SOLVER} from zero to a certified {COUNT_TOLERANCE:.0e} on the given-friction subproblem (g = {BOUND_OF_SCALE}·𝓕P): at most {ITERATION_GOAL} iterations at every h"
            ),
            measured: list.join(", "),
            pass: Some(m.iterations.iter().all(|(_, k, ok)| *ok && *k <= ITERATION_GOAL)),
        });
    }
    for used in &m.coulomb {
        let f = factorization(rows, used.h);
        let ratio = f.map_or(f64::NAN, |f| used.seconds / f);
        out.push(Goal {
            goal: format!(
                "`solve --solver {SOLVER}` (whole Coulomb problem, default settings) at h = {}, certified: at most {DEFAULT_GOAL} × the best factorization (faer, the faster of 1 and 2 threads)",
                used.h
            ),
            measured: format!(
                "{:.2} s = {ratio:.2} × factorization ({}), peak {:.2} GiB, {} ({})",
                used.seconds,
                f.map_or("not measured".into(), |f| format!("{f:.2} s")),
                used.peak_kb as f64 / GIB_KB,
                used.status,
                runs_text(m.runs),
            ),
            pass: Some(used.status == "converged" && ratio <= DEFAULT_GOAL),
        });
    }
    if let Some(used) = m.coulomb.last() {
        out.push(work_units_goal(used));
    }
    if let (Some(one), Some(all)) = (&m.one_thread, m.coulomb.last()) {
        let speed_up = one.seconds / all.seconds;
        out.push(Goal {
            goal: format!(
                "speed-up of {SOLVER} from 1 thread (`tnnmg.threads=1`) to the machine's {} at h = {}: at least {THREADS_GOAL}",
                contactlab_solvers::numerics::threads::cores(),
                all.h
            ),
            measured: format!(
                "{speed_up:.2}× ({:.2} s on 1 thread, {}; {:.2} s on all, {}; {})",
                one.seconds,
                one.status,
                all.seconds,
                all.status,
                match m.runs {
                    1 => "one fresh process each, one after the other".to_string(),
                    n => format!("medians of {n} fresh processes each, in alternation"),
                }
            ),
            pass: Some(
                one.status == "converged" && all.status == "converged" && speed_up >= THREADS_GOAL,
            ),
        });
    }
    if !m.coulomb.is_empty() {
        out.push(finest_goal(
            m,
            PEAK_GOAL_LEVEL,
            |u| {
                (u.peak_kb as f64 <= PEAK_GOAL_GIB * GIB_KB)
                    .then_some(())
                    .ok_or(format!("peak above {PEAK_GOAL_GIB} GiB"))
            },
            &format!(
                "peak memory of {SOLVER} at h = 1/{} at most {PEAK_GOAL_GIB} GiB, certified",
                1u32 << PEAK_GOAL_LEVEL
            ),
        ));
        out.push(finest_goal(m, FINEST_GOAL_LEVEL, |u| {
            let over: Vec<String> = [
                (u.peak_kb as f64 > FINEST_GOAL_GIB * GIB_KB).then(|| format!("peak above {FINEST_GOAL_GIB} GiB")),
                (u.seconds > FINEST_GOAL_SECONDS).then(|| format!("above {FINEST_GOAL_SECONDS} s")),
            ]
            .into_iter()
            .flatten()
            .collect();
            if over.is_empty() { Ok(()) } else { Err(over.join(", ")) }
        }, &format!("h = 1/{} certified by {SOLVER}, peak at most {FINEST_GOAL_GIB} GiB, at most {FINEST_GOAL_SECONDS} s", 1u64 << FINEST_GOAL_LEVEL)));
    }
    if let Some((h, seconds, status)) = &m.paper {
        out.push(Goal {
            goal: format!(
                "the paper's method with relaxation.inner = multigrid and target = 1e-6 at h = {h}: at most {PAPER_GOAL_SECONDS} s, certified"
            ),
            measured: format!("{seconds:.2} s, {status}"),
            pass: Some(status.starts_with("converged,") && *seconds <= PAPER_GOAL_SECONDS),
        });
    }
    if !m.agreement.is_empty() {
        let list: Vec<String> = m
            .agreement
            .iter()
            .map(|(h, gap)| format!("{h}: {gap:.1e}"))
            .collect();
        out.push(Goal {
            goal: format!("{SOLVER} against newton-coulomb: max|Δp|/P at most 1e-9"),
            measured: list.join(", "),
            pass: Some(m.agreement.iter().all(|(_, gap)| *gap <= 1e-9)),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(seconds: f64, peak_kb: u64, status: &str) -> MemoryUse {
        MemoryUse {
            h: MeshSize::from_level(10).unwrap(),
            solver: SOLVER.into(),
            status: status.into(),
            seconds,
            peak_kb,
            assembly_peak_kb: 0,
            problem_kb: 0,
            factor_values_bytes: None,
            schur_bytes: None,
            product_seconds: None,
            product_sides: None,
            phases: Vec::new(),
        }
    }

    /// The median run's time, whatever the order of the runs; the largest
    /// peak of any run; a failure in any run is the measurement's. Taking
    /// the first or fastest run, the median run's own peak or the median
    /// run's status fails it.
    #[test]
    fn the_median_run_keeps_the_worst_peak_and_status() {
        let used = median_run(vec![
            run(5.0, 100, "converged"),
            run(3.0, 300, "converged"),
            run(4.0, 200, "converged"),
        ])
        .unwrap();
        assert_eq!((used.seconds, used.peak_kb), (4.0, 300));
        assert_eq!(used.status, "converged");
        let used = median_run(vec![
            run(4.0, 100, "converged"),
            run(9.0, 100, "max_iterations"),
            run(3.0, 100, "converged"),
        ])
        .unwrap();
        assert_eq!(
            (used.seconds, used.status.as_str()),
            (4.0, "max_iterations")
        );
        assert!(median_run(Vec::new()).is_none());
    }

    /// A finer mesh is skipped, with the reason, when four times the peak
    /// of the mesh before it with a tenth to spare exceeds what is
    /// available, and run otherwise; one without a measured predecessor is
    /// run. An estimate from the wrong mesh, or without the factor 4, fails.
    #[test]
    fn a_finer_mesh_is_skipped_only_when_it_would_not_fit() {
        let gib = 1024 * 1024;
        let mut done = vec![run(10.0, 3 * gib, "converged")];
        done[0].h = MeshSize::from_level(11).unwrap();
        let h = MeshSize::from_level(12).unwrap();
        // Needs 4 × 3 × 1.1 = 13.2 GiB.
        assert!(too_large(&done, h, 14 * gib).is_none());
        let why = too_large(&done, h, 12 * gib).expect("13.2 GiB do not fit in 12");
        assert!(
            why.contains("13 GiB") && why.contains("1/2048") && why.contains("12 GiB"),
            "{why}"
        );
        // Nothing measured one level below: no estimate, so it runs.
        assert!(too_large(&done, MeshSize::from_level(11).unwrap(), 1).is_none());
    }

    /// Work units are seconds over the product's, each phase too, and the
    /// rest is what the solver's own total leaves; a run without a timed
    /// product fails the goal rather than dividing by nothing.
    #[test]
    fn work_units_divide_by_the_product() {
        let mut used = run(3.0, 100, "converged");
        used.product_seconds = Some(0.01);
        used.phases = vec![
            ("tnnmg_smoothing_seconds".into(), 1.5),
            (contactlab_solvers::multigrid::TOTAL_SECONDS.into(), 2.5),
        ];
        let g = work_units_goal(&used);
        assert!(g.measured.starts_with("300 work units"), "{}", g.measured);
        assert!(g.measured.contains("smoothing 150"), "{}", g.measured);
        assert!(g.measured.contains("the rest 50"), "{}", g.measured);
        assert_eq!(g.pass, Some(false));
        // Both sides of the solve, when timed, are stated with the unit.
        used.product_sides = Some((0.008, 0.012));
        let g = work_units_goal(&used);
        assert!(
            g.measured.contains(
                "÷ 10.00 ms, the median of 22 products: 8.00 ms before the solve, 12.00 ms after)"
            ),
            "{}",
            g.measured
        );
        used.seconds = 0.25;
        assert_eq!(work_units_goal(&used).pass, Some(true));
        used.product_seconds = None;
        assert_eq!(work_units_goal(&used).pass, Some(false));
    }

    /// The goal on a mesh beyond the accepted range says it is refused; on
    /// a mesh skipped for memory, why; on one run, its verdict.
    #[test]
    fn a_finest_goal_names_refusals_and_skips() {
        let ok = |_: &MemoryUse| Ok(());
        let m = MultigridRows::default();
        let g = finest_goal(&m, crate::mechanics::mesh_size::MAX_LEVEL + 1, ok, "g");
        assert!(g.measured.starts_with("refused"), "{}", g.measured);
        let mut m = MultigridRows::default();
        let h = MeshSize::from_level(12).unwrap();
        m.skipped.push((h, "it would need about 40 GiB".into()));
        let g = finest_goal(&m, 12, ok, "g");
        assert!(
            g.measured.contains("40 GiB") && g.pass == Some(false),
            "{}",
            g.measured
        );
        let mut used = run(40.0, 100, "converged");
        used.h = h;
        m.finest.push(used);
        assert_eq!(finest_goal(&m, 12, ok, "g").pass, Some(true));
        let refuse = |_: &MemoryUse| Err("peak above".to_string());
        assert_eq!(finest_goal(&m, 12, refuse, "g").pass, Some(false));
        // A mesh this run did not plan (the main job's bench stops at
        // 1/2048) is the long run's, not a shortfall; planned and missing,
        // its measurement failed.
        let g = finest_goal(&m, 13, ok, "g");
        assert!(
            g.pass.is_none() && g.measured.contains("--long"),
            "{}",
            g.measured
        );
        m.planned.push(MeshSize::from_level(13).unwrap());
        assert_eq!(finest_goal(&m, 13, ok, "g").pass, Some(false));
    }
}
