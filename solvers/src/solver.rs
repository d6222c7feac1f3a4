//! The one interface every solver implements.

use std::borrow::Cow;

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

/// The friction law of one solve with its data. The problem itself never
/// changes between solves: the friction bound of the given-friction
/// subproblem is an argument, so that a solver, the certificate and a
/// report of one solve all read the same g.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Friction<'a> {
    /// The given-friction (Tresca) subproblem, paper (10), with the bound
    /// g_i ≥ 0 (force per unit length of Γ_K) at each contact node.
    Given(&'a [f64]),
    /// The static Coulomb problem, paper (7)-(8): the bound 𝓕_i p_i of the
    /// solution's own pressures.
    Coulomb,
}

impl Friction<'_> {
    pub fn law(&self) -> Law {
        match self {
            Friction::Given(_) => Law::GivenFriction,
            Friction::Coulomb => Law::Coulomb,
        }
    }

    /// The bound at contact node i for pressure p: g_i, or 𝓕_i p⁺.
    pub fn bound(&self, i: usize, coefficient: f64, pressure: f64) -> f64 {
        match self {
            Friction::Given(g) => g[i],
            Friction::Coulomb => coefficient * pressure.max(0.0),
        }
    }

    /// Checks a given bound against `problem`: one finite g_i ≥ 0 per
    /// contact node.
    pub fn check(&self, problem: &ContactProblem) -> Result<(), String> {
        let Friction::Given(g) = self else {
            return Ok(());
        };
        let m = problem.contacts().len();
        if g.len() != m {
            return Err(format!(
                "the friction bound has {} values, the problem {m} contact nodes",
                g.len()
            ));
        }
        match g.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
            Some(i) => Err(format!(
                "the friction bound at contact node {i} is {}, not a finite number ≥ 0",
                g[i]
            )),
            None => Ok(()),
        }
    }
}

/// A starting point: unknowns and contact pressures (per contact node).
/// Solvers that cannot warm-start ignore it.
#[derive(Clone, Debug)]
pub struct Start<'a> {
    /// The unknowns: borrowed, or handed over when the caller is done with
    /// them, so that a solver that iterates on its start
    /// ([`Cow::into_owned`]) takes them without a copy (a vector of the
    /// finest size less at a solve's peak, 8 of its 185 bytes per unknown
    /// at h = 1/4096).
    pub v: Cow<'a, [f64]>,
    pub pressure: &'a [f64],
    /// The accuracy the caller needs of this solve, relative (in the
    /// problem's scales), when it needs less than the solver's own
    /// tolerance: the friction fixed point asks a fraction of its last
    /// relative change of g (an inexact fixed point: Newton-like forcing
    /// terms, Dembo, Eisenstat & Steihaug 1982). It is an accuracy of the
    /// contact pressure, relative to P (g = 𝓕p is what the caller uses). A
    /// solver may stop at the looser of this and its own tolerance, or
    /// ignore it; None: its own. A solver that stopped at this need says
    /// so with the diagnostic [`STOPPED_AT_NEED`] (the need's value): the
    /// fixed point never ends on such a step when the need was looser than
    /// its own stopping accuracy.
    pub accuracy: Option<f64>,
}

/// The [`Solution::diagnostics`](crate::Solution) name of a solve that
/// stopped at the caller's [`Start::accuracy`] rather than at its own
/// tolerance; its value is that accuracy.
pub const STOPPED_AT_NEED: &str = "stopped_at_need";

/// A solver of the algebraic contact problem.
///
/// `&mut self` lets a solver keep work that depends only on A and M (a
/// factorization, a Schur complement) across calls with the same
/// [`ContactProblem::operator_id`], such as the steps of the Coulomb
/// fixed point, which change only the friction bound g they are given.
pub trait Solver {
    /// Solves `problem` under the law `friction` names, with its bound;
    /// never panics on a bad problem, reports a status. A law the solver does
    /// not treat, or a bound that does not fit the problem, gives
    /// [`crate::Status::NotRun`].
    fn solve(
        &mut self,
        problem: &ContactProblem,
        friction: Friction<'_>,
        start: Option<Start<'_>>,
        observer: &mut dyn Observer,
    ) -> Solution;

    /// Drops what the solver keeps across calls for the problems solved so
    /// far (multigrid hierarchies, vectors): the harness calls it when it
    /// will not solve them again, as the nested schedule leaving its coarse
    /// levels. What is kept changes no answer, only the work of a repeated
    /// solve; by default nothing is kept.
    fn release(&mut self) {}

    /// Tightens the solver's own stopping tolerance by one step, for a
    /// caller that found its answers not accurate enough: the friction
    /// fixed point when it stalls at the noise of the solves, a
    /// given-friction solve the certificate rejected. Says what changed
    /// (`clarabel.tol 1e-10 → 1e-11`), or None when the solver cannot
    /// tighten further (by default: it has no such tolerance). An interior
    /// point's accuracy at its default tolerance falls as the mesh is
    /// refined; this is how the oracle certifies at every h without a
    /// tolerance chosen for the finest mesh slowing the coarse ones.
    fn tighten(&mut self) -> Option<String> {
        None
    }

    /// Whether the solver poses an initial gap itself (t_i ≤ d_i,
    /// [`ContactProblem::gap`]). One that does not is handed the problem in
    /// the closed unknowns ṽ = v − D ([`crate::reduction::gap`]), exact
    /// but with the load f − A D, which a gap far larger than the
    /// displacements makes large; by default the harness does that.
    fn poses_gaps(&self) -> bool {
        false
    }

    /// Whether the solver poses a slip offset itself (friction on s_i −
    /// σ_i, [`ContactProblem::slip_offset`]); one that does not is handed
    /// the problem in the unknowns with s̃ = s − σ, whose load f − A D
    /// strains the layer of elements at Γ_K by σ. By default the harness
    /// does that.
    fn poses_slip_offsets(&self) -> bool {
        false
    }

    /// How many rigid modes (the kernel of A) the solver handles: the
    /// paper's problem has one, the upper body's vertical translation; a
    /// body free sideways adds its horizontal one, which only friction
    /// holds. A problem with more is refused before any work
    /// ([`crate::reduction::gap::ClosingGap`]), with the reason. By default
    /// one: a method built around the paper's mode (a dual operator made
    /// definite along it, a line search along it) must say it handles more.
    fn rigid_modes_handled(&self) -> usize {
        1
    }
}
