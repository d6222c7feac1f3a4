//! Coulomb friction by successive approximations (MPP), paper (9):
//! g⁰ = 0, solve the given-friction problem with g^m, set g^{m+1} = 𝓕 p(u^m),
//! stop when max_i |g^{m+1}_i − g^m_i| ≤ ε. Whether this converges in theory
//! is an open question (the paper says so), so every step is recorded.

use std::time::Instant;

use contactlab_solvers::{
    GivenFrictionProblem, GivenFrictionSolver, Iterations, Observer, Progress, Solution, Stage,
    Start, Status,
};
use serde::{Deserialize, Serialize};

/// Settings of the fixed point; defaults are the paper's (ε = 1e-4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CoulombSettings {
    /// Stop when max_i |g^{m+1}_i − g^m_i| ≤ epsilon.
    pub epsilon: f64,
    /// Cap on given-friction solves.
    pub max_iterations: usize,
    /// Stop as not contracting when max|Δg| has not fallen over this many
    /// iterations (0: never).
    pub stall_window: usize,
}

impl Default for CoulombSettings {
    fn default() -> Self {
        Self {
            epsilon: 1e-4,
            max_iterations: 50,
            stall_window: 5,
        }
    }
}

impl CoulombSettings {
    pub fn validate(&self) -> Result<(), String> {
        if !(self.epsilon.is_finite() && self.epsilon > 0.0) {
            return Err(format!(
                "coulomb.epsilon = {} is invalid: the friction tolerance must be a positive number (the paper: 1e-4)",
                self.epsilon
            ));
        }
        if self.max_iterations == 0 {
            return Err("coulomb.max_iterations = 0 is invalid: allow at least 1 friction iteration (default 50)".into());
        }
        Ok(())
    }
}

/// One way of solving the given-friction subproblem for a bound g on the
/// finest level's contact nodes (one level, or mesh continuation).
pub trait GivenFrictionStep {
    /// Number of contact nodes of the finest level.
    fn contacts(&self) -> usize;
    /// Solves with friction bound `g`.
    fn solve_step(&mut self, g: &[f64], observer: &mut dyn Observer) -> Solution;
}

/// One step of the fixed point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrictionIteration {
    /// 1-based.
    pub iteration: usize,
    /// max_i |g^{m+1}_i − g^m_i| after this step.
    pub change: f64,
    /// change / previous change (the observed contraction factor).
    pub contraction: Option<f64>,
    pub status: Status,
    pub iterations: Iterations,
    /// Wall-clock seconds of this step, and the part the solver spent setting up.
    pub seconds: f64,
    pub setup_seconds: f64,
}

/// The outcome of the fixed point.
#[derive(Clone, Debug)]
pub struct CoulombSolution {
    /// The last given-friction solution (for the bound `g`).
    pub solution: Solution,
    /// The bound the last solution was computed with.
    pub g: Vec<f64>,
    pub history: Vec<FrictionIteration>,
    pub status: Status,
    pub detail: String,
    pub seconds: f64,
}

impl CoulombSolution {
    /// Inner iterations summed over all friction steps.
    pub fn total_iterations(&self) -> Iterations {
        self.history
            .iter()
            .fold(Iterations::default(), |a, h| Iterations {
                outer: a.outer + h.iterations.outer,
                inner: a.inner + h.iterations.inner,
            })
    }
}

/// Successive approximations (9) with friction coefficient `coefficient`.
pub fn friction_fixed_point(
    step: &mut dyn GivenFrictionStep,
    coefficient: f64,
    settings: &CoulombSettings,
    observer: &mut dyn Observer,
) -> CoulombSolution {
    let start = Instant::now();
    let mut g = vec![0.0; step.contacts()];
    let mut history: Vec<FrictionIteration> = Vec::new();
    let mut last_change: Option<f64> = None;
    for m in 1..=settings.max_iterations {
        let t = Instant::now();
        let solution = step.solve_step(&g, observer);
        let g_next: Vec<f64> = solution
            .pressure
            .iter()
            .map(|p| coefficient * p.max(0.0))
            .collect();
        let change = g_next
            .iter()
            .zip(&g)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f64, |c, d| if d.is_nan() { f64::NAN } else { c.max(d) });
        history.push(FrictionIteration {
            iteration: m,
            change,
            contraction: last_change.filter(|c| *c > 0.0).map(|c| change / c),
            status: solution.status,
            iterations: solution.iterations,
            seconds: t.elapsed().as_secs_f64(),
            setup_seconds: solution.timing.setup,
        });
        observer.observe(&Progress {
            stage: Stage::Friction,
            iteration: m,
            residual: change,
            seconds: start.elapsed().as_secs_f64(),
        });
        let finish =
            |status, detail: String, solution: Solution, g: Vec<f64>, history| CoulombSolution {
                solution,
                g,
                history,
                status,
                detail,
                seconds: start.elapsed().as_secs_f64(),
            };
        if !solution.status.is_converged() {
            let detail = format!(
                "given-friction step {m} did not converge: {}",
                solution.detail
            );
            return finish(solution.status, detail, solution, g, history);
        }
        if !change.is_finite() {
            let detail = format!("friction step {m}: the new friction bound is not finite");
            return finish(Status::NonFinite, detail, solution, g, history);
        }
        if change <= settings.epsilon {
            let detail = format!(
                "max|Δg| = {change:.3e} ≤ ε = {:e} after {m} friction iterations",
                settings.epsilon
            );
            return finish(Status::Converged, detail, solution, g, history);
        }
        let w = settings.stall_window;
        if w > 0 && m > w && change >= history[m - 1 - w].change {
            let detail = format!(
                "the fixed point is not contracting: max|Δg| went from {:.3e} to {change:.3e} over the last {w} friction iterations",
                history[m - 1 - w].change
            );
            return finish(Status::InsufficientProgress, detail, solution, g, history);
        }
        if m == settings.max_iterations {
            let detail = format!(
                "friction iteration cap {m} reached with max|Δg| = {change:.3e} > ε = {:e}",
                settings.epsilon
            );
            return finish(Status::MaxIterations, detail, solution, g, history);
        }
        g = g_next;
        last_change = Some(change);
    }
    unreachable!("max_iterations ≥ 1 is validated")
}

