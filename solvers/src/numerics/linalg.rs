//! Sparse linear algebra shared by the solvers: products, and sparse Cholesky
//! through faer.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky, simplicial, supernodal,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Mat, MatMut, Par, Side};
use nalgebra_sparse::{CooMatrix, CscMatrix, CsrMatrix};
use thiserror::Error;

/// A failed factorization.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum LinalgError {
    #[error("sparse Cholesky: the matrix is not numerically positive definite (pivot {index})")]
    NotPositiveDefinite { index: usize },
    #[error("sparse Cholesky: {0}")]
    Faer(String),
}

/// y = A x for a CSR matrix.
pub fn spmv(a: &CsrMatrix<f64>, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; a.nrows()];
    spmv_into(a, x, &mut y);
    y
}

/// y = A x for a CSR matrix, into a caller's buffer (no allocation).
pub fn spmv_into(a: &CsrMatrix<f64>, x: &[f64], y: &mut [f64]) {
    spmv_values_into(a, a.values(), x, y);
}

/// y = B x where B has the pattern of `pattern` and the stored values
/// `values` (one per stored entry, in its order): the product with a matrix
/// kept as values on another's pattern, such as the mass matrix on the
/// stiffness's. No allocation.
pub(crate) fn spmv_values_into(pattern: &CsrMatrix<f64>, values: &[f64], x: &[f64], y: &mut [f64]) {
    assert_eq!(x.len(), pattern.ncols(), "spmv: x has the wrong length");
    assert_eq!(y.len(), pattern.nrows(), "spmv: y has the wrong length");
    assert_eq!(
        values.len(),
        pattern.nnz(),
        "spmv: one value per stored entry"
    );
    let (offsets, cols) = (pattern.row_offsets(), pattern.col_indices());
    let rows = |first: usize, y: &mut [f64]| {
        for (i, yi) in (first..).zip(y.iter_mut()) {
            let (lo, hi) = (offsets[i], offsets[i + 1]);
            // SAFETY: a CsrMatrix keeps its column indices below ncols =
            // x.len(), and values has one entry per stored index.
            *yi = unsafe { row_dot(&cols[lo..hi], &values[lo..hi], x) };
        }
    };
    if pattern.nnz() < PARALLEL_NNZ {
        rows(0, y);
    } else {
        // Each row is the same sum on either thread: the product is the
        // same to the bit as the sequential one.
        let half = y.len() / 2;
        let (lower, upper) = y.split_at_mut(half);
        std::thread::scope(|scope| {
            scope.spawn(|| rows(half, upper));
            rows(0, lower);
        });
    }
}

