//! Mesh continuation (Algorithm 1, lines 2-8): the given-friction problem is
//! solved on h = 1/8, 1/16, ... (the scene's levels), each level started from
//! the linear interpolation of the previous level's displacement and
//! multiplier, as the paper does.
//!
//! The pseudocode leaves open whether the coarse levels are revisited in every
//! friction iteration; both readings are implemented:
//! - [`Schedule::Revisit`]: every friction iteration runs all levels, the
//!   coarsest started from the injection of the latest finest solution;
//! - [`Schedule::FinestOnly`]: the coarse levels are run in the first friction
//!   iteration only (h keeps its value between friction iterations), later
//!   ones warm-start on the finest level.
//!
//! A third, [`Schedule::Nested`], is ours: nested iteration (full multigrid)
//! of the whole Coulomb problem. The fixed point runs to its tolerance on
//! 1/8, then on 1/16 started from 1/8's answer and its bound 𝓕p, and so on;
//! the finest level's fixed point starts from g⁰ = 𝓕p of the level below
//! instead of 0, so its first steps are no longer far from the fixed point
//! (with tnnmg at 1/1024 the second and third friction steps from g⁰ = 0
//! took 33 of 48 s).

use std::borrow::Cow;
use std::sync::Arc;

use contactlab_solvers::{
    ContactProblem, Friction, Iterations, Observer, Solution, Solver, Start, Timing,
};
use serde::Serialize;

use crate::coulomb::fixed_point::{
    CoulombSettings, GivenFrictionStep, SingleLevel, bound_of, friction_fixed_point,
};
use crate::mechanics::discretization::Discretization;
use crate::mechanics::mesh_size::MeshSize;

pub use contactlab_solvers::schedule::Schedule;

/// Work done on one level, summed over all friction iterations: the paper's
/// Table 1 counts Uzawa iterations (MU) and relaxation sweeps (MPR).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LevelCount {
    pub h: MeshSize,
    pub visits: usize,
    pub uzawa: usize,
    pub sweeps: usize,
    pub seconds: f64,
}

/// The given-friction step by mesh continuation over `levels` (coarse to
/// fine), which it owns: the nested schedule drops the coarse levels once it
/// is done with them, so that they do not add to the finest solve's peak
/// (a third of the finest level's memory).
pub struct Continuation<'a> {
    /// None: a coarse level dropped.
    levels: Vec<Option<Arc<Discretization>>>,
    solver: &'a mut dyn Solver,
    schedule: Schedule,
    last: Option<Solution>,
    /// The nested schedule's start on the finest level (displacements,
    /// pressures) and the work done below it, added to the first step.
    nested: Option<(Vec<f64>, Vec<f64>, Iterations, Timing)>,
    pub counts: Vec<LevelCount>,
}

impl<'a> Continuation<'a> {
    /// `levels` owned, or lent (an [`Arc`] the caller keeps: the Python
    /// package's problem lends its finest level, which a copy would double).
    pub fn new(
        levels: impl IntoIterator<Item = impl Into<Arc<Discretization>>>,
        solver: &'a mut dyn Solver,
        schedule: Schedule,
    ) -> Self {
        let levels: Vec<Arc<Discretization>> = levels.into_iter().map(Into::into).collect();
        let counts = levels
            .iter()
            .map(|d| LevelCount {
                h: d.h(),
                visits: 0,
                uzawa: 0,
                sweeps: 0,
                seconds: 0.0,
            })
            .collect();
        Self {
            levels: levels.into_iter().map(Some).collect(),
            solver,
            schedule,
            last: None,
            nested: None,
            counts,
        }
    }

    /// The finest level.
    pub fn finest(&self) -> &Discretization {
        at(&self.levels, self.levels.len() - 1)
    }

    /// The meshes of the levels it still holds, coarse to fine.
    pub fn kept_levels(&self) -> Vec<MeshSize> {
        self.levels.iter().flatten().map(|d| d.h()).collect()
    }

