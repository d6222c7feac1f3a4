//! The Galerkin coarse operator Pᵀ A P in one pass (Gräser & Sander 2019,
//! section 4.2: the coarse spaces of the linear V-cycle are the Galerkin
//! products of the nested meshes' prolongations).
//!
//! Row I of Pᵀ A P is Σ_i (Pᵀ)_{Ii} Σ_j A_ij P_{j,:}: a row-wise triple
//! product with a dense accumulator over a band of columns, blocks of rows
//! on every thread (on two before, each with an accumulator as long as the
//! coarse level: 9 bytes per coarse unknown and thread, which on 64 cores
//! would have outweighed the matrices). The two general sparse products
//! it replaces (A P, then Pᵀ (A P)) were most of TNNMG's set-up at
//! h = 1/1024. The pattern is the symbolic product's
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
use crate::numerics::threads::{MAX_THREADS, threads};
use crate::with_values;

/// Rows per block: a block's entries (a few hundred kB) are pushed into
/// the builder before the next is computed.
const BLOCK: usize = 1 << 13;

/// One block of consecutive coarse rows, offsets from 0, with the dense
/// accumulator of its product over the block's window of columns (a band
/// on nested meshes: a few coarse mesh rows around the block, not the
/// whole coarse level, so that each worker's costs little). Its rows'
/// vectors are allocated by the calling thread, also for the other
/// workers' blocks: glibc keeps what a thread allocates in that thread's
/// arena. The window's sums are set by the worker (a few hundred kB).
/// Aligned to two cache lines: the workers' blocks lie side by side in one
/// vector, and each push writes its vectors' lengths (sharing a line cost
/// the set-up at h = 1/1024 a sixth on two threads).
#[repr(align(128))]
struct Rows {
    offsets: Vec<usize>,
    cols: Vec<u32>,
    vals: Vec<f64>,
    /// The first column of the window; acc[c − first] is column c's sum.
    first: usize,
    acc: Vec<f64>,
    seen: Vec<bool>,
    touched: Vec<usize>,
    /// A row's (column, term) outside the window, in the order summed.
    overflow: Vec<(usize, f64)>,
}

impl Rows {
    /// For blocks of `rows` rows, about `per_row` entries each.
    fn new(rows: usize, per_row: usize) -> Self {
        Self {
            offsets: Vec::with_capacity(rows + 1),
            cols: Vec::with_capacity(rows * per_row),
            vals: Vec::with_capacity(rows * per_row),
            first: 0,
            acc: Vec::new(),
            seen: Vec::new(),
            touched: Vec::with_capacity(8 * per_row),
            overflow: Vec::new(),
        }
    }

