//! Tests of the friction fixed point on affine model steps.

use super::*;
use contactlab_solvers::{ContactNode, STOPPED_AT_NEED, Silent, Timing};
use nalgebra_sparse::CsrMatrix;

/// A step whose pressure is an affine function of g: p = p0 + k g, so the
/// fixed point g = 𝓕 p contracts with factor 𝓕 k (𝓕 = ½ at every node).
struct Affine {
    p0: Vec<f64>,
    k: f64,
    problem: ContactProblem,
}

fn affine(p0: Vec<f64>, k: f64) -> Affine {
    let m = p0.len();
    let contacts = (0..m)
        .map(|i| ContactNode {
            t: 2 * i,
            s: 2 * i + 1,
            weight: 1.0,
            coefficient: 0.5,
        })
        .collect();
    let problem = ContactProblem::new(
        CsrMatrix::identity(2 * m),
        vec![1.0; 2 * m],
        CsrMatrix::identity(2 * m),
        contacts,
        vec![],
    )
    .unwrap();
    Affine { p0, k, problem }
}

impl GivenFrictionStep for Affine {
    fn problem(&self) -> &ContactProblem {
        &self.problem
    }

    fn solve_step(&mut self, g: &[f64], _: Option<f64>, _: &mut dyn Observer) -> Solution {
        Solution {
            v: vec![],
            pressure: self.p0.iter().zip(g).map(|(p, g)| p + self.k * g).collect(),
            friction_traction: vec![0.0; g.len()],
            status: Status::Converged,
            detail: String::new(),
            iterations: Iterations { outer: 1, inner: 0 },
            timing: Timing::default(),
            diagnostics: Vec::new(),
        }
    }
}

/// The paper's absolute stop at ε = 1e-9, with room for 200 iterations.
fn tight() -> CoulombSettings {
    CoulombSettings {
        epsilon: 1e-9,
        max_iterations: 200,
        ..CoulombSettings::defaults(Stopping::Paper)
    }
}

#[test]
fn contracting_map_converges_with_the_expected_factor() {
    let mut step = affine(vec![10.0, 20.0], 0.8);
    let s = tight();
    let out = friction_fixed_point(&mut step, &s, &mut Silent);
    assert_eq!(out.ending, Ending::Converged);
    assert_eq!(out.status, Status::Converged);
    // Fixed point g = 𝓕 (p0 + k g) ⇒ g = 𝓕 p0 / (1 − 𝓕 k).
    for (g, p0) in out.g.iter().zip([10.0, 20.0]) {
        assert!((g - 0.5 * p0 / (1.0 - 0.4)).abs() < 1e-8);
    }
    for h in &out.history[1..] {
        assert!((h.contraction.unwrap() - 0.4).abs() < 1e-6, "{h:?}");
    }
}

/// A step that, asked for a loose accuracy, returns its last pressure
/// unchanged (as a warm-started solver may, its first iteration already
/// within the need; the revisit schedule did, from the same coarse
/// start): the change of g it shows is zero and proves nothing. The
/// fixed point must go on to the true g = 𝓕 p0 / (1 − 𝓕 k), not stop
/// at the stale one.
struct Stale {
    exact: Affine,
    last: Option<Vec<f64>>,
}

impl GivenFrictionStep for Stale {
    fn problem(&self) -> &ContactProblem {
        &self.exact.problem
    }

    fn solve_step(&mut self, g: &[f64], accuracy: Option<f64>, o: &mut dyn Observer) -> Solution {
        let mut s = self.exact.solve_step(g, None, o);
        if let (Some(last), Some(a)) = (&self.last, accuracy)
            && a > 1e-3
        {
            s.pressure.clone_from(last);
            s.diagnostics.push((STOPPED_AT_NEED, a));
        }
        self.last = Some(s.pressure.clone());
        s
    }
}

#[test]
fn a_loose_step_showing_no_change_does_not_end_the_fixed_point() {
    let mut step = Stale {
        exact: affine(vec![10.0, 20.0], 0.8),
        last: None,
    };
    let s = CoulombSettings {
        forcing: 0.1,
        ..tight()
    };
    let out = friction_fixed_point(&mut step, &s, &mut Silent);
    assert_eq!(out.ending, Ending::Converged, "{}", out.detail);
    for (g, p0) in out.g.iter().zip([10.0, 20.0]) {
        assert!(
            (g - 0.5 * p0 / (1.0 - 0.4)).abs() < 1e-8,
            "g = {g}: {}",
            out.detail
        );
    }
}

#[test]
fn expanding_map_stops_at_the_cap_with_that_status() {
    let mut step = affine(vec![1.0], 3.0);
    let exact = CoulombSettings {
        epsilon: 1e-4,
        forcing: 0.0,
        ..CoulombSettings::defaults(Stopping::Paper)
    };
    let s = CoulombSettings {
        max_iterations: 7,
        stall_window: 0,
        ..exact.clone()
    };
    let out = friction_fixed_point(&mut step, &s, &mut Silent);
    assert_eq!(out.status, Status::MaxIterations);
    assert_eq!(out.ending, Ending::IterationCap);
    assert_eq!(out.history.len(), 7);
    assert!(out.history.last().unwrap().contraction.unwrap() > 1.0);
    // With stall detection it stops as soon as W steps bring no decrease.
    let s = CoulombSettings {
        max_iterations: 50,
        stall_window: 3,
        ..exact
    };
    let out = friction_fixed_point(&mut step, &s, &mut Silent);
    assert_eq!(out.status, Status::InsufficientProgress);
    assert_eq!(out.ending, Ending::NotContracting);
    assert_eq!(out.history.len(), 4, "{}", out.detail);
}

