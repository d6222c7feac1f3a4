//! The one interface every solver implements.

use serde::{Deserialize, Serialize};

use crate::observer::Observer;
use crate::problem::ContactProblem;
use crate::solution::Solution;

/// Which friction law a solve enforces on Γ_K.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Law {
    /// The given-friction (Tresca) subproblem, paper (10): |q_i| ≤ g_i with
    /// the problem's bounds g_i.
    GivenFriction,
    /// The static Coulomb problem, paper (7)-(8): |q_i| ≤ 𝓕_i p_i with the
    /// problem's coefficients and the solution's own pressures.
    Coulomb,
}

impl Law {
    pub fn as_str(self) -> &'static str {
        match self {
            Law::GivenFriction => "given_friction",
            Law::Coulomb => "coulomb",
        }
    }
}

/// A starting point: unknowns and contact pressures (per contact node).
/// Solvers that cannot warm-start ignore it.
#[derive(Clone, Copy, Debug)]
pub struct Start<'a> {
    pub v: &'a [f64],
    pub pressure: &'a [f64],
}

/// A solver of the algebraic contact problem.
///
/// `&mut self` lets a solver keep work that depends only on A and M (a
/// factorization, a Schur complement) across calls with the same
/// [`ContactProblem::operator_id`], such as the steps of the Coulomb
/// fixed point, which change only the friction bound g.
pub trait Solver {
    /// Solves `problem` under `law`; never panics on a bad problem, reports a
    /// status. A law the solver does not treat gives [`crate::Status::NotRun`].
    fn solve(
        &mut self,
        problem: &ContactProblem,
        law: Law,
        start: Option<Start<'_>>,
        observer: &mut dyn Observer,
    ) -> Solution;
}
