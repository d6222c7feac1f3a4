//! The Galerkin coarse operator Pᵀ A P in one pass (Gräser & Sander 2019,
//! section 4.2: the coarse spaces of the linear V-cycle are the Galerkin
//! products of the nested meshes' prolongations).
//!
//! Row I of Pᵀ A P is Σ_i (Pᵀ)_{Ii} Σ_j A_ij P_{j,:}: a row-wise triple
//! product with a dense accumulator, rows split between two threads. The
//! two general sparse products it replaces (A P, then Pᵀ (A P)) were most
//! of TNNMG's set-up at h = 1/1024. The pattern is the symbolic product's
//! (an entry that cancels to zero is kept), so that a truncation's
//! correction always lies on it.

use nalgebra_sparse::CsrMatrix;

use crate::numerics::linalg::Csr;

/// One block of consecutive coarse rows: offsets (from 0), columns, values.
type Rows = (Vec<usize>, Vec<u32>, Vec<f64>);

/// Rows `rows` of R A P, R = Pᵀ given as CSR, with `nc` columns.
fn rows_of_product(
    r: &CsrMatrix<f64>,
    a: &Csr,
    p: &CsrMatrix<f64>,
    rows: std::ops::Range<usize>,
    nc: usize,
) -> Rows {
    let (ro, rc, rv) = (r.row_offsets(), r.col_indices(), r.values());
    let (ao, ac, av) = (a.row_offsets(), a.col_indices(), a.values());
    let (po, pc, pv) = (p.row_offsets(), p.col_indices(), p.values());
    let mut acc = vec![0.0; nc];
    let mut seen = vec![false; nc];
    let mut touched: Vec<usize> = Vec::new();
    let mut offsets = Vec::with_capacity(rows.len() + 1);
    offsets.push(0);
    let (mut cols, mut vals) = (Vec::new(), Vec::new());
    for row in rows {
        for q in ro[row]..ro[row + 1] {
            let (i, r_i) = (rc[q], rv[q]);
            for s in ao[i]..ao[i + 1] {
                let (j, ra) = (ac[s] as usize, r_i * av[s]);
                for t in po[j]..po[j + 1] {
                    let col = pc[t];
                    if !seen[col] {
                        seen[col] = true;
                        touched.push(col);
                    }
                    acc[col] += ra * pv[t];
                }
            }
        }
        touched.sort_unstable();
        for &col in &touched {
            cols.push(col as u32);
            vals.push(acc[col]);
            acc[col] = 0.0;
            seen[col] = false;
        }
        touched.clear();
        offsets.push(cols.len());
    }
    (offsets, cols, vals)
}

/// R A P for R = Pᵀ (CSR), on two threads (the rows in two halves).
pub(crate) fn galerkin(r: &CsrMatrix<f64>, a: &Csr, p: &CsrMatrix<f64>) -> Csr {
    let (n, nc) = (r.nrows(), p.ncols());
    let half = n / 2;
    let (lower, upper) = std::thread::scope(|scope| {
        let upper = scope.spawn(|| rows_of_product(r, a, p, half..n, nc));
        let lower = rows_of_product(r, a, p, 0..half, nc);
        (
            lower,
            upper
                .join()
                .expect("the Galerkin product's thread ran to its end"),
        )
    });
    let (mut offsets, mut cols, mut vals) = lower;
    let base = cols.len();
    offsets.extend(upper.0[1..].iter().map(|o| o + base));
    // Exact capacities: the halves grew by doubling, and a level keeps its
    // matrix for the whole solve.
    cols.reserve_exact(upper.1.len());
    vals.reserve_exact(upper.2.len());
    cols.extend(upper.1);
    vals.extend(upper.2);
    cols.shrink_to_fit();
    vals.shrink_to_fit();
    Csr::try_from_csr_data(n, nc, offsets, cols, vals)
        .expect("the rows of a product are sorted and in range")
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::CooMatrix;

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
        let got = galerkin(&r, &Csr::try_from(&a).unwrap(), &p).to_nalgebra();
        assert_eq!(got.row_offsets(), expected.row_offsets());
        assert_eq!(got.col_indices(), expected.col_indices());
        for (x, y) in got.values().iter().zip(expected.values()) {
            assert!((x - y).abs() <= 1e-14 * y.abs().max(1.0), "{x} vs {y}");
        }
    }
}
