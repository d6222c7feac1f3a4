//! The stored values of a [`super::Csr`]: each row by itself, or the
//! distinct rows once.
//!
//! A stiffness matrix assembled from the element matrices of a uniform
//! mesh has very few distinct rows: each row is one node's stencil, and on
//! the paper's scenes there are 45 of them (543 numbers) at every h, from
//! the interior, the edges, the corners and Γ_K of the two bodies. Kept
//! once, with the start of each row's values among them, A's values take 4
//! bytes per row instead of 8 per entry: at h = 1/4096 (4.7·10⁸ entries)
//! 3.6 GB of a 14 GB solve. A row's values are then a slice of a table
//! that stays in the cache, so the kernels that stream A (products,
//! sweeps) read the same numbers in the same order: the same sums to the
//! bit, and less memory traffic.

use super::csr::ColumnIndex;
use super::sharer::Sharer;

/// Row i's values (at stored positions lo..hi), whichever way they are
/// stored. The kernels that stream a matrix are generic over it, so that
/// each kind is compiled into its own loop ([`crate::with_values`]).
pub trait RowValues<'a>: Copy + Send + Sync {
    /// Row `i`'s values; `lo..hi` are its stored positions (the matrix's
    /// row offsets i and i + 1).
    fn row(self, i: usize, lo: usize, hi: usize) -> &'a [f64];

    /// Number of stored values (one per stored entry of the matrix).
    fn len(self) -> usize;

    /// Whether there are none.
    fn is_empty(self) -> bool {
        self.len() == 0
    }

    /// The value at stored position `p` of row `i` (`offsets`: the
    /// matrix's row offsets).
    ///
    /// # Panics
    /// If `p` is not among row i's positions (plain values are read at `p`
    /// directly, without looking at the row).
    #[inline(always)]
    fn at<O: ColumnIndex>(self, offsets: &[O], i: usize, p: usize) -> f64 {
        let (lo, hi) = (offsets[i].at(), offsets[i + 1].at());
        assert!(
            (lo..hi).contains(&p),
            "stored position {p} is not in row {i}"
        );
        self.row(i, lo, hi)[p - lo]
    }

    /// The largest |value| (0 for none), or None when some value is not
    /// finite.
    fn max_abs_if_finite(self) -> Option<f64>;
}

impl<'a> RowValues<'a> for &'a [f64] {
    #[inline(always)]
    fn row(self, _: usize, lo: usize, hi: usize) -> &'a [f64] {
        &self[lo..hi]
    }
    fn len(self) -> usize {
        <[f64]>::len(self)
    }
    #[inline(always)]
    fn at<O: ColumnIndex>(self, _: &[O], _: usize, p: usize) -> f64 {
        self[p]
    }
    fn max_abs_if_finite(self) -> Option<f64> {
        super::max_abs_if_finite(self)
    }
}

/// Values kept as a table of distinct rows and the start of each row's.
#[derive(Clone, Copy, Debug)]
pub struct SharedRows<'a> {
    table: &'a [f64],
    start: &'a [u32],
    entries: usize,
}

impl<'a> RowValues<'a> for SharedRows<'a> {
    #[inline(always)]
    fn row(self, i: usize, lo: usize, hi: usize) -> &'a [f64] {
        let s = self.start[i] as usize;
        &self.table[s..s + (hi - lo)]
    }
    fn len(self) -> usize {
        self.entries
    }
    /// From the table: every entry of it is some row's.
    fn max_abs_if_finite(self) -> Option<f64> {
        super::max_abs_if_finite(self.table)
    }
}

