//! Gauss-Seidel on both cores: an ordering of the unknowns in two halves
//! that do not couple, and the separator between them.
//!
//! Gauss-Seidel converges in any ordering of the unknowns (it is the
//! coordinate descent of a convex energy), so an ordering that lets two
//! threads sweep at once changes the smoother's bits, not what it is. The
//! classic one is a nested-dissection split (George 1973): rows [0, m) and
//! the rows ≥ m that couple to none of them sweep at the same time, then the
//! separator S = {k ≥ m : A_kj ≠ 0 for some j < m} in order. In the paper's
//! meshes, numbered row by row, S is a band of about two mesh rows, so the
//! sequential tail is O(h⁻¹) of O(h⁻²) unknowns. Nothing here looks at a
//! mesh: m is chosen from A's pattern alone, for the least work on the
//! longer of the two threads plus the separator, and the split is checked
//! entry by entry (no half reads an unknown the other half writes).
//!
//! Forward: both halves ascending, then S ascending. Backward: the exact
//! reverse (S descending, then both halves descending), so that a forward
//! and a backward sweep make a symmetric Gauss-Seidel as before.

use crate::numerics::linalg::{Csr, PARALLEL_NNZ, row_dot_by};

/// Above this share of the stored entries in the separator the split is
/// not worth a thread (a matrix numbered without locality).
const LARGEST_SEPARATOR_SHARE: f64 = 0.05;

/// The two halves of a matrix's rows and their separator.
#[derive(Clone, Debug)]
pub(crate) struct Halves {
    /// Rows [0, split) are the first half.
    split: usize,
    /// Rows ≥ split in the separator (the rest of them: the second half).
    in_separator: Vec<bool>,
    /// The separator's rows, ascending.
    separator: Vec<usize>,
}

/// The vector a sweep updates, shared by the two threads of a split sweep.
/// Each writes only the unknowns of its half and reads only its half and
/// the separator, which nobody writes meanwhile (checked by
/// [`Halves::new`]): the accesses through it never race.
#[derive(Clone, Copy)]
pub(crate) struct Shared(*mut f64);

// SAFETY: see the type: the two threads touch disjoint unknowns, except the
// separator's, which both only read.
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

impl Shared {
    /// The vector `x`, to be written through while `x` is borrowed by the
    /// sweep that uses it.
    pub(crate) fn of(x: &mut [f64]) -> Self {
        Shared(x.as_mut_ptr())
    }

    /// x[k].
    ///
    /// # Safety
    /// k is below the length of the vector it was made from, and no other
    /// thread writes x[k] meanwhile.
    #[inline]
    pub(crate) unsafe fn get(self, k: usize) -> f64 {
        unsafe { *self.0.add(k) }
    }

    /// x[k] = value.
    ///
    /// # Safety
    /// k is below the vector's length, and no other thread touches x[k]
    /// meanwhile.
    #[inline]
    pub(crate) unsafe fn set(self, k: usize, value: f64) {
        unsafe { *self.0.add(k) = value }
    }

    /// Σ_q vals[q]·x[cols[q]], the partial sums of
    /// [`crate::numerics::linalg::row_dot`].
    ///
    /// # Safety
    /// Every entry of `cols` is below the vector's length, `vals` is at
    /// least as long as `cols`, and no other thread writes x at `cols`.
    #[inline]
    pub(crate) unsafe fn row_dot(self, cols: &[u32], vals: &[f64]) -> f64 {
        // SAFETY: by the contract.
        unsafe { row_dot_by(cols, vals, |c| self.get(c)) }
    }
}

