//! The contact law φ_k of every unknown, stored for the contact unknowns
//! alone: a [`Local`] is 32 bytes, and all but O(h⁻¹) of the O(h⁻²)
//! unknowns are free (at h = 1/1024 a law per unknown was 67 MB of a solve's
//! peak). Which unknowns have a law is one bit each (a 32-bit slot per
//! unknown was 4 bytes of a solve's 185 per unknown at h = 1/4096); the
//! slot of one that has is looked up in a map of the O(h⁻¹) contact
//! unknowns.

use std::collections::HashMap;
use std::ops::Index;

use super::smoother::Local;

static FREE: Local = Local::Free;

/// φ_k for k = 0 … n−1, indexed like a slice of laws.
#[derive(Clone, Debug)]
pub(crate) struct Laws {
    /// Bit k % 64 of word k / 64: whether unknown k has a slot.
    has_slot: Vec<u64>,
    /// The slot in `local` of each unknown that has one.
    slot: HashMap<usize, u32>,
    /// The laws of the unknowns that have a slot.
    local: Vec<Local>,
}

impl Laws {
    /// n unknowns, every one free.
    pub(crate) fn free(n: usize) -> Self {
        Self {
            has_slot: vec![0; n.div_ceil(64)],
            slot: HashMap::new(),
            local: Vec::new(),
        }
    }

    /// The laws of a slice (the tests' small cases).
    #[cfg(test)]
    pub(crate) fn of(laws: &[Local]) -> Self {
        let mut out = Self::free(laws.len());
        for (k, &law) in laws.iter().enumerate() {
            if law != Local::Free {
                out.set(k, law);
            }
        }
        out
    }

    /// φ_k = `law`.
    pub(crate) fn set(&mut self, k: usize, law: Local) {
        let next = u32::try_from(self.local.len()).expect("fewer than 2³² contact unknowns");
        let s = *self.slot.entry(k).or_insert(next);
        if s == next {
            self.has_slot[k / 64] |= 1 << (k % 64);
            self.local.push(law);
        } else {
            self.local[s as usize] = law;
        }
    }

    /// Every unknown free again, in O(contact unknowns).
    pub(crate) fn clear(&mut self) {
        for &k in self.slot.keys() {
            self.has_slot[k / 64] &= !(1 << (k % 64));
        }
        self.slot.clear();
        self.local.clear();
    }
}

impl Index<usize> for Laws {
    type Output = Local;

    #[inline]
    fn index(&self, k: usize) -> &Local {
        if self.has_slot[k / 64] & (1 << (k % 64)) == 0 {
            &FREE
        } else {
            &self.local[self.slot[&k] as usize]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Set, overwritten, read back and cleared: every unknown reads the law
    /// last given to it, and free after a clear.
    #[test]
    fn laws_read_back_what_was_set() {
        let mut laws = Laws::free(6);
        laws.set(4, Local::Jump(0.0));
        laws.set(1, Local::Slip(0.5));
        laws.set(4, Local::Slip(2.0));
        let read: Vec<Local> = (0..6).map(|k| laws[k]).collect();
        use Local::*;
        assert_eq!(read, [Free, Slip(0.5), Free, Free, Slip(2.0), Free]);
        laws.clear();
        assert!((0..6).all(|k| laws[k] == Free));
        laws.set(2, Jump(0.5));
        assert_eq!(laws[2], Jump(0.5));
    }
}
