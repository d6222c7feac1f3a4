//! The Galerkin coarse operator Pᵀ A P in one pass (Gräser & Sander 2019,
//! section 4.2: the coarse spaces of the linear V-cycle are the Galerkin
//! products of the nested meshes' prolongations).
//!
//! Row I of Pᵀ A P is Σ_i (Pᵀ)_{Ii} Σ_j A_ij P_{j,:}: a row-wise triple
//! product with a dense accumulator, blocks of rows on two threads. The
//! two general sparse products it replaces (A P, then Pᵀ (A P)) were most
//! of TNNMG's set-up at h = 1/1024. The pattern is the symbolic product's
//! (an entry that cancels to zero is kept), so that a truncation's
//! correction always lies on it.
//!
//! The rows go into a [`CsrBuilder`] as each block is done, which keeps
//! each distinct stencil and row of values once as they come (a coarse
//! level of a uniform mesh has as few as the stiffness). Built whole, the
//! level below the finest held 12 bytes per entry, twice while its two
//! halves were joined: at h = 1/2048 that was the solve's peak, 0.7 GB
//! above the matrix it keeps.

use crate::numerics::linalg::{Csr, CsrBuilder, RowValues};
use crate::numerics::threads::threads;
use crate::with_values;

/// Rows per block: a block's entries (a few hundred kB) are pushed into
/// the builder before the next is computed.
const BLOCK: usize = 1 << 13;

/// One block of consecutive coarse rows, offsets from 0, with the dense
/// accumulator of its product. Allocated by the calling thread, also for
/// the rows of the second thread: glibc keeps what a thread allocates in
/// that thread's arena.
struct Rows {
    offsets: Vec<usize>,
    cols: Vec<u32>,
    vals: Vec<f64>,
    acc: Vec<f64>,
    seen: Vec<bool>,
    touched: Vec<usize>,
}

impl Rows {
    /// For blocks of `rows` rows of `nc` columns, about `per_row` entries
    /// each.
    fn new(rows: usize, nc: usize, per_row: usize) -> Self {
        Self {
            offsets: Vec::with_capacity(rows + 1),
            cols: Vec::with_capacity(rows * per_row),
            vals: Vec::with_capacity(rows * per_row),
            acc: vec![0.0; nc],
            seen: vec![false; nc],
            touched: Vec::with_capacity(8 * per_row),
        }
    }

    /// Its rows into `out`, and itself emptied for the next block.
    fn push_into(&mut self, out: &mut CsrBuilder<1>) {
        for w in self.offsets.windows(2) {
            let (lo, hi) = (w[0], w[1]);
            out.push_row(&self.cols[lo..hi], [&self.vals[lo..hi]]);
        }
        self.offsets.clear();
        self.cols.clear();
        self.vals.clear();
    }
}

/// Rows `rows` of R A P, R = Pᵀ given as CSR, into `out`: one loop
/// compiled for each way A and P store their values (R's rows are read
/// once per coarse row, through the match).
fn rows_of_product(r: &Csr, a: &Csr, p: &Csr, rows: std::ops::Range<usize>, out: &mut Rows) {
    with_values!(a.values(), av => with_values!(p.values(), pv =>
        rows_of_product_with(r, (a, av), (p, pv), rows, out)
    ))
}