    /// Makes the accumulator cover `window` (zeros where it grows: what
    /// it held is back at zero after every row; its capacity stays, so
    /// that a block costs no allocation once the widest has been seen).
    fn cover(&mut self, window: std::ops::Range<usize>) {
        self.first = window.start;
        self.acc.resize(window.len(), 0.0);
        self.seen.resize(window.len(), false);
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

/// A's local band: the largest over its rows of the row's nearer reach,
/// below or above its own index. A row that also couples far away (a
/// contact unknown of one body to the other's, which the relative
/// unknowns t and s do) counts by its near side. Once per product: O(A's
/// rows) reads.
fn local_band(a: &Csr) -> usize {
    (0..a.nrows())
        .filter_map(|i| {
            let (c, _) = a.row(i);
            Some(
                i.saturating_sub(c.first()?)
                    .min(c.last()?.saturating_sub(i)),
            )
        })
        .max()
        .unwrap_or(0)
}

/// The band of columns of R A P that coarse rows `rows` reach, bar a few:
/// P's columns at the fine rows that R's rows reach, widened by A's local
/// band ([`local_band`]). The far couplings of a few rows would otherwise
/// stretch the window of every block they fall in to most of the level;
/// what falls outside goes the slower way ([`Rows::overflow`]). O(rows
/// reached) reads, against the product's hundreds of multiplications a
/// row. Empty if the rows reach nothing.
fn window(r: &Csr, p: &Csr, band: usize, rows: std::ops::Range<usize>) -> std::ops::Range<usize> {
    // The smallest first column and the largest last column of the rows.
    let reach = |m: &Csr, rows: std::ops::Range<usize>| {
        let (mut lo, mut hi) = (usize::MAX, 0);
        for i in rows {
            let (c, _) = m.row(i);
            if let (Some(f), Some(l)) = (c.first(), c.last()) {
                lo = lo.min(f);
                hi = hi.max(l + 1);
            }
        }
        (lo < hi).then_some(lo..hi)
    };
    let Some(fine) = reach(r, rows) else {
        return 0..0;
    };
    let near = fine.start.saturating_sub(band)..(fine.end + band).min(p.nrows());
    reach(p, near).unwrap_or(0..0)
}

/// Rows `rows` of R A P, R = Pᵀ given as CSR, into `out` (its window
/// covering them, [`window`]): one loop compiled for each way A and P
/// store their values (R's rows are read once per coarse row, through the
/// match).
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
        first,
        acc,
        seen,
        touched,
        overflow,
    } = out;
    let (first, width) = (*first, acc.len());
    assert_eq!(seen.len(), width, "a window's flags and sums of one size");
    offsets.push(0);
    for row in rows {
        let (r_cols, r_vals) = r.row(row);
        for (i, &r_i) in r_cols.iter().zip(r_vals) {
            let (alo, ahi) = a.row_range(i);
            for (j, &a_ij) in ac.row(i, alo, ahi).iter().zip(av.row(i, alo, ahi)) {
                let ra = r_i * a_ij;
                let (plo, phi) = p.row_range(j);
                for (col, &p_jc) in pc.row(j, plo, phi).iter().zip(pv.row(j, plo, phi)) {
                    let c = col.wrapping_sub(first);
                    if c < width {
                        // SAFETY: acc and seen are `width` long
                        // ([`Rows::cover`] sizes both).
                        unsafe {
                            let s = seen.get_unchecked_mut(c);
                            if !*s {
                                *s = true;
                                touched.push(c);
                            }
                            *acc.get_unchecked_mut(c) += ra * p_jc;
                        }
                    } else {
                        overflow.push((col, ra * p_jc));
                    }
                }
            }
        }
        touched.sort_unstable();
        // The window's columns, in order, its sums back to zero.
        let mut window_into = |cols: &mut Vec<u32>, vals: &mut Vec<f64>| {
            for &c in touched.iter() {
                cols.push((first + c) as u32);
                vals.push(acc[c]);
                acc[c] = 0.0;
                seen[c] = false;
            }
            touched.clear();
        };
        if overflow.is_empty() {
            window_into(cols, vals);
        } else {
            // The terms outside the window, each column's summed from zero
            // in the order met (a stable sort), as the window's are: the
            // same bits whatever the window. Those below it first, then
            // the window's, then those above.
            overflow.sort_by_key(|&(col, _)| col);
            let mut outside = overflow.chunk_by(|x, y| x.0 == y.0).map(|terms| {
                let sum = terms.iter().fold(0.0, |s, &(_, t)| s + t);
                (terms[0].0, sum)
            });
            let mut next = outside.next();
            while let Some((col, sum)) = next.filter(|&(col, _)| col < first) {
                cols.push(col as u32);
                vals.push(sum);
                next = outside.next();
            }
            window_into(cols, vals);
            while let Some((col, sum)) = next {
                cols.push(col as u32);
                vals.push(sum);
                next = outside.next();
            }
            overflow.clear();
        }
        offsets.push(cols.len());
    }
}

