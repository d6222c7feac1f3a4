//! y = Pᵀ x on any number of threads, without Pᵀ stored and without a
//! scratch vector: the multigrid's restriction of a residual to the level
//! below. Each thread owns a band of P's columns (of y) and reads only the
//! runs of P's rows that reach it, adding P_ic·x_i into its own y_c in
//! ascending i. Every y_c is then the sum the sequential scatter forms, in
//! its order: the same bits on any thread count.
//!
//! For the geometric prolongations of a structured hierarchy the rows that
//! reach a band of coarse unknowns are a band of fine rows and a few far
//! ones (the contact unknowns, numbered apart). Problem 1 at h = 1/1024:
//! each band's rows are 3-6 runs, and the bands together read P's rows
//! 1.001 (2 threads), 1.016 (16) and 1.06 (64) times over.

use std::ops::Range;

use super::{RowValues, SparseRows};
use crate::numerics::threads::{MAX_THREADS, for_each_piece, threads};

/// A plan whose bands would read P's rows more often than this (summed
/// over the bands) is refused: its rows reach columns far apart, and the
/// two-half scatter of [`super::spmv_transpose_into`] does better.
const MAX_READS: f64 = 1.25;

/// At most this many runs of rows per band (a band's list stays a few
/// cache lines; a geometric prolongation needs 3-6).
const MAX_RUNS: usize = 64;

/// The bands of P's columns and, for each, the runs of rows that reach it.
#[derive(Clone, Debug)]
pub struct TransposePlan {
    nrows: usize,
    ncols: usize,
    nnz: usize,
    /// Columns per band (the last may have fewer).
    width: usize,
    /// Band b's rows, ascending: the rows with a column in
    /// b·width .. (b + 1)·width.
    runs: Vec<Vec<Range<usize>>>,
}

impl TransposePlan {
    /// The plan of P for `threads` bands (at most [`MAX_THREADS`]); None
    /// for one thread, for P below [`super::PARALLEL_NNZ`] entries (a
    /// thread's start would cost more than it saves), or for a P whose
    /// bands' rows would be many runs or read P more than [`MAX_READS`]
    /// times over.
    pub fn new(p: &impl SparseRows, threads: usize) -> Option<Self> {
        let bands = threads.min(MAX_THREADS);
        let (nrows, ncols) = (p.nrows(), p.ncols());
        if bands < 2 || p.nnz() < super::PARALLEL_NNZ || ncols < bands {
            return None;
        }
        let width = ncols.div_ceil(bands);
        let bands = ncols.div_ceil(width);
        let mut runs: Vec<Vec<Range<usize>>> = vec![Vec::new(); bands];
        let mut reads = 0usize;
        let limit = (MAX_READS * nrows as f64) as usize;
        for i in 0..nrows {
            let (lo, hi) = p.row_range(i);
            // The bands row i reaches (at most 64: MAX_THREADS).
            let mut reached = 0u64;
            for c in p.row_columns(i, lo, hi).iter() {
                reached |= 1 << (c / width);
            }
            while reached != 0 {
                let b = reached.trailing_zeros() as usize;
                reached &= reached - 1;
                let band = &mut runs[b];
                if let Some(run) = band.last_mut().filter(|run| run.end == i) {
                    run.end = i + 1;
                } else if band.len() == MAX_RUNS {
                    return None;
                } else {
                    band.push(i..i + 1);
                }
                reads += 1;
            }
            if reads > limit {
                return None;
            }
        }
        Some(Self {
            nrows,
            ncols,
            nnz: p.nnz(),
            width,
            runs,
        })
    }

    /// y = Pᵀ x, P the matrix of the plan (its sizes are checked). With
    /// one thread ([`crate::numerics::threads::threads`]) the rows are
    /// scattered in one pass on the calling thread; the bits are the same.
    pub fn apply(&self, p: &impl SparseRows, x: &[f64], y: &mut [f64]) {
        assert!(
            (p.nrows(), p.ncols(), p.nnz()) == (self.nrows, self.ncols, self.nnz),
            "restriction: a plan of another matrix"
        );
        assert_eq!(x.len(), self.nrows, "restriction: x has the wrong length");
        assert_eq!(y.len(), self.ncols, "restriction: y has the wrong length");
        crate::with_values!(p.values(), vals => self.apply_values(p, vals, x, y));
    }