impl Halves {
    /// The split of `a`'s rows, or None when `a` is too small for a second
    /// thread to pay (fewer than [`PARALLEL_NNZ`] stored entries, as for the
    /// product) or has no split with a small separator.
    pub(crate) fn new(a: &Csr) -> Option<Self> {
        let n = a.nrows();
        if a.nnz() < PARALLEL_NNZ || n != a.ncols() {
            return None;
        }
        let (offsets, cols) = (a.row_offsets(), a.col_indices());
        let work = |k: usize| (offsets[k + 1] - offsets[k]) as i64;
        // Row k is in S(m) for m in (first column of k, k]: difference
        // arrays of |S(m)|'s work over every m at once.
        let mut in_s = vec![0i64; n + 2];
        for k in 0..n {
            let Some(first) = cols[offsets[k]..offsets[k + 1]]
                .first()
                .map(|&j| j as usize)
            else {
                continue;
            };
            if first < k {
                in_s[first + 1] += work(k);
                in_s[k + 1] -= work(k);
            }
        }
        let total = a.nnz() as i64;
        let (mut best, mut best_cost) = (0, i64::MAX);
        let (mut before, mut separator_work) = (0i64, 0i64);
        for (m, entering) in in_s.iter().enumerate().take(n).skip(1) {
            before += work(m - 1);
            separator_work += entering;
            let after = total - before - separator_work;
            let cost = before.max(after) + separator_work;
            if cost < best_cost {
                (best, best_cost) = (m, cost);
            }
        }
        let split = best;
        let mut in_separator = vec![false; n];
        for (k, flag) in in_separator.iter_mut().enumerate().skip(split) {
            *flag = cols[offsets[k]..offsets[k + 1]]
                .first()
                .is_some_and(|&j| (j as usize) < split);
        }
        let separator: Vec<usize> = (split..n).filter(|&k| in_separator[k]).collect();
        let separator_work: i64 = separator.iter().map(|&k| work(k)).sum();
        if separator_work as f64 > LARGEST_SEPARATOR_SHARE * total as f64 {
            return None;
        }
        // The halves must not read what the other writes: a first-half row
        // sees only the first half and S, a second-half row only rows ≥ m
        // (a pattern that is not symmetric could break the first).
        let sound = (0..n).all(|k| {
            let row = &cols[offsets[k]..offsets[k + 1]];
            if k < split {
                row.iter()
                    .all(|&j| (j as usize) < split || in_separator[j as usize])
            } else {
                in_separator[k] || row.iter().all(|&j| j as usize >= split)
            }
        });
        sound.then_some(Self {
            split,
            in_separator,
            separator,
        })
    }

    /// Whether each row is in the separator (swept after both halves).
    pub(crate) fn in_separator(&self) -> &[bool] {
        &self.in_separator
    }

    /// The separator's rows, ascending.
    pub(crate) fn separator(&self) -> &[usize] {
        &self.separator
    }

    /// Whether row k (not in the separator) is in the first half.
    #[cfg(test)]
    pub(crate) fn in_first_half(&self, k: usize) -> bool {
        k < self.split
    }

    /// One Gauss-Seidel sweep over x in this ordering (see the module),
    /// `update(k, x)` setting x[k] from the others; the halves on two
    /// threads. `update` must read only the unknowns of row k's pattern.
    pub(crate) fn sweep<F>(&self, x: &mut [f64], forward: bool, update: F)
    where
        F: Fn(usize, Shared) + Sync,
    {
        let n = x.len();
        assert_eq!(n, self.in_separator.len(), "a sweep of the split's size");
        let shared = Shared(x.as_mut_ptr());
        let (split, skip) = (self.split, &self.in_separator);
        let first = || {
            if forward {
                (0..split).for_each(|k| update(k, shared));
            } else {
                (0..split).rev().for_each(|k| update(k, shared));
            }
        };
        let second = || {
            let rows = (split..n).filter(|&k| !skip[k]);
            if forward {
                rows.for_each(|k| update(k, shared));
            } else {
                rows.rev().for_each(|k| update(k, shared));
            }
        };
        if !forward {
            self.separator.iter().rev().for_each(|&k| update(k, shared));
        }
        std::thread::scope(|scope| {
            scope.spawn(second);
            first();
        });
        if forward {
            self.separator.iter().for_each(|&k| update(k, shared));
        }
    }
}

