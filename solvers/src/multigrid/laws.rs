//! The contact law φ_k of every unknown, stored for the contact unknowns
//! alone: a [`Local`] is 32 bytes, and all but O(h⁻¹) of the O(h⁻²)
//! unknowns are free (at h = 1/1024 a law per unknown was 67 MB of a solve's
//! peak; a slot index per unknown is 8 MB).

use std::ops::Index;

use super::smoother::Local;

/// No slot: the unknown's law is `Free`.
const FREE_SLOT: u32 = u32::MAX;
static FREE: Local = Local::Free;

/// φ_k for k = 0 … n−1, indexed like a slice of laws.
#[derive(Clone, Debug)]
pub(crate) struct Laws {
    /// Each unknown's slot in `local`, or [`FREE_SLOT`].
    slot: Vec<u32>,
    /// The laws of the unknowns that have a slot.
    local: Vec<Local>,
    /// Those unknowns, in the order their slots were given.
    at: Vec<usize>,
}

impl Laws {
    /// n unknowns, every one free.
    pub(crate) fn free(n: usize) -> Self {
        Self {
            slot: vec![FREE_SLOT; n],
            local: Vec::new(),
            at: Vec::new(),
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
        match self.slot[k] {
            FREE_SLOT => {
                self.slot[k] =
                    u32::try_from(self.local.len()).expect("fewer than 2³² contact unknowns");
                self.local.push(law);
                self.at.push(k);
            }
            s => self.local[s as usize] = law,
        }
    }

    /// Every unknown free again, in O(contact unknowns).
    pub(crate) fn clear(&mut self) {
        for &k in &self.at {
            self.slot[k] = FREE_SLOT;
        }
        self.local.clear();
        self.at.clear();
    }
}

impl Index<usize> for Laws {
    type Output = Local;

    #[inline]
    fn index(&self, k: usize) -> &Local {
        match self.slot[k] {
            FREE_SLOT => &FREE,
            s => &self.local[s as usize],
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
        laws.set(4, Local::Jump);
        laws.set(1, Local::Slip(0.5));
        laws.set(4, Local::Slip(2.0));
        let read: Vec<Local> = (0..6).map(|k| laws[k]).collect();
        use Local::*;
        assert_eq!(read, [Free, Slip(0.5), Free, Free, Slip(2.0), Free]);
        laws.clear();
        assert!((0..6).all(|k| laws[k] == Free));
        laws.set(2, Jump);
        assert_eq!(laws[2], Jump);
    }
}
