//! The certificate's own linear solve with the stiffness A, for the error
//! bound ([`super::error_bound`]): a sparse LLᵀ (faer's supernodal
//! Cholesky, AMD ordering) of A with the unknowns in `pinned` removed, so
//! that a semicoercive A (a rigid mode z, A z = 0) becomes definite. It
//! reads A's rows itself and shares no code with the solvers crate, whose
//! answers it helps to judge.
//!
//! With one unknown k pinned where z_k ≠ 0, the reduced system gives the
//! y with y_k = 0 and (A y)_j = b_j for j ≠ k; if zᵀb = 0 the k-th row
//! holds too (zᵀA y = 0), so y solves A y = b and bᵀy = bᵀA⁺b.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use contactlab_solvers::ContactProblem;

/// Why the solve could not be set up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EnergySolveError {
    #[error("its factorization needs {need:.1} GB, {room:.1} GB are free")]
    TooLarge { need: f64, room: f64 },
    #[error("A with the rigid modes pinned is not positive definite (pivot {0})")]
    NotDefinite(usize),
    #[error("faer's analysis failed: {0}")]
    Analysis(String),
    #[error(
        "the preconditioned conjugate gradients did not converge in {steps} steps (relative residual {residual:.1e})"
    )]
    NotConverged { steps: usize, residual: f64 },
}

/// A factorization of A without the pinned unknowns.
pub struct EnergySolve {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    /// Old index → index in the reduced system (`usize::MAX`: pinned).
    map: Vec<usize>,
    par: Par,
}

impl EnergySolve {
    /// Factors A without the unknowns `pinned`, refusing (before the
    /// factor's values are allocated) if they would take more than `room`
    /// bytes.
    pub fn new(
        problem: &ContactProblem,
        pinned: &[usize],
        room: f64,
    ) -> Result<Self, EnergySolveError> {
        let a = problem.a();
        let n = problem.n();
        // The lower triangle's copy (a row index and a value, 16 bytes, per
        // entry) and faer's ordering of it (a few times that) come before
        // the factor: refused here too, before they are allocated.
        let copy = 16.0 * (a.nnz() / 2 + n) as f64 + 8.0 * n as f64;
        if 4.0 * copy > room {
            return Err(EnergySolveError::TooLarge {
                need: 4.0 * copy / 1e9,
                room: room / 1e9,
            });
        }
        let mut map = vec![0usize; n];
        for &k in pinned {
            map[k] = usize::MAX;
        }
        let mut kept = 0;
        for m in map.iter_mut() {
            if *m != usize::MAX {
                *m = kept;
                kept += 1;
            }
        }
        // The lower triangle, column by column: for a symmetric A, row j's
        // entries at or beyond j are column j of the lower triangle.
        let mut col_offsets = Vec::with_capacity(kept + 1);
        let mut rows = Vec::new();
        let mut vals = Vec::new();
        col_offsets.push(0);
        for (j, &mj) in map.iter().enumerate() {
            if mj == usize::MAX {
                continue;
            }
            let (cols, row) = a.row(j);
            for (c, &v) in cols.iter().zip(row) {
                let i = c;
                if i >= j && map[i] != usize::MAX {
                    rows.push(map[i]);
                    vals.push(v);
                }
            }
            col_offsets.push(rows.len());
        }
        let lower = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(kept, kept, &col_offsets, None, &rows),
            &vals,
        );
        let symbolic = factorize_symbolic_cholesky(
            lower.symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            Default::default(),
        )
        .map_err(|e| EnergySolveError::Analysis(format!("{e:?}")))?;
        let par = Par::rayon(std::thread::available_parallelism().map_or(1, |n| n.get()));
        let scratch = symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default());
        let need = 8.0 * symbolic.len_val() as f64 + scratch.size_bytes() as f64;
        if need > room {
            return Err(EnergySolveError::TooLarge {
                need: need / 1e9,
                room: room / 1e9,
            });
        }
        let mut values = vec![0.0; symbolic.len_val()];
        let mut mem = MemBuffer::new(scratch);
        symbolic
            .factorize_numeric_llt(
                &mut values,
                lower,
                Side::Lower,
                LltRegularization::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| match e {
                faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                    EnergySolveError::NotDefinite(index)
                }
            })?;
        Ok(Self {
            symbolic,
            values,
            map,
            par,
        })
    }

    /// y with A y = b off the pinned rows and y = 0 on them.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut reduced: Vec<f64> = b
            .iter()
            .zip(&self.map)
            .filter(|&(_, &m)| m != usize::MAX)
            .map(|(&x, _)| x)
            .collect();
        let k = reduced.len();
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(1, self.par));
        faer::sparse::linalg::cholesky::LltRef::new(&self.symbolic, &self.values)
            .solve_in_place_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(&mut reduced, k, 1),
                self.par,
                MemStack::new(&mut mem),
            );
        self.map
            .iter()
            .map(|&m| if m == usize::MAX { 0.0 } else { reduced[m] })
            .collect()
    }
}
