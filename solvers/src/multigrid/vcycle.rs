//! The linear multigrid step of TNNMG: one V-cycle with symmetric
//! Gauss-Seidel on the truncated Galerkin hierarchy (Gräser & Sander 2019,
//! section 4.2; Kornhuber 1994 for truncated bases in contact).
//!
//! The coordinates at a kink of the nonsmooth energy (closed contact
//! t_i = 0, stick s_i = 0) are truncated: the correction keeps them at
//! zero, so the fine-level operator is A restricted to the others, and the
//! prolongation onto the finest level is P with those rows removed,
//! P_T = T P. The coarse operators are Galerkin products, A_{L−1} = P_Tᵀ A
//! P_T and A_l = P_lᵀ A_{l+1} P_l below, rebuilt only when the truncated
//! set changes. A coarse unknown whose fine support is truncated entirely
//! has a zero row and is left at zero.

use nalgebra_sparse::CsrMatrix;

use crate::multigrid::smoother::{diagonal_position, linear_sweep};
use crate::numerics::linalg::spmv_into;

/// Eigenvalues below this fraction of the largest are the coarsest
/// operator's kernel (the rigid mode, when no jump is truncated): its
/// solve is the pseudo-inverse's, the least-squares answer of a consistent
/// system.
const KERNEL_FRACTION: f64 = 1e-12;

/// The exact solve on the coarsest level (h = 1/2: at most 17 unknowns,
/// whatever the mesh): the pseudo-inverse of its matrix on the unknowns
/// that are not fixed, from a symmetric eigendecomposition (faer). Gauss-
/// Seidel there left the near-rigid motion of an upper body held at a few
/// closed nodes unresolved, and TNNMG's line search then stretched every
/// correction by 1.5-1.7 at a rate of 0.5 per iteration.
struct CoarsestSolve {
    free: Vec<usize>,
    pinv: faer::Mat<f64>,
}

impl CoarsestSolve {
    fn new(level: &Level) -> Self {
        let free: Vec<usize> = (0..level.a.nrows()).filter(|&k| !level.fixed[k]).collect();
        let mut dense = faer::Mat::<f64>::zeros(free.len(), free.len());
        let mut position = vec![usize::MAX; level.a.nrows()];
        for (i, &k) in free.iter().enumerate() {
            position[k] = i;
        }
        for (row, col, &v) in level.a.triplet_iter() {
            if position[row] != usize::MAX && position[col] != usize::MAX {
                dense[(position[row], position[col])] = v;
            }
        }
        let nf = free.len();
        let pinv = match dense.self_adjoint_eigen(faer::Side::Lower) {
            Ok(evd) => {
                let (u, s) = (evd.U(), evd.S().column_vector());
                let largest = (0..nf).fold(0.0f64, |m, i| m.max(s[i].abs()));
                faer::Mat::from_fn(nf, nf, |i, j| {
                    (0..nf)
                        .filter(|&e| s[e] > KERNEL_FRACTION * largest)
                        .map(|e| u[(i, e)] * u[(j, e)] / s[e])
                        .sum()
                })
            }
            Err(_) => faer::Mat::zeros(nf, nf),
        };
        Self { free, pinv }
    }

    fn solve(&self, b: &[f64], x: &mut [f64]) {
        x.fill(0.0);
        for (i, &k) in self.free.iter().enumerate() {
            x[k] = self
                .free
                .iter()
                .enumerate()
                .map(|(j, &l)| self.pinv[(i, j)] * b[l])
                .sum();
        }
    }
}

/// A coarse level: its Galerkin matrix, the positions of its diagonal
/// entries, and the unknowns left at zero (no positive diagonal).
struct Level {
    a: CsrMatrix<f64>,
    diag: Vec<usize>,
    fixed: Vec<bool>,
}

impl Level {
    fn new(a: CsrMatrix<f64>) -> Self {
        let scale = a.values().iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let found: Vec<Option<usize>> = (0..a.nrows())
            .map(|k| diagonal_position(&a, k, 1e-14 * scale))
            .collect();
        let fixed = found.iter().map(Option::is_none).collect();
        let diag = found.into_iter().map(|p| p.unwrap_or(0)).collect();
        Self { a, diag, fixed }
    }
}

/// P with the rows of the truncated unknowns removed.
fn without_rows(p: &CsrMatrix<f64>, truncated: &[bool]) -> CsrMatrix<f64> {
    let (offsets, cols, vals) = (p.row_offsets(), p.col_indices(), p.values());
    let mut new_offsets = Vec::with_capacity(p.nrows() + 1);
    let (mut new_cols, mut new_vals) = (Vec::new(), Vec::new());
    new_offsets.push(0);
    for (k, &cut) in truncated.iter().enumerate() {
        if !cut {
            new_cols.extend_from_slice(&cols[offsets[k]..offsets[k + 1]]);
            new_vals.extend_from_slice(&vals[offsets[k]..offsets[k + 1]]);
        }
        new_offsets.push(new_cols.len());
    }
    CsrMatrix::try_from_csr_data(p.nrows(), p.ncols(), new_offsets, new_cols, new_vals)
        .expect("rows of a valid matrix")
}

