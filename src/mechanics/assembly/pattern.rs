//! The pattern an assembly writes (32-bit columns, as A is kept) and the
//! append of one row's entries.

use crate::solvers::Csr;

/// The stored positions of an assembled matrix: row offsets and sorted
/// 32-bit column indices (the [`Csr`] layout, half the index memory of a
/// nalgebra pattern).
#[derive(Debug, PartialEq)]
pub struct Pattern {
    pub(super) offsets: Vec<usize>,
    pub(super) columns: Vec<u32>,
}

impl Pattern {
    /// The matrix with these positions and `values` (one per position).
    pub fn with_values(self, values: Vec<f64>) -> Csr {
        let n = self.offsets.len() - 1;
        Csr::try_from_csr_data(n, n, self.offsets, self.columns, values)
            .expect("an assembly's rows are sorted, distinct, in range, one value each")
    }
}

/// Appends `get` of each of `from` to `v`: one reservation, then a loop
/// that only writes. Pushing entry by entry into three arrays at once
/// stored each length back per entry, `extend` stayed a call per row, and
/// `resize` wrote every entry twice; this is 0.9 × the first's time at 1/64.
#[inline(always)]
pub(super) fn append<T, S>(v: &mut Vec<T>, from: &[S], get: impl Fn(&S) -> T) {
    v.reserve(from.len());
    let len = v.len();
    for (slot, s) in v.spare_capacity_mut().iter_mut().zip(from) {
        slot.write(get(s));
    }
    // SAFETY: the reservation left at least from.len() spare slots, and the
    // loop wrote the first from.len() of them.
    unsafe { v.set_len(len + from.len()) };
}
