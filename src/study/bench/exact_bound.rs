//! Coulomb without the outer loop, bounded by measurement (issue 50): how
//! many finest-level TNNMG iterations the friction fixed point spends, and
//! how many TNNMG needs from the same start when the friction bound is
//! already exact (g = 𝓕p* of the converged answer).
//!
//! A method that updates the bound inside the multigrid iteration (a
//! nonsmooth Newton on the whole Coulomb law, Hüeber, Stadler & Wohlmuth,
//! SIAM J. Sci. Comput. 30 (2008)) with the same linear correction starts
//! from the same error and has the bound's error to remove besides: TNNMG
//! at the exact bound is its best case, and the gap between the two counts
//! estimates all that the outer loop costs.
//! Both runs start from the nested schedule's start on the finest level
//! (the level below solved to `coulomb.coarse_epsilon`, interpolated), and
//! both are judged by one error: max|p − p*|/P against a reference solved
//! far tighter than the default.

use std::borrow::Cow;
use std::time::Instant;

use anyhow::Result;
use contactlab_solvers::multigrid::{Tnnmg, TnnmgSettings};
use contactlab_solvers::{Friction, Silent, Solver, Start};
use serde::Serialize;
use serde_json::json;

use crate::coulomb::fixed_point::bound_of;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::solve::{solve_scene, solver_entry};
use crate::study::bench::PerfRow;
use crate::study::bench::multigrid::{SOLVER, factorization, largest_gap, tight_settings};

/// The most iterations tried at the exact bound.
const MAX_ITERATIONS: usize = 30;

/// One mesh's comparison.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ExactBound {
    pub h: MeshSize,
    /// The default solve (nested fixed point): its friction steps, its
    /// TNNMG iterations on the finest level, its error max|p − p*|/P and
    /// its seconds (in this process, once).
    pub friction_steps: usize,
    pub finest_iterations: usize,
    pub error: f64,
    pub seconds: f64,
    /// The error of the finest level's start, and TNNMG's iterations at the
    /// exact bound from it to `error` or less (None: not within
    /// [`MAX_ITERATIONS`]).
    pub start_error: f64,
    pub exact_iterations: Option<usize>,
    /// One finest TNNMG iteration, seconds: the median increment of the
    /// exact-bound runs of 1, 2, … iterations.
    pub iteration_seconds: f64,
}

impl ExactBound {
    /// The default solve's seconds less the iterations the exact bound
    /// saves, each at [`Self::iteration_seconds`]: the time a single-loop
    /// method with this linear correction could at best reach.
    pub fn best_case_seconds(&self) -> Option<f64> {
        let saved = self
            .finest_iterations
            .saturating_sub(self.exact_iterations?);
        Some(self.seconds - saved as f64 * self.iteration_seconds)
    }
}

/// The comparison on problem `problem` at `h` (h coarser than 1/8 has no
/// level below: None).
pub fn measure(problem: u32, h: MeshSize) -> Result<Option<ExactBound>> {
    let Some(below) = h.level().checked_sub(1).filter(|&k| k >= 3) else {
        return Ok(None);
    };
    let below = MeshSize::from_level(below)?;
    let entry = solver_entry(SOLVER)?;
    let scene = Scene::paper_problem_to(problem, h)?;
    // The reference: as the agreement goal's.
    let reference = solve_scene(
        &scene,
        Friction::Coulomb,
        entry,
        &tight_settings()?,
        &mut Silent,
    )?;
    anyhow::ensure!(
        reference.outcome.status.is_converged(),
        "the reference at h = {h} is {}",
        reference.outcome.status
    );
    let d = &reference.finest;
    let p_star = &reference.outcome.solution.pressure;
    let scale = d.problem.scales().pressure;
    let error = |p: &[f64]| largest_gap(p, p_star) / scale;
    let default = solve_scene(
        &scene,
        Friction::Coulomb,
        entry,
        &Settings::default(),
        &mut Silent,
    )?;
    let o = &default.outcome;
    anyhow::ensure!(
        o.status.is_converged(),
        "the default solve at h = {h} is {}",
        o.status
    );
    // The nested schedule's start: the level below, its own fixed point run
    // to the coarse ε (as the schedule runs it on every level below).
    let coarse_epsilon = Settings::default()
        .coulomb()
        .map_err(anyhow::Error::msg)?
        .coarse_epsilon;
    let mut loose = Settings::default();
    loose
        .set("coulomb.epsilon", json!(coarse_epsilon))
        .map_err(anyhow::Error::msg)?;
    let coarse_scene = Scene::paper_problem_to(problem, below)?;
    let coarse = solve_scene(&coarse_scene, Friction::Coulomb, entry, &loose, &mut Silent)?;
    let v0 = d.transfer_from(&coarse.finest, &coarse.outcome.solution.v);
    let p0 = d.transfer_contact(&coarse.finest, &coarse.outcome.solution.pressure);
    // The exact bound, and k TNNMG iterations from the start for k = 1, 2,
    // …: one solver, so that its hierarchy is built once.
    let g_star = bound_of(&d.problem, p_star);
    let mut tnnmg = Tnnmg::new(TnnmgSettings {
        tolerance: 1e-15,
        ..TnnmgSettings::default()
    });
    let fixed_point_error = error(&o.solution.pressure);
    let (mut exact, mut increments, mut last) = (None, Vec::new(), None);
    for k in 1..=MAX_ITERATIONS {
        tnnmg.settings.max_iter = k;
        let t = Instant::now();
        let s = tnnmg.solve(
            &d.problem,
            Friction::Given(&g_star),
            Some(Start {
                v: Cow::Borrowed(&v0),
                pressure: &p0,
                accuracy: None,
            }),
            &mut Silent,
        );
        let seconds = t.elapsed().as_secs_f64();
        if let Some(before) = last.replace(seconds) {
            increments.push(seconds - before);
        }
        if error(&s.pressure) <= fixed_point_error {
            exact = Some(k);
            break;
        }
    }
    increments.sort_by(f64::total_cmp);
    let finest = o.levels.last().map_or(0, |l| l.uzawa);
    Ok(Some(ExactBound {
        h,
        friction_steps: o.friction_iterations(),
        finest_iterations: finest,
        error: fixed_point_error,
        seconds: o.timing.total(),
        start_error: error(&p0),
        exact_iterations: exact,
        iteration_seconds: increments
            .get(increments.len() / 2)
            .copied()
            .unwrap_or(f64::NAN),
    }))
}

