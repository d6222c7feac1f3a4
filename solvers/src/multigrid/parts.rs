//! Gauss-Seidel on several cores: an ordering of the unknowns in parts
//! that do not couple, and the separator between them.
//!
//! Gauss-Seidel converges in any ordering of the unknowns (it is the
//! coordinate descent of a convex energy), so an ordering that lets several
//! threads sweep at once changes the smoother's bits, not what it is. The
//! classic one is a nested-dissection split (George 1973), here in bands:
//! the rows are cut at m_1 < … < m_{t−1} into t parts of equal work; the
//! separator S is every row ≥ m_j of part j that couples to a row below m_j.
//! The parts' other rows (their interiors) sweep at the same time, one
//! thread each, then S in order. For a symmetric pattern an interior row
//! of part j reads only its own part and S: a row of another part that it
//! reads couples back to below that part's start, so it is in S. In the
//! paper's meshes, numbered row by row, each cut adds a band of about two
//! mesh rows to S, so the sequential tail is O(t·h⁻¹) of O(h⁻²) unknowns.
//! Nothing here looks at a mesh: the cuts are chosen from A's pattern alone
//! (equal stored entries per part), and the split is checked entry by entry
//! (no interior reads an unknown another part writes).
//!
//! Forward: every part ascending, then S ascending. Backward: the exact
//! reverse (S descending, then every part descending), so that a forward
//! and a backward sweep make a symmetric Gauss-Seidel as before. How many
//! parts: [`crate::numerics::threads`].

use crate::numerics::linalg::{Csr, PARALLEL_NNZ, RowColumns, row_dot_by};

/// Above this share of the stored entries in the separator the split is
/// not worth the threads (a matrix numbered without locality, or too many
/// parts for its size).
const LARGEST_SEPARATOR_SHARE: f64 = 0.05;

/// The parts of a matrix's rows and their separator.
#[derive(Clone, Debug)]
pub(crate) struct Parts {
    /// Part j is rows [cuts[j], cuts[j + 1]): cuts[0] = 0, the last n.
    cuts: Vec<usize>,
    /// Whether each row is in the separator.
    in_separator: Vec<bool>,
    /// The separator's rows, ascending.
    separator: Vec<usize>,
}

/// The vector a sweep updates, shared by the threads of a split sweep.
/// Each writes only the unknowns of its part and reads only its part and
/// the separator, which nobody writes meanwhile (checked by
/// [`Parts::new`]): the accesses through it never race.
#[derive(Clone, Copy)]
pub(crate) struct Shared(*mut f64);

// SAFETY: see the type: the threads touch disjoint unknowns, except the
// separator's, which they only read.
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
    /// Every column of `cols` is below the vector's length, `vals` is at
    /// least as long as `cols`, and no other thread writes x at `cols`.
    #[inline]
    pub(crate) unsafe fn row_dot(self, cols: RowColumns<'_>, vals: &[f64]) -> f64 {
        let base = cols.base;
        // SAFETY: by the contract.
        unsafe { row_dot_by(cols.rel, vals, |c| self.get(base + c)) }
    }
}

impl Parts {
    /// The split of `a`'s rows in `threads` parts, or None for one thread,
    /// for a matrix too small for more threads to pay (fewer than
    /// [`PARALLEL_NNZ`] stored entries, as for the product) or one without
    /// a split with a small separator.
    pub(crate) fn new(a: &Csr, threads: usize) -> Option<Self> {
        let n = a.nrows();
        if threads < 2 || a.nnz() < PARALLEL_NNZ || n != a.ncols() || n < threads {
            return None;
        }
        let cuts = cuts(a, threads);
        let mut in_separator = vec![false; n];
        for part in cuts.windows(2).skip(1) {
            for (k, sep) in in_separator
                .iter_mut()
                .enumerate()
                .take(part[1])
                .skip(part[0])
            {
                *sep = a.row_columns(k).first().is_some_and(|j| j < part[0]);
            }
        }
        let separator: Vec<usize> = (0..n).filter(|&k| in_separator[k]).collect();
        let separator_work: usize = separator
            .iter()
            .map(|&k| {
                let (lo, hi) = a.row_range(k);
                hi - lo
            })
            .sum();
        if separator_work as f64 > LARGEST_SEPARATOR_SHARE * a.nnz() as f64 {
            return None;
        }
        // An interior row must read only its own part and S (a pattern
        // that is not symmetric could break it).
        let split = Self {
            cuts,
            in_separator,
            separator,
        };
        // A row's columns ascend: one whose first and last lie in its own
        // part needs no look at the others (all but the rows near a cut;
        // the entry-by-entry walk was 0.05 s of TNNMG's set-up at 1/1024).
        let sep = &split.in_separator;
        let sound = split.cuts.windows(2).all(|part| {
            let own = part[0]..part[1];
            own.clone().all(|k| {
                let cols = a.row_columns(k);
                let inside = |j: Option<usize>| j.is_none_or(|j| own.contains(&j));
                sep[k]
                    || (inside(cols.first()) && inside(cols.last()))
                    || cols.iter().all(|j| sep[j] || own.contains(&j))
            })
        });
        sound.then_some(split)
    }

