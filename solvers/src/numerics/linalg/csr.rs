//! Compressed sparse rows with 32-bit column indices: the stiffness matrix
//! A of a contact problem and the multigrid's own matrices.
//!
//! Why not `nalgebra_sparse::CsrMatrix`: its column indices are `usize`, 8
//! bytes beside each 8-byte value. At h = 1/1024 A has 33.6 million stored
//! entries, so its indices were 269 MB of a 1.2 GiB solve, and every
//! Gauss–Seidel sweep and product streams them. 32 bits hold any column of
//! a mesh up to 2³² − 1 unknowns (h = 1/4096 has 3.4·10⁷), and the row
//! offsets are 32-bit too ([`Offset`]): h = 1/8192 has 1.9·10⁹ entries,
//! below 2³², and a larger matrix would not fit this machine's memory
//! anyway; one that outgrows them is refused ([`CsrError::TooManyEntries`]).
//! Offsets of `usize` were 8 bytes per row of every matrix, A's and the
//! prolongations' alike (about 10 of a solve's 157 bytes per unknown at
//! h = 1/4096). Solvers that factorize or
//! hand the matrix to another library convert it ([`Csr::to_nalgebra`]):
//! they need many times its memory anyway.

use nalgebra_sparse::CsrMatrix;
use thiserror::Error;

use super::columns::{Columns, RowColumns, StoredColumns};
use super::values::{RowValues, Stored, Values};

/// A matrix that cannot be held as a [`Csr`].
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CsrError {
    #[error(
        "a sparse matrix with {0} columns: column indices are 32-bit, at most {max} columns",
        max = u32::MAX
    )]
    TooManyColumns(usize),
    #[error(
        "a sparse matrix with {0} stored entries: row offsets are 32-bit, at most {max} entries",
        max = u32::MAX
    )]
    TooManyEntries(usize),
    #[error("sparse matrix: {0}")]
    Malformed(&'static str),
}

/// A row offset as a [`Csr`] stores it.
pub type Offset = u32;

/// A column index or row offset as stored: `usize` (nalgebra's matrices)
/// or `u32` ([`Csr`]), so that one product kernel serves both.
pub trait ColumnIndex: Copy + Send + Sync + 'static {
    /// The index as a `usize`.
    fn at(self) -> usize;
}

impl ColumnIndex for usize {
    #[inline(always)]
    fn at(self) -> usize {
        self
    }
}

impl ColumnIndex for u32 {
    #[inline(always)]
    fn at(self) -> usize {
        self as usize
    }
}

/// Read access to a matrix in compressed rows whose column indices are
/// sorted within each row and below [`SparseRows::ncols`].
pub trait SparseRows: Sync {
    /// The stored column index type.
    type Index: ColumnIndex;
    /// The stored row offset type.
    type Offset: ColumnIndex;
    fn nrows(&self) -> usize;
    fn ncols(&self) -> usize;
    /// nrows + 1 offsets into the stored entries, from 0.
    fn row_offsets(&self) -> &[Self::Offset];
    /// Row i's stored positions, lo..hi.
    #[inline(always)]
    fn row_range(&self, i: usize) -> (usize, usize) {
        let o = self.row_offsets();
        (o[i].at(), o[i + 1].at())
    }
    /// Row i's columns; `lo..hi` are its stored positions (the offsets i
    /// and i + 1).
    fn row_columns(&self, i: usize, lo: usize, hi: usize) -> RowColumns<'_, Self::Index>;
    fn values(&self) -> Values<'_>;
    /// Number of stored entries.
    fn nnz(&self) -> usize {
        self.row_offsets()[self.nrows()].at()
    }
}

impl SparseRows for CsrMatrix<f64> {
    type Index = usize;
    type Offset = usize;
    fn nrows(&self) -> usize {
        CsrMatrix::nrows(self)
    }
    fn ncols(&self) -> usize {
        CsrMatrix::ncols(self)
    }
    fn row_offsets(&self) -> &[usize] {
        CsrMatrix::row_offsets(self)
    }
    #[inline(always)]
    fn row_columns(&self, _: usize, lo: usize, hi: usize) -> RowColumns<'_, usize> {
        RowColumns {
            base: 0,
            rel: &CsrMatrix::col_indices(self)[lo..hi],
        }
    }
    fn values(&self) -> Values<'_> {
        Values::Plain(CsrMatrix::values(self))
    }
}

