//! The stored column indices of a [`super::Csr`]: each row's own, or each
//! distinct *stencil* once.
//!
//! On a uniform mesh numbered row by row, node after node, a row of the
//! stiffness couples its unknown to the same neighbours at the same
//! distances in the numbering wherever the node is of the same kind: row i
//! holds the columns i − d + r₀ < i − d + r₁ < … for a stencil (d, r) that
//! only some dozens of rows differ in (edges, corners, Γ_K, the other
//! body). Kept once, each row's stencil is 4 bytes of a start instead of 4
//! bytes per entry: at h = 1/4096 (4.7·10⁸ entries) 1.9 GB of the solve,
//! and every sweep and product streamed those indices. The kernels read a
//! row as a base and offsets from it ([`RowColumns`]): the same entries in
//! the same order, so the same sums to the bit.

use super::csr::ColumnIndex;
use super::sharer::Sharer;

/// One row's columns: `base + rel[k]` for the stored offsets `rel`,
/// increasing (base 0 for indices stored whole). Equal when they name the
/// same columns, however stored.
#[derive(Clone, Copy, Debug)]
pub struct RowColumns<'a, I = u32> {
    pub base: usize,
    pub rel: &'a [I],
}

impl<I: ColumnIndex> PartialEq for RowColumns<'_, I> {
    fn eq(&self, other: &Self) -> bool {
        self.iter().eq(other.iter())
    }
}

impl<'a, I: ColumnIndex> RowColumns<'a, I> {
    /// Number of entries.
    #[inline(always)]
    pub fn len(self) -> usize {
        self.rel.len()
    }

    /// Whether the row is empty.
    pub fn is_empty(self) -> bool {
        self.rel.is_empty()
    }

    /// The column of entry `k`.
    #[inline(always)]
    pub fn get(self, k: usize) -> usize {
        self.base + self.rel[k].at()
    }

    /// The columns, in increasing order.
    #[inline(always)]
    pub fn iter(self) -> impl ExactSizeIterator<Item = usize> + DoubleEndedIterator + 'a {
        let base = self.base;
        self.rel.iter().map(move |c| base + c.at())
    }

    /// The first (smallest) column.
    pub fn first(self) -> Option<usize> {
        self.rel.first().map(|c| self.base + c.at())
    }

    /// The last (largest) column.
    pub fn last(self) -> Option<usize> {
        self.rel.last().map(|c| self.base + c.at())
    }

    /// The entry at column `j`, if the row holds it.
    pub fn find(self, j: usize) -> Option<usize> {
        let r = j.checked_sub(self.base)?;
        self.rel.binary_search_by(|c| c.at().cmp(&r)).ok()
    }
}

/// The column indices as a [`super::Csr`] owns them.
#[derive(Clone, Debug)]
pub(super) enum StoredColumns {
    Plain(Vec<u32>),
    /// Row i's stencil at `table[start[i]..]`: d, then the offsets r_k of
    /// its columns i − d + r_k (r_0 = 0: d is i minus the first column).
    Shared {
        table: Vec<u32>,
        start: Vec<u32>,
        entries: usize,
    },
}

/// The column indices as read: a row's through [`Columns::row`].
#[derive(Clone, Copy, Debug)]
pub enum Columns<'a> {
    Plain(&'a [u32]),
    Shared { table: &'a [u32], start: &'a [u32] },
}

impl<'a> Columns<'a> {
    /// Row `i`'s columns; `lo..hi` are its stored positions (the matrix's
    /// row offsets i and i + 1).
    #[inline(always)]
    pub fn row(self, i: usize, lo: usize, hi: usize) -> RowColumns<'a> {
        match self {
            Columns::Plain(c) => RowColumns {
                base: 0,
                rel: &c[lo..hi],
            },
            Columns::Shared { table, start } => {
                let s = start[i] as usize;
                RowColumns {
                    base: i - table[s] as usize,
                    rel: &table[s + 1..s + 1 + (hi - lo)],
                }
            }
        }
    }
}

impl StoredColumns {
    pub(super) fn view(&self) -> Columns<'_> {
        match self {
            StoredColumns::Plain(c) => Columns::Plain(c),
            StoredColumns::Shared { table, start, .. } => Columns::Shared { table, start },
        }
    }

    /// Number of stored entries.
    pub(super) fn entries(&self) -> usize {
        match self {
            StoredColumns::Plain(c) => c.len(),
            StoredColumns::Shared { entries, .. } => *entries,
        }
    }

    /// The columns of `cols` (`offsets`: the row offsets) as stencils kept
    /// once, if the distinct ones fit [`MAX_STENCILS`] numbers and every
    /// row's first column is at most its own index; None otherwise.
    pub(super) fn share<O: ColumnIndex>(offsets: &[O], cols: &[u32]) -> Option<StoredColumns> {
        let mut sharer = StencilSharer::with_rows(offsets.len() - 1);
        for (i, w) in offsets.windows(2).enumerate() {
            if !sharer.push(i, &cols[w[0].at()..w[1].at()]) {
                return None;
            }
        }
        Some(sharer.finish())
    }

    /// Every row's columns whole, in stored order.
    pub(super) fn to_vec<O: ColumnIndex>(&self, offsets: &[O]) -> Vec<u32> {
        match self {
            StoredColumns::Plain(c) => c.clone(),
            StoredColumns::Shared { .. } => whole(self.view(), offsets, self.entries()),
        }
    }
}

