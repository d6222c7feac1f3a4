//! A budget for a solve, enforced through the observer hook, so that the
//! harness limits every registered solver the same way without knowing its
//! settings: a cap on the solver's work (events of the stage its registry
//! entry names as its unit of work, summed over friction iterations and mesh
//! levels) and/or a wall-clock deadline. Studies whose results must be
//! reproducible use the work cap; the deadline is a safety net.

use std::time::{Duration, Instant};

use contactlab_solvers::registry::Entry;
use contactlab_solvers::{Control, Limits, Observer, Progress, Status};

/// Passes events on to `inner` and stops the solver when the budget is spent.
pub struct Budget<'a> {
    work_stage: &'static str,
    max_work: Option<usize>,
    deadline: Option<Instant>,
    work: usize,
    /// Where events go on to (none: nowhere).
    inner: Option<&'a mut dyn Observer>,
}

impl<'a> Budget<'a> {
    /// A budget for `entry`'s solves: at most `max_work` events of its work
    /// stage, and at most `seconds` of wall-clock time from now.
    pub fn new(
        entry: &Entry,
        max_work: Option<usize>,
        seconds: Option<f64>,
        inner: &'a mut dyn Observer,
    ) -> Self {
        Self {
            work_stage: entry.work_stage,
            max_work,
            deadline: seconds.and_then(deadline_after),
            work: 0,
            inner: Some(inner),
        }
    }

    /// A budget that passes events on to nobody.
    pub fn silent(entry: &Entry, max_work: Option<usize>, seconds: Option<f64>) -> Budget<'static> {
        Budget {
            work_stage: entry.work_stage,
            max_work,
            deadline: seconds.and_then(deadline_after),
            work: 0,
            inner: None,
        }
    }

    /// Work done so far (events of the work stage).
    pub fn work(&self) -> usize {
        self.work
    }
}

/// The instant `seconds` from now, or None (no deadline) when it lies
/// beyond what the clock can represent: `Duration::from_secs_f64` panics
/// past about 1.8e19 s and `Instant + Duration` past the clock's range.
fn deadline_after(seconds: f64) -> Option<Instant> {
    Duration::try_from_secs_f64(seconds.max(0.0))
        .ok()
        .and_then(|d| Instant::now().checked_add(d))
}

impl Observer for Budget<'_> {
    fn observe(&mut self, p: &Progress) -> Control {
        if p.stage == self.work_stage {
            self.work += 1;
        }
        let inner = match self.inner.as_deref_mut() {
            Some(o) if o.wants(p.stage) => o.observe(p),
            _ => Control::Continue,
        };
        if self.max_work.is_some_and(|m| self.work >= m) {
            return Control::Stop(Status::MaxIterations);
        }
        if self.deadline.is_some_and(|d| Instant::now() >= d) {
            return Control::Stop(Status::TimeLimit);
        }
        inner
    }

    fn wants(&self, stage: &str) -> bool {
        stage == self.work_stage || self.inner.as_deref().is_some_and(|o| o.wants(stage))
    }

    fn limits(&self) -> Limits {
        let inner = self
            .inner
            .as_deref()
            .map(|o| o.limits())
            .unwrap_or_default();
        let work = self.max_work.map(|m| m.saturating_sub(self.work));
        Limits {
            work: match (work, inner.work) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            },
            deadline: match (self.deadline, inner.deadline) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::deadline_after;

    #[test]
    fn a_deadline_past_the_clock_is_no_deadline_not_a_panic() {
        for s in [1e19, 1e20, 1e300, f64::INFINITY, f64::NAN] {
            let _ = deadline_after(s);
        }
        assert!(deadline_after(1e300).is_none());
        assert!(deadline_after(10.0).is_some());
    }
}