/// A sparse matrix in compressed rows, 32-bit column indices, sorted and
/// without duplicates within each row (checked on construction); its
/// columns and values stored row by row or, after [`Csr::shared`], each
/// distinct stencil and row of values once (see [`super::columns`] and
/// [`super::values`]).
#[derive(Clone, Debug)]
pub struct Csr {
    ncols: usize,
    offsets: Vec<Offset>,
    cols: StoredColumns,
    values: Stored,
}

/// Equal when they hold the same entries at the same positions, however
/// their values are stored.
impl PartialEq for Csr {
    fn eq(&self, other: &Csr) -> bool {
        self.same_pattern(other)
            && self
                .values()
                .iter(&self.offsets)
                .eq(other.values().iter(&other.offsets))
    }
}

impl Csr {
    /// From its three arrays, checked: nrows + 1 nondecreasing offsets from
    /// 0 to the number of entries, one value per column index, and the
    /// columns of each row strictly increasing and below `ncols`; at most
    /// 2³² − 1 entries ([`Offset`]).
    pub fn try_from_csr_data(
        nrows: usize,
        ncols: usize,
        offsets: Vec<usize>,
        cols: Vec<u32>,
        values: Vec<f64>,
    ) -> Result<Self, CsrError> {
        if offsets.len() != nrows + 1 {
            return Err(CsrError::Malformed(
                "the row offsets must run from 0 to the number of entries, one per row and one more",
            ));
        }
        let offsets = narrow(&offsets)?;
        Self::from_parts(
            ncols,
            offsets,
            StoredColumns::Plain(cols),
            Stored::Plain(values),
        )
    }

    /// From stored parts, checked as [`Csr::try_from_csr_data`] checks its
    /// arrays (the columns row by row, however they are stored).
    pub(super) fn from_parts(
        ncols: usize,
        offsets: Vec<Offset>,
        cols: StoredColumns,
        values: Stored,
    ) -> Result<Self, CsrError> {
        if ncols > u32::MAX as usize {
            return Err(CsrError::TooManyColumns(ncols));
        }
        let entries = cols.entries();
        if offsets.is_empty() || offsets[0] != 0 || offsets[offsets.len() - 1] as usize != entries {
            return Err(CsrError::Malformed(
                "the row offsets must run from 0 to the number of entries, one per row and one more",
            ));
        }
        if values.view().len() != entries {
            return Err(CsrError::Malformed("one value per stored column index"));
        }
        let view = cols.view();
        for (i, w) in offsets.windows(2).enumerate() {
            let (lo, hi) = (w[0] as usize, w[1] as usize);
            if lo > hi || hi > entries {
                return Err(CsrError::Malformed("the row offsets must not decrease"));
            }
            let row = view.row(i, lo, hi);
            if row.rel.windows(2).any(|w| w[0] >= w[1]) || row.last().is_some_and(|c| c >= ncols) {
                return Err(CsrError::Malformed(
                    "the columns of a row must increase strictly and stay below the column count",
                ));
            }
        }
        Ok(Self {
            ncols,
            offsets,
            cols,
            values,
        })
    }

    /// The same matrix with each distinct row of values stored once, if
    /// they are few (a stiffness on a uniform mesh: 45 rows, whatever h;
    /// at most 2¹⁶ values in all), and likewise each distinct stencil of
    /// columns ([`super::columns`]); each as it is otherwise. Every row
    /// reads back to the bit, so every product and sweep gives the same
    /// numbers, without the 8 bytes per entry of its values and the 4 of
    /// its columns.
    pub fn shared(mut self) -> Csr {
        if let Stored::Plain(v) = &self.values
            && let Some(shared) = Stored::share(&self.offsets, v)
        {
            self.values = shared;
        }
        if let StoredColumns::Plain(c) = &self.cols
            && let Some(shared) = StoredColumns::share(&self.offsets, c)
        {
            self.cols = shared;
        }
        self
    }

    /// Whether the columns are kept as stencils ([`Csr::shared`]).
    pub fn has_shared_columns(&self) -> bool {
        matches!(self.cols, StoredColumns::Shared { .. })
    }

    /// Row i's values, to change in place without giving up the sharing of
    /// the others: a shared row whose values start before `own_from` (the
    /// table's length when the caller began to change rows) is first given
    /// a copy of its own at the table's end. Returns the values and, when a
    /// copy was made, the start the row had ([`Csr::unshare_undo`] puts it
    /// back). Plain values: the row's own, and None.
    pub fn row_values_mut(&mut self, i: usize, own_from: usize) -> (&mut [f64], Option<u32>) {
        let (lo, hi) = self.row_range(i);
        match &mut self.values {
            Stored::Plain(v) => (&mut v[lo..hi], None),
            Stored::Shared { table, start, .. } => {
                let s = start[i] as usize;
                let moved = (s < own_from).then(|| {
                    let from = table.len();
                    table.extend_from_within(s..s + (hi - lo));
                    let before = start[i];
                    start[i] = u32::try_from(from).expect("a shared table stays below 2³² values");
                    before
                });
                let s = start[i] as usize;
                (&mut table[s..s + (hi - lo)], moved)
            }
        }
    }

