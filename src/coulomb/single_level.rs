//! The given-friction step on one mesh: one solver, warm-started from the
//! previous step's answer, which the fixed point hands back.

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
        let start = match (&self.last, &self.first) {
            (Some(s), _) => Some((&s.v[..], &s.pressure[..])),
            (None, Some((v, p))) => Some((&v[..], &p[..])),
            (None, None) => None,
        }
        .map(|(v, pressure)| Start {
            v,
            pressure,
            accuracy,
        });
        let solution = self
            .solver
            .solve(self.problem, Friction::Given(g), start, observer);
        // Used: the fixed point hands the new one back ([`keep`]).
        self.last = None;
        solution
    }

    fn keep(&mut self, solution: Solution) {
        self.last = Some(solution);
    }

    fn tighten(&mut self) -> Option<String> {
        self.solver.tighten()
    }
}