    /// How many rows the bands read together (P's rows once each would
    /// be its row count).
    pub fn reads(&self) -> usize {
        self.runs.iter().flatten().map(|r| r.len()).sum()
    }

    /// The most runs of rows one band reads.
    pub fn most_runs(&self) -> usize {
        self.runs.iter().map(Vec::len).max().unwrap_or(0)
    }

    fn apply_values<'v>(
        &self,
        p: &impl SparseRows,
        vals: impl RowValues<'v>,
        x: &[f64],
        y: &mut [f64],
    ) {
        // One thread: every row once, in the same order, so the same bits.
        if threads() < 2 {
            y.fill(0.0);
            super::scatter_rows(p, vals, 0..self.nrows, 0, x, y);
            return;
        }
        for_each_piece(y, self.width, |b, y| {
            y.fill(0.0);
            for run in &self.runs[b] {
                super::scatter_rows(p, vals, run.clone(), b * self.width, x, y);
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numerics::linalg::{PARALLEL_NNZ, spmv};
    use crate::numerics::threads::Threads;
    use nalgebra_sparse::{CooMatrix, CsrMatrix};

    /// A prolongation-like P: row i reaches columns near i/4 (a band), and
    /// the last 200 rows (like the contact unknowns, numbered apart) also
    /// reach columns a third of the way in.
    fn banded(rows: usize) -> CsrMatrix<f64> {
        let cols = rows / 4 + 1;
        let mut coo = CooMatrix::new(rows, cols);
        for i in 0..rows {
            coo.push(i, i / 4, 1.0);
            if i % 4 != 0 && i / 4 + 1 < cols {
                coo.push(i, i / 4 + 1, 0.5 + (i % 3) as f64 / 7.0);
            }
            if i + 200 >= rows {
                coo.push(i, cols / 3 + (i + 200 - rows), -0.25);
            }
        }
        CsrMatrix::from(&coo)
    }

    fn sequential(p: &CsrMatrix<f64>, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; p.ncols()];
        for (i, row) in p.row_iter().enumerate() {
            for (&c, v) in row.col_indices().iter().zip(row.values()) {
                y[c] += v * x[i];
            }
        }
        y
    }

    /// Every thread count gives the sequential scatter's bits, and the
    /// product with the stored transpose to rounding; a far coupling now
    /// and then adds runs, not reads of the whole matrix.
    #[test]
    fn any_thread_count_gives_the_sequential_bits() {
        let p = banded(PARALLEL_NNZ + 13);
        let x: Vec<f64> = (0..p.nrows())
            .map(|i| ((i * 13 % 17) as f64 - 8.0) / 3.0)
            .collect();
        let want = sequential(&p, &x);
        let stored = spmv(&p.transpose(), &x);
        for (w, s) in want.iter().zip(&stored) {
            assert!((w - s).abs() <= 1e-13 * s.abs().max(1.0));
        }
        for bands in [2, 3, 5, 16, 64] {
            let plan = TransposePlan::new(&p, bands).expect("a banded P has a plan");
            let reads = plan.reads();
            assert!(reads as f64 <= 1.25 * p.nrows() as f64, "{bands}: {reads}");
            for threads in [1, 2, 3] {
                let _budget = Threads::set(threads);
                let mut y = vec![f64::NAN; p.ncols()];
                plan.apply(&p, &x, &mut y);
                let same = y.iter().zip(&want).all(|(a, b)| a.to_bits() == b.to_bits());
                assert!(same, "{bands} bands on {threads} threads");
            }
        }
    }

    /// A P whose every row reaches every band is refused (the bands would
    /// read it once each), and so are one thread and a small P.
    #[test]
    fn a_plan_that_would_read_too_much_is_refused() {
        let rows = PARALLEL_NNZ / 4 + 1;
        let cols = 64;
        let mut coo = CooMatrix::new(rows, cols);
        for i in 0..rows {
            for q in 0..4 {
                coo.push(i, (i + q * 16) % cols, 1.0);
            }
        }
        let dense = CsrMatrix::from(&coo);
        assert!(TransposePlan::new(&dense, 4).is_none());
        let p = banded(PARALLEL_NNZ + 13);
        assert!(TransposePlan::new(&p, 1).is_none());
        assert!(TransposePlan::new(&banded(4000), 4).is_none());
    }
}