    /// Undoes [`Csr::row_values_mut`]'s copies: each row (row, start before)
    /// back at its shared start, the table cut back to `len` values.
    /// Nothing for plain values.
    pub fn unshare_undo(&mut self, rows: impl IntoIterator<Item = (usize, u32)>, len: usize) {
        if let Stored::Shared { table, start, .. } = &mut self.values {
            for (i, s) in rows {
                start[i] = s;
            }
            table.truncate(len);
        }
    }

    /// How many numbers the values take: one per stored entry, or the
    /// distinct rows' when they are shared.
    pub fn stored_values(&self) -> usize {
        match &self.values {
            Stored::Plain(v) => v.len(),
            Stored::Shared { table, .. } => table.len(),
        }
    }

    /// How many numbers the column indices take: one per stored entry, or
    /// the distinct stencils' when they are shared.
    pub fn stored_columns(&self) -> usize {
        match &self.cols {
            StoredColumns::Plain(c) => c.len(),
            StoredColumns::Shared { table, .. } => table.len(),
        }
    }

    /// Whether the distinct rows are stored once ([`Csr::shared`]).
    pub fn is_shared(&self) -> bool {
        matches!(self.values, Stored::Shared { .. })
    }

    /// The same matrix as a nalgebra one (a copy with 64-bit indices), for
    /// a solver that factorizes or hands it to another library.
    pub fn to_nalgebra(&self) -> CsrMatrix<f64> {
        self.nalgebra_with_values(self.values().to_vec(&self.offsets))
    }

    /// The nalgebra matrix with this pattern and other `values` (one per
    /// stored entry, in order), such as the mass matrix kept on A's pattern.
    ///
    /// # Panics
    /// If `values` does not have one entry per stored entry.
    pub fn nalgebra_with_values(&self, values: Vec<f64>) -> CsrMatrix<f64> {
        assert_eq!(values.len(), self.nnz(), "one value per stored entry");
        let cols = (0..self.nrows())
            .flat_map(|i| self.row_columns(i).iter())
            .collect();
        let offsets = self.offsets.iter().map(|&o| o as usize).collect();
        CsrMatrix::try_from_csr_data(self.nrows(), self.ncols, offsets, cols, values)
            .expect("checked on construction: sorted rows, columns in range")
    }

