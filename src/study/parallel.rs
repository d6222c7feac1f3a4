//! Independent work on the machine's cores: the one primitive beneath a
//! study's parts run with the lab's references and progress (the `cores`
//! module) and beneath the references' candidates. Each item runs whole on one
//! thread, at most as many at once as there are cores and as fit in
//! memory, and the results come back in the items' order, so that what
//! is made of them does not depend on which finished first.
//!
//! Only for work that reports no time: two solves at once each take
//! longer than one alone.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use anyhow::Result;

/// The items run at once: the machine's cores, at most the number of
/// items, and one if that many of `need_each` bytes do not fit in what the
/// process may use.
pub fn workers(items: usize, need_each: f64) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let at_once = cores.min(items).max(1);
    match crate::memory::room() {
        Some(room) if at_once as f64 * need_each > room.bytes => 1,
        _ => at_once,
    }
}

/// Runs `work` on each of `items` on [`workers`] threads while the calling
/// thread runs `meanwhile` (given whether any item is still running), and
/// gives each item's result in the items' order: None for an item not
/// started because `stop` was set (by a failed item, or by the caller).
pub fn each_on_cores<T: Sync, R: Send>(
    items: &[T],
    need_each: f64,
    stop: &AtomicBool,
    work: impl Fn(&T) -> Result<R> + Sync,
    meanwhile: impl FnOnce(&dyn Fn() -> bool),
) -> Vec<Option<Result<R>>> {
    let next = AtomicUsize::new(0);
    let results: Vec<Mutex<Option<Result<R>>>> = items.iter().map(|_| Mutex::new(None)).collect();
    let workers = workers(items.len(), need_each);
    let running = AtomicUsize::new(workers);
    std::thread::scope(|scope| {
        for _ in 0..workers {
            let (next, results, work, running) = (&next, &results, &work, &running);
            scope.spawn(move || {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    if i >= items.len() || stop.load(Ordering::Relaxed) {
                        break;
                    }
                    let result = work(&items[i]);
                    if result.is_err() {
                        stop.store(true, Ordering::Relaxed);
                    }
                    if let Ok(mut slot) = results[i].lock() {
                        *slot = Some(result);
                    }
                }
                running.fetch_sub(1, Ordering::Release);
            });
        }
        meanwhile(&|| running.load(Ordering::Acquire) > 0);
    });
    results
        .into_iter()
        .map(|slot| slot.into_inner().ok().flatten())
        .collect()
}

/// [`each_on_cores`] with nothing to do meanwhile: every item's result in
/// order, or the first error in the items' order.
pub fn map_on_cores<T: Sync, R: Send>(
    items: &[T],
    need_each: f64,
    work: impl Fn(&T) -> Result<R> + Sync,
) -> Result<Vec<R>> {
    let stop = AtomicBool::new(false);
    let mut out = Vec::with_capacity(items.len());
    for r in each_on_cores(items, need_each, &stop, work, |_| {}) {
        match r {
            Some(r) => out.push(r?),
            None => anyhow::bail!("an item of the work did not run (an earlier one failed)"),
        }
    }
    Ok(out)
}
