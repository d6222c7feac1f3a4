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
use crate::study::bench::goal::{
    AtMesh, Count, Exceeded, FineLimit, FineOutcome, FineRun, Goal, Measured, Phase, ProductSides,
    WorkUnits,
};
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
        log(&format!("{SOLVER} against {AGAINST} at h = {h}"));
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
        run(AGAINST, &Settings::default())?,
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

/// The solver TNNMG's Coulomb pressures are held against, and how close:
/// max|Δp|/P at most this.
const AGAINST: &str = "newton-coulomb";
const AGREEMENT_GOAL: f64 = 1e-9;

/// The whole Coulomb problem in work units (its seconds over one product
/// A·v with the finest level's A, timed in the same process before and
/// after the solve, [`MemoryUse::product_seconds`]), by phase:
/// the solver's own phases, and the rest (the friction fixed point's
/// updates, the continuation's transfers, the harness).
fn work_units_goal(used: &MemoryUse) -> Goal {
    let measured = |units| Measured::WorkUnits {
        solver: used.solver.clone(),
        h: used.h.to_string(),
        limit: WORK_UNITS_GOAL,
        units,
    };
    let Some(unit) = used.product_seconds.filter(|&u| u > 0.0) else {
        return Goal {
            measured: measured(None),
            pass: Some(false),
        };
    };
    let total = used.seconds / unit;
    let solver_total = used
        .phases
        .iter()
        .find(|(k, _)| k == contactlab_solvers::multigrid::TOTAL_SECONDS)
        .map(|(_, s)| *s);
    let phases = used
        .phases
        .iter()
        .filter(|(k, _)| k != contactlab_solvers::multigrid::TOTAL_SECONDS)
        .map(|(k, s)| Phase {
            name: k
                .trim_start_matches(&format!("{}_", used.solver))
                .trim_end_matches(crate::study::trial::SECONDS_SUFFIX)
                .replace('_', " "),
            units: s / unit,
        })
        .collect();
    // The product's medians before and after the solve, when both were
    // timed: how far the machine's speed moved while it ran.
    let sides = used.product_sides.map(|(before, after)| ProductSides {
        products: 2 * crate::study::bench::memory::PRODUCTS,
        before_ms: before * 1e3,
        after_ms: after * 1e3,
    });
    Goal {
        measured: measured(Some(WorkUnits {
            total,
            seconds: used.seconds,
            unit_ms: unit * 1e3,
            sides,
            phases,
            rest: solver_total.map(|inside| (used.seconds - inside) / unit),
            status: used.status.clone(),
        })),
        pass: Some(used.status == "converged" && total <= WORK_UNITS_GOAL),
    }
}

/// A fine mesh's run as the goals describe it.
fn fine_run(u: &MemoryUse) -> FineRun {
    FineRun {
        h: u.h.to_string(),
        seconds: u.seconds,
        peak_gib: u.peak_kb as f64 / GIB_KB,
        status: u.status.clone(),
    }
}

/// What `u` exceeded of `limit`.
fn exceeded(u: &MemoryUse, limit: &FineLimit) -> Exceeded {
    let (gib, seconds) = match *limit {
        FineLimit::Peak { gib } => (gib, None),
        FineLimit::PeakAndTime { gib, seconds } => (gib, Some(seconds)),
    };
    Exceeded {
        peak_gib: (u.peak_kb as f64 > gib * GIB_KB).then_some(gib),
        seconds: seconds.filter(|&s| u.seconds > s),
    }
}