    pub fn nrows(&self) -> usize {
        self.offsets.len() - 1
    }

    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.cols.entries()
    }

    pub fn row_offsets(&self) -> &[Offset] {
        &self.offsets
    }

    /// Row i's stored positions, lo..hi.
    #[inline(always)]
    pub fn row_range(&self, i: usize) -> (usize, usize) {
        (self.offsets[i] as usize, self.offsets[i + 1] as usize)
    }

    /// The stored columns: read a row's with [`Columns::row`] or
    /// [`Csr::row_columns`].
    pub fn columns(&self) -> Columns<'_> {
        self.cols.view()
    }

    /// Row i's columns.
    #[inline(always)]
    pub fn row_columns(&self, i: usize) -> RowColumns<'_> {
        let (lo, hi) = self.row_range(i);
        self.columns().row(i, lo, hi)
    }

    /// Every column index whole, in stored order, for a solver that hands
    /// the matrix to another library: a copy of all of them when the
    /// columns are shared, so never in a loop (the paper's sweep once took
    /// it per sweep); a kernel reads a row with [`Csr::row`] or
    /// [`Csr::columns`].
    pub fn whole_col_indices(&self) -> std::borrow::Cow<'_, [u32]> {
        match &self.cols {
            StoredColumns::Plain(c) => std::borrow::Cow::Borrowed(c),
            shared => std::borrow::Cow::Owned(shared.to_vec(&self.offsets)),
        }
    }

    /// The stored values: read a row's with [`RowValues::row`].
    pub fn values(&self) -> Values<'_> {
        self.values.view()
    }

    /// The stored values in order, to change in place (the pattern stays);
    /// shared rows are copied out first, for good.
    pub fn values_mut(&mut self) -> &mut [f64] {
        self.values.make_plain(&self.offsets)
    }

    /// The value at stored position `p`, which row `i` holds.
    ///
    /// # Panics
    /// If it does not.
    pub fn value_at(&self, i: usize, p: usize) -> f64 {
        self.values().at(&self.offsets, i, p)
    }

    /// Offsets, column indices (whole: a copy when shared) and values.
    pub fn csr_data(&self) -> (&[Offset], std::borrow::Cow<'_, [u32]>, Values<'_>) {
        (&self.offsets, self.whole_col_indices(), self.values())
    }

    /// Row i's columns and values.
    #[inline(always)]
    pub fn row(&self, i: usize) -> (RowColumns<'_>, &[f64]) {
        let (lo, hi) = self.row_range(i);
        (self.columns().row(i, lo, hi), self.values().row(i, lo, hi))
    }

    /// The position of entry (i, j) among the stored entries, if stored.
    pub fn position(&self, i: usize, j: usize) -> Option<usize> {
        self.row_columns(i).find(j).map(|q| self.row_range(i).0 + q)
    }

    /// Whether both have the same rows, columns and stored positions.
    pub fn same_pattern(&self, other: &Csr) -> bool {
        self.ncols == other.ncols
            && self.offsets == other.offsets
            && (0..self.nrows()).all(|i| self.row_columns(i).iter().eq(other.row_columns(i).iter()))
    }

    /// The stored entries as (row, column, value), row by row.
    pub fn triplet_iter(&self) -> impl Iterator<Item = (usize, usize, &f64)> {
        (0..self.nrows()).flat_map(move |i| {
            let (cols, vals) = self.row(i);
            cols.iter().zip(vals).map(move |(c, v)| (i, c, v))
        })
    }

    /// The transpose (a new matrix, its values and columns stored like
    /// these).
    pub fn transpose(&self) -> Csr {
        let (m, n) = (self.nrows(), self.ncols);
        let mut offsets: Vec<Offset> = vec![0; n + 1];
        for i in 0..m {
            for c in self.row_columns(i).iter() {
                offsets[c + 1] += 1;
            }
        }
        for j in 0..n {
            offsets[j + 1] += offsets[j];
        }
        let mut next: Vec<usize> = offsets[..n].iter().map(|&o| o as usize).collect();
        let (mut cols, mut values) = (vec![0u32; self.nnz()], vec![0.0; self.nnz()]);
        for i in 0..m {
            let (row_cols, row_vals) = self.row(i);
            for (j, &v) in row_cols.iter().zip(row_vals) {
                cols[next[j]] = i as u32;
                values[next[j]] = v;
                next[j] += 1;
            }
        }
        let t = Csr {
            ncols: m,
            offsets,
            cols: StoredColumns::Plain(cols),
            values: Stored::Plain(values),
        };
        if self.is_shared() || self.has_shared_columns() {
            t.shared()
        } else {
            t
        }
    }
}

/// A matrix a problem takes ([`crate::ContactProblem::new`]'s A, its
/// prolongations): a [`Csr`] as it is, or a nalgebra matrix, converted to
/// 32-bit column indices.
pub trait IntoCsr {
    fn into_csr(self) -> Result<Csr, CsrError>;
}

impl IntoCsr for Csr {
    fn into_csr(self) -> Result<Csr, CsrError> {
        Ok(self)
    }
}

impl IntoCsr for CsrMatrix<f64> {
    fn into_csr(self) -> Result<Csr, CsrError> {
        Csr::try_from(self)
    }
}

impl TryFrom<CsrMatrix<f64>> for Csr {
    type Error = CsrError;

    /// Takes the offsets and values over; the 64-bit column indices are
    /// converted, then freed.
    fn try_from(m: CsrMatrix<f64>) -> Result<Self, CsrError> {
        let (nrows, ncols) = (m.nrows(), m.ncols());
        if ncols > u32::MAX as usize || nrows > u32::MAX as usize {
            return Err(CsrError::TooManyColumns(ncols.max(nrows)));
        }
        let (offsets, cols, values) = m.disassemble();
        let offsets = narrow(&offsets)?;
        let cols = cols.into_iter().map(|c| c as u32).collect();
        Ok(Self {
            ncols,
            offsets,
            cols: StoredColumns::Plain(cols),
            values: Stored::Plain(values),
        })
    }
}

impl TryFrom<&CsrMatrix<f64>> for Csr {
    type Error = CsrError;

    fn try_from(m: &CsrMatrix<f64>) -> Result<Self, CsrError> {
        Csr::try_from(m.clone())
    }
}

