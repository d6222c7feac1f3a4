//! The check that A and M are square, finite and symmetric, made in one
//! pass over the pattern where possible (it is part of every problem's
//! set-up, a fifth of an assembly at h = 1/64 before it was made cheap).

use super::{Mass, ProblemError};
use crate::numerics::linalg::{ColumnIndex, Csr, RowValues, SparseRows, Values};

/// Checks that A and M are n × n, finite and symmetric. When M lives on A's
/// pattern, one pass over it checks both.
/// A's values are read as a slice when A keeps them row by row (as
/// assembled), through [`Values`] when it shares its rows.
pub(super) fn check_stiffness_and_mass(a: &Csr, mass: &Mass, n: usize) -> Result<(), ProblemError> {
    if let Values::Plain(av) = a.values() {
        return check_pair(a, av, mass, n);
    }
    check_pair(a, a.values(), mass, n)
}

/// [`check_stiffness_and_mass`] with A's values `av`, of one kind.
fn check_pair<'v, V: RowValues<'v> + From<&'v [f64]>>(
    a: &Csr,
    av: V,
    mass: &'v Mass,
    n: usize,
) -> Result<(), ProblemError> {
    match mass {
        Mass::OnStiffnessPattern(m) => {
            check_square_symmetric(a, [("A", av), ("M", V::from(m.as_slice()))], n)
        }
        Mass::Matrix(m) => {
            check_square_symmetric(a, [("A", av)], n)?;
            check_square_symmetric(m, [("M", m.values())], n)
        }
        Mass::Omitted => check_square_symmetric(a, [("A", av)], n),
    }
}