/// The truncated hierarchy for one truncated set, with the V-cycle's
/// vectors (allocated once per set, not per cycle).
pub(crate) struct Hierarchy {
    truncated: Vec<bool>,
    /// P_T and P_Tᵀ onto the finest level.
    prolong_fine: CsrMatrix<f64>,
    restrict_fine: CsrMatrix<f64>,
    /// Levels 0 … L−1, coarse to fine.
    levels: Vec<Level>,
    coarsest: CoarsestSolve,
    x: Vec<Vec<f64>>,
    b: Vec<Vec<f64>>,
    r: Vec<Vec<f64>>,
}

impl Hierarchy {
    /// Builds the truncated Galerkin hierarchy of `a` for the prolongations
    /// `p` (coarse to fine; `restrict[l]` = `p[l]`ᵀ).
    pub(crate) fn new(
        a: &CsrMatrix<f64>,
        p: &[CsrMatrix<f64>],
        restrict: &[CsrMatrix<f64>],
        truncated: Vec<bool>,
    ) -> Self {
        let top = p.len() - 1;
        let prolong_fine = without_rows(&p[top], &truncated);
        let restrict_fine = prolong_fine.transpose();
        let mut coarse = vec![&restrict_fine * &(a * &prolong_fine)];
        for l in (0..top).rev() {
            let above = coarse.last().expect("one at least");
            let next = &restrict[l] * &(above * &p[l]);
            coarse.push(next);
        }
        coarse.reverse();
        let levels: Vec<Level> = coarse.into_iter().map(Level::new).collect();
        let sizes: Vec<usize> = levels
            .iter()
            .map(|l| l.a.nrows())
            .chain([a.nrows()])
            .collect();
        let zeros = || sizes.iter().map(|&n| vec![0.0; n]).collect::<Vec<_>>();
        let coarsest = CoarsestSolve::new(&levels[0]);
        Self {
            coarsest,
            truncated,
            prolong_fine,
            restrict_fine,
            levels,
            x: zeros(),
            b: zeros(),
            r: zeros(),
        }
    }

    /// The truncated set it was built for.
    pub(crate) fn truncated(&self) -> &[bool] {
        &self.truncated
    }

    /// One V-cycle from zero for A_T c = d (d zero on the truncated set),
    /// `sweeps` symmetric Gauss-Seidel sweeps before and after each coarse
    /// correction; the correction is written to `c` (zero on the truncated
    /// set). `a` and `diag` are the finest level's, `p` the untruncated
    /// prolongations below it.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn v_cycle(
        &mut self,
        a: &CsrMatrix<f64>,
        diag: &[usize],
        p: &[CsrMatrix<f64>],
        restrict: &[CsrMatrix<f64>],
        d: &[f64],
        sweeps: usize,
        c: &mut [f64],
    ) {
        let top = self.levels.len();
        self.b[top].copy_from_slice(d);
        // Down: smooth, restrict the residual.
        for l in (1..=top).rev() {
            let (matrix, dg, fixed) = if l == top {
                (a, diag, &self.truncated[..])
            } else {
                let lv = &self.levels[l];
                (&lv.a, &lv.diag[..], &lv.fixed[..])
            };
            let x = &mut self.x[l];
            x.fill(0.0);
            for _ in 0..sweeps {
                linear_sweep(matrix, dg, &self.b[l], x, fixed, true);
            }
            let r = &mut self.r[l];
            spmv_into(matrix, x, r);
            for ((rk, bk), &cut) in r.iter_mut().zip(&self.b[l]).zip(fixed) {
                *rk = if cut { 0.0 } else { bk - *rk };
            }
            let down = if l == top {
                &self.restrict_fine
            } else {
                &restrict[l - 1]
            };
            spmv_into(down, &self.r[l], &mut self.b[l - 1]);
        }
        // The coarsest level.
        self.coarsest.solve(&self.b[0], &mut self.x[0]);
        // Up: prolongate, add, smooth backward.
        for l in 1..=top {
            let up = if l == top {
                &self.prolong_fine
            } else {
                &p[l - 1]
            };
            spmv_into(up, &self.x[l - 1], &mut self.r[l]);
            for (x, r) in self.x[l].iter_mut().zip(&self.r[l]) {
                *x += r;
            }
            let (matrix, dg, fixed) = if l == top {
                (a, diag, &self.truncated[..])
            } else {
                let lv = &self.levels[l];
                (&lv.a, &lv.diag[..], &lv.fixed[..])
            };
            for _ in 0..sweeps {
                linear_sweep(matrix, dg, &self.b[l], &mut self.x[l], fixed, false);
            }
        }
        c.copy_from_slice(&self.x[top]);
    }
}