/// Stored entries from which a matrix-vector product runs on both cores:
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
pub unsafe fn row_dot(cols: &[usize], vals: &[f64], x: &[f64]) -> f64 {
    debug_assert!(vals.len() >= cols.len() && cols.iter().all(|&c| c < x.len()));
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
pub(crate) unsafe fn row_dot_by(cols: &[usize], vals: &[f64], x_at: impl Fn(usize) -> f64) -> f64 {
    let n = cols.len();
    let mut acc = [0.0f64; 4];
    let mut k = 0;
    // SAFETY: k + q < n ≤ vals.len() by the contract.
    unsafe {
        while k + 3 < n {
            for (q, a) in acc.iter_mut().enumerate() {
                *a += vals.get_unchecked(k + q) * x_at(*cols.get_unchecked(k + q));
            }
            k += 4;
        }
        while k < n {
            acc[0] += vals.get_unchecked(k) * x_at(*cols.get_unchecked(k));
            k += 1;
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
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

/// Keeps one triangle (`lower`: row ≥ col) of a square matrix, as CSC for faer.
fn triangle_csc(a: &CsrMatrix<f64>, lower: bool, perm_inv: Option<&[usize]>) -> CscMatrix<f64> {
    let n = a.nrows();
    let mut coo = CooMatrix::new(n, n);
    for (i, j, &v) in a.triplet_iter() {
        let (pi, pj) = match perm_inv {
            Some(inv) => (inv[i], inv[j]),
            None => (i, j),
        };
        if (lower && pi >= pj) || (!lower && pi <= pj) {
            coo.push(pi, pj, v);
        }
    }
    CscMatrix::from(&coo)
}

/// The lower triangle of a symmetric CSR matrix, as CSC for faer.
fn lower_of(a: &CsrMatrix<f64>) -> CscMatrix<f64> {
    let (offsets, cols, vals) = a.csr_data();
    let all: Vec<usize> = (0..a.nrows()).collect();
    lower_part(a.nrows(), offsets, cols, vals, &all)
}

/// The lower triangle, as CSC, of the principal submatrix of a symmetric
/// matrix kept by `map` (old index → new index, `usize::MAX` to drop; the
/// kept indices in increasing order). The input is compressed by rows or by
/// columns (`offsets`, `indices`, `values`, indices sorted within each line):
/// for a symmetric matrix, line j's entries at or beyond j are column j of
/// the lower triangle, either way. One pass, no intermediate copy: at
/// h = 1/1024 the triplet route held two more copies of A at once.
pub(crate) fn lower_part(
    k: usize,
    offsets: &[usize],
    indices: &[usize],
    values: &[f64],
    map: &[usize],
) -> CscMatrix<f64> {
    let mut col_offsets = Vec::with_capacity(k + 1);
    let mut rows = Vec::new();
    let mut vals = Vec::new();
    col_offsets.push(0);
    for (j, &nj) in map.iter().enumerate() {
        if nj == usize::MAX {
            continue;
        }
        for p in offsets[j]..offsets[j + 1] {
            let i = indices[p];
            if i >= j && map[i] != usize::MAX {
                rows.push(map[i]);
                vals.push(values[p]);
            }
        }
        col_offsets.push(rows.len());
    }
    CscMatrix::try_from_csc_data(k, k, col_offsets, rows, vals)
        .expect("a monotone map of sorted lines gives sorted columns")
}

fn faer_ref(m: &CscMatrix<f64>) -> SparseColMatRef<'_, usize, f64> {
    let n = m.nrows();
    SparseColMatRef::new(
        SymbolicSparseColMatRef::new_checked(n, m.ncols(), m.col_offsets(), None, m.row_indices()),
        m.values(),
    )
}

/// Sparse Cholesky LLᵀ of a symmetric positive definite matrix (faer,
/// fill-reducing AMD ordering).
pub struct SparseCholesky {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
}

/// The symbolic analysis (AMD ordering, elimination tree, supernodes) of a
/// symmetric matrix, done once so that numeric factorizations of the same
/// pattern can be timed alone: how a code that refactors one pattern
/// (a Newton method, a time stepper) pays for a factorization.
pub struct CholeskyAnalysis {
    symbolic: SymbolicCholesky<usize>,
    lower: CscMatrix<f64>,
}

impl CholeskyAnalysis {
    /// The analysis of `a` (full symmetric storage).
    pub fn new(a: &CsrMatrix<f64>) -> Result<Self, LinalgError> {
        let lower = lower_of(a);
        let symbolic = factorize_symbolic_cholesky(
            faer_ref(&lower).symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            Default::default(),
        )
        .map_err(|e| LinalgError::Faer(format!("{e:?}")))?;
        Ok(Self { symbolic, lower })
    }

    /// The numeric factorization on `threads` threads (faer's supernodal
    /// LLᵀ with rayon parallelism; 1: sequential) and one solve of A x = b
    /// in place on as many.
    pub fn factor_and_solve(&self, threads: usize, b: &mut [f64]) -> Result<(), LinalgError> {
        let par = if threads > 1 {
            Par::rayon(threads)
        } else {
            Par::Seq
        };
        let values = numeric_values(&self.symbolic, &self.lower, par)?;
        let n = b.len();
        let rhs = faer::MatMut::from_column_major_slice_mut(b, n, 1);
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(1, par));
        faer::sparse::linalg::cholesky::LltRef::new(&self.symbolic, &values)
            .solve_in_place_with_conj(Conj::No, rhs, par, MemStack::new(&mut mem));
        Ok(())
    }
}

/// The values of L for a symbolic analysis and the lower triangle of A.
fn numeric_values(
    symbolic: &SymbolicCholesky<usize>,
    lower: &CscMatrix<f64>,
    par: Par,
) -> Result<Vec<f64>, LinalgError> {
    let mut values = vec![0.0; symbolic.len_val()];
    let mut mem =
        MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()));
    symbolic
        .factorize_numeric_llt(
            &mut values,
            faer_ref(lower),
            Side::Lower,
            LltRegularization::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .map(|_| ())
        .map_err(|e| match e {
            faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                LinalgError::NotPositiveDefinite { index }
            }
        })?;
    Ok(values)
}