/// A goal on the multigrid-only mesh of `level`: its run held to `limit`,
/// or why it was not run.
fn finest_goal(m: &MultigridRows, level: u32, limit: FineLimit) -> Goal {
    let coarser = m
        .finest
        .iter()
        .filter(|u| u.h.level() < level)
        .map(fine_run)
        .collect();
    let (outcome, pass) = match MeshSize::from_level(level) {
        Err(e) => (FineOutcome::Refused { why: e.to_string() }, Some(false)),
        Ok(h) => match (
            m.finest.iter().find(|u| u.h == h),
            m.skipped.iter().find(|(s, _)| *s == h),
        ) {
            (Some(u), _) => {
                let exceeded = exceeded(u, &limit);
                let pass = u.status == "converged" && exceeded.nothing();
                (
                    FineOutcome::Run {
                        run: fine_run(u),
                        exceeded,
                    },
                    Some(pass),
                )
            }
            (None, Some((_, why))) => (
                FineOutcome::Skipped {
                    h: h.to_string(),
                    why: why.clone(),
                },
                Some(false),
            ),
            (None, None) if !m.planned.contains(&h) => {
                (FineOutcome::NotPlanned { h: h.to_string() }, None)
            }
            (None, None) => (FineOutcome::NotMeasured { h: h.to_string() }, Some(false)),
        },
    };
    Goal {
        measured: Measured::Fine {
            solver: SOLVER,
            h: format!("1/{}", 1u64 << level.min(63)),
            limit,
            outcome,
            coarser,
        },
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
        out.push(Goal {
            measured: Measured::Iterations {
                solver: SOLVER,
                tolerance: COUNT_TOLERANCE,
                bound_of_scale: BOUND_OF_SCALE,
                limit: ITERATION_GOAL,
                counts: m
                    .iterations
                    .iter()
                    .map(|&(h, iterations, certified)| Count {
                        h: h.to_string(),
                        iterations,
                        certified,
                    })
                    .collect(),
            },
            pass: Some(
                m.iterations
                    .iter()
                    .all(|(_, k, ok)| *ok && *k <= ITERATION_GOAL),
            ),
        });
    }
    for used in &m.coulomb {
        let f = factorization(rows, used.h);
        let ratio = f.map_or(f64::NAN, |f| used.seconds / f);
        out.push(Goal {
            measured: Measured::DefaultSolve {
                solver: SOLVER,
                h: used.h.to_string(),
                limit: DEFAULT_GOAL,
                seconds: used.seconds,
                ratio,
                factorization: f,
                peak_gib: used.peak_kb as f64 / GIB_KB,
                status: used.status.clone(),
                runs: m.runs,
            },
            pass: Some(used.status == "converged" && ratio <= DEFAULT_GOAL),
        });
    }
    if let Some(used) = m.coulomb.last() {
        out.push(work_units_goal(used));
    }
    if let (Some(one), Some(all)) = (&m.one_thread, m.coulomb.last()) {
        let speed_up = one.seconds / all.seconds;
        out.push(Goal {
            measured: Measured::ThreadSpeedUp {
                solver: SOLVER,
                cores: contactlab_solvers::numerics::threads::cores(),
                h: all.h.to_string(),
                limit: THREADS_GOAL,
                speed_up,
                one_seconds: one.seconds,
                one_status: one.status.clone(),
                all_seconds: all.seconds,
                all_status: all.status.clone(),
                runs: m.runs,
            },
            pass: Some(
                one.status == "converged" && all.status == "converged" && speed_up >= THREADS_GOAL,
            ),
        });
    }
    if !m.coulomb.is_empty() {
        out.push(finest_goal(
            m,
            PEAK_GOAL_LEVEL,
            FineLimit::Peak { gib: PEAK_GOAL_GIB },
        ));
        out.push(finest_goal(
            m,
            FINEST_GOAL_LEVEL,
            FineLimit::PeakAndTime {
                gib: FINEST_GOAL_GIB,
                seconds: FINEST_GOAL_SECONDS,
            },
        ));
    }
    if let Some((h, seconds, status)) = &m.paper {
        out.push(Goal {
            measured: Measured::PaperMultigrid {
                h: h.to_string(),
                limit_seconds: PAPER_GOAL_SECONDS,
                seconds: *seconds,
                status: status.clone(),
            },
            pass: Some(status.starts_with("converged,") && *seconds <= PAPER_GOAL_SECONDS),
        });
    }
    if !m.agreement.is_empty() {
        out.push(Goal {
            measured: Measured::Agreement {
                solver: SOLVER,
                against: AGAINST,
                limit: AGREEMENT_GOAL,
                gaps: m
                    .agreement
                    .iter()
                    .map(|&(h, gap)| AtMesh {
                        h: h.to_string(),
                        value: gap,
                    })
                    .collect(),
            },
            pass: Some(m.agreement.iter().all(|(_, gap)| *gap <= AGREEMENT_GOAL)),
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

    /// The work units of `g`, a work-units goal.
    fn units(g: &Goal) -> Option<&WorkUnits> {
        match &g.measured {
            Measured::WorkUnits { units, .. } => units.as_ref(),
            other => panic!("not a work-units goal: {other:?}"),
        }
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
        let u = units(&g).unwrap();
        assert!((u.total - 300.0).abs() < 1e-9, "{u:?}");
        assert_eq!(u.phases.len(), 1, "{u:?}");
        assert_eq!(u.phases[0].name, "smoothing");
        assert!((u.phases[0].units - 150.0).abs() < 1e-9, "{u:?}");
        assert!((u.rest.unwrap() - 50.0).abs() < 1e-9, "{u:?}");
        assert_eq!(g.pass, Some(false));
        // Both sides of the solve, when timed, are stated with the unit.
        used.product_sides = Some((0.008, 0.012));
        let text = crate::study::bench::goals::goals_markdown(&[work_units_goal(&used)]).unwrap();
        assert!(
            text.contains(
                "| 300 work units (3.00 s ÷ 10.00 ms, the median of 22 products: 8.00 ms before the solve, 12.00 ms after): smoothing 150, friction updates, transfers and the rest 50 (converged) | falls short |"
            ),
            "{text}"
        );
        used.seconds = 0.25;
        assert_eq!(work_units_goal(&used).pass, Some(true));
        used.product_seconds = None;
        let g = work_units_goal(&used);
        assert!(units(&g).is_none());
        assert_eq!(g.pass, Some(false));
    }

    /// The outcome of `g`, a fine-mesh goal.
    fn outcome(g: &Goal) -> &FineOutcome {
        match &g.measured {
            Measured::Fine { outcome, .. } => outcome,
            other => panic!("not a fine-mesh goal: {other:?}"),
        }
    }

    /// The goal on a mesh beyond the accepted range says it is refused; on
    /// a mesh skipped for memory, why; on one run, its verdict against its
    /// limits: what it exceeded, named.
    #[test]
    fn a_finest_goal_names_refusals_and_skips() {
        let peak = FineLimit::Peak { gib: 4.0 };
        let m = MultigridRows::default();
        let g = finest_goal(&m, crate::mechanics::mesh_size::MAX_LEVEL + 1, peak.clone());
        assert!(matches!(outcome(&g), FineOutcome::Refused { .. }), "{g:?}");
        assert_eq!(g.pass, Some(false));
        let mut m = MultigridRows::default();
        let h = MeshSize::from_level(12).unwrap();
        m.skipped.push((h, "it would need about 40 GiB".into()));
        let g = finest_goal(&m, 12, peak.clone());
        let text = crate::study::bench::goals::goals_markdown(std::slice::from_ref(&g)).unwrap();
        assert!(
            text.contains("| 1/4096 not run: it would need about 40 GiB | falls short |")
                && g.pass == Some(false),
            "{text}"
        );
        let mut used = run(40.0, 100, "converged");
        used.h = h;
        m.finest.push(used.clone());
        assert_eq!(finest_goal(&m, 12, peak.clone()).pass, Some(true));
        // Above both limits: each is named, and the goal falls short.
        m.finest[0].peak_kb = 5 * 1024 * 1024;
        let both = FineLimit::PeakAndTime {
            gib: 4.0,
            seconds: 30.0,
        };
        let g = finest_goal(&m, 12, both);
        let FineOutcome::Run { exceeded, .. } = outcome(&g) else {
            panic!("{g:?}")
        };
        assert_eq!(
            exceeded,
            &Exceeded {
                peak_gib: Some(4.0),
                seconds: Some(30.0)
            }
        );
        assert_eq!(g.pass, Some(false));
        let text = crate::study::bench::goals::goals_markdown(&[g]).unwrap();
        assert!(
            text.contains(
                "1/4096: 40.0 s, peak 5.00 GiB, converged (peak above 4 GiB, above 30 s)"
            ),
            "{text}"
        );
        // A mesh this run did not plan (the main job's bench stops at
        // 1/2048) is the long run's, not a shortfall; planned and missing,
        // its measurement failed. The run on the coarser mesh is named.
        m.finest[0].peak_kb = 100;
        let g = finest_goal(&m, 13, peak.clone());
        let text = crate::study::bench::goals::goals_markdown(std::slice::from_ref(&g)).unwrap();
        assert!(
            g.pass.is_none()
                && text.contains(
                    "1/8192 not in this run (the long run's: `reproduce --long`) (coarser: 1/4096: 40.0 s, peak 0.00 GiB, converged)"
                ),
            "{text}"
        );
        m.planned.push(MeshSize::from_level(13).unwrap());
        assert_eq!(finest_goal(&m, 13, peak).pass, Some(false));
    }
}
