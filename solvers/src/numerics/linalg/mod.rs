//! Sparse linear algebra shared by the solvers: products (here), and sparse
//! Cholesky through faer ([`cholesky`]).

mod builder;
mod cholesky;
mod columns;
mod csr;
mod restriction;
mod sharer;
pub mod values;

pub use builder::CsrBuilder;
pub(crate) use cholesky::lower_part;
pub use cholesky::{CholeskyAnalysis, SparseCholesky, kernel_dimension};
pub use columns::{Columns, RowColumns};
pub use csr::{ColumnIndex, Csr, CsrError, IntoCsr, SparseRows};
pub use restriction::TransposePlan;
pub use values::{RowValues, SharedRows, Values};

use thiserror::Error;

use crate::numerics::threads::{for_each_piece, threads};

/// A failed factorization.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum LinalgError {
    #[error("sparse Cholesky: the matrix is not numerically positive definite (pivot {index})")]
    NotPositiveDefinite { index: usize },
    /// An allocation of the factorization failed: the machine's memory,
    /// not the matrix, is at fault.
    #[error(
        "out of memory in a sparse Cholesky factorization (an allocation of {} MB failed): use a coarser mesh, or a solver without a factorization (tnnmg)",
        bytes / 1_000_000
    )]
    OutOfMemory { bytes: usize },
    #[error("sparse Cholesky: {0}")]
    Faer(String),
}

impl From<faer::sparse::FaerError> for LinalgError {
    fn from(e: faer::sparse::FaerError) -> Self {
        match e {
            faer::sparse::FaerError::OutOfMemory => LinalgError::OutOfMemory { bytes: 0 },
            other => LinalgError::Faer(format!("{other:?}")),
        }
    }
}

impl From<faer::dyn_stack::mem::AllocError> for LinalgError {
    fn from(_: faer::dyn_stack::mem::AllocError) -> Self {
        LinalgError::OutOfMemory { bytes: 0 }
    }
}

/// y = A x for a CSR matrix.
pub fn spmv(a: &impl SparseRows, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; a.nrows()];
    spmv_into(a, x, &mut y);
    y
}

/// y = A x for a CSR matrix, into a caller's buffer (no allocation).
pub fn spmv_into(a: &impl SparseRows, x: &[f64], y: &mut [f64]) {
    crate::with_values!(a.values(), v => spmv_values_into(a, v, x, y));
}

/// y = B x where B has the pattern of `pattern` and the stored values
/// `values` (one per stored entry, in its order): the product with a matrix
/// kept as values on another's pattern, such as the mass matrix on the
/// stiffness's. No allocation.
pub(crate) fn spmv_values_into<'v>(
    pattern: &impl SparseRows,
    values: impl RowValues<'v>,
    x: &[f64],
    y: &mut [f64],
) {
    assert_eq!(x.len(), pattern.ncols(), "spmv: x has the wrong length");
    assert_eq!(y.len(), pattern.nrows(), "spmv: y has the wrong length");
    assert_eq!(
        values.len(),
        pattern.nnz(),
        "spmv: one value per stored entry"
    );
    let rows = |first: usize, y: &mut [f64]| {
        for (i, yi) in (first..).zip(y.iter_mut()) {
            let (lo, hi) = pattern.row_range(i);
            // SAFETY: a SparseRows keeps its column indices below ncols =
            // x.len(), and values has one entry per stored index.
            *yi = unsafe { row_dot_at(pattern.row_columns(i, lo, hi), values.row(i, lo, hi), x) };
        }
    };
    let threads = threads();
    if pattern.nnz() < PARALLEL_NNZ || threads < 2 {
        rows(0, y);
    } else {
        // Each row is the same sum on any thread: the product is the same
        // to the bit as the sequential one.
        let chunk = y.len().div_ceil(threads);
        for_each_piece(y, chunk, |c, ys| rows(c * chunk, ys));
    }
}

/// y = Pᵀ x for a CSR matrix P, without Pᵀ stored: each row i of P
/// scatters P_iI·x_i into y_I. Above [`PARALLEL_NNZ`], and with more than
/// one thread ([`threads`]), the rows are split in two halves, the upper
/// one scattering into `scratch` (P's column count), which is then added:
/// a half's columns may overlap the other's. Bits depend only on the
/// matrix and whether one thread is asked for. No allocation. The
/// multigrid restricts with a [`TransposePlan`] on every thread where P
/// has one, and with this where it has none.
pub(crate) fn spmv_transpose_into(
    p: &impl SparseRows,
    x: &[f64],
    y: &mut [f64],
    scratch: &mut [f64],
) {
    assert_eq!(x.len(), p.nrows(), "spmv_transpose: x has the wrong length");
    assert_eq!(y.len(), p.ncols(), "spmv_transpose: y has the wrong length");
    crate::with_values!(p.values(), vals => transpose_product(p, vals, x, y, scratch));
}

