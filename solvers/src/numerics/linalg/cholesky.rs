//! Sparse Cholesky through faer: the factorization of a whole matrix, its
//! symbolic analysis once and numeric factorizations on several threads
//! (the bench's best factorization), one with its trailing block apart
//! (the Schur complement of the contact unknowns), and the dimension of a
//! kernel measured from the pivots.

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

use super::LinalgError;

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
pub(crate) fn lower_part<'v, I: super::ColumnIndex, O: super::ColumnIndex>(
    k: usize,
    offsets: &[O],
    indices: &[I],
    values: impl super::RowValues<'v>,
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
        let (lo, hi) = (offsets[j].at(), offsets[j + 1].at());
        for (index, &v) in indices[lo..hi].iter().zip(values.row(j, lo, hi)) {
            let i = index.at();
            if i >= j && map[i] != usize::MAX {
                rows.push(map[i]);
                vals.push(v);
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
        .map_err(LinalgError::from)?;
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

/// `len` zeros, or [`LinalgError::OutOfMemory`] if they cannot be had: the
/// values of a factor are its largest allocation, and one that fails must
/// be an error the caller reports, not an abort.
fn zeros(len: usize) -> Result<Vec<f64>, LinalgError> {
    let mut values = Vec::new();
    values
        .try_reserve_exact(len)
        .map_err(|_| LinalgError::OutOfMemory {
            bytes: len.saturating_mul(8),
        })?;
    values.resize(len, 0.0);
    Ok(values)
}

/// The values of L for a symbolic analysis and the lower triangle of A.
fn numeric_values(
    symbolic: &SymbolicCholesky<usize>,
    lower: &CscMatrix<f64>,
    par: Par,
) -> Result<Vec<f64>, LinalgError> {
    let mut values = zeros(symbolic.len_val())?;
    let mut mem =
        MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()))?;
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
            .map_err(LinalgError::from)?;
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
        .map_err(LinalgError::from)?;
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
    .map_err(LinalgError::from)?;
    let inv: Option<Vec<usize>> = symbolic.perm().map(|p| p.arrays().1.to_vec());
    let regularization = LltRegularization {
        dynamic_regularization_delta: scale,
        dynamic_regularization_epsilon: rel_tol * scale,
    };
    let mut values = zeros(symbolic.len_val())?;
    let par = Par::Seq;
    let info = match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            let upper = triangle_csc(a, false, inv.as_deref());
            let mut mem =
                MemBuffer::try_new(simplicial::factorize_simplicial_numeric_llt_scratch::<
                    usize,
                    f64,
                >(a.nrows()))?;
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
            let mut mem =
                MemBuffer::try_new(supernodal::factorize_supernodal_numeric_llt_scratch::<
                    usize,
                    f64,
                >(s, par, Default::default()))?;
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