/// A row of the table (`templates/bench_exact_bound.md`): the
/// measurement, its best case, and each time over the best factorization
/// at its mesh (none without one).
#[derive(Serialize)]
struct Row<'a> {
    #[serde(flatten)]
    found: &'a ExactBound,
    h: String,
    seconds_over_factorization: Option<f64>,
    best: Option<f64>,
    best_over_factorization: Option<f64>,
}

/// The table, each time also over the best factorization of `rows`.
pub fn markdown(found: &[ExactBound], rows: &[PerfRow]) -> Result<String> {
    let table: Vec<Row> = found
        .iter()
        .map(|e| {
            let f = factorization(rows, e.h);
            let best = e.best_case_seconds();
            Row {
                found: e,
                h: e.h.to_string(),
                seconds_over_factorization: f.map(|f| e.seconds / f),
                best,
                best_over_factorization: best.and_then(|b| f.map(|f| b / f)),
            }
        })
        .collect();
    crate::study::template::render(
        "bench_exact_bound",
        include_str!("../templates/bench_exact_bound.md"),
        crate::study::template::facts! { rows => table, max_iterations => MAX_ITERATIONS },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The best case takes off the saved iterations at their measured cost
    /// and never adds: an exact count above the fixed point's saves none.
    #[test]
    fn the_best_case_removes_only_the_saved_iterations() {
        let mut e = ExactBound {
            h: MeshSize::from_level(10).unwrap(),
            friction_steps: 6,
            finest_iterations: 7,
            error: 1e-8,
            seconds: 3.0,
            start_error: 1e-3,
            exact_iterations: Some(5),
            iteration_seconds: 0.3,
        };
        assert!((e.best_case_seconds().unwrap() - 2.4).abs() < 1e-12);
        e.exact_iterations = Some(9);
        assert_eq!(e.best_case_seconds(), Some(3.0));
        e.exact_iterations = None;
        assert_eq!(e.best_case_seconds(), None);
    }

    /// At 1/32: the start is far from the answer and the fixed point ends
    /// near it; at the exact bound TNNMG reaches the fixed point's error
    /// from that start, in no more finest iterations than the fixed point
    /// spent. A wrong bound (the start's 𝓕p⁰ instead of 𝓕p*) never reaches
    /// that error (checked by hand: the cap is hit).
    #[test]
    fn the_exact_bound_reaches_the_fixed_point_s_error_in_no_more_iterations() {
        let e = measure(1, MeshSize::from_level(5).unwrap())
            .unwrap()
            .expect("1/32 has a level below");
        assert!(e.start_error > 1e-3, "{e:?}");
        assert!(e.error < 1e-7, "{e:?}");
        let exact = e.exact_iterations.expect("reached within the cap");
        assert!(exact <= e.finest_iterations, "{e:?}");
        assert!(e.friction_steps >= 2, "{e:?}");
        assert!(
            measure(1, MeshSize::from_level(3).unwrap())
                .unwrap()
                .is_none()
        );
    }
}