impl SparseCholesky {
    /// Symbolic analysis and numeric factorization of `a` (full symmetric storage).
    pub fn new(a: &CsrMatrix<f64>) -> Result<Self, LinalgError> {
        let CholeskyAnalysis { symbolic, lower } = CholeskyAnalysis::new(a)?;
        Self::from_symbolic(symbolic, lower)
    }

    /// Factorization with the unknowns `trailing` ordered last, in that order
    /// (the rest by AMD), and the supernodal layout forced, so that the
    /// trailing block of L can be read with [`SparseCholesky::trailing_factor`].
    /// Takes the lower triangle (see [`lower_part`]), which it keeps: no
    /// other copy of the matrix is made.
    pub(crate) fn with_trailing(
        lower: CscMatrix<f64>,
        trailing: &[usize],
    ) -> Result<Self, LinalgError> {
        let n = lower.nrows();
        let mut local = vec![0usize; n];
        for &j in trailing {
            local[j] = usize::MAX;
        }
        let mut rest = Vec::with_capacity(n - trailing.len());
        for (j, l) in local.iter_mut().enumerate() {
            if *l != usize::MAX {
                *l = rest.len();
                rest.push(j);
            }
        }
        // AMD on the rest alone.
        let mut fwd: Vec<usize> = if rest.is_empty() {
            Vec::new()
        } else {
            let rest_lower = lower_part(
                rest.len(),
                lower.col_offsets(),
                lower.row_indices(),
                lower.values(),
                &local,
            );
            let sym = factorize_symbolic_cholesky(
                faer_ref(&rest_lower).symbolic(),
                Side::Lower,
                SymmetricOrdering::Amd,
                Default::default(),
            )
            .map_err(|e| LinalgError::Faer(format!("{e:?}")))?;
            match sym.perm() {
                Some(p) => p.arrays().0.iter().map(|&k| rest[k]).collect(),
                None => rest.clone(),
            }
        };
        fwd.extend_from_slice(trailing);
        let mut inv = vec![0usize; n];
        for (new, &old) in fwd.iter().enumerate() {
            inv[old] = new;
        }
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(
            faer_ref(&lower).symbolic(),
            Side::Lower,
            SymmetricOrdering::Custom(PermRef::new_checked(&fwd, &inv, n)),
            params,
        )
        .map_err(|e| LinalgError::Faer(format!("{e:?}")))?;
        Self::from_symbolic(symbolic, lower)
    }

    /// The dense lower-triangular block of L on the last `k` pivots (in
    /// elimination order): for a factorization built by
    /// [`SparseCholesky::with_trailing`], the trailing unknowns in their order.
    pub(crate) fn trailing_factor(&self, k: usize) -> Option<Mat<f64>> {
        let n = self.n();
        let off = n.checked_sub(k)?;
        let SymbolicCholeskyRaw::Supernodal(sym) = self.symbolic.raw() else {
            return None;
        };
        let l = supernodal::SupernodalLltRef::new(sym, &self.values);
        let mut out = Mat::<f64>::zeros(k, k);
        for s in 0..sym.n_supernodes() {
            let node = l.supernode(s);
            let (start, val, pattern) = (node.start(), node.val(), node.pattern());
            let ncols = val.ncols();
            if start + ncols <= off {
                continue;
            }
            for c in 0..ncols {
                let col = start + c;
                if col < off {
                    continue;
                }
                for r in c..ncols {
                    out[(start + r - off, col - off)] = val[(r, c)];
                }
                for (p, &row) in pattern.iter().enumerate() {
                    out[(row - off, col - off)] = val[(ncols + p, c)];
                }
            }
        }
        Some(out)
    }