    /// How many parts sweep at once.
    #[cfg(test)]
    pub(crate) fn count(&self) -> usize {
        self.cuts.len() - 1
    }

    /// The part of row k.
    #[cfg(test)]
    pub(crate) fn part_of(&self, k: usize) -> usize {
        self.cuts.partition_point(|&c| c <= k) - 1
    }

    /// Whether each row is in the separator (swept after all parts).
    pub(crate) fn in_separator(&self) -> &[bool] {
        &self.in_separator
    }

    /// The separator's rows, ascending.
    pub(crate) fn separator(&self) -> &[usize] {
        &self.separator
    }

    /// One Gauss-Seidel sweep over x in this ordering (see the module),
    /// `update(k, x)` setting x[k] from the others and reporting what the
    /// sweep joins over its rows ([`Joined`]); the parts on one thread each
    /// (the first on the calling thread). `update` must read only the
    /// unknowns of row k's pattern.
    pub(crate) fn sweep<U: RowUpdate>(&self, x: &mut [f64], forward: bool, update: &U) -> U::Out {
        let n = x.len();
        assert_eq!(n, self.in_separator.len(), "a sweep of the split's size");
        let shared = Shared(x.as_mut_ptr());
        let skip = &self.in_separator;
        let separator = || match forward {
            true => each_row(self.separator.iter().copied(), update, shared),
            false => each_row(self.separator.iter().rev().copied(), update, shared),
        };
        let part = move |(lo, hi): (usize, usize)| match forward {
            true => each_row((lo..hi).filter(|&k| !skip[k]), update, shared),
            false => each_row((lo..hi).rev().filter(|&k| !skip[k]), update, shared),
        };
        let mut joined = U::Out::NONE;
        if !forward {
            joined = separator();
        }
        let parts = std::sync::Mutex::new(U::Out::NONE);
        std::thread::scope(|scope| {
            let parts = &parts;
            for w in self.cuts.windows(2).skip(1) {
                let (lo, hi) = (w[0], w[1]);
                scope.spawn(move || {
                    let r = part((lo, hi));
                    let mut all = parts.lock().unwrap_or_else(|e| e.into_inner());
                    *all = all.join(r);
                });
            }
            let r = part((self.cuts[0], self.cuts[1]));
            let mut all = parts.lock().unwrap_or_else(|e| e.into_inner());
            *all = all.join(r);
        });
        joined = joined.join(parts.into_inner().unwrap_or_else(|e| e.into_inner()));
        if forward {
            joined = joined.join(separator());
        }
        joined
    }
}

/// One row's update in a sweep: sets x[k] from the others and reports
/// what the sweep joins over its rows. A closure is one; the sweeps of
/// the smoother are structs whose update is inlined into the sweep's loop
/// over rows (a closure's body was not: its call per row, and the
/// reloading of what it captures, were 15-19 % of a sweep on a
/// 2×2-block stencil matrix held in the cache).
pub(crate) trait RowUpdate: Sync {
    type Out: Joined;

    /// Sets x[k].
    ///
    /// # Safety
    /// Reads only the unknowns of row k's pattern, writes only x[k] (and
    /// what its sweep's contract allows, see [`Parts`]).
    unsafe fn update(&self, k: usize, x: Shared) -> Self::Out;
}

impl<F, R> RowUpdate for F
where
    F: Fn(usize, Shared) -> R + Sync,
    R: Joined,
{
    type Out = R;
    #[inline(always)]
    unsafe fn update(&self, k: usize, x: Shared) -> R {
        self(k, x)
    }
}

/// What a sweep's row updates report, joined over its rows: nothing
/// (`()`), or the largest move of an unknown ([`Largest`]), which the
/// TNNMG stopping test bounds its change by without a copy of the iterate.
pub(crate) trait Joined: Copy + Send {
    /// The join of no rows.
    const NONE: Self;
    fn join(self, other: Self) -> Self;
}

impl Joined for () {
    const NONE: Self = ();
    #[inline(always)]
    fn join(self, _: ()) {}
}

/// The largest of the values joined (non-negative: |x_k − x_k before|).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Largest(pub f64);

impl Joined for Largest {
    const NONE: Self = Largest(0.0);
    #[inline(always)]
    fn join(self, other: Self) -> Self {
        Largest(self.0.max(other.0))
    }
}

