//! The given-friction step on one mesh: one solver, warm-started from the
//! previous step's answer, which the fixed point hands back.

use std::borrow::Cow;

use contactlab_solvers::{ContactProblem, Friction, Observer, Solution, Solver, Start};

use super::fixed_point::GivenFrictionStep;

/// The given-friction step on one mesh with one solver, warm-started from the
/// previous step where the solver can use it.
pub struct SingleLevel<'a> {
    pub problem: &'a ContactProblem,
    pub solver: &'a mut dyn Solver,
    last: Option<Solution>,
    /// The start of the first step (displacements, pressures), if any.
    first: Option<(Vec<f64>, Vec<f64>)>,
}

impl<'a> SingleLevel<'a> {
    pub fn new(problem: &'a ContactProblem, solver: &'a mut dyn Solver) -> Self {
        Self::starting(problem, solver, None)
    }

    /// Its first step started from `first` (displacements, pressures).
    pub fn starting(
        problem: &'a ContactProblem,
        solver: &'a mut dyn Solver,
        first: Option<(Vec<f64>, Vec<f64>)>,
    ) -> Self {
        Self {
            problem,
            solver,
            last: None,
            first,
        }
    }
}

impl GivenFrictionStep for SingleLevel<'_> {
    fn problem(&self) -> &ContactProblem {
        self.problem
    }

    fn solve_step(
        &mut self,
        g: &[f64],
        accuracy: Option<f64>,
        observer: &mut dyn Observer,
    ) -> Solution {
        // The start is handed over, not lent: the fixed point hands the new
        // answer back ([`keep`]) before the next step, so the solver may
        // iterate on these unknowns themselves.
        let (v, pressure) = match self.last.take() {
            Some(s) => (Some(s.v), s.pressure),
            None => match self.first.take() {
                Some((v, p)) => (Some(v), p),
                None => (None, Vec::new()),
            },
        };
        let start = v.map(|v| Start {
            v: Cow::Owned(v),
            pressure: &pressure,
            accuracy,
        });
        self.solver
            .solve(self.problem, Friction::Given(g), start, observer)
    }

    fn keep(&mut self, solution: Solution) {
        self.last = Some(solution);
    }

    fn tighten(&mut self) -> Option<String> {
        self.solver.tighten()
    }
}