/// [`spmv_transpose_into`] for one kind of stored values.
fn transpose_product<'v>(
    p: &impl SparseRows,
    vals: impl RowValues<'v>,
    x: &[f64],
    y: &mut [f64],
    scratch: &mut [f64],
) {
    let scatter = |rows: std::ops::Range<usize>, y: &mut [f64]| {
        y.fill(0.0);
        scatter_rows(p, vals, rows, 0, x, y);
    };
    let n = x.len();
    if p.nnz() < PARALLEL_NNZ || threads() < 2 {
        scatter(0..n, y);
    } else {
        assert_eq!(
            scratch.len(),
            y.len(),
            "spmv_transpose: scratch has the wrong length"
        );
        let half = n / 2;
        std::thread::scope(|scope| {
            scope.spawn(|| scatter(half..n, scratch));
            scatter(0..half, y);
        });
        for (yk, sk) in y.iter_mut().zip(scratch.iter()) {
            *yk += sk;
        }
    }
}

/// y_{c − first} += P_ic·x_i over the rows i of `rows`, ascending, for the
/// columns c of y's band (from `first`, y.len() of them): with `first` = 0
/// and y of P's column count, the sequential scatter of y = Pᵀ x. Another
/// band's column (below `first` it wraps past the end) is that band's.
pub(super) fn scatter_rows<'v>(
    p: &impl SparseRows,
    vals: impl RowValues<'v>,
    rows: std::ops::Range<usize>,
    first: usize,
    x: &[f64],
    y: &mut [f64],
) {
    for i in rows {
        let xi = x[i];
        let (lo, hi) = p.row_range(i);
        for (c, v) in p.row_columns(i, lo, hi).iter().zip(vals.row(i, lo, hi)) {
            if let Some(yc) = y.get_mut(c.wrapping_sub(first)) {
                *yc += v * xi;
            }
        }
    }
}

/// Stored entries from which a matrix-vector product runs on several cores:
/// below it (h ≥ 1/64 for the paper's scenes) the thread's start costs more
/// than it saves, and a product stays the single-thread one that the
/// sweep-against-product goal compares.
pub const PARALLEL_NNZ: usize = 1 << 18;

/// Σ_k vals[k]·x[cols[k]] of one sparse row, with four independent partial
/// sums: a Gauss-Seidel sweep waits for each row before the next, so the
/// latency of one long chain of additions would dominate it. Used by both
/// the sweep and the product, so that they are compared like with like.
///
/// # Safety
/// Every entry of `cols` must be below `x.len()`, and `vals` must be at least
/// as long as `cols`.
#[inline]
pub unsafe fn row_dot<I: ColumnIndex>(cols: &[I], vals: &[f64], x: &[f64]) -> f64 {
    debug_assert!(vals.len() >= cols.len() && cols.iter().all(|&c| c.at() < x.len()));
    // SAFETY: cols[k] < x.len() by the contract.
    unsafe { row_dot_by(cols, vals, |c| *x.get_unchecked(c)) }
}