/// One sweep over x: in the split's ordering on two threads when there is
/// one, else in the natural order (forward: 0, 1, …; backward: the reverse).
pub(crate) fn sweep<F>(halves: Option<&Halves>, x: &mut [f64], forward: bool, update: F)
where
    F: Fn(usize, Shared) + Sync,
{
    match halves {
        Some(h) => h.sweep(x, forward, update),
        None => {
            let shared = Shared(x.as_mut_ptr());
            if forward {
                (0..x.len()).for_each(|k| update(k, shared));
            } else {
                (0..x.len()).rev().for_each(|k| update(k, shared));
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use nalgebra_sparse::{CooMatrix, CsrMatrix};

    /// The 5-point Laplacian of a q × q grid, numbered row by row.
    pub(crate) fn grid(q: usize) -> Csr {
        let mut coo = CooMatrix::new(q * q, q * q);
        for i in 0..q {
            for j in 0..q {
                let k = i * q + j;
                coo.push(k, k, 4.0);
                if j + 1 < q {
                    coo.push(k, k + 1, -1.0);
                    coo.push(k + 1, k, -1.0);
                }
                if i + 1 < q {
                    coo.push(k, k + q, -1.0);
                    coo.push(k + q, k, -1.0);
                }
            }
        }
        Csr::try_from(CsrMatrix::from(&coo)).expect("a small grid")
    }

    /// On a grid numbered row by row the separator is one grid row in the
    /// middle, and the halves are balanced.
    #[test]
    fn a_grid_splits_at_one_row_in_the_middle() {
        let q = 300;
        let a = grid(q);
        let h = Halves::new(&a).expect("a grid splits");
        assert_eq!(h.separator.len(), q, "one grid row");
        let second = q * q - h.split - q;
        assert!(h.split.abs_diff(second) <= 2 * q, "{} vs {second}", h.split);
    }

    /// A matrix whose rows all couple to the first has no useful split.
    #[test]
    fn a_dense_coupling_has_no_split() {
        let n = 200_000;
        let mut coo = CooMatrix::new(n, n);
        for k in 0..n {
            coo.push(k, k, 2.0);
            if k > 0 {
                coo.push(k, 0, -1e-6);
                coo.push(0, k, -1e-6);
            }
            if k + 1 < n {
                coo.push(k, k + 1, -0.5);
                coo.push(k + 1, k, -0.5);
            }
        }
        assert!(Halves::new(&Csr::try_from(CsrMatrix::from(&coo)).unwrap()).is_none());
    }

    /// A split sweep is the Gauss-Seidel sweep of its ordering: the same
    /// bits as the sequential sweep over (halves, separator), forward and
    /// backward; and the two orderings differ (the split is used).
    #[test]
    fn a_split_sweep_is_the_sequential_sweep_in_its_order() {
        let a = grid(300);
        let h = Halves::new(&a).expect("a grid splits");
        let n = a.nrows();
        let b: Vec<f64> = (0..n).map(|k| ((k * 37) % 11) as f64 - 5.0).collect();
        let update = |k: usize, x: Shared| {
            let (cols, vals) = a.row(k);
            // SAFETY: the grid's columns are below n; the split's halves
            // read only their own rows and the separator.
            unsafe {
                let sum = x.row_dot(cols, vals);
                let xk = x.get(k);
                x.set(k, xk + (b[k] - sum) / 4.0);
            }
        };
        let mut order: Vec<usize> = (0..n)
            .filter(|&k| k < h.split || !h.in_separator[k])
            .collect();
        order.extend(&h.separator);
        for forward in [true, false] {
            let mut split = vec![0.5; n];
            let mut sequential = split.clone();
            let mut natural = split.clone();
            h.sweep(&mut split, forward, update);
            let ordered: Box<dyn Iterator<Item = &usize>> = if forward {
                Box::new(order.iter())
            } else {
                Box::new(order.iter().rev())
            };
            let shared = Shared(sequential.as_mut_ptr());
            ordered.for_each(|&k| update(k, shared));
            sweep(None, &mut natural, forward, update);
            assert_eq!(split, sequential, "forward {forward}");
            assert_ne!(split, natural, "forward {forward}");
        }
    }
}