/// The cuts 0 = m_0 < m_1 < … < m_{t−1} < m_t = n of a split in t parts,
/// each chosen in turn for the least work on the longest thread plus the
/// separator: cut j minimizes max(interior of part j − 1, what remains ÷
/// the parts left) + S(m_j), where S(m) is the work of the rows ≥ m that
/// couple below m (the separator a cut at m makes) and work is stored
/// entries. For two parts this is the least max(before, after) + S(m)
/// over every m, the rule of the two-core sweep it generalizes. S(m) of
/// every m at once by difference arrays: row k is in S(m) for m in (its
/// first column, k].
fn cuts(a: &Csr, threads: usize) -> Vec<usize> {
    let offsets = a.row_offsets();
    let n = offsets.len() - 1;
    let work = |k: usize| (offsets[k + 1] - offsets[k]) as i64;
    let mut entering = vec![0i64; n + 2];
    for k in 0..n {
        if let Some(first) = a.row_columns(k).first()
            && first < k
        {
            entering[first + 1] += work(k);
            entering[k + 1] -= work(k);
        }
    }
    let total = offsets[n] as i64;
    let mut cuts = vec![0];
    // The row m of the last cut, the entries before it and its separator's.
    let (mut m, mut before, mut s) = (0usize, 0i64, 0i64);
    for left in (1..threads).rev() {
        let (mut best, mut best_cost) = (None, i64::MAX);
        let (mut mm, mut bb, mut ss) = (m, before, 0i64);
        // S of a cut at mm: the rows entering from m on (those entering
        // before m were counted in the last cut's; a cut ≥ m sees them
        // again only if they reach past it, which `entering` keeps).
        ss += (0..=m).map(|i| entering[i]).sum::<i64>();
        while mm + 1 < n {
            bb += work(mm);
            mm += 1;
            ss += entering[mm];
            let interior = bb - before - s;
            let remaining = total - bb - ss;
            let cost = interior.max(remaining / left as i64) + ss;
            if cost < best_cost {
                (best, best_cost) = (Some((mm, bb, ss)), cost);
            }
            // Past the balance the interior only grows; the last cut
            // scans on (a smaller separator further on may still win).
            if left > 1 && interior > remaining {
                break;
            }
        }
        let Some(cut) = best else { break };
        (m, before, s) = cut;
        cuts.push(m);
    }
    cuts.push(n);
    cuts
}

/// `update` of each of `rows` in turn, joined: a plain loop, into which
/// the update is inlined (a fold's closure per row was not, and cost a
/// call and the reloading of its captures per row).
#[inline(always)]
fn each_row<U: RowUpdate>(rows: impl Iterator<Item = usize>, update: &U, x: Shared) -> U::Out {
    let mut joined = U::Out::NONE;
    for k in rows {
        // SAFETY: the sweeps pass each row once, in the ordering the
        // caller's update is written for.
        joined = joined.join(unsafe { update.update(k, x) });
    }
    joined
}