    /// The finest level, the continuation done.
    pub fn into_finest(mut self) -> Arc<Discretization> {
        self.levels
            .pop()
            .flatten()
            .expect("the finest level is never dropped")
    }
}

/// Level `idx`; the schedules visit no level they dropped.
fn at(levels: &[Option<Arc<Discretization>>], idx: usize) -> &Discretization {
    levels[idx]
        .as_deref()
        .expect("a schedule visits only the levels it keeps")
}

impl GivenFrictionStep for Continuation<'_> {
    fn problem(&self) -> &ContactProblem {
        &self.finest().problem
    }

    fn solve_step(
        &mut self,
        g: &[f64],
        accuracy: Option<f64>,
        observer: &mut dyn Observer,
    ) -> Solution {
        let top = self.levels.len() - 1;
        let first = match (self.schedule, &self.last) {
            // The nested schedule past its initial bound keeps the finest
            // level alone (it starts there from the bound's answer, or,
            // not handed its predecessor ([`keep`]), from zero).
            _ if self.levels[0].is_none() => top,
            (Schedule::FinestOnly | Schedule::Nested, Some(_)) => top,
            _ => 0,
        };
        let (mut total, mut timing) = (Iterations::default(), Timing::default());
        let (mut v, mut l) = match &self.last {
            _ if self.last.is_none() && self.nested.is_some() => {
                let (v, l, work, time) = self.nested.take().expect("just matched");
                (total, timing) = (work, time);
                (v, l)
            }
            // On the finest level the last answer is the start as it is (no
            // copy, no round trip through the nodal displacements); the
            // loop below returns at that level and keeps its answer.
            Some(_) if first == top => {
                let s = self.last.take().expect("just matched");
                (s.v, s.pressure)
            }
            Some(s) => (
                at(&self.levels, first).transfer_from(at(&self.levels, top), &s.v),
                at(&self.levels, first).transfer_contact(at(&self.levels, top), &s.pressure),
            ),
            None => (
                vec![0.0; at(&self.levels, first).problem.n()],
                vec![0.0; at(&self.levels, first).problem.contacts().len()],
            ),
        };
        for idx in first..=top {
            let g_level = at(&self.levels, idx).transfer_contact(at(&self.levels, top), g);
            let level = at(&self.levels, idx);
            let mut s = self.solver.solve(
                &level.problem,
                Friction::Given(&g_level),
                // Handed over: v is the transfer's (or the last answer's)
                // and is replaced below before it is read again.
                Some(Start {
                    v: Cow::Owned(std::mem::take(&mut v)),
                    pressure: &l,
                    accuracy,
                }),
                observer,
            );
            let count = &mut self.counts[idx];
            count.visits += 1;
            count.uzawa += s.iterations.outer;
            count.sweeps += s.iterations.inner;
            count.seconds += s.timing.total();
            total.outer += s.iterations.outer;
            total.inner += s.iterations.inner;
            timing.setup += s.timing.setup;
            timing.solve += s.timing.solve;
            if !s.status.is_converged() || idx == top {
                if idx < top {
                    // Report on the finest level whatever level failed.
                    s.detail = format!("at h = {}: {}", at(&self.levels, idx).h(), s.detail);
                    let (here, finest) = (at(&self.levels, idx), at(&self.levels, top));
                    s.v = finest.transfer_from(here, &s.v);
                    s.pressure = finest.transfer_contact(here, &s.pressure);
                    s.friction_traction = finest.transfer_contact(here, &s.friction_traction);
                }
                s.iterations = total;
                s.timing = timing;
                // Used: the fixed point hands the new one back ([`keep`]).
                self.last = None;
                return s;
            }
            let (coarse, fine) = (at(&self.levels, idx), at(&self.levels, idx + 1));
            v = fine.transfer_from(coarse, &s.v);
            l = fine.transfer_contact(coarse, &s.pressure);
        }
        unreachable!("the loop returns at the finest level")
    }

    fn keep(&mut self, solution: Solution) {
        self.last = Some(solution);
    }

    fn tighten(&mut self) -> Option<String> {
        self.solver.tighten()
    }

    /// The nested schedule: the fixed point on each coarse level in turn,
    /// to the larger of ε and `coarse_epsilon` (each level's answer only
    /// starts the next: nested iteration); returns 𝓕p⁺ of the level below the finest, on the finest, and keeps
    /// that level's answer as the finest level's start. None (g⁰ = 0, the
    /// usual first step) for the other schedules, one level, or a coarse
    /// fixed point that did not converge.
    fn initial_bound(
        &mut self,
        settings: &CoulombSettings,
        observer: &mut dyn Observer,
    ) -> Option<Vec<f64>> {
        let top = self.levels.len() - 1;
        if self.schedule != Schedule::Nested || top == 0 {
            return None;
        }
        let coarse = CoulombSettings {
            epsilon: settings.epsilon.max(settings.coarse_epsilon),
            ..settings.clone()
        };
        let (mut work, mut time) = (Iterations::default(), Timing::default());
        let mut carry: Option<(Vec<f64>, Vec<f64>)> = None;
        for idx in 0..top {
            let level = at(&self.levels, idx);
            let g0 = carry.as_ref().map(|(_, p)| bound_of(&level.problem, p));
            // Without friction the fixed point is one solve and sets no
            // accuracy of its own: a coarse level's solve is then asked for
            // the coarse ε (its answer only starts the next level), not
            // for the solver's full tolerance.
            let frictionless = !level.problem.contacts().iter().any(|c| c.coefficient > 0.0);
            let mut single = NestedLevel {
                inner: SingleLevel::starting(&level.problem, &mut *self.solver, carry.take()),
                g0,
                need: frictionless.then_some(coarse.epsilon),
            };
            let c = friction_fixed_point(&mut single, &coarse, observer);
            let done = c.total_iterations();
            let count = &mut self.counts[idx];
            count.visits += c.history.len();
            count.uzawa += done.outer;
            count.sweeps += done.inner;
            count.seconds += c.seconds;
            work.outer += done.outer;
            work.inner += done.inner;
            time.solve += c.seconds;
            if !c.status.is_converged() {
                return None;
            }
            let fine = at(&self.levels, idx + 1);
            carry = Some((
                fine.transfer_from(level, &c.solution.v),
                fine.transfer_contact(level, &c.solution.pressure),
            ));
        }
        // The coarse levels are done with: they, and what the solver kept
        // for them, would only add to the finest level's peak.
        self.solver.release();
        for level in &mut self.levels[..top] {
            *level = None;
        }
        let (v, p) = carry?;
        let g = bound_of(&at(&self.levels, top).problem, &p);
        self.nested = Some((v, p, work, time));
        Some(g)
    }
}

/// One coarse level of the nested schedule: a single level whose fixed
/// point starts from the bound carried up from the level below.
struct NestedLevel<'a> {
    inner: SingleLevel<'a>,
    g0: Option<Vec<f64>>,
    /// The accuracy its steps are asked for when the fixed point asks none
    /// (a frictionless problem: [`Start::accuracy`]).
    need: Option<f64>,
}

impl GivenFrictionStep for NestedLevel<'_> {
    fn problem(&self) -> &ContactProblem {
        self.inner.problem()
    }

    fn solve_step(
        &mut self,
        g: &[f64],
        accuracy: Option<f64>,
        observer: &mut dyn Observer,
    ) -> Solution {
        self.inner.solve_step(g, accuracy.or(self.need), observer)
    }

    fn keep(&mut self, solution: Solution) {
        self.inner.keep(solution);
    }

    fn tighten(&mut self) -> Option<String> {
        self.inner.tighten()
    }

    fn initial_bound(&mut self, _: &CoulombSettings, _: &mut dyn Observer) -> Option<Vec<f64>> {
        self.g0.take()
    }
}
