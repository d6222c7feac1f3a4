//! Work measured on both cores: a study's independent parts (such as each
//! solver's trials of the stability map) run on as many threads as the
//! machine has cores, at most two of them at once in memory, and come back
//! in their own order, so that the files they make are the ones a run on
//! one core makes.
//!
//! Only for work that reports no time: two trials at once each take
//! longer than one alone, so work whose trials are timed, or stopped by
//! the clock, runs in a [`Lab`] on one core (the guide's "time alone what
//! you report as a time"). Trials stopped by a work cap (a count) give the
//! same answer on any number of cores.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Sender, channel};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use anyhow::{Result, anyhow};
use contactlab_solvers::registry::Entry;

use crate::study::lab::{Lab, ticked};
use crate::study::parallel::each_on_cores;
use crate::study::reference::{Reference, References};
use crate::study::runner::{Keep, Measured, measure};
use crate::study::trial::TrialSpec;

/// What a part of the work shares with the others: the lab's references
/// (earned on first use, one at a time) and its progress.
pub struct Shared<'s, 'r> {
    references: &'s Mutex<&'r mut References>,
    ticks: Sender<TrialSpec>,
    stop: &'s AtomicBool,
}

impl Shared<'_, '_> {
    /// The reference `trial` is measured against (None if it asks for
    /// none), earned on first use.
    pub fn reference(&self, trial: &TrialSpec) -> Result<Option<Arc<Reference>>> {
        if !trial.wants_reference() {
            return Ok(None);
        }
        let mut references = self
            .references
            .lock()
            .map_err(|_| anyhow!("the references were left half-earned by a failed part"))?;
        references.shared(&trial.scene, &trial.settings)
    }

    /// Tells the lab's progress that `trial` is done; an error once the
    /// run was asked to stop (interrupted, or another part failed).
    pub fn tick(&self, trial: &TrialSpec) -> Result<()> {
        if self.stop.load(Ordering::Relaxed) {
            return Err(Stopped.into());
        }
        // The receiver lives until every part is done.
        let _ = self.ticks.send(trial.clone());
        Ok(())
    }
}

/// A part's error when it stopped because another failed (not its own).
#[derive(Debug, thiserror::Error)]
#[error("stopped: another part of the work failed")]
struct Stopped;

/// Runs `work` on each of `parts` on the machine's cores (see
/// [`crate::study::parallel::workers`];
/// each part needing `need_each` bytes), each part whole on one thread, and
/// gives the results in the parts' order. The lab's progress hears of
/// every trial a part ticks ([`Shared::tick`]), on this thread; a part's
/// error stops the others at their next trial and is the error returned
/// (the first in the parts' order if several failed).
pub fn on_both_cores<T: Sync, R: Send>(
    lab: &mut Lab,
    parts: &[T],
    need_each: f64,
    work: impl Fn(&T, &Shared) -> Result<R> + Sync,
) -> Result<Vec<R>> {
    let tracker = lab.tracker();
    let references = Mutex::new(&mut lab.references);
    let stop = AtomicBool::new(false);
    let (ticks, heard) = channel::<TrialSpec>();
    let shared = Shared {
        references: &references,
        ticks,
        stop: &stop,
    };
    let mut interrupted = None;
    let results = each_on_cores(
        parts,
        need_each,
        &stop,
        |part| work(part, &shared),
        |running| {
            // Until every part is done, then what is left in the channel.
            let mut hear = |trial: TrialSpec| {
                if interrupted.is_none()
                    && let Err(e) = ticked(tracker, &trial)
                {
                    stop.store(true, Ordering::Relaxed);
                    interrupted = Some(e);
                }
            };
            while running() {
                if let Ok(trial) = heard.recv_timeout(Duration::from_millis(50)) {
                    hear(trial);
                }
            }
            while let Ok(trial) = heard.try_recv() {
                hear(trial);
            }
        },
    );
    if let Some(e) = interrupted {
        return Err(e);
    }
    // The failure itself, not a part it stopped.
    let failed = results
        .iter()
        .position(|r| matches!(r, Some(Err(e)) if !e.is::<Stopped>()));
    let mut out = Vec::with_capacity(parts.len());
    for (i, result) in results.into_iter().enumerate() {
        match result {
            Some(Ok(r)) if failed.is_none() => out.push(r),
            Some(Err(e)) if failed == Some(i) => return Err(e),
            _ => {}
        }
    }
    match failed {
        None if out.len() == parts.len() => Ok(out),
        _ => Err(Stopped.into()),
    }
}

/// What one trial of `entry` at mesh `h` needs while another runs beside
/// it: its solve and its error bound's factors (every trial bounds its
/// answer unless told not to).
pub fn trial_need(h: crate::mechanics::mesh_size::MeshSize, entry: &Entry) -> f64 {
    crate::memory::solve(h, entry) + crate::memory::error_bound(crate::memory::unknowns(h))
}

/// Measures trials that need no reference and report no time (their
/// times are written nowhere), each on one of the machine's cores, in the
/// trials' order, as [`Lab::measure_alone`] does on one (the comparison's
/// frictionless profiles).
pub fn measure_alone_on_cores(
    lab: &mut Lab,
    specs: &[TrialSpec],
    keep: Keep,
) -> Result<Vec<Measured>> {
    let need = specs
        .iter()
        .map(|s| trial_need(s.scene.finest(), s.solver))
        .fold(0.0, f64::max);
    let tracker = lab.tracker();
    tracker.start(lab.current(), vec![1.0; specs.len()], f64::INFINITY);
    let measured = on_both_cores(lab, specs, need, |spec, shared| {
        let m = measure(spec, None, keep)?;
        shared.tick(spec)?;
        Ok(m)
    });
    tracker.finish();
    let mut measured = measured?;
    for (i, m) in measured.iter_mut().enumerate() {
        m.timing.trial = i;
    }
    Ok(measured)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::Settings;
    use crate::study::lab::Quiet;

    fn lab_run<R: Send>(
        parts: &[usize],
        work: impl Fn(&usize, &Shared) -> Result<R> + Sync,
    ) -> Result<Vec<R>> {
        let log = |_: &str| {};
        let mut lab = Lab::new(Settings::default(), &log, &Quiet);
        on_both_cores(&mut lab, parts, 0.0, work)
    }

    /// The results come back in the parts' order whichever finishes first
    /// (the early parts here take longest).
    #[test]
    fn results_keep_the_parts_order() {
        let parts: Vec<usize> = (0..9).collect();
        let out = lab_run(&parts, |&i, _| {
            std::thread::sleep(std::time::Duration::from_millis(3 * (9 - i as u64)));
            Ok(i * i)
        })
        .unwrap();
        assert_eq!(out, parts.iter().map(|i| i * i).collect::<Vec<_>>());
    }

    /// A failing part's own error is the one returned, not the "stopped"
    /// of a part it cut short.
    #[test]
    fn the_failure_is_reported_not_what_it_stopped() {
        let parts: Vec<usize> = (0..6).collect();
        let err = lab_run(&parts, |&i, _| -> Result<usize> {
            if i == 3 {
                anyhow::bail!("part 3 failed");
            }
            Ok(i)
        })
        .unwrap_err();
        assert_eq!(err.to_string(), "part 3 failed");
    }
}