/// The columns of the rows of `offsets` read through `view`, whole.
fn whole<O: ColumnIndex>(view: Columns<'_>, offsets: &[O], entries: usize) -> Vec<u32> {
    let mut out = Vec::with_capacity(entries);
    for (i, w) in offsets.windows(2).enumerate() {
        out.extend(view.row(i, w[0].at(), w[1].at()).iter().map(|c| c as u32));
    }
    out
}

/// Stencils are kept once only while they take at most this many numbers
/// (256 KB): a matrix with more distinct stencils keeps its columns whole.
pub(super) const MAX_STENCILS: usize = 1 << 16;

/// Builds shared columns row by row, so that an assembly never holds its
/// columns whole ([`StoredColumns::share`] for columns already whole). A
/// row's stencil is the word d (its distance to its first column)
/// followed by its columns' offsets from that first column.
pub(super) struct StencilSharer {
    rows: Sharer<u32>,
    /// The stencil of the row being taken (scratch: no allocation a row).
    stencil: Vec<u32>,
    entries: usize,
}

impl StencilSharer {
    pub(super) fn with_rows(rows: usize) -> Self {
        Self {
            rows: Sharer::with_rows(rows, MAX_STENCILS),
            stencil: Vec::new(),
            entries: 0,
        }
    }

    /// Takes row `i` (the rows in order from 0), its columns `cols`
    /// increasing. False if it cannot be shared: its first column is
    /// beyond i, or the stencils would exceed [`MAX_STENCILS`].
    pub(super) fn push(&mut self, i: usize, cols: &[u32]) -> bool {
        debug_assert_eq!(i, self.rows.start.len(), "rows in order");
        let first = cols.first().map_or(i, |&c| c as usize);
        let Some(d) = i.checked_sub(first).and_then(|d| u32::try_from(d).ok()) else {
            return false;
        };
        self.stencil.clear();
        self.stencil.push(d);
        self.stencil.extend(cols.iter().map(|&c| c - first as u32));
        if !self.rows.push(&self.stencil) {
            return false;
        }
        self.entries += cols.len();
        true
    }

    /// The rows taken so far, each whole, in order (`offsets`: their row
    /// offsets), for a matrix that turned out to have too many stencils.
    pub(super) fn to_plain<O: ColumnIndex>(&self, offsets: &[O]) -> Vec<u32> {
        let view = Columns::Shared {
            table: &self.rows.table,
            start: &self.rows.start,
        };
        whole(view, offsets, self.entries)
    }

    pub(super) fn finish(self) -> StoredColumns {
        let (table, start) = self.rows.finish();
        StoredColumns::Shared {
            table,
            start,
            entries: self.entries,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A banded matrix's interior rows share one stencil; every row reads
    /// back its own columns; a row whose first column lies beyond its index
    /// is not shared.
    #[test]
    fn stencils_read_back_every_row() {
        let n: usize = 50;
        let (mut offsets, mut cols) = (vec![0usize], Vec::new());
        for i in 0..n {
            for j in [i.wrapping_sub(7), i.wrapping_sub(1), i, i + 1, i + 7] {
                if j < n {
                    cols.push(j as u32);
                }
            }
            offsets.push(cols.len());
        }
        let shared = StoredColumns::share(&offsets, &cols).expect("few stencils");
        let StoredColumns::Shared { table, .. } = &shared else {
            panic!("shared")
        };
        assert!(table.len() < 100, "{} numbers", table.len());
        assert_eq!(shared.to_vec(&offsets), cols);
        let view = shared.view();
        for i in 0..n {
            let row = view.row(i, offsets[i], offsets[i + 1]);
            let expected: Vec<usize> = cols[offsets[i]..offsets[i + 1]]
                .iter()
                .map(|&c| c as usize)
                .collect();
            assert_eq!(row.iter().collect::<Vec<_>>(), expected);
            assert_eq!(row.find(i), expected.iter().position(|&c| c == i));
            assert_eq!(row.find(n + 3), None);
        }
        // Row 0 holds column 1 only: its first column is beyond it.
        assert!(StoredColumns::share(&[0usize, 1], &[1]).is_none());
    }
}
