//! What every solver returns, for the given-friction subproblem and the
//! Coulomb problem alike.

use crate::problem::ContactProblem;
use crate::solver::{Friction, Law};
use serde::{Deserialize, Serialize};

/// How a solve ended. A solver's own [`Status::Converged`] is only its claim:
/// the harness certifies every answer against the problem and turns a claim
/// that fails into [`Status::Inaccurate`]. Everything else is reported as it is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// The solver's own stopping test was met.
    Converged,
    /// Met only relaxed tolerances (Clarabel's AlmostSolved).
    ReducedAccuracy,
    /// An iteration cap was reached first.
    MaxIterations,
    /// A time limit was reached first.
    TimeLimit,
    /// The solver stopped making progress.
    InsufficientProgress,
    /// The constraints admit no point (should not happen here: v = 0 is feasible).
    Infeasible,
    /// The solver reports the objective unbounded below (which condition
    /// (13) excludes: on a problem that satisfies it, a solver failure).
    Unbounded,
    /// A factorization or another numerical step failed.
    NumericalError,
    /// A NaN or an infinity appeared in the iterates.
    NonFinite,
    /// The solver was not run (e.g. a problem it cannot take).
    NotRun,
    /// The solve needed more memory than the process may use: an
    /// allocation of its set-up failed (a factorization), or the harness's
    /// estimate refused it before it started. A resource, not a property
    /// of the problem or the method.
    OutOfMemory,
    /// Never returned by a solver: its claim of convergence failed the
    /// harness's certificate (the failing condition is named beside it).
    Inaccurate,
}

impl Status {
    /// Every status, in the order of the declaration.
    pub const ALL: [Status; 12] = [
        Status::Converged,
        Status::ReducedAccuracy,
        Status::MaxIterations,
        Status::TimeLimit,
        Status::InsufficientProgress,
        Status::Infeasible,
        Status::Unbounded,
        Status::NumericalError,
        Status::NonFinite,
        Status::NotRun,
        Status::OutOfMemory,
        Status::Inaccurate,
    ];

    pub fn is_converged(self) -> bool {
        self == Status::Converged
    }

    /// Stable lower-case name, as written in output files.
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Converged => "converged",
            Status::ReducedAccuracy => "reduced_accuracy",
            Status::MaxIterations => "max_iterations",
            Status::TimeLimit => "time_limit",
            Status::InsufficientProgress => "insufficient_progress",
            Status::Infeasible => "infeasible",
            Status::Unbounded => "unbounded",
            Status::NumericalError => "numerical_error",
            Status::NonFinite => "non_finite",
            Status::NotRun => "not_run",
            Status::OutOfMemory => "out_of_memory",
            Status::Inaccurate => "inaccurate",
        }
    }
}

impl std::fmt::Display for Status {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Why a solver could not set up a solve (a factorization failed or ran
/// out of memory): the status to report and the sentence.
#[derive(Clone, Debug, PartialEq)]
pub struct SetupError {
    pub status: Status,
    pub detail: String,
}

impl From<String> for SetupError {
    /// A numerical failure, in words.
    fn from(detail: String) -> Self {
        Self {
            status: Status::NumericalError,
            detail,
        }
    }
}

impl From<crate::numerics::linalg::LinalgError> for SetupError {
    fn from(e: crate::numerics::linalg::LinalgError) -> Self {
        let status = match e {
            crate::numerics::linalg::LinalgError::OutOfMemory { .. } => Status::OutOfMemory,
            _ => Status::NumericalError,
        };
        Self {
            status,
            detail: e.to_string(),
        }
    }
}

/// Iteration counts. Their meaning depends on the solver: interior-point
/// iterations for Clarabel; Uzawa iterations (MU) and relaxation sweeps (MPR)
/// for the paper's method; Newton steps for a Newton method.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Iterations {
    /// Main loop: interior-point, Uzawa or Newton iterations.
    pub outer: usize,
    /// Inner loop: relaxation sweeps (0 where there is none).
    pub inner: usize,
}

/// Wall-clock seconds, set-up (building, factorizing) apart from solving.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    pub setup: f64,
    pub solve: f64,
}

impl Timing {
    pub fn total(&self) -> f64 {
        self.setup + self.solve
    }
}