/// [`row_dot`] with x read through `x_at` (the two-core sweeps read a
/// vector that the other thread writes elsewhere through a raw pointer):
/// the same partial sums in the same order, so the same bits.
///
/// # Safety
/// `vals` must be at least as long as `cols`, and `x_at` sound at every
/// entry of `cols`.
#[inline(always)]
pub(crate) unsafe fn row_dot_by<I: ColumnIndex>(
    cols: &[I],
    vals: &[f64],
    x_at: impl Fn(usize) -> f64,
) -> f64 {
    let n = cols.len();
    let mut acc = [0.0f64; 4];
    let mut k = 0;
    // SAFETY: k + q < n ≤ vals.len() by the contract.
    unsafe {
        while k + 3 < n {
            for (q, a) in acc.iter_mut().enumerate() {
                *a += vals.get_unchecked(k + q) * x_at(cols.get_unchecked(k + q).at());
            }
            k += 4;
        }
        while k < n {
            acc[0] += vals.get_unchecked(k) * x_at(cols.get_unchecked(k).at());
            k += 1;
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// [`row_dot`] of a row read as a base and offsets ([`RowColumns`]):
/// Σ_q vals[q]·x[base + rel[q]], the same sums.
///
/// # Safety
/// Every column of the row is below x.len(), and vals at least as long.
#[inline(always)]
pub unsafe fn row_dot_at<I: ColumnIndex>(cols: RowColumns<'_, I>, vals: &[f64], x: &[f64]) -> f64 {
    debug_assert!(cols.last().is_none_or(|c| c < x.len()));
    // SAFETY: base + rel[q] < x.len() by the contract.
    unsafe { row_dot_by(cols.rel, vals, |c| *x.get_unchecked(cols.base + c)) }
}

/// Maximum norm of a vector (0 for an empty one).
pub fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// The largest |x_i| (0 for an empty slice), or None when some x_i is not
/// finite. Eight independent lanes, so that the maxima do not wait on each
/// other in one chain of comparisons: this pass over a matrix's values was a
/// tenth of a 1/64 assembly as one chain.
pub(crate) fn max_abs_if_finite(x: &[f64]) -> Option<f64> {
    const LANES: usize = 8;
    let (mut max, mut bad) = ([0.0f64; LANES], [false; LANES]);
    let chunks = x.chunks_exact(LANES);
    let rest = chunks.remainder();
    let mut lane = |l: usize, v: f64| {
        let a = v.abs();
        bad[l] |= !a.is_finite();
        // NaN fails the comparison and is caught by `bad`.
        max[l] = if a > max[l] { a } else { max[l] };
    };
    for chunk in chunks {
        for (l, &v) in chunk.iter().enumerate() {
            lane(l, v);
        }
    }
    for (l, &v) in rest.iter().enumerate() {
        lane(l, v);
    }
    if bad.iter().any(|&b| b) {
        None
    } else {
        Some(max.into_iter().fold(0.0, f64::max))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::CsrMatrix;

    /// The lanes must agree with one plain chain, find a bad value in any
    /// lane and in the remainder, and count −x like x.
    #[test]
    fn max_abs_if_finite_sees_every_lane_and_the_remainder() {
        for len in [0, 1, 7, 8, 9, 17, 23] {
            let x: Vec<f64> = (0..len)
                .map(|i| ((i * 37 % 11) as f64 - 5.0) * 1.5)
                .collect();
            assert_eq!(max_abs_if_finite(&x), Some(max_abs(&x)), "len {len}");
            for at in 0..len {
                for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                    let mut y = x.clone();
                    y[at] = bad;
                    assert_eq!(max_abs_if_finite(&y), None, "len {len}, {bad} at {at}");
                }
                let mut y = x.clone();
                y[at] = -1e300;
                assert_eq!(
                    max_abs_if_finite(&y),
                    Some(1e300),
                    "len {len}, −1e300 at {at}"
                );
            }
        }
    }

    /// The product with values on another matrix's pattern is the product
    /// with the matrix those values make.
    #[test]
    fn spmv_with_values_on_a_pattern_is_the_matrix_product() {
        let mut coo = nalgebra_sparse::CooMatrix::new(3, 3);
        for (i, j, v) in [
            (0, 0, 2.0),
            (0, 2, -1.0),
            (1, 1, 3.0),
            (2, 0, -1.0),
            (2, 2, 4.0),
        ] {
            coo.push(i, j, v);
        }
        let a = CsrMatrix::from(&coo);
        let m = [1.0, 0.5, 2.0, 0.5, 1.0];
        let b = CsrMatrix::try_from_pattern_and_values(a.pattern().clone(), m.to_vec()).unwrap();
        let x = [1.0, -2.0, 3.0];
        let mut y = [0.0; 3];
        spmv_values_into(&a, &m[..], &x, &mut y);
        assert_eq!(y.to_vec(), spmv(&b, &x));
        assert_eq!(y, [2.5, -4.0, 3.5]);
    }

    /// Pᵀ x without Pᵀ equals the product with the stored transpose, on a
    /// matrix small enough for one thread and on one large enough for two
    /// (whose halves scatter into the same coarse unknowns).
    #[test]
    fn transposed_product_equals_the_stored_transpose() {
        for (rows, per_row) in [(50, 3), (PARALLEL_NNZ / 2 + 7, 3)] {
            let cols = rows / 4 + 1;
            let mut coo = nalgebra_sparse::CooMatrix::new(rows, cols);
            for i in 0..rows {
                for q in 0..per_row {
                    // Columns wrap around, so that the first and the last
                    // rows meet in the same columns.
                    let j = (i * 7 + q * (cols / 2 + 1)) % cols;
                    coo.push(i, j, 1.0 + ((i + q) % 5) as f64 * 0.25);
                }
            }
            let p = CsrMatrix::from(&coo);
            let x: Vec<f64> = (0..rows)
                .map(|i| ((i * 13 % 17) as f64 - 8.0) / 3.0)
                .collect();
            let expected = spmv(&p.transpose(), &x);
            let (mut y, mut scratch) = (vec![f64::NAN; cols], vec![f64::NAN; cols]);
            spmv_transpose_into(&p, &x, &mut y, &mut scratch);
            for (k, (got, want)) in y.iter().zip(&expected).enumerate() {
                assert!(
                    (got - want).abs() <= 1e-13 * want.abs().max(1.0),
                    "rows {rows}, column {k}: {got} vs {want}"
                );
            }
        }
    }
}