    /// Numeric factorization of `lower` (lower triangle) after its symbolic
    /// analysis. `lower` is not kept (it goes when this returns): only L is
    /// needed to solve, and at h = 1/1024 the triangle is about 250 MB.
    fn from_symbolic(
        symbolic: SymbolicCholesky<usize>,
        lower: CscMatrix<f64>,
    ) -> Result<Self, LinalgError> {
        Self::numeric(symbolic, &lower, Par::Seq)
    }

    /// The numeric factorization for a symbolic analysis, on `par`.
    fn numeric(
        symbolic: SymbolicCholesky<usize>,
        lower: &CscMatrix<f64>,
        par: Par,
    ) -> Result<Self, LinalgError> {
        let values = numeric_values(&symbolic, lower, par)?;
        Ok(Self { symbolic, values })
    }

    /// Dimension of the factored matrix.
    pub fn n(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Nonzeros of the factor L.
    pub(crate) fn factor_nnz(&self) -> usize {
        self.values.len()
    }

    /// Solves A X = B in place for the columns of `rhs`.
    pub(crate) fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        let par = Par::Seq;
        let mut mem = MemBuffer::new(
            self.symbolic
                .solve_in_place_scratch::<f64>(rhs.ncols(), par),
        );
        faer::sparse::linalg::cholesky::LltRef::new(&self.symbolic, &self.values)
            .solve_in_place_with_conj(Conj::No, rhs, par, MemStack::new(&mut mem));
    }

    /// Solves A x = b in place for one vector.
    pub fn solve_vec(&self, b: &mut [f64]) {
        let n = b.len();
        self.solve_in_place(faer::MatMut::from_column_major_slice_mut(b, n, 1));
    }
}

/// Measured dimension of the kernel of a symmetric positive semidefinite
/// matrix: the number of pivots of its Cholesky factorization (AMD ordering)
/// that fall below `rel_tol` times the largest diagonal entry. Each such pivot
/// is replaced by that diagonal entry (a rank-one spring), which removes one
/// kernel direction and lets the factorization go on.
pub fn kernel_dimension(a: &CsrMatrix<f64>, rel_tol: f64) -> Result<usize, LinalgError> {
    let scale = a
        .diagonal_as_csr()
        .values()
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    if scale == 0.0 {
        return Ok(a.nrows());
    }
    let lower = lower_of(a);
    let symbolic = factorize_symbolic_cholesky(
        faer_ref(&lower).symbolic(),
        Side::Lower,
        SymmetricOrdering::Amd,
        Default::default(),
    )
    .map_err(|e| LinalgError::Faer(format!("{e:?}")))?;
    let inv: Option<Vec<usize>> = symbolic.perm().map(|p| p.arrays().1.to_vec());
    let regularization = LltRegularization {
        dynamic_regularization_delta: scale,
        dynamic_regularization_epsilon: rel_tol * scale,
    };
    let mut values = vec![0.0; symbolic.len_val()];
    let par = Par::Seq;
    let info = match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            let upper = triangle_csc(a, false, inv.as_deref());
            let mut mem = MemBuffer::new(simplicial::factorize_simplicial_numeric_llt_scratch::<
                usize,
                f64,
            >(a.nrows()));
            simplicial::factorize_simplicial_numeric_llt(
                &mut values,
                faer_ref(&upper),
                regularization,
                s,
                MemStack::new(&mut mem),
            )
        }
        SymbolicCholeskyRaw::Supernodal(s) => {
            let lower = triangle_csc(a, true, inv.as_deref());
            let mut mem = MemBuffer::new(supernodal::factorize_supernodal_numeric_llt_scratch::<
                usize,
                f64,
            >(s, par, Default::default()));
            supernodal::factorize_supernodal_numeric_llt(
                &mut values,
                faer_ref(&lower),
                regularization,
                s,
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
        }
    };
    info.map(|i| i.dynamic_regularization_count)
        .map_err(|e| match e {
            faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                LinalgError::NotPositiveDefinite { index }
            }
        })
}

#[cfg(test)]
mod tests {
    use super::*;

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
        spmv_values_into(&a, &m, &x, &mut y);
        assert_eq!(y.to_vec(), spmv(&b, &x));
        assert_eq!(y, [2.5, -4.0, 3.5]);
    }
}