/// The affine step that records what the fixed point hands back.
struct Keeping {
    exact: Affine,
    returned: Vec<Vec<f64>>,
    kept: Vec<Vec<f64>>,
}

impl GivenFrictionStep for Keeping {
    fn problem(&self) -> &ContactProblem {
        &self.exact.problem
    }

    fn solve_step(&mut self, g: &[f64], a: Option<f64>, o: &mut dyn Observer) -> Solution {
        let s = self.exact.solve_step(g, a, o);
        self.returned.push(s.pressure.clone());
        s
    }

    fn keep(&mut self, solution: Solution) {
        self.kept.push(solution.pressure);
    }
}

/// Every solution but the last comes back to the step, in order, as the
/// next step's start (the warm start holds it instead of a copy); the last
/// one is the answer.
#[test]
fn each_solution_but_the_answer_is_handed_back_to_the_step() {
    let mut step = Keeping {
        exact: affine(vec![10.0, 20.0], 0.8),
        returned: Vec::new(),
        kept: Vec::new(),
    };
    let s = tight();
    let out = friction_fixed_point(&mut step, &s, &mut Silent);
    assert_eq!(out.ending, Ending::Converged);
    let n = step.returned.len();
    assert!(n > 2, "{n} steps");
    assert_eq!(step.kept, step.returned[..n - 1]);
    assert_eq!(out.solution.pressure, step.returned[n - 1]);
}

/// An affine step whose answers carry noise of alternating sign (an
/// interior point stopped at its tolerance), which tightening divides by
/// ten, at most `tightenings` times.
struct Noisy {
    affine: Affine,
    noise: std::rc::Rc<std::cell::Cell<f64>>,
    calls: usize,
    tightenings: usize,
}

impl GivenFrictionStep for Noisy {
    fn problem(&self) -> &ContactProblem {
        &self.affine.problem
    }

    fn solve_step(&mut self, g: &[f64], a: Option<f64>, o: &mut dyn Observer) -> Solution {
        self.calls += 1;
        let sign = if self.calls.is_multiple_of(2) {
            1.0
        } else {
            -1.0
        };
        let mut s = self.affine.solve_step(g, a, o);
        for p in &mut s.pressure {
            *p += sign * self.noise.get();
        }
        s
    }

    fn tighten(&mut self) -> Option<String> {
        (self.tightenings > 0).then(|| {
            self.tightenings -= 1;
            self.noise.set(self.noise.get() / 10.0);
            format!("noise {:.0e}", self.noise.get())
        })
    }
}

/// A fixed point stalled at the noise of its solves tightens the solver
/// and goes on to converge, saying so; a solver that cannot tighten ends
/// it as not contracting, as before.
#[test]
fn a_stall_at_the_solves_noise_tightens_the_solver() {
    let noisy = |tightenings| Noisy {
        affine: affine(vec![10.0, 20.0], 0.8),
        noise: std::rc::Rc::new(std::cell::Cell::new(1e-7)),
        calls: 0,
        tightenings,
    };
    let mut step = noisy(3);
    let out = friction_fixed_point(&mut step, &tight(), &mut Silent);
    assert_eq!(out.ending, Ending::Converged, "{}", out.detail);
    // Noise 1e-7 stalls above ε = 1e-9; after one tightening it no
    // longer does, and the fixed point stops tightening.
    assert_eq!(step.tightenings, 2, "{}", out.detail);
    assert!(
        out.detail
            .ends_with("(the solver tightened: noise 1e-8 at step 26, the fixed point stalled)"),
        "{}",
        out.detail
    );
    let mut stuck = noisy(0);
    let out = friction_fixed_point(&mut stuck, &tight(), &mut Silent);
    assert_eq!(out.ending, Ending::NotContracting, "{}", out.detail);
}

/// A converged fixed point whose answer the harness rejects tightens the
/// solver and goes on; without `accept` it ends at its tolerance.
#[test]
fn a_rejected_answer_tightens_the_solver_and_the_fixed_point_goes_on() {
    let noisy = || Noisy {
        affine: affine(vec![10.0, 20.0], 0.8),
        noise: std::rc::Rc::new(std::cell::Cell::new(1e-10)),
        calls: 0,
        tightenings: 3,
    };
    // The harness accepts only answers with noise below 1e-11 (what a
    // certificate would see, here read from the step).
    let mut step = noisy();
    let noise = step.noise.clone();
    let out = friction_fixed_point_accepting(&mut step, &tight(), &mut Silent, &|_, _| {
        noise.get() < 0.5e-11
    });
    assert_eq!(out.ending, Ending::Converged, "{}", out.detail);
    assert_eq!(step.tightenings, 1, "{}", out.detail);
    assert!(out.detail.contains("noise 1e-11 at step"), "{}", out.detail);
    assert!(
        out.detail.contains("then noise 1e-12 at step"),
        "{}",
        out.detail
    );
    let mut plain = noisy();
    let out = friction_fixed_point(&mut plain, &tight(), &mut Silent);
    assert_eq!(out.ending, Ending::Converged);
    assert_eq!(plain.tightenings, 3, "{}", out.detail);
}
