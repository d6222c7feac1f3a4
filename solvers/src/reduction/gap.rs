//! How every solver meets an initial gap and a slip offset: in the
//! unknowns ṽ = v − D both are closed ([`ContactProblem::closed`]), so each
//! solver solves the problem it was written for (t̃ ≤ 0, friction on s̃)
//! and its answer is moved back, v = ṽ + D. The pressures and frictional
//! tractions are the same in both unknowns. A solver that poses gaps
//! itself ([`Solver::poses_gaps`]) keeps its gap; no solver poses slip
//! offsets. The harness wraps every registered solver in [`ClosingGap`]
//! ([`crate::entry::Build::call`]); the certificate checks the answer
//! against the problem with its gap and offset (t ≤ d, slip s − σ), not
//! against the closed one.

use std::borrow::Cow;

use crate::observer::Observer;
use crate::problem::ContactProblem;
use crate::solution::Solution;
use crate::solver::{Friction, Solver, Start};

/// A solver that meets a problem with a gap or a slip offset in the
/// closed unknowns.
pub struct ClosingGap {
    inner: Box<dyn Solver>,
    /// The closed problem of the last problem with an offset, by its
    /// operator id: the fixed point's steps solve one problem many times.
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
        let (modes, handled) = (
            problem.rigid_modes().len(),
            self.inner.rigid_modes_handled(),
        );
        if modes > handled {
            return Solution::failed(
                problem.n(),
                problem.contacts().len(),
                crate::solution::Status::NotRun,
                format!(
                    "this solver handles {handled} rigid mode (the upper body's vertical translation), and this problem has {modes} (a body free to slide keeps its horizontal translation too): solve it with newton-coulomb or clarabel"
                ),
            );
        }
        let gap = problem.has_gap() && !self.inner.poses_gaps();
        let slip = problem.has_slip_offset() && !self.inner.poses_slip_offsets();
        if !gap && !slip {
            return self.inner.solve(problem, friction, start, observer);
        }
        let id = problem.operator_id();
        if self.closed.as_ref().is_none_or(|(k, _)| *k != id) {
            self.closed = Some((id, problem.closed(gap, slip)));
        }
        let closed = &self.closed.as_ref().expect("set above").1;
        let start = start.map(|s| {
            let mut v = s.v.into_owned();
            shift(problem, (gap, slip), &mut v, -1.0);
            Start {
                v: Cow::Owned(v),
                pressure: s.pressure,
                accuracy: s.accuracy,
            }
        });
        let mut solution = self.inner.solve(closed, friction, start, observer);
        if solution.v.len() == problem.n() {
            shift(problem, (gap, slip), &mut solution.v, 1.0);
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

    fn poses_slip_offsets(&self) -> bool {
        true
    }

    fn rigid_modes_handled(&self) -> usize {
        self.inner.rigid_modes_handled()
    }
}

/// v ± D: the gap (if `gap`) added to (sign 1) or taken from (sign −1)
/// each jump, the slip offset (if `slip`) to or from each slip.
fn shift(problem: &ContactProblem, (gap, slip): (bool, bool), v: &mut [f64], sign: f64) {
    if v.len() != problem.n() {
        return;
    }
    for (i, c) in problem.contacts().iter().enumerate() {
        if gap {
            v[c.t] += sign * problem.gap()[i];
        }
        if slip {
            v[c.s] += sign * problem.slip_offset()[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::observer::Silent;
    use crate::solution::{Iterations, Status, Timing};
    use nalgebra_sparse::{CooMatrix, CsrMatrix};

    /// A solver of two springs, 2·t = f̃ projected on t ≤ 0 and the slip
    /// s = f̃ soft-thresholded by g (½ s² − f̃ s + g|s|), that records the
    /// problem it was handed: it must see the closed problem (f̃ = f − A D,
    /// no gap, no slip offset), and its answer must come back moved by D.
    struct Spring;
    impl Solver for Spring {
        fn solve(
            &mut self,
            problem: &ContactProblem,
            friction: Friction<'_>,
            _: Option<Start<'_>>,
            _: &mut dyn Observer,
        ) -> Solution {
            assert!(!problem.has_gap() && !problem.has_slip_offset());
            let t = (problem.f()[0] / 2.0).min(0.0);
            let g = match friction {
                Friction::Given(g) => g[0],
                Friction::Coulomb => unreachable!("given friction only"),
            };
            let fs = problem.f()[1];
            let s = fs.signum() * (fs.abs() - g).max(0.0);
            Solution {
                v: vec![t, s],
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

    /// The problem [`Spring`] solves: A = diag(2, 1) on (t, s), f = (4, 0),
    /// one contact node.
    fn springs() -> ContactProblem {
        let mut coo = CooMatrix::new(2, 2);
        coo.push(0, 0, 2.0);
        coo.push(1, 1, 1.0);
        let contact = crate::problem::ContactNode {
            t: 0,
            s: 1,
            weight: 1.0,
            coefficient: 0.0,
        };
        ContactProblem::new(
            CsrMatrix::from(&coo),
            vec![4.0, 0.0],
            crate::problem::Mass::Omitted,
            vec![contact],
            vec![],
        )
        .unwrap()
    }

    /// ½·2t² − f t subject to t ≤ d: t = min(f/2, d), p = f − 2t. With
    /// f = 4 and d = 0.5 the bodies touch (t = d, p = 3); with d = 5 they
    /// do not (t = 2, p = 0).
    #[test]
    fn a_gap_is_met_in_the_closed_unknowns_and_moved_back() {
        let problem = springs();
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

    /// ½ s² − f s + g|s − σ|: the slip sticks at σ while |f − σ| ≤ g and
    /// is f ± g short of it otherwise. With f = 0 and g = 1, an offset
    /// σ = 3 pulls the slip to 1 (slipping), σ = 0.5 holds it at 0.5
    /// (sticking).
    #[test]
    fn a_slip_offset_is_met_in_the_closed_unknowns_and_moved_back() {
        let problem = springs();
        let mut solver = ClosingGap::new(Box::new(Spring));
        for (sigma, slip) in [(3.0, 1.0), (0.5, 0.5), (-3.0, -1.0), (0.0, 0.0)] {
            let offset = problem.clone().with_slip_offset(vec![sigma]).unwrap();
            assert_eq!(
                offset.scales(),
                problem.scales(),
                "the offset moves no scale"
            );
            let s = solver.solve(&offset, Friction::Given(&[1.0]), None, &mut Silent);
            assert_eq!((s.v[0], s.v[1]), (0.0, slip), "σ = {sigma}");
            assert_eq!(offset.slip(&s.v, 0), slip - sigma);
            // The objective sees the slip past the offset: at the answer,
            // ½ s² + |s − σ| (the t spring is closed, t = 0).
            let e = 0.5 * slip * slip + (slip - sigma).abs();
            assert_eq!(offset.objective(&s.v, &[1.0]), e);
        }
        // Both offsets at once, the gap on t and σ on s.
        let both = problem
            .clone()
            .with_gap(vec![0.5])
            .and_then(|p| p.with_slip_offset(vec![3.0]))
            .unwrap();
        let s = solver.solve(&both, Friction::Given(&[1.0]), None, &mut Silent);
        assert_eq!((s.v[0], s.v[1], s.pressure[0]), (0.5, 1.0, 3.0));
        assert!(problem.clone().with_slip_offset(vec![f64::NAN]).is_err());
        assert!(problem.clone().with_slip_offset(vec![1.0, 2.0]).is_err());
        assert!(problem.clone().with_slip_offset(vec![1e300]).is_err());
    }
}