/// A matrix's stored values as read: row by row, or shared. Kernels that
/// stream the matrix match on it once ([`crate::with_values`]).
#[derive(Clone, Copy, Debug)]
pub enum Values<'a> {
    Plain(&'a [f64]),
    Shared(SharedRows<'a>),
}

impl<'a> RowValues<'a> for Values<'a> {
    #[inline(always)]
    fn row(self, i: usize, lo: usize, hi: usize) -> &'a [f64] {
        match self {
            Values::Plain(v) => v.row(i, lo, hi),
            Values::Shared(s) => s.row(i, lo, hi),
        }
    }
    fn len(self) -> usize {
        match self {
            Values::Plain(v) => v.len(),
            Values::Shared(s) => s.entries,
        }
    }
    #[inline(always)]
    fn at<O: ColumnIndex>(self, offsets: &[O], i: usize, p: usize) -> f64 {
        match self {
            Values::Plain(v) => v.at(offsets, i, p),
            Values::Shared(s) => s.at(offsets, i, p),
        }
    }
    fn max_abs_if_finite(self) -> Option<f64> {
        match self {
            Values::Plain(v) => v.max_abs_if_finite(),
            Values::Shared(s) => s.max_abs_if_finite(),
        }
    }
}

impl<'a> Values<'a> {
    /// Row `i`'s values ([`RowValues::row`], without the trait in scope).
    #[inline(always)]
    pub fn row(self, i: usize, lo: usize, hi: usize) -> &'a [f64] {
        RowValues::row(self, i, lo, hi)
    }

    /// The values in stored order (`offsets`: the matrix's row offsets).
    pub fn iter<O: ColumnIndex>(self, offsets: &'a [O]) -> impl Iterator<Item = &'a f64> + 'a {
        offsets
            .windows(2)
            .enumerate()
            .flat_map(move |(i, w)| self.row(i, w[0].at(), w[1].at()).iter())
    }

    /// The values in stored order, as a vector of their own.
    pub fn to_vec<O: ColumnIndex>(self, offsets: &[O]) -> Vec<f64> {
        match self {
            Values::Plain(v) => v.to_vec(),
            Values::Shared(_) => {
                let mut out = Vec::with_capacity(offsets[offsets.len() - 1].at());
                for (i, w) in offsets.windows(2).enumerate() {
                    out.extend_from_slice(self.row(i, w[0].at(), w[1].at()));
                }
                out
            }
        }
    }
}

impl<'a> From<&'a [f64]> for Values<'a> {
    fn from(v: &'a [f64]) -> Self {
        Values::Plain(v)
    }
}

/// Runs `$body` with `$v` bound to the matched kind of `$values` (a
/// [`Values`]): the body is compiled once for plain rows and once for
/// shared ones, so that a hot loop in it does not match per row.
#[macro_export]
macro_rules! with_values {
    ($values:expr, $v:ident => $body:expr) => {
        match $values {
            $crate::numerics::linalg::Values::Plain($v) => $body,
            $crate::numerics::linalg::Values::Shared($v) => $body,
        }
    };
}

/// The values as a [`super::Csr`] owns them.
#[derive(Clone, Debug)]
pub(super) enum Stored {
    Plain(Vec<f64>),
    Shared {
        table: Vec<f64>,
        start: Vec<u32>,
        entries: usize,
    },
}

/// Shared rows are kept only while their table stays this small (512 KB,
/// a core's L2 cache): a matrix with more distinct rows keeps its values
/// row by row.
const MAX_TABLE: usize = 1 << 16;

impl Stored {
    pub(super) fn view(&self) -> Values<'_> {
        match self {
            Stored::Plain(v) => Values::Plain(v),
            Stored::Shared {
                table,
                start,
                entries,
            } => Values::Shared(SharedRows {
                table,
                start,
                entries: *entries,
            }),
        }
    }

    /// The rows of `values` (`offsets`: the row offsets) kept once each, if
    /// the distinct ones fit [`MAX_TABLE`] values; None otherwise.
    pub(super) fn share<O: ColumnIndex>(offsets: &[O], values: &[f64]) -> Option<Stored> {
        let mut sharer = RowSharer::with_rows(offsets.len() - 1);
        for w in offsets.windows(2) {
            if !sharer.push(&values[w[0].at()..w[1].at()]) {
                return None;
            }
        }
        Some(sharer.finish())
    }

    /// The values row by row (copied out, if they were shared).
    pub(super) fn make_plain<O: ColumnIndex>(&mut self, offsets: &[O]) -> &mut Vec<f64> {
        if let Stored::Shared { .. } = self {
            *self = Stored::Plain(self.view().to_vec(offsets));
        }
        match self {
            Stored::Plain(v) => v,
            Stored::Shared { .. } => unreachable!("copied out just above"),
        }
    }
}