/// A solution of the given-friction subproblem with its multipliers per
/// contact node (in contact order, increasing x).
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    /// The unknowns v (displacements, jumps t_i and slips s_i).
    pub v: Vec<f64>,
    /// Contact pressure p_i ≥ 0 per unit length (the paper's l = −σ_n).
    pub pressure: Vec<f64>,
    /// x-component of the contact traction on the lower body per unit length,
    /// q_i with |q_i| ≤ g_i, opposing the slip where the contact slips.
    pub friction_traction: Vec<f64>,
    pub status: Status,
    /// A sentence on why the solver stopped, for logs and output files.
    pub detail: String,
    pub iterations: Iterations,
    pub timing: Timing,
    /// Numbers a solver can tell about its answer beyond the above (e.g.
    /// the condition number of its final Newton matrix), by name.
    pub diagnostics: Vec<(&'static str, f64)>,
}

impl Solution {
    /// A solution with no usable iterate (the solver could not start).
    pub fn failed(n: usize, contacts: usize, status: Status, detail: impl Into<String>) -> Self {
        Self {
            v: vec![0.0; n],
            pressure: vec![0.0; contacts],
            friction_traction: vec![0.0; contacts],
            status,
            detail: detail.into(),
            iterations: Iterations::default(),
            timing: Timing::default(),
            diagnostics: Vec::new(),
        }
    }

    /// The checks a solve starts with: the law of `friction` is one of the
    /// solver's `laws`, its bound fits the problem, and the solver's
    /// settings passed validation (`valid`). The refusal, with status
    /// [`Status::NotRun`], if not.
    pub fn refusal(
        problem: &ContactProblem,
        laws: &[Law],
        friction: Friction<'_>,
        valid: Result<(), String>,
    ) -> Option<Self> {
        let (n, m) = (problem.n(), problem.contacts().len());
        let law = friction.law();
        if !laws.contains(&law) {
            let names: Vec<&str> = laws.iter().map(|l| l.as_str()).collect();
            return Some(Self::failed(
                n,
                m,
                Status::NotRun,
                format!(
                    "this solver solves {} only, not {}",
                    names.join(" and "),
                    law.as_str()
                ),
            ));
        }
        friction
            .check(problem)
            .and(valid)
            .err()
            .map(|e| Self::failed(n, m, Status::NotRun, e))
    }

    /// For a solver of the given-friction subproblem alone: the bound g of
    /// `friction`, or the refusal ([`Solution::refusal`]).
    pub fn given_bound<'a>(
        problem: &ContactProblem,
        friction: Friction<'a>,
        valid: Result<(), String>,
    ) -> Result<&'a [f64], Box<Self>> {
        match (
            Self::refusal(problem, &[Law::GivenFriction], friction, valid),
            friction,
        ) {
            (Some(refused), _) => Err(Box::new(refused)),
            (None, Friction::Given(g)) => Ok(g),
            (None, Friction::Coulomb) => unreachable!("refused above: not the given-friction law"),
        }
    }

    /// True when every number in the solution is finite.
    pub fn is_finite(&self) -> bool {
        self.v
            .iter()
            .chain(&self.pressure)
            .chain(&self.friction_traction)
            .all(|x| x.is_finite())
    }

    /// The solution with status [`Status::NonFinite`] if any of its numbers
    /// is not finite, whatever the solver said: every solver ends through
    /// this one rule, so a NaN never passes as a claim of any kind.
    pub(crate) fn flag_non_finite(mut self) -> Self {
        if !self.is_finite() {
            self.status = Status::NonFinite;
        }
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A NaN anywhere marks the answer non-finite whatever the solver
    /// claimed, converged or not; a finite answer keeps its status.
    #[test]
    fn any_non_finite_number_overrides_the_status() {
        for status in [Status::Converged, Status::MaxIterations, Status::TimeLimit] {
            for field in 0..3 {
                let mut s = Solution::failed(4, 2, status, "");
                match field {
                    0 => s.v[3] = f64::NAN,
                    1 => s.pressure[1] = f64::INFINITY,
                    _ => s.friction_traction[0] = f64::NEG_INFINITY,
                }
                assert_eq!(s.flag_non_finite().status, Status::NonFinite);
            }
            assert_eq!(
                Solution::failed(4, 2, status, "").flag_non_finite().status,
                status
            );
        }
    }
}