/// [`rows_of_product`] with A's and P's values.
fn rows_of_product_with<'v>(
    r: &Csr,
    (a, av): (&Csr, impl RowValues<'v>),
    (p, pv): (&Csr, impl RowValues<'v>),
    rows: std::ops::Range<usize>,
    out: &mut Rows,
) {
    let (ac, pc) = (a.columns(), p.columns());
    let Rows {
        offsets,
        cols,
        vals,
        acc,
        seen,
        touched,
    } = out;
    offsets.push(0);
    for row in rows {
        let (r_cols, r_vals) = r.row(row);
        for (i, &r_i) in r_cols.iter().zip(r_vals) {
            let (alo, ahi) = a.row_range(i);
            for (j, &a_ij) in ac.row(i, alo, ahi).iter().zip(av.row(i, alo, ahi)) {
                let ra = r_i * a_ij;
                let (plo, phi) = p.row_range(j);
                for (col, &p_jc) in pc.row(j, plo, phi).iter().zip(pv.row(j, plo, phi)) {
                    if !seen[col] {
                        seen[col] = true;
                        touched.push(col);
                    }
                    acc[col] += ra * p_jc;
                }
            }
        }
        touched.sort_unstable();
        for &col in touched.iter() {
            cols.push(col as u32);
            vals.push(acc[col]);
            acc[col] = 0.0;
            seen[col] = false;
        }
        touched.clear();
        offsets.push(cols.len());
    }
}

/// R A P for R = Pᵀ (CSR), blocks of rows on two threads unless one is
/// asked for ([`threads`]): a set-up step, once per operator. Refused when
/// its entries outgrow a [`Csr`]'s 32-bit offsets.
pub(crate) fn galerkin(r: &Csr, a: &Csr, p: &Csr) -> Result<Csr, String> {
    let (n, nc) = (r.nrows(), p.ncols());
    let workers = if threads() < 2 { 1 } else { 2 };
    // On nested P1 meshes a coarse row has about as many entries as a
    // fine one; a wrong guess only costs a reallocation.
    let per_row = a.nnz().div_ceil(a.nrows().max(1)) + 2;
    let block = BLOCK.min(n.div_ceil(workers)).max(1);
    let mut out = CsrBuilder::<1>::new(n, nc);
    let (mut first, mut second) = (Rows::new(block, nc, per_row), None);
    if workers == 2 {
        second = Some(Rows::new(block, nc, per_row));
    }
    let mut start = 0;
    while start < n {
        let mid = (start + block).min(n);
        let end = (mid + block).min(n);
        match &mut second {
            Some(rows) if mid < end => std::thread::scope(|scope| {
                scope.spawn(|| rows_of_product(r, a, p, mid..end, rows));
                rows_of_product(r, a, p, start..mid, &mut first);
            }),
            _ => rows_of_product(r, a, p, start..mid, &mut first),
        }
        first.push_into(&mut out);
        if let Some(rows) = &mut second
            && mid < end
        {
            rows.push_into(&mut out);
        }
        start = if second.is_some() { end } else { mid };
    }
    let [product] = out
        .finish()
        .map_err(|e| format!("a coarse level of the multigrid: {e}"))?;
    Ok(product)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::{CooMatrix, CsrMatrix};

    /// Equals the two general products on a small matrix, entry by entry
    /// and pattern by pattern (a cancelling entry included).
    #[test]
    fn equals_the_two_general_products() {
        let mut a = CooMatrix::new(5, 5);
        for (i, j, v) in [
            (0, 0, 4.0),
            (0, 1, -1.0),
            (1, 0, -1.0),
            (1, 1, 4.0),
            (1, 2, -1.0),
            (2, 1, -1.0),
            (2, 2, 4.0),
            (2, 4, 2.0),
            (4, 2, 2.0),
            (3, 3, 1.0),
            (4, 4, 3.0),
        ] {
            a.push(i, j, v);
        }
        let mut p = CooMatrix::new(5, 3);
        for (i, j, v) in [
            (0, 0, 1.0),
            (1, 0, 0.5),
            (1, 1, 0.5),
            (2, 1, 1.0),
            (3, 2, 1.0),
            (4, 1, -0.5),
            (4, 2, 0.5),
        ] {
            p.push(i, j, v);
        }
        let (a, p) = (CsrMatrix::from(&a), CsrMatrix::from(&p));
        let r = p.transpose();
        let expected = &r * &(&a * &p);
        let csr = |m: &CsrMatrix<f64>| Csr::try_from(m).unwrap();
        let got = galerkin(&csr(&r), &csr(&a), &csr(&p))
            .unwrap()
            .to_nalgebra();
        assert_eq!(got.row_offsets(), expected.row_offsets());
        assert_eq!(got.col_indices(), expected.col_indices());
        for (x, y) in got.values().iter().zip(expected.values()) {
            assert!((x - y).abs() <= 1e-14 * y.abs().max(1.0), "{x} vs {y}");
        }
        // A and P with their distinct rows stored once give the same
        // product to the bit.
        let shared = |m: &CsrMatrix<f64>| csr(m).shared();
        assert!(shared(&a).is_shared() && shared(&p).is_shared());
        let from_shared = galerkin(&shared(&r), &shared(&a), &shared(&p)).unwrap();
        assert_eq!(from_shared.to_nalgebra(), got);
        // On one thread: the same rows, to the bit.
        let _one = crate::numerics::threads::Threads::set(1);
        assert_eq!(
            galerkin(&csr(&r), &csr(&a), &csr(&p))
                .unwrap()
                .to_nalgebra(),
            got
        );
    }
}
