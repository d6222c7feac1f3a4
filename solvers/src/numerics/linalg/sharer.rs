//! Each distinct row kept once, as it comes: the table behind a matrix's
//! shared stencils ([`super::columns`]) and shared values
//! ([`super::values`]). A row is looked for first among the last rows'
//! (on a mesh a row is mostly that of a row shortly before it), then by
//! its hash; a new one is appended to the table, up to a cap.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// How many of the last rows' starts [`Sharer::push`] tries before it
/// hashes a row.
const RECENT: usize = 4;

/// The rows' own hash ([`row_hash`]) is the map's key: no second hashing.
#[derive(Default)]
struct Prehashed(u64);

impl Hasher for Prehashed {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, _: &[u8]) {
        unreachable!("only u64 keys are hashed")
    }
    fn write_u64(&mut self, h: u64) {
        self.0 = h;
    }
}

/// A word of a shared table, compared and hashed by its bits: a value's
/// −0.0 apart from 0.0 and a NaN's payload kept, so that sharing gives
/// back every bit.
pub(super) trait Word: Copy {
    fn bits(self) -> u64;
}

impl Word for u32 {
    #[inline(always)]
    fn bits(self) -> u64 {
        u64::from(self)
    }
}

impl Word for f64 {
    #[inline(always)]
    fn bits(self) -> u64 {
        self.to_bits()
    }
}

/// A hash of a row's bits and length.
fn row_hash<W: Word>(row: &[W]) -> u64 {
    row.iter().fold(row.len() as u64, |h, &w| {
        (h ^ w.bits())
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .rotate_left(29)
    })
}

/// Whether `table` holds `row` from `start` on, bit for bit. (A loop, not
/// `==` on slices: that calls memcmp, whose call costs more than a
/// stencil's dozen words, and compares floats by value.)
fn holds<W: Word>(table: &[W], start: u32, row: &[W]) -> bool {
    let s = start as usize;
    table
        .get(s..s + row.len())
        .is_some_and(|t| t.iter().zip(row).all(|(a, b)| a.bits() == b.bits()))
}

/// The distinct rows met so far, each once in `table`, and where each row
/// taken starts in it.
pub(super) struct Sharer<W> {
    pub(super) table: Vec<W>,
    pub(super) start: Vec<u32>,
    seen: HashMap<u64, Vec<u32>, BuildHasherDefault<Prehashed>>,
    /// The starts of the last rows met.
    recent: [u32; RECENT],
    /// The most words the table may hold.
    max: usize,
}

impl<W: Word> Sharer<W> {
    /// For `rows` rows (a capacity), the table capped at `max` words.
    pub(super) fn with_rows(rows: usize, max: usize) -> Self {
        Self {
            table: Vec::new(),
            start: Vec::with_capacity(rows),
            seen: HashMap::default(),
            recent: [u32::MAX; RECENT],
            max,
        }
    }

    /// Takes the next row; false, and nothing taken, if it is new and
    /// would take the table past its cap. A row may start inside a longer
    /// one (its prefix).
    pub(super) fn push(&mut self, row: &[W]) -> bool {
        let i = self.start.len();
        // Row i − 2 first: the same kind of node's other component comes
        // two rows on.
        let mut order = (0..RECENT).map(|back| self.recent[(i + RECENT - 2 + back) % RECENT]);
        if let Some(s) = order.find(|&s| holds(&self.table, s, row)) {
            self.start.push(s);
            return true;
        }
        let candidates = self.seen.entry(row_hash(row)).or_default();
        let found = candidates
            .iter()
            .copied()
            .find(|&s| holds(&self.table, s, row));
        let s = match found {
            Some(s) => s,
            None => {
                if self.table.len() + row.len() > self.max {
                    return false;
                }
                let s = self.table.len() as u32;
                self.table.extend_from_slice(row);
                candidates.push(s);
                s
            }
        };
        self.start.push(s);
        self.recent[i % RECENT] = s;
        true
    }

    /// The table, fitted to its length, and the rows' starts.
    pub(super) fn finish(mut self) -> (Vec<W>, Vec<u32>) {
        self.table.shrink_to_fit();
        (self.table, self.start)
    }
}
