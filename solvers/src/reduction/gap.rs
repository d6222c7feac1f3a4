//! How every solver meets an initial gap: in the unknowns ṽ = v − D the
//! gap is closed ([`ContactProblem::closed_gap`]), so each solver solves
//! the problem it was written for (t̃ ≤ 0) and its answer is moved back,
//! v = ṽ + D. The pressures and frictional tractions are the same in both
//! unknowns. The harness wraps every registered solver in [`ClosingGap`]
//! ([`crate::entry::Build::call`]); the certificate checks the answer
//! against the problem with its gap (t ≤ d), not against the closed one.

use std::borrow::Cow;

use crate::observer::Observer;
use crate::problem::ContactProblem;
use crate::solution::Solution;
use crate::solver::{Friction, Solver, Start};

/// A solver that meets a problem with a gap in the closed unknowns.
pub struct ClosingGap {
    inner: Box<dyn Solver>,
    /// The closed problem of the last problem with a gap, by its operator
    /// id: the fixed point's steps solve one problem many times.
    closed: Option<(u64, ContactProblem)>,
}

impl ClosingGap {
    pub fn new(inner: Box<dyn Solver>) -> Self {
        Self {
            inner,
            closed: None,
        }
    }
}

impl Solver for ClosingGap {
    fn solve(
        &mut self,
        problem: &ContactProblem,
        friction: Friction<'_>,
        start: Option<Start<'_>>,
        observer: &mut dyn Observer,
    ) -> Solution {
        if !problem.has_gap() || self.inner.poses_gaps() {
            return self.inner.solve(problem, friction, start, observer);
        }
        let id = problem.operator_id();
        if self.closed.as_ref().is_none_or(|(k, _)| *k != id) {
            self.closed = Some((id, problem.closed_gap()));
        }
        let closed = &self.closed.as_ref().expect("set above").1;
        let start = start.map(|s| {
            let mut v = s.v.into_owned();
            shift(problem, &mut v, -1.0);
            Start {
                v: Cow::Owned(v),
                pressure: s.pressure,
                accuracy: s.accuracy,
            }
        });
        let mut solution = self.inner.solve(closed, friction, start, observer);
        if solution.v.len() == problem.n() {
            shift(problem, &mut solution.v, 1.0);
        }
        solution
    }

    fn release(&mut self) {
        self.closed = None;
        self.inner.release();
    }

    fn tighten(&mut self) -> Option<String> {
        self.inner.tighten()
    }

    fn poses_gaps(&self) -> bool {
        true
    }
}

/// v ± D: the gap added to (sign 1) or taken from (sign −1) each jump.
fn shift(problem: &ContactProblem, v: &mut [f64], sign: f64) {
    if v.len() != problem.n() {
        return;
    }
    for (c, d) in problem.contacts().iter().zip(problem.gap()) {
        v[c.t] += sign * d;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::observer::Silent;
    use crate::solution::{Iterations, Status, Timing};
    use nalgebra_sparse::{CooMatrix, CsrMatrix};

    /// A solver of one spring, 2·t = f̃ projected on t ≤ 0, that records
    /// the problem it was handed: it must see the closed problem (f̃ =
    /// f − A D, no gap), and its answer must come back moved by D.
    struct Spring;
    impl Solver for Spring {
        fn solve(
            &mut self,
            problem: &ContactProblem,
            _: Friction<'_>,
            _: Option<Start<'_>>,
            _: &mut dyn Observer,
        ) -> Solution {
            assert!(!problem.has_gap());
            let t = (problem.f()[0] / 2.0).min(0.0);
            Solution {
                v: vec![t, 0.0],
                pressure: vec![problem.f()[0] - 2.0 * t],
                friction_traction: vec![0.0],
                status: Status::Converged,
                detail: String::new(),
                iterations: Iterations::default(),
                timing: Timing::default(),
                diagnostics: Vec::new(),
            }
        }
    }

    /// ½·2t² − f t subject to t ≤ d: t = min(f/2, d), p = f − 2t. With
    /// f = 4 and d = 0.5 the bodies touch (t = d, p = 3); with d = 5 they
    /// do not (t = 2, p = 0).
    #[test]
    fn a_gap_is_met_in_the_closed_unknowns_and_moved_back() {
        let mut coo = CooMatrix::new(2, 2);
        coo.push(0, 0, 2.0);
        coo.push(1, 1, 1.0);
        let a = CsrMatrix::from(&coo);
        let contact = crate::problem::ContactNode {
            t: 0,
            s: 1,
            weight: 1.0,
            coefficient: 0.0,
        };
        let problem = ContactProblem::new(
            a,
            vec![4.0, 0.0],
            crate::problem::Mass::Omitted,
            vec![contact],
            vec![],
        )
        .unwrap();
        let mut solver = ClosingGap::new(Box::new(Spring));
        for (d, t, p) in [(0.5, 0.5, 3.0), (5.0, 2.0, 0.0), (0.0, 0.0, 4.0)] {
            let gapped = problem.clone().with_gap(vec![d]).unwrap();
            assert_eq!(gapped.scales(), problem.scales(), "the gap moves no scale");
            let s = solver.solve(&gapped, Friction::Given(&[0.0]), None, &mut Silent);
            assert_eq!((s.v[0], s.pressure[0]), (t, p), "d = {d}");
        }
        assert!(problem.clone().with_gap(vec![-1.0]).is_err());
        assert!(problem.clone().with_gap(vec![f64::NAN]).is_err());
        assert!(problem.clone().with_gap(vec![1.0, 2.0]).is_err());
    }
}
