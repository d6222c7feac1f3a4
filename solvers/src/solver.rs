//! The one interface every given-friction solver implements.

use crate::observer::Observer;
use crate::problem::GivenFrictionProblem;
use crate::solution::Solution;

/// A starting point: unknowns and contact pressures (per contact node).
/// Solvers that cannot warm-start ignore it.
#[derive(Clone, Copy, Debug)]
pub struct Start<'a> {
    pub v: &'a [f64],
    pub pressure: &'a [f64],
}

/// A solver of the given-friction subproblem (paper (10), discretized).
///
/// `&mut self` lets a solver keep work that depends only on A and M (a
/// factorization, a Schur complement) across calls with the same
/// [`GivenFrictionProblem::operator_id`], such as the steps of the Coulomb
/// fixed point, which change only the friction bound g.
pub trait GivenFrictionSolver {
    /// The registered name (`clarabel`, `relaxation`, ...).
    fn name(&self) -> &'static str;

    /// Solves the subproblem; never panics on a bad problem, reports a status.
    fn solve(
        &mut self,
        problem: &GivenFrictionProblem,
        start: Option<Start<'_>>,
        observer: &mut dyn Observer,
    ) -> Solution;
}
