//! How many threads the solvers' parallel loops use: the split
//! Gauss-Seidel sweeps ([`crate::multigrid`]), the matrix-vector products
//! and the Galerkin products. A solver with a thread setting sets it for
//! the calling thread while it solves ([`Threads::set`]); everything else
//! uses every core the machine offers. One thread is the sequential code
//! itself: no split ordering, no spawned thread.

use std::cell::Cell;
use std::sync::OnceLock;

thread_local! {
    /// The calling thread's budget; 0: every core.
    static BUDGET: Cell<usize> = const { Cell::new(0) };
}

/// The cores the machine offers (1 when it cannot tell).
pub fn cores() -> usize {
    static CORES: OnceLock<usize> = OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// The threads a parallel loop started from this thread uses (≥ 1).
pub fn threads() -> usize {
    match BUDGET.with(Cell::get) {
        0 => cores(),
        n => n,
    }
}

/// The calling thread's budget while it lives; the one before restored on
/// drop (a solve inside a solve, such as the paper's method's multigrid
/// inner minimization, keeps its caller's afterwards).
pub struct Threads {
    before: usize,
}

impl Threads {
    /// Sets the calling thread's budget to `n` threads (0: every core).
    pub fn set(n: usize) -> Self {
        Self {
            before: BUDGET.with(|b| b.replace(n)),
        }
    }
}

impl Drop for Threads {
    fn drop(&mut self) {
        BUDGET.with(|b| b.set(self.before));
    }
}

/// The most threads a loop over chunks uses.
pub const MAX_THREADS: usize = 64;

/// Vectors shorter than this are swept on the calling thread: a thread's
/// start (about 20 µs) costs more than half such a loop saves.
pub const PARALLEL_LEN: usize = 1 << 16;

/// The chunks 0..n is cut into for [`threads`] threads: at most
/// [`MAX_THREADS`], one below [`PARALLEL_LEN`].
fn chunks(n: usize) -> (usize, usize) {
    let t = if n < PARALLEL_LEN {
        1
    } else {
        threads().min(MAX_THREADS)
    };
    (t, n.div_ceil(t).max(1))
}

/// Σ over the chunks of 0..n of `f(chunk)`, the chunks on one thread each
/// (the first on the calling thread), their sums added in order: the bits
/// depend on the thread count, not on the timing. No allocation.
pub fn sum_over_chunks(n: usize, f: impl Fn(std::ops::Range<usize>) -> f64 + Sync) -> f64 {
    let (t, chunk) = chunks(n);
    if t == 1 {
        return f(0..n);
    }
    let mut partial = [0.0; MAX_THREADS];
    let f = &f;
    std::thread::scope(|scope| {
        let mut slots = partial[..t].iter_mut().enumerate();
        let (_, first) = slots.next().expect("t ≥ 2");
        for (c, slot) in slots {
            let range = (c * chunk).min(n)..((c + 1) * chunk).min(n);
            scope.spawn(move || *slot = f(range));
        }
        *first = f(0..chunk.min(n));
    });
    partial[..t].iter().sum()
}

/// `f(chunk)` for the chunks of 0..n, one thread each (see
/// [`sum_over_chunks`]); `f` writes through [`Disjoint`] vectors at its
/// chunk's indices only.
pub fn for_each_chunk(n: usize, f: impl Fn(std::ops::Range<usize>) + Sync) {
    sum_over_chunks(n, |r| {
        f(r);
        0.0
    });
}

/// `f(c, piece)` for the pieces of `y`, `width` entries each (the last may
/// be shorter), one thread each, the first on the calling thread: a loop
/// whose pieces own their output (a product's rows, a restriction's band
/// of coarse unknowns). The caller decides the pieces, and so how many
/// threads; one piece spawns none.
pub fn for_each_piece(y: &mut [f64], width: usize, f: impl Fn(usize, &mut [f64]) + Sync) {
    let f = &f;
    let mut pieces = y.chunks_mut(width.max(1)).enumerate();
    let Some((_, first)) = pieces.next() else {
        return;
    };
    std::thread::scope(|scope| {
        for (c, piece) in pieces {
            scope.spawn(move || f(c, piece));
        }
        f(0, first);
    });
}

/// A vector that the threads of [`for_each_chunk`] write at disjoint
/// indices: each takes the slice of its own chunk.
#[derive(Clone, Copy)]
pub struct Disjoint<'a> {
    at: *mut f64,
    len: usize,
    _vector: std::marker::PhantomData<&'a mut [f64]>,
}

