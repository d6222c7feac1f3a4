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

use contactlab_solvers::{
    ContactProblem, Friction, Iterations, Observer, Solution, Solver, Start, Timing,
};
use serde::{Deserialize, Serialize};

use crate::coulomb::fixed_point::GivenFrictionStep;
use crate::mechanics::discretization::Discretization;
use crate::mechanics::mesh_size::MeshSize;

/// Whether coarse levels are revisited in every friction iteration.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Schedule {
    #[default]
    /// All levels in every friction iteration.
    Revisit,
    /// All levels in the first friction iteration, then the finest only.
    FinestOnly,
}

impl Schedule {
    pub const ALL: [Self; 2] = [Self::Revisit, Self::FinestOnly];

    /// Its name in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Schedule::Revisit => "revisit",
            Schedule::FinestOnly => "finest-only",
        }
    }
}

impl std::fmt::Display for Schedule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

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

/// The given-friction step by mesh continuation over `levels` (coarse to fine).
pub struct Continuation<'a> {
    levels: &'a [Discretization],
    solver: &'a mut dyn Solver,
    schedule: Schedule,
    last: Option<Solution>,
    pub counts: Vec<LevelCount>,
}

impl<'a> Continuation<'a> {
    pub fn new(
        levels: &'a [Discretization],
        solver: &'a mut dyn Solver,
        schedule: Schedule,
    ) -> Self {
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
            levels,
            solver,
            schedule,
            last: None,
            counts,
        }
    }

    /// The finest level.
    pub fn finest(&self) -> &Discretization {
        self.levels.last().expect("at least one level")
    }
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
            (Schedule::FinestOnly, Some(_)) => top,
            _ => 0,
        };
        let (mut v, mut l) = match &self.last {
            Some(s) => (
                self.levels[first].transfer_from(&self.levels[top], &s.v),
                self.levels[first].transfer_contact(&self.levels[top], &s.pressure),
            ),
            None => (
                vec![0.0; self.levels[first].problem.n()],
                vec![0.0; self.levels[first].problem.contacts().len()],
            ),
        };
        let mut total = Iterations::default();
        let mut timing = Timing::default();
        for idx in first..=top {
            let g_level = self.levels[idx].transfer_contact(&self.levels[top], g);
            let level = &self.levels[idx];
            let mut s = self.solver.solve(
                &level.problem,
                Friction::Given(&g_level),
                Some(Start {
                    v: &v,
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
                    s.detail = format!("at h = {}: {}", self.levels[idx].h(), s.detail);
                    let (here, finest) = (&self.levels[idx], &self.levels[top]);
                    s.v = finest.transfer_from(here, &s.v);
                    s.pressure = finest.transfer_contact(here, &s.pressure);
                    s.friction_traction = finest.transfer_contact(here, &s.friction_traction);
                }
                s.iterations = total;
                s.timing = timing;
                if idx == top {
                    self.last = Some(s.clone());
                }
                return s;
            }
            let (coarse, fine) = (&self.levels[idx], &self.levels[idx + 1]);
            v = fine.transfer_from(coarse, &s.v);
            l = fine.transfer_contact(coarse, &s.pressure);
        }
        unreachable!("the loop returns at the finest level")
    }
}
