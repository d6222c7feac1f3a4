//! Gauss-Seidel sweeps: the paper's pointwise relaxation with exact local
//! minimizers of the nonsmooth energy (the TNNMG smoother), and the linear
//! symmetric Gauss-Seidel of the V-cycle.
//!
//! Along coordinate k the energy J(v) = ½ vᵀAv − fᵀv + Σ w_i g_i |s_i|
//! (t_i ≤ 0) is ½A_kk x² − c x + φ_k(x), c = f_k − Σ_{j≠k} A_kj v_j, whose
//! exact minimizer is c/A_kk for an unknown without a contact law, the
//! projection min(0, c/A_kk) for a jump t_i (paper (12)'s projection), and
//! the soft thresholding sign(c) max(|c| − w_i g_i, 0)/A_kk for a slip s_i
//! (no smoothing of |s|: Gräser & Sander 2019, section 5.1, Example 5.3).

use nalgebra_sparse::CsrMatrix;

/// The contact law along one coordinate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Local {
    /// No contact law: the energy is quadratic along it.
    Free,
    /// A jump t_i: the constraint t_i ≤ 0.
    Jump,
    /// A slip s_i with its nodal friction bound w_i g_i.
    Slip(f64),
}

/// The position of row k's diagonal entry among A's stored entries, if it
/// is stored and above `floor`.
pub(crate) fn diagonal_position(a: &CsrMatrix<f64>, k: usize, floor: f64) -> Option<usize> {
    let offsets = a.row_offsets();
    (offsets[k]..offsets[k + 1])
        .find(|&p| a.col_indices()[p] == k)
        .filter(|&p| a.values()[p] > floor)
}

/// The position of each row's diagonal entry among A's stored entries.
pub(crate) fn diagonal_positions(a: &CsrMatrix<f64>) -> Result<Vec<usize>, String> {
    (0..a.nrows())
        .map(|k| {
            diagonal_position(a, k, 0.0)
                .ok_or_else(|| format!("row {k} has no positive diagonal entry"))
        })
        .collect()
}

/// c_k = b_k − Σ_{j≠k} A_kj x_j.
#[inline]
fn off_diagonal_rhs(a: &CsrMatrix<f64>, k: usize, diag: usize, b: f64, x: &[f64]) -> f64 {
    let (offsets, cols, vals) = (a.row_offsets(), a.col_indices(), a.values());
    let mut sum = 0.0;
    for p in offsets[k]..offsets[k + 1] {
        sum += vals[p] * x[cols[p]];
    }
    b - (sum - vals[diag] * x[k])
}

/// The exact minimizer of ½ a x² − c x + φ(x).
#[inline]
pub(crate) fn local_minimizer(law: Local, a: f64, c: f64) -> f64 {
    match law {
        Local::Free => c / a,
        Local::Jump => (c / a).min(0.0),
        Local::Slip(bound) => c.signum() * (c.abs() - bound).max(0.0) / a,
    }
}

/// One forward sweep of the nonlinear Gauss-Seidel on J (see the module).
pub(crate) fn nonlinear_sweep(
    a: &CsrMatrix<f64>,
    diag: &[usize],
    f: &[f64],
    laws: &[Local],
    v: &mut [f64],
) {
    let vals = a.values();
    for k in 0..v.len() {
        let c = off_diagonal_rhs(a, k, diag[k], f[k], v);
        v[k] = local_minimizer(laws[k], vals[diag[k]], c);
    }
}

/// Forward (`forward`) or backward linear Gauss-Seidel on A x = b, keeping
/// x_k = 0 where `fixed` says so (the truncated coordinates).
pub(crate) fn linear_sweep(
    a: &CsrMatrix<f64>,
    diag: &[usize],
    b: &[f64],
    x: &mut [f64],
    fixed: &[bool],
    forward: bool,
) {
    let vals = a.values();
    let n = x.len();
    for step in 0..n {
        let k = if forward { step } else { n - 1 - step };
        if fixed[k] {
            continue;
        }
        let c = off_diagonal_rhs(a, k, diag[k], b[k], x);
        x[k] = c / vals[diag[k]];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each local minimizer is the minimum of its 1-D energy: no sampled
    /// admissible point is lower.
    #[test]
    fn local_minimizers_are_exact() {
        for law in [Local::Free, Local::Jump, Local::Slip(0.7)] {
            for c in [-2.0, -0.3, 0.0, 0.5, 3.0] {
                let a = 1.7;
                let energy = |x: f64| {
                    0.5 * a * x * x - c * x
                        + match law {
                            Local::Slip(b) => b * x.abs(),
                            _ => 0.0,
                        }
                };
                let x = local_minimizer(law, a, c);
                assert!(law != Local::Jump || x <= 0.0);
                for i in -400..=400 {
                    let y = i as f64 * 0.01;
                    if law == Local::Jump && y > 0.0 {
                        continue;
                    }
                    assert!(
                        energy(x) <= energy(y) + 1e-12,
                        "{law:?} c = {c}: {x} vs {y}"
                    );
                }
            }
        }
    }
}