// SAFETY: the threads touch disjoint ranges (the contract of `slice`).
unsafe impl Send for Disjoint<'_> {}
unsafe impl Sync for Disjoint<'_> {}

impl<'a> Disjoint<'a> {
    pub fn of(x: &'a mut [f64]) -> Self {
        Self {
            at: x.as_mut_ptr(),
            len: x.len(),
            _vector: std::marker::PhantomData,
        }
    }

    /// The elements in `range`.
    ///
    /// # Safety
    /// No other slice of the same range, or overlapping it, is alive: each
    /// thread of a [`for_each_chunk`] takes its own chunk's once.
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn slice(&self, range: std::ops::Range<usize>) -> &'a mut [f64] {
        assert!(range.start <= range.end && range.end <= self.len);
        // SAFETY: in bounds (checked); exclusive by the contract.
        unsafe { std::slice::from_raw_parts_mut(self.at.add(range.start), range.len()) }
    }
}

/// dst = src, by chunks on [`threads`] threads.
pub fn copy(dst: &mut [f64], src: &[f64]) {
    assert_eq!(dst.len(), src.len(), "copy: vectors of one length");
    let d = Disjoint::of(dst);
    // SAFETY: each chunk once.
    for_each_chunk(src.len(), |r| {
        unsafe { d.slice(r.clone()) }.copy_from_slice(&src[r])
    });
}

/// x = value everywhere, by chunks on [`threads`] threads.
pub fn fill(x: &mut [f64], value: f64) {
    let n = x.len();
    let d = Disjoint::of(x);
    // SAFETY: each chunk once.
    for_each_chunk(n, |r| unsafe { d.slice(r) }.fill(value));
}

/// x += alpha·y, by chunks on [`threads`] threads.
pub fn axpy(x: &mut [f64], alpha: f64, y: &[f64]) {
    assert_eq!(x.len(), y.len(), "axpy: vectors of one length");
    let n = x.len();
    let dx = Disjoint::of(x);
    for_each_chunk(n, |r| {
        // SAFETY: each chunk once.
        let xs = unsafe { dx.slice(r.clone()) };
        for (xk, yk) in xs.iter_mut().zip(&y[r]) {
            *xk += alpha * yk;
        }
    });
}

/// x = alpha·x, by chunks on [`threads`] threads.
pub fn scale(x: &mut [f64], alpha: f64) {
    let n = x.len();
    let dx = Disjoint::of(x);
    // SAFETY: each chunk once.
    for_each_chunk(n, |r| {
        unsafe { dx.slice(r) }
            .iter_mut()
            .for_each(|xk| *xk *= alpha)
    });
}

/// aᵀb, by chunks on [`threads`] threads.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "dot: vectors of one length");
    sum_over_chunks(a.len(), |r| {
        a[r.clone()].iter().zip(&b[r]).map(|(x, y)| x * y).sum()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The chunked sum is the sum: each chunk once, for 1, 2 and 5
    /// threads, and a chunked update writes every element once.
    #[test]
    fn chunks_cover_the_vector_once() {
        let n = PARALLEL_LEN * 3 + 17;
        let a: Vec<f64> = (0..n).map(|k| (k % 7) as f64).collect();
        let exact: f64 = a.iter().sum();
        for t in [1, 2, 5] {
            let _t = Threads::set(t);
            assert_eq!(dot(&a, &vec![1.0; n]), exact, "{t} threads");
            let mut x = vec![0.0; n];
            let dx = Disjoint::of(&mut x);
            for_each_chunk(n, |r| {
                // SAFETY: each chunk once.
                for (xk, k) in unsafe { dx.slice(r.clone()) }.iter_mut().zip(r) {
                    *xk += k as f64;
                }
            });
            assert!(x.iter().enumerate().all(|(k, &v)| v == k as f64), "{t}");
            axpy(&mut x, 2.0, &a);
            assert!(
                x.iter()
                    .enumerate()
                    .all(|(k, &v)| v == k as f64 + 2.0 * a[k]),
                "axpy, {t} threads"
            );
        }
    }

    /// A budget holds while its guard lives, nests, and is restored.
    #[test]
    fn a_budget_holds_while_its_guard_lives() {
        let all = threads();
        assert_eq!(all, cores());
        {
            let _one = Threads::set(1);
            assert_eq!(threads(), 1);
            {
                let _three = Threads::set(3);
                assert_eq!(threads(), 3);
            }
            assert_eq!(threads(), 1);
            // Another thread keeps its own.
            std::thread::scope(|s| {
                s.spawn(|| assert_eq!(threads(), cores()));
            });
        }
        assert_eq!(threads(), all);
    }
}