/// R A P for R = Pᵀ (CSR), a set-up step, once per operator: blocks of
/// [`BLOCK`] rows, as many at a time as there are threads ([`threads`], at
/// most [`MAX_THREADS`]), one on each, pushed in order. Each row is the
/// same sum on any thread, so the product is the same to the bit for any
/// thread count. Refused when its entries outgrow a [`Csr`]'s 32-bit
/// offsets.
pub(crate) fn galerkin(r: &Csr, a: &Csr, p: &Csr) -> Result<Csr, String> {
    let n = r.nrows();
    let workers = threads().clamp(1, MAX_THREADS);
    // On nested P1 meshes a coarse row has about as many entries as a
    // fine one; a wrong guess only costs a reallocation.
    let per_row = a.nnz().div_ceil(a.nrows().max(1)) + 2;
    let block = BLOCK.min(n.div_ceil(workers)).max(1);
    let workers = workers.min(n.div_ceil(block)).max(1);
    let mut out = CsrBuilder::<1>::new(n, p.ncols());
    let mut blocks: Vec<Rows> = (0..workers).map(|_| Rows::new(block, per_row)).collect();
    let band = local_band(a);
    let mut start = 0;
    while start < n {
        // This round's blocks: the w-th worker takes the w-th.
        let round = |w: usize| {
            let lo = (start + w * block).min(n);
            lo..(lo + block).min(n)
        };
        // A block's window is found, and its sums sized, by its worker.
        let block_of = |range: std::ops::Range<usize>, rows: &mut Rows| {
            rows.cover(window(r, p, band, range.clone()));
            rows_of_product(r, a, p, range, rows);
        };
        if let [only] = &mut blocks[..] {
            block_of(round(0), only);
        } else {
            std::thread::scope(|scope| {
                let (mine, others) = blocks.split_first_mut().expect("two workers at least");
                for (w, rows) in (1..).zip(others) {
                    let range = round(w);
                    if !range.is_empty() {
                        scope.spawn(move || block_of(range, rows));
                    }
                }
                block_of(round(0), mine);
            });
        }
        for rows in &mut blocks {
            rows.push_into(&mut out);
        }
        start += workers * block;
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

    /// On a 1D Laplacian with linear interpolation and a few far couplings
    /// (as a contact unknown couples the two bodies), coarse enough rows
    /// for several rounds of blocks: one, two, three and five threads give
    /// the two general products' matrix, each the same to the bit (each
    /// row is one sum on any thread), and a block's window is the band
    /// around it although its rows couple far away (those terms go outside
    /// the window, into the same entries).
    #[test]
    fn any_thread_count_gives_the_same_product() {
        let nc = 3 * BLOCK + 7;
        let nf = 2 * nc - 1;
        let mut a = CooMatrix::new(nf, nf);
        for i in 0..nf {
            a.push(i, i, 2.0 + (i % 3) as f64 * 0.125);
            if i + 1 < nf {
                a.push(i, i + 1, -1.0);
                a.push(i + 1, i, -1.0);
            }
        }
        for (i, j) in [(5, nf - 3), (3 * BLOCK, 7), (3 * BLOCK + 1, nf - 1)] {
            a.push(i, j, 0.25);
            a.push(j, i, 0.25);
        }
        let mut p = CooMatrix::new(nf, nc);
        for c in 0..nc {
            p.push(2 * c, c, 1.0);
            if c + 1 < nc {
                p.push(2 * c + 1, c, 0.5);
                p.push(2 * c + 1, c + 1, 0.5);
            }
        }
        let (a, p) = (CsrMatrix::from(&a), CsrMatrix::from(&p));
        let r = p.transpose();
        let expected = &r * &(&a * &p);
        let csr = |m: &CsrMatrix<f64>| Csr::try_from(m).unwrap();
        let (r, a, p) = (csr(&r), csr(&a), csr(&p));
        let on = |t: usize| {
            let _t = crate::numerics::threads::Threads::set(t);
            galerkin(&r, &a, &p).unwrap().to_nalgebra()
        };
        let one = on(1);
        assert_eq!(one.row_offsets(), expected.row_offsets());
        assert_eq!(one.col_indices(), expected.col_indices());
        for (x, y) in one.values().iter().zip(expected.values()) {
            assert!((x - y).abs() <= 1e-14 * y.abs().max(1.0), "{x} vs {y}");
        }
        for t in [2, 3, 5] {
            assert_eq!(on(t), one, "{t} threads");
        }
        // A block's window is a band around it, not the coarse level, also
        // where its rows couple far away.
        for b in [0, 1] {
            let w = window(&r, &p, local_band(&a), b * BLOCK..(b + 1) * BLOCK);
            let near = b * BLOCK..(b + 1) * BLOCK;
            assert!(w.start <= near.start && w.end >= near.end, "{b}: {w:?}");
            assert!(w.len() <= BLOCK + 4, "{b}: {w:?}");
        }
    }
}
