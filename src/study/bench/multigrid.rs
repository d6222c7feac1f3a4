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
    /// The paper's method with multigrid inside: (h, seconds, status).
    pub paper: Option<(MeshSize, f64, String)>,
    /// max|p − p_Newton| / P of the Coulomb answers: (h, gap).
    pub agreement: Vec<(MeshSize, f64)>,
}

/// The meshes of each measurement for a benchmark spec: every mesh of the
/// spec and its large ones for the counts; the large ones (the finest mesh
/// without) for the Coulomb problem; 1/256 (or the finest) for the paper's
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
    let paper = at(8).unwrap_or(finest);
    let agreement = [at(6), at(8)].into_iter().flatten().collect();
    (all, large, paper, agreement)
}

/// Fresh-process runs of the whole Coulomb problem on the large meshes
/// (1/2048, at 40 s a run, runs once): one run moved by a third from one
/// `bench` to the next (1/1024: 5.9 s, 4.2 s, 2.9 s).
pub const COULOMB_RUNS: usize = 3;

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
    for h in counts {
        log(&format!("{SOLVER} from zero at h = {h}"));
        out.iterations.push(count_from_zero(spec.problem, h)?);
    }
    for (&h, finest) in large
        .iter()
        .map(|h| (h, false))
        .chain(spec.multigrid_only.iter().map(|h| (h, true)))
    {
        let runs = if finest { 1 } else { COULOMB_RUNS };
        if let Some(why) = finest
            .then(|| too_large(&out.finest, h, available_memory_kb()?))
            .flatten()
        {
            log(&format!("{SOLVER} at h = {h} not run: {why}"));
            out.skipped.push((h, why));
            continue;
        }
        let mut uses = Vec::new();
        for run in 1..=runs {
            log(&format!(
                "{SOLVER} on the Coulomb problem at h = {h} (fresh process, run {run} of {runs})"
            ));
            match measure_in_fresh_process(spec.problem, h, SOLVER, Schedule::Nested) {
                Ok(used) => uses.push(used),
                Err(e) => log(&format!("not measured: {e:#}")),
            }
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
    out.paper = Some((paper, o.timing.total(), o.status.to_string()));
    for h in agreement {
        log(&format!("{SOLVER} against newton-coulomb at h = {h}"));
        out.agreement.push((h, agreement_at(spec.problem, h)?));
    }
    Ok(out)
}

/// Why a mesh finer than those measured would not fit here, if it would
/// not: its estimate, four times the unknowns of the mesh before it at
/// that mesh's peak per unknown, with a tenth to spare, against the memory
/// `available_kb` this machine has available now (1/4096 takes about 14
/// GB).
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
    let mut tight = Settings::default();
    tight.schedule = Some(Schedule::Nested);
    tight
        .set("tnnmg.tolerance", json!(1e-12))
        .map_err(anyhow::Error::msg)?;
    tight
        .set("coulomb.epsilon", json!(1e-11))
        .map_err(anyhow::Error::msg)?;
    let (Some((mg, scale)), Some((newton, _))) = (
        run(SOLVER, &tight)?,
        run("newton-coulomb", &Settings::default())?,
    ) else {
        return Ok(f64::NAN);
    };
    Ok(mg
        .iter()
        .zip(&newton)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
        / scale)
}

/// The best factorization's median seconds at `h` in `rows`.
fn factorization(rows: &[PerfRow], h: MeshSize) -> Option<f64> {
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
                "whole Coulomb problem at h = {} by {SOLVER} (nested schedule), certified: at most 0.5 × the best factorization, peak at most 1 GiB",
                used.h
            ),
            measured: format!(
                "{:.2} s = {ratio:.2} × factorization ({}), peak {:.2} GiB, {} (median of {} runs, each in a fresh process)",
                used.seconds,
                f.map_or("not measured".into(), |f| format!("{f:.2} s")),
                used.peak_kb as f64 / (1024.0 * 1024.0),
                used.status,
                COULOMB_RUNS,
            ),
            pass: Some(
                used.status == "converged"
                    && ratio <= 0.5
                    && used.peak_kb <= 1024 * 1024,
            ),
        });
    }
    if !m.coulomb.is_empty() {
        let finer: Vec<String> = m
            .finest
            .iter()
            .map(|u| {
                format!(
                    "{}: {:.1} s, peak {:.2} GiB, {}",
                    u.h,
                    u.seconds,
                    u.peak_kb as f64 / GIB_KB,
                    u.status
                )
            })
            .collect();
        let mut missing: Vec<String> = m
            .skipped
            .iter()
            .map(|(h, why)| format!("{h} not run: {why}"))
            .collect();
        for h in ["1/2048", "1/4096"] {
            let seen = |name: String| name == h;
            if !m.finest.iter().any(|u| seen(u.h.to_string()))
                && !m.skipped.iter().any(|(s, _)| seen(s.to_string()))
            {
                missing.push(format!("{h} not measured"));
            }
        }
        out.push(Goal {
            goal: "h = 1/2048 and 1/4096 certified, peak at most 12 GiB".into(),
            measured: finer
                .into_iter()
                .chain(missing.iter().cloned())
                .collect::<Vec<_>>()
                .join("; "),
            pass: Some(
                missing.is_empty()
                    && m.finest
                        .iter()
                        .all(|u| u.status == "converged" && u.peak_kb as f64 <= 12.0 * GIB_KB),
            ),
        });
    }
    if let Some((h, seconds, status)) = &m.paper {
        out.push(Goal {
            goal: format!(
                "the paper's method with relaxation.inner = multigrid and target = 1e-6 at h = {h}: at most 10 s, certified"
            ),
            measured: format!("{seconds:.2} s, {status}"),
            pass: Some(status == "converged" && *seconds <= 10.0),
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
}