/// One sweep over x: in the split's ordering on its threads when there is
/// one, else in the natural order (forward: 0, 1, …; backward: the reverse).
pub(crate) fn sweep<U: RowUpdate>(
    parts: Option<&Parts>,
    x: &mut [f64],
    forward: bool,
    update: &U,
) -> U::Out {
    match parts {
        Some(p) => p.sweep(x, forward, update),
        None => {
            let shared = Shared(x.as_mut_ptr());
            match forward {
                true => each_row(0..x.len(), update, shared),
                false => each_row((0..x.len()).rev(), update, shared),
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

    /// On a grid numbered row by row each cut's separator is one grid row,
    /// and the parts are balanced to a grid row, for 2 and 5 parts; one
    /// thread has no split.
    #[test]
    fn a_grid_splits_at_one_row_per_cut() {
        let q = 300;
        let a = grid(q);
        assert!(Parts::new(&a, 1).is_none());
        for t in [2, 5] {
            let p = Parts::new(&a, t).expect("a grid splits");
            assert_eq!(p.count(), t);
            assert_eq!(p.separator.len(), (t - 1) * q, "one grid row per cut");
            for w in p.cuts.windows(2) {
                assert!((w[1] - w[0]).abs_diff(q * q / t) <= q, "{:?}", p.cuts);
            }
        }
    }

    /// For two parts the cut attains the least max(before, after) + S(m)
    /// over every m, each S(m) counted row by row here (not by difference
    /// arrays): on a grid and on a grid with long couplings. For three,
    /// the parts' interiors differ by at most two grid rows' work.
    #[test]
    fn the_cuts_balance_the_interiors() {
        let q = 40;
        let mut coo = CooMatrix::new(q * q, q * q);
        let g = grid(q).to_nalgebra();
        for (i, j, v) in g.triplet_iter() {
            coo.push(i, j, *v);
        }
        for k in (3 * q..q * q).step_by(97) {
            coo.push(k, k - 3 * q, -0.1);
            coo.push(k - 3 * q, k, -0.1);
        }
        let long = Csr::try_from(CsrMatrix::from(&coo)).unwrap();
        for a in [grid(q), long] {
            let offsets = a.row_offsets();
            let n = a.nrows();
            let work = |k: usize| (offsets[k + 1] - offsets[k]) as i64;
            let cost = |m: usize| {
                let s: i64 = (m..n)
                    .filter(|&k| a.row_columns(k).first().is_some_and(|j| j < m))
                    .map(work)
                    .sum();
                let before = offsets[m] as i64;
                before.max(offsets[n] as i64 - before - s) + s
            };
            let best = (1..n).map(cost).min().unwrap();
            let c = cuts(&a, 2);
            assert_eq!(c.len(), 3);
            assert_eq!(cost(c[1]), best, "cut {} of {n}", c[1]);
        }
        let p = Parts::new(&grid(300), 3).unwrap();
        let interiors: Vec<usize> = p
            .cuts
            .windows(2)
            .map(|w| (w[0]..w[1]).filter(|&k| !p.in_separator[k]).count())
            .collect();
        let (lo, hi) = (
            interiors.iter().min().unwrap(),
            interiors.iter().max().unwrap(),
        );
        assert!(hi - lo <= 2 * 300, "{interiors:?}");
    }

    /// A pattern that is not symmetric can let an interior row read a row
    /// of another part that is not in the separator: an entry past the
    /// row's last column in its part (the first part reading the second's
    /// interior) must make the split be refused. An entry before a row's
    /// first column (the second part reading the first) instead puts that
    /// row in the separator, which is sound. Either way no split may keep
    /// an interior row reading across parts.
    #[test]
    fn a_split_whose_interior_reads_another_part_is_refused() {
        let q = 300;
        let n = q * q;
        let g = grid(q).to_nalgebra();
        let p = Parts::new(&grid(q), 2).expect("a grid splits");
        let (cut, sep) = (p.cuts[1], &p.in_separator);
        // An interior row of the first part, and one of the second that is
        // not in the separator, far from the cut.
        let (first, second) = (cut / 2, (cut + n) / 2);
        assert!(!sep[first] && !sep[second]);
        for (row, col) in [(first, second), (second, first)] {
            let mut coo = CooMatrix::new(n, n);
            for (i, j, v) in g.triplet_iter() {
                coo.push(i, j, *v);
            }
            coo.push(row, col, -1e-3);
            let a = Csr::try_from(CsrMatrix::from(&coo)).unwrap();
            let split = Parts::new(&a, 2);
            assert!(
                split.as_ref().is_none_or(|p| {
                    let part = p.part_of(row);
                    p.in_separator[row] || p.in_separator[col] || p.part_of(col) == part
                }),
                "row {row} reads {col} across parts"
            );
        }
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
        assert!(Parts::new(&Csr::try_from(CsrMatrix::from(&coo)).unwrap(), 2).is_none());
    }

    /// A split sweep is the Gauss-Seidel sweep of its ordering: the same
    /// bits as the sequential sweep over (parts, separator), forward and
    /// backward; and the two orderings differ (the split is used); for 2
    /// and 3 parts.
    #[test]
    fn a_split_sweep_is_the_sequential_sweep_in_its_order() {
        let a = grid(300);
        for t in [2, 3] {
            split_sweep_in_order(&a, &Parts::new(&a, t).expect("a grid splits"));
        }
    }

    fn split_sweep_in_order(a: &Csr, h: &Parts) {
        let n = a.nrows();
        let b: Vec<f64> = (0..n).map(|k| ((k * 37) % 11) as f64 - 5.0).collect();
        let update = |k: usize, x: Shared| {
            let (cols, vals) = a.row(k);
            // SAFETY: the grid's columns are below n; the split's parts
            // read only their own rows and the separator.
            unsafe {
                let sum = x.row_dot(cols, vals);
                let xk = x.get(k);
                x.set(k, xk + (b[k] - sum) / 4.0);
            }
        };
        let mut order: Vec<usize> = (0..n).filter(|&k| !h.in_separator[k]).collect();
        order.extend(&h.separator);
        for forward in [true, false] {
            let mut split = vec![0.5; n];
            let mut sequential = split.clone();
            let mut natural = split.clone();
            h.sweep(&mut split, forward, &update);
            let ordered: Box<dyn Iterator<Item = &usize>> = if forward {
                Box::new(order.iter())
            } else {
                Box::new(order.iter().rev())
            };
            let shared = Shared(sequential.as_mut_ptr());
            ordered.for_each(|&k| update(k, shared));
            sweep(None, &mut natural, forward, &update);
            assert_eq!(split, sequential, "forward {forward}");
            assert_ne!(split, natural, "forward {forward}");
        }
    }
}
