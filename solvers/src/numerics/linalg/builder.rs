//! A [`Csr`] built row by row with its stencils and rows of values kept
//! once as they come ([`Csr::shared`]'s storage), so that an assembly never
//! holds the whole arrays: at h = 1/4096 those were 16 bytes per entry,
//! 7.5 GB, for a matrix that keeps 0.3 GB.

use super::columns::{StencilSharer, StoredColumns};
use super::csr::{Csr, CsrError, Offset};
use super::values::{RowSharer, Stored};

/// Where the columns go: shared while they can be, whole after.
enum ColumnSink {
    Sharing(StencilSharer),
    Plain(Vec<u32>),
}

/// Where one matrix's values go, likewise.
enum ValueSink {
    Sharing(RowSharer),
    Plain(Vec<f64>),
}

/// K matrices on one pattern, built row by row ([`CsrBuilder::push_row`]).
pub struct CsrBuilder<const K: usize> {
    ncols: usize,
    offsets: Vec<Offset>,
    /// The entries outgrew 32-bit offsets: the rows that follow are
    /// dropped and [`CsrBuilder::finish`] refuses the matrix.
    entries_beyond: Option<usize>,
    columns: ColumnSink,
    values: [ValueSink; K],
}

impl<const K: usize> CsrBuilder<K> {
    /// For `nrows` rows (a capacity, not a promise) of `ncols` columns.
    pub fn new(nrows: usize, ncols: usize) -> Self {
        let mut offsets = Vec::with_capacity(nrows + 1);
        offsets.push(0);
        Self {
            ncols,
            offsets,
            entries_beyond: None,
            columns: ColumnSink::Sharing(StencilSharer::with_rows(nrows)),
            values: std::array::from_fn(|_| ValueSink::Sharing(RowSharer::with_rows(nrows))),
        }
    }

    /// Appends the next row: its columns (increasing, below ncols: checked
    /// by [`CsrBuilder::finish`] only where kept whole) and each matrix's
    /// values at them.
    pub fn push_row(&mut self, cols: &[u32], values: [&[f64]; K]) {
        let i = self.offsets.len() - 1;
        let end = self.offsets[i] as usize + cols.len();
        if let Some(beyond) = &mut self.entries_beyond {
            *beyond += cols.len();
            return;
        }
        let Ok(end_offset) = Offset::try_from(end) else {
            self.entries_beyond = Some(end);
            return;
        };
        let done = &self.offsets;
        if let ColumnSink::Sharing(sharer) = &mut self.columns
            && !sharer.push(i, cols)
        {
            self.columns = ColumnSink::Plain(sharer.to_plain(done));
        }
        if let ColumnSink::Plain(c) = &mut self.columns {
            c.extend_from_slice(cols);
        }
        for (sink, row) in self.values.iter_mut().zip(values) {
            debug_assert_eq!(row.len(), cols.len(), "one value per column");
            if let ValueSink::Sharing(sharer) = sink
                && !sharer.push(row)
            {
                let mut plain = sharer.to_plain(done);
                // The row the sharer refused is not among them.
                plain.extend_from_slice(row);
                *sink = ValueSink::Plain(plain);
                continue;
            }
            if let ValueSink::Plain(v) = sink {
                v.extend_from_slice(row);
            }
        }
        self.offsets.push(end_offset);
    }

    /// The K matrices, each with its own copy of the pattern (a few
    /// hundred numbers when shared), checked like
    /// [`Csr::try_from_csr_data`]'s arrays.
    pub fn finish(self) -> Result<[Csr; K], CsrError> {
        let Self {
            ncols,
            offsets,
            entries_beyond,
            columns,
            values,
        } = self;
        if let Some(entries) = entries_beyond {
            return Err(CsrError::TooManyEntries(entries));
        }
        let columns = match columns {
            ColumnSink::Sharing(s) => s.finish(),
            ColumnSink::Plain(c) => StoredColumns::Plain(c),
        };
        let mut out = Vec::with_capacity(K);
        for sink in values {
            let values = match sink {
                ValueSink::Sharing(s) => s.finish(),
                ValueSink::Plain(v) => Stored::Plain(v),
            };
            out.push(Csr::from_parts(
                ncols,
                offsets.clone(),
                columns.clone(),
                values,
            )?);
        }
        Ok(out
            .try_into()
            .unwrap_or_else(|_| unreachable!("one matrix per value sink")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows whose entries add up past what 32-bit offsets hold are refused
    /// with their whole count, not wrapped into a matrix whose rows would
    /// read other rows' entries: 131 073 rows of one band of 32 768
    /// entries, 2³² + 32 768 in all (one stencil and one row of values,
    /// each kept once, so that the test itself holds a few hundred KB).
    #[test]
    fn entries_past_32_bit_offsets_are_refused_whole() {
        let width = 1usize << 15;
        let rows = (1usize << 17) + 1;
        let mut builder = CsrBuilder::<1>::new(rows, rows + width);
        let values = vec![1.0; width];
        let mut cols = vec![0u32; width];
        for i in 0..rows {
            for (q, c) in cols.iter_mut().enumerate() {
                *c = (i + q) as u32;
            }
            builder.push_row(&cols, [&values]);
        }
        assert!(matches!(
            builder.finish(),
            Err(CsrError::TooManyEntries(n)) if n == rows * width
        ));
    }
}