impl SparseRows for Csr {
    type Index = u32;
    type Offset = Offset;
    fn nrows(&self) -> usize {
        Csr::nrows(self)
    }
    fn ncols(&self) -> usize {
        self.ncols
    }
    fn row_offsets(&self) -> &[Offset] {
        &self.offsets
    }
    #[inline(always)]
    fn row_columns(&self, i: usize, lo: usize, hi: usize) -> RowColumns<'_, u32> {
        self.columns().row(i, lo, hi)
    }
    fn nnz(&self) -> usize {
        self.cols.entries()
    }
    fn values(&self) -> Values<'_> {
        Csr::values(self)
    }
}

/// Row offsets in 32 bits, or the first offset that does not fit. Filled
/// into a vector of its final size (collected from `Result`s, it would
/// grow by doubling, as the diagonal positions once did).
fn narrow(offsets: &[usize]) -> Result<Vec<Offset>, CsrError> {
    let mut out = Vec::with_capacity(offsets.len());
    for &o in offsets {
        out.push(Offset::try_from(o).map_err(|_| CsrError::TooManyEntries(o))?);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::CooMatrix;

    fn example() -> CsrMatrix<f64> {
        let mut coo = CooMatrix::new(3, 4);
        for (i, j, v) in [(0, 0, 2.0), (0, 3, -1.0), (2, 1, 3.0), (2, 2, 0.5)] {
            coo.push(i, j, v);
        }
        CsrMatrix::from(&coo)
    }

    /// To and from nalgebra the matrix is the same, entry by entry; the
    /// transpose agrees with nalgebra's.
    #[test]
    fn round_trips_through_nalgebra_and_transposes_like_it() {
        let m = example();
        let c = Csr::try_from(&m).unwrap();
        assert_eq!(c.to_nalgebra(), m);
        assert_eq!(c.transpose().to_nalgebra(), m.transpose());
        let triplets: Vec<_> = c.triplet_iter().map(|(i, j, &v)| (i, j, v)).collect();
        let expected: Vec<_> = m.triplet_iter().map(|(i, j, &v)| (i, j, v)).collect();
        assert_eq!(triplets, expected);
        assert_eq!(c.row(2).0.iter().collect::<Vec<_>>(), [1, 2]);
        assert_eq!(c.row(2).1, &[3.0, 0.5][..]);
        let shared = c.clone().shared();
        assert!(shared.is_shared());
        assert!(shared.has_shared_columns());
        assert_eq!(shared, c);
        assert_eq!(shared.to_nalgebra(), m);
        assert_eq!(shared.row(2), c.row(2));
        assert_eq!(shared.transpose(), c.transpose());
        assert!(shared.transpose().is_shared());
        let mut copied = shared.clone();
        copied.values_mut()[0] = 5.0;
        assert!(!copied.is_shared());
        assert_eq!(copied.value_at(0, 0), 5.0);
        assert_eq!(shared.value_at(2, 3), 0.5);
    }

    /// Each malformed input is refused, with the reason.
    #[test]
    fn refuses_malformed_arrays() {
        let ok = |o: Vec<usize>, c: Vec<u32>| {
            Csr::try_from_csr_data(2, 3, o, c.clone(), vec![1.0; c.len()])
        };
        assert!(ok(vec![0, 1, 2], vec![0, 2]).is_ok());
        assert!(ok(vec![0, 1], vec![0]).is_err(), "too few offsets");
        assert!(ok(vec![1, 1, 2], vec![0, 2]).is_err(), "not from 0");
        assert!(ok(vec![0, 2, 1], vec![0, 2]).is_err(), "decreasing");
        assert!(ok(vec![0, 2, 2], vec![2, 1]).is_err(), "unsorted");
        assert!(ok(vec![0, 2, 2], vec![1, 1]).is_err(), "duplicate");
        assert!(
            ok(vec![0, 1, 2], vec![0, 3]).is_err(),
            "column out of range"
        );
        assert!(Csr::try_from_csr_data(1, 1, vec![0, 1], vec![0], vec![]).is_err());
        assert!(matches!(
            Csr::try_from_csr_data(0, 1 << 33, vec![0], vec![], vec![]),
            Err(CsrError::TooManyColumns(_))
        ));
        // Offsets past 2³² − 1 are refused before anything is checked or
        // allocated for the entries.
        assert_eq!(
            Csr::try_from_csr_data(1, 1, vec![0, 1 << 32], vec![0], vec![1.0]),
            Err(CsrError::TooManyEntries(1 << 32))
        );
    }
}
