//! The reduced Newton system against the whole Jacobian.

use super::*;
use faer::linalg::solvers::Solve;

/// A symmetric positive definite S, a load and a state with every kind of
/// node: open, closed and sticking, closed and slipping (λ > 0 so the
/// ∂Φ_F/∂λ coupling is present).
fn state(m: usize) -> (Mat<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut random = crate::numerics::random::Lcg::new(7);
    let mut rand = move || random.symmetric();
    let b = Mat::from_fn(2 * m, 2 * m, |_, _| rand());
    let mut s = b.transpose() * &b;
    for k in 0..2 * m {
        s[(k, k)] += 2.0 * m as f64;
    }
    let load: Vec<f64> = (0..2 * m).map(|_| rand()).collect();
    let coefficient: Vec<f64> = (0..m).map(|i| 0.3 + 0.1 * i as f64).collect();
    let mut x: Vec<f64> = (0..4 * m).map(|_| rand()).collect();
    x[2 * m] = -0.5; // an open node (λ < 0)
    x[2 * m + 1] = 2.0; // λ > 0: the bound 𝓕λ is active in Φ_F
    (s, load, coefficient, x)
}

#[test]
fn reduced_direction_and_gradient_equal_the_whole_jacobians() {
    let m = 5;
    let (s, load, coefficient, x) = state(m);
    let sys = System {
        s: &s,
        b: &load,
        coefficient: &coefficient,
        kappa: 1.7,
    };
    let phi = sys.residual(&x);
    let j = sys.jacobian(&x);
    let n = 4 * m;
    let whole = j.partial_piv_lu().solve(Mat::from_fn(n, 1, |r, _| -phi[r]));
    let grad: Vec<f64> = (0..n)
        .map(|c| (0..n).map(|r| j[(r, c)] * phi[r]).sum())
        .collect();
    let (dir, reduced_grad) = sys.direction(&x, &phi);
    let dir = dir.expect("a finite direction");
    let scale = (0..n).fold(0.0f64, |a, r| a.max(whole[(r, 0)].abs()));
    for r in 0..n {
        assert!(
            (dir[r] - whole[(r, 0)]).abs() <= 1e-10 * scale,
            "direction {r}: {} vs {}",
            dir[r],
            whole[(r, 0)]
        );
        assert!(
            (reduced_grad[r] - grad[r]).abs() <= 1e-12 * (1.0 + grad[r].abs()),
            "gradient {r}: {} vs {}",
            reduced_grad[r],
            grad[r]
        );
    }
    // The coupling ∂Φ_F/∂λ is in the test: node 1 has λ > 0 and 𝓕 > 0.
    assert!(j[(3 * m + 1, 2 * m + 1)] != 0.0);
}