/// Builds shared values row by row, so that an assembly never holds its
/// values whole ([`Stored::share`] for values already whole).
pub(super) struct RowSharer {
    rows: Sharer<f64>,
    entries: usize,
}

impl RowSharer {
    pub(super) fn with_rows(rows: usize) -> Self {
        Self {
            rows: Sharer::with_rows(rows, MAX_TABLE),
            entries: 0,
        }
    }

    /// Takes the next row; false if the distinct rows would exceed
    /// [`MAX_TABLE`] values.
    pub(super) fn push(&mut self, row: &[f64]) -> bool {
        if !self.rows.push(row) {
            return false;
        }
        self.entries += row.len();
        true
    }

    /// The rows taken so far, each whole, in order (`offsets`: their row
    /// offsets), for a matrix that turned out to have too many.
    pub(super) fn to_plain<O: ColumnIndex>(&self, offsets: &[O]) -> Vec<f64> {
        Values::Shared(SharedRows {
            table: &self.rows.table,
            start: &self.rows.start,
            entries: self.entries,
        })
        .to_vec(offsets)
    }

    pub(super) fn finish(self) -> Stored {
        let (table, start) = self.rows.finish();
        Stored::Shared {
            table,
            start,
            entries: self.entries,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sharing keeps every bit (−0.0 apart from 0.0, a NaN's payload, a
    /// row that is another's prefix), reads like the plain rows through
    /// every accessor, and gives up when the distinct rows are too many.
    #[test]
    fn shared_rows_keep_every_bit_and_give_up_when_too_many() {
        let odd_nan = f64::from_bits(0x7ff8_0000_0000_0123);
        let stencils: [&[f64]; 5] = [
            &[1.0, -0.0, 2.5],
            &[1.0, 0.0, 2.5],
            &[odd_nan, 1.0 / 3.0],
            &[1.0, -0.0],
            &[],
        ];
        let (mut offsets, mut values) = (vec![0usize], Vec::new());
        for k in 0..100 {
            values.extend_from_slice(stencils[(k * 7) % 5]);
            offsets.push(values.len());
        }
        let shared = Stored::share(&offsets, &values).expect("five distinct rows");
        let Stored::Shared { table, start, .. } = &shared else {
            panic!("shared")
        };
        // Each distinct row once; [1, −0] reads the start of [1, −0, 2.5],
        // met among the last rows.
        assert_eq!(table.len(), 8, "each distinct row once");
        assert_eq!(start.len(), 100);
        let view = shared.view();
        assert_eq!(view.len(), values.len());
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&view.to_vec(&offsets)), bits(&values));
        let listed: Vec<f64> = view.iter(&offsets).copied().collect();
        assert_eq!(bits(&listed), bits(&values));
        for i in [0, 1, 2, 3, 99] {
            let (lo, hi) = (offsets[i], offsets[i + 1]);
            assert_eq!(bits(view.row(i, lo, hi)), bits(&values[lo..hi]));
            for (p, v) in values.iter().enumerate().take(hi).skip(lo) {
                assert_eq!(view.at(&offsets, i, p).to_bits(), v.to_bits());
            }
        }
        let mut plain = shared.clone();
        assert_eq!(bits(plain.make_plain(&offsets)), bits(&values));

        // Distinct rows of 2^16 + 1 values in all.
        let n = MAX_TABLE / 2 + 1;
        let offsets: Vec<usize> = (0..=n).map(|i| 2 * i).collect();
        let values: Vec<f64> = (0..2 * n).map(|k| k as f64).collect();
        assert!(Stored::share(&offsets, &values).is_none());
        assert!(Stored::share(&offsets[..n], &values[..2 * (n - 1)]).is_some());
    }
}