/// The given-friction step on one mesh with one solver, warm-started from the
/// previous step where the solver can use it.
pub struct SingleLevel<'a> {
    pub problem: GivenFrictionProblem,
    pub solver: &'a mut dyn GivenFrictionSolver,
    last: Option<Solution>,
}

impl<'a> SingleLevel<'a> {
    pub fn new(problem: GivenFrictionProblem, solver: &'a mut dyn GivenFrictionSolver) -> Self {
        Self {
            problem,
            solver,
            last: None,
        }
    }
}

impl GivenFrictionStep for SingleLevel<'_> {
    fn contacts(&self) -> usize {
        self.problem.contacts().len()
    }

    fn solve_step(&mut self, g: &[f64], observer: &mut dyn Observer) -> Solution {
        if let Err(e) = self.problem.set_friction_bound(g) {
            return Solution::failed(self.problem.n(), g.len(), Status::NonFinite, e.to_string());
        }
        let start = self.last.as_ref().map(|s| Start {
            v: &s.v,
            pressure: &s.pressure,
        });
        let solution = self.solver.solve(&self.problem, start, observer);
        self.last = Some(solution.clone());
        solution
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use contactlab_solvers::{Silent, Timing};

    /// A step whose pressure is an affine function of g: p = p0 + k g, so the
    /// fixed point g = 𝓕 p contracts with factor 𝓕 k.
    struct Affine {
        p0: Vec<f64>,
        k: f64,
    }

    impl GivenFrictionStep for Affine {
        fn contacts(&self) -> usize {
            self.p0.len()
        }

        fn solve_step(&mut self, g: &[f64], _: &mut dyn Observer) -> Solution {
            Solution {
                v: vec![],
                pressure: self.p0.iter().zip(g).map(|(p, g)| p + self.k * g).collect(),
                friction_traction: vec![0.0; g.len()],
                status: Status::Converged,
                detail: String::new(),
                iterations: Iterations { outer: 1, inner: 0 },
                timing: Timing::default(),
            }
        }
    }

    #[test]
    fn contracting_map_converges_with_the_expected_factor() {
        let mut step = Affine {
            p0: vec![10.0, 20.0],
            k: 0.8,
        };
        let s = CoulombSettings {
            epsilon: 1e-9,
            max_iterations: 200,
            ..Default::default()
        };
        let out = friction_fixed_point(&mut step, 0.5, &s, &mut Silent);
        assert_eq!(out.status, Status::Converged);
        // Fixed point g = 𝓕 (p0 + k g) ⇒ g = 𝓕 p0 / (1 − 𝓕 k).
        for (g, p0) in out.g.iter().zip([10.0, 20.0]) {
            assert!((g - 0.5 * p0 / (1.0 - 0.4)).abs() < 1e-8);
        }
        for h in &out.history[1..] {
            assert!((h.contraction.unwrap() - 0.4).abs() < 1e-6, "{h:?}");
        }
    }

    #[test]
    fn expanding_map_stops_at_the_cap_with_that_status() {
        let mut step = Affine {
            p0: vec![1.0],
            k: 3.0,
        };
        let s = CoulombSettings {
            epsilon: 1e-4,
            max_iterations: 7,
            stall_window: 0,
        };
        let out = friction_fixed_point(&mut step, 0.5, &s, &mut Silent);
        assert_eq!(out.status, Status::MaxIterations);
        assert_eq!(out.history.len(), 7);
        assert!(out.history.last().unwrap().contraction.unwrap() > 1.0);
        // With stall detection it stops as soon as W steps bring no decrease.
        let s = CoulombSettings {
            epsilon: 1e-4,
            max_iterations: 50,
            stall_window: 3,
        };
        let out = friction_fixed_point(&mut step, 0.5, &s, &mut Silent);
        assert_eq!(out.status, Status::InsufficientProgress);
        assert_eq!(out.history.len(), 4, "{}", out.detail);
    }
}