/// Checks that each matrix, given as its values on `pattern` (one per stored
/// entry), is n × n, finite and symmetric to 1e-12 of its largest entry.
///
/// A sequential pass measures each matrix's largest entry and whether it is
/// finite. Then each entry above the diagonal is compared with its mirror:
/// when every entry below the diagonal was met as such a mirror, that covers
/// every pair, at half the random accesses of visiting every entry. Only
/// when an entry below has no stored mirror above, or a matrix fails, is
/// the whole pattern walked, the second time to name the first offending
/// entry.
pub(super) fn check_square_symmetric<'v, const K: usize, V: RowValues<'v>>(
    pattern: &impl SparseRows,
    named: [(&'static str, V); K],
    n: usize,
) -> Result<(), ProblemError> {
    let Some(&(first, _)) = named.first() else {
        return Ok(());
    };
    for (dim, got) in [(n, pattern.nrows()), (n, pattern.ncols())] {
        if dim != got {
            return Err(ProblemError::Dimension {
                what: first,
                expected: dim,
                got,
            });
        }
    }
    for (what, values) in &named {
        if values.len() != pattern.nnz() {
            return Err(ProblemError::Dimension {
                what,
                expected: pattern.nnz(),
                got: values.len(),
            });
        }
    }
    let offsets = pattern.row_offsets();
    let values = named.map(|(_, v)| v);
    let mut scale = [0.0f64; K];
    for m in 0..K {
        scale[m] = values[m]
            .max_abs_if_finite()
            .ok_or(ProblemError::NonFinite { what: named[m].0 })?;
    }
    let below: usize = (0..n)
        .map(|row| {
            let (lo, hi) = pattern.row_range(row);
            let cols = pattern.row_columns(row, lo, hi);
            cols.rel.partition_point(|&col| cols.base + col.at() < row)
        })
        .sum();
    let tol = scale.map(|s| 1e-12 * s);
    let (mut asymmetry, mirrored) = asymmetry(pattern, &values, Triangle::Upper);
    if mirrored < below {
        asymmetry = self::asymmetry(pattern, &values, Triangle::Both).0;
    }
    if (0..K).all(|m| asymmetry[m] <= tol[m]) {
        return Ok(());
    }
    let mut offending = None;
    walk_mirrors(pattern, Triangle::Both, |row, col, k, mirror| {
        for m in 0..K {
            let across = mirror.map_or(0.0, |c| values[m].at(offsets, col, c));
            if (across - values[m].at(offsets, row, k)).abs() > tol[m] {
                offending = Some(ProblemError::NotSymmetric {
                    what: named[m].0,
                    row,
                    col,
                });
                return false;
            }
        }
        true
    });
    Err(offending.expect("an asymmetry was measured, so an entry exceeds it"))
}

/// Each matrix's largest |x_ij − x_ji| over the entries of `which` (a
/// missing mirror counts as 0), and how many of them had a stored mirror.
fn asymmetry<'v, const K: usize, V: RowValues<'v>>(
    pattern: &impl SparseRows,
    values: &[V; K],
    which: Triangle,
) -> ([f64; K], usize) {
    let offsets = pattern.row_offsets();
    let (mut asymmetry, mut mirrored) = ([0.0f64; K], 0);
    walk_mirrors(pattern, which, |row, col, k, mirror| {
        mirrored += usize::from(mirror.is_some());
        for m in 0..K {
            let across = mirror.map_or(0.0, |c| values[m].at(offsets, col, c));
            asymmetry[m] = asymmetry[m].max((across - values[m].at(offsets, row, k)).abs());
        }
        true
    });
    (asymmetry, mirrored)
}

/// Which stored entries [`walk_mirrors`] visits.
#[derive(Clone, Copy, PartialEq)]
enum Triangle {
    /// Those strictly above the diagonal.
    Upper,
    /// All of them.
    Both,
}

/// Visits each stored (row, col, position) of `which` in row order with the
/// position of its mirror (col, row), if stored, until `visit` returns
/// false. The mirror is found by a cursor per row that only moves forward:
/// the rows visiting column `col` come in increasing order, and so do the
/// columns of row `col`. One pass over the pattern, no search (a binary
/// search per entry was a third of the set-up at h = 1/256). Inlined, so
/// that what `visit` accumulates stays in registers (a store and a load per
/// entry otherwise).
#[inline(always)]
fn walk_mirrors(
    pattern: &impl SparseRows,
    which: Triangle,
    mut visit: impl FnMut(usize, usize, usize, Option<usize>) -> bool,
) {
    let n = pattern.nrows();
    let mut cursor: Vec<usize> = (0..n).map(|row| pattern.row_range(row).0).collect();
    for row in 0..n {
        let (lo, hi) = pattern.row_range(row);
        let cols = pattern.row_columns(row, lo, hi);
        for k in lo..hi {
            let col = cols.get(k - lo);
            if which == Triangle::Upper && col <= row {
                continue;
            }
            let (start, end) = pattern.row_range(col);
            let mirror_cols = pattern.row_columns(col, start, end);
            let at = |c: usize| mirror_cols.get(c - start);
            let mut c = cursor[col];
            while c < end && at(c) < row {
                c += 1;
            }
            cursor[col] = c;
            let mirror = (c < end && at(c) == row).then_some(c);
            if !visit(row, col, k, mirror) {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::{CooMatrix, CsrMatrix};

    fn csr(n: usize, entries: &[(usize, usize, f64)]) -> CsrMatrix<f64> {
        let mut coo = CooMatrix::new(n, n);
        for &(i, j, v) in entries {
            coo.push(i, j, v);
        }
        CsrMatrix::from(&coo)
    }

    /// The check must fail naming matrix `what` and entry (row, col).
    fn assert_names(result: Result<(), ProblemError>, what: &str, row: usize, col: usize) {
        match result {
            Err(ProblemError::NotSymmetric {
                what: w,
                row: r,
                col: c,
            }) if (w, r, c) == (what, row, col) => {}
            other => panic!("expected {what}'s ({row}, {col}) to be named, got {other:?}"),
        }
    }

    /// The check of one matrix on its own pattern.
    fn check(what: &'static str, m: &CsrMatrix<f64>, n: usize) -> Result<(), ProblemError> {
        check_square_symmetric(m, [(what, m.values())], n)
    }

    /// A's pattern with M's values.
    fn on_a(m: &CsrMatrix<f64>) -> Mass {
        Mass::OnStiffnessPattern(m.values().to_vec())
    }

    #[test]
    fn a_symmetric_matrix_passes() {
        let m = csr(
            4,
            &[
                (0, 0, 2.0),
                (0, 3, -1.0),
                (3, 0, -1.0),
                (1, 2, 5.0),
                (2, 1, 5.0),
                (3, 3, 1.0),
            ],
        );
        assert!(check("A", &m, 4).is_ok());
    }

    #[test]
    fn a_differing_mirror_is_named() {
        let m = csr(3, &[(0, 0, 1.0), (0, 2, 1.0), (2, 0, 1.5), (1, 1, 1.0)]);
        assert_names(check("A", &m, 3), "A", 0, 2);
    }

    #[test]
    fn an_entry_without_a_stored_mirror_is_caught() {
        // (2, 1) is stored, (1, 2) is not: only the visit of row 2 sees it.
        let m = csr(3, &[(0, 0, 1.0), (1, 1, 1.0), (2, 1, 0.5), (2, 2, 1.0)]);
        assert_names(check("M", &m, 3), "M", 2, 1);
        // A stored explicit zero mirrors a missing entry.
        let m = csr(3, &[(0, 0, 1.0), (1, 2, 0.0), (2, 2, 1.0)]);
        assert!(check("M", &m, 3).is_ok());
        // Below the diagonal without a mirror: the walk over the upper
        // triangle cannot meet it, the whole walk must.
        let m = csr(3, &[(0, 0, 1.0), (2, 0, 0.0), (1, 1, 1.0), (2, 2, 1.0)]);
        assert!(check("M", &m, 3).is_ok());
        let m = csr(3, &[(0, 0, 1.0), (2, 0, 1e-3), (1, 1, 1.0), (2, 2, 1.0)]);
        assert_names(check("M", &m, 3), "M", 2, 0);
        // Above the diagonal without a mirror.
        let m = csr(3, &[(0, 0, 1.0), (0, 2, 1e-3), (1, 1, 1.0), (2, 2, 1.0)]);
        assert_names(check("M", &m, 3), "M", 0, 2);
    }

    /// Shared rows are read like plain ones: the same entry is named.
    #[test]
    fn shared_rows_are_checked_like_plain_ones() {
        let m = csr(3, &[(0, 0, 1.0), (0, 2, 1e-3), (1, 1, 1.0), (2, 2, 1.0)]);
        let shared = Csr::try_from(&m).unwrap().shared();
        assert!(shared.is_shared());
        assert_names(
            check_stiffness_and_mass(&shared, &Mass::Omitted, 3),
            "A",
            0,
            2,
        );
        let m = csr(3, &[(0, 0, 1.0), (0, 2, 1e-3), (2, 0, 1e-3), (2, 2, 1.0)]);
        let shared = Csr::try_from(&m).unwrap().shared();
        assert!(check_stiffness_and_mass(&shared, &Mass::Omitted, 3).is_ok());
    }

    #[test]
    fn a_pair_on_one_pattern_names_the_matrix_that_fails() {
        let entries = [(0, 0, 1.0), (0, 1, 2.0), (1, 0, 2.0), (1, 1, 1.0)];
        let mut m = csr(2, &entries);
        let a = Csr::try_from(&m).unwrap();
        m.values_mut()[2] = 2.5; // (1, 0) of M only
        assert!(
            check_stiffness_and_mass(
                &a,
                &Mass::OnStiffnessPattern(a.values().to_vec(a.row_offsets())),
                2
            )
            .is_ok()
        );
        assert_names(check_stiffness_and_mass(&a, &on_a(&m), 2), "M", 0, 1);
        // The same M with a pattern of its own.
        assert_names(
            check_stiffness_and_mass(&a, &Mass::Matrix(m.clone()), 2),
            "M",
            0,
            1,
        );
        m.values_mut()[2] = f64::NAN;
        assert!(matches!(
            check_stiffness_and_mass(&a, &on_a(&m), 2),
            Err(ProblemError::NonFinite { what: "M" })
        ));
        // Values on A's pattern must be one per stored entry.
        let short = Mass::OnStiffnessPattern(vec![1.0; 3]);
        assert!(matches!(
            check_stiffness_and_mass(&a, &short, 2),
            Err(ProblemError::Dimension {
                what: "M",
                expected: 4,
                got: 3
            })
        ));
    }
}
