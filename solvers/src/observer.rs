//! One small hook through which solvers report progress (iteration, residual,
//! time) and through which the harness may stop them. Solvers never print.
//!
//! Stages are names the solver declares in its registry entry (`sweep`,
//! `uzawa`, `newton`, ...), so the harness draws and counts them without a
//! closed list of solvers.

use std::time::Instant;

use crate::solution::Status;

/// One progress event.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// The loop it comes from, as declared in the solver's registry entry.
    pub stage: &'static str,
    /// 1-based count within the stage (for the current call).
    pub iteration: usize,
    /// That loop's own residual (see the stage's description).
    pub residual: f64,
    /// Seconds since the reporting solver started.
    pub seconds: f64,
}

/// The observer's answer to an event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Control {
    Continue,
    /// Stop now and report this status (the harness's budget was reached:
    /// `MaxIterations` for a work budget, `TimeLimit` for a deadline).
    Stop(Status),
}

/// What the harness allows the rest of a solve: solvers that cannot call
/// back during their iterations (an external library) read these up front.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Limits {
    /// Iterations of the solver's work stage still allowed.
    pub work: Option<usize>,
    /// Wall-clock deadline.
    pub deadline: Option<Instant>,
}

/// Receives progress events.
pub trait Observer {
    fn observe(&mut self, progress: &Progress) -> Control;

    /// Whether events of this stage are wanted (some are many; a solver may
    /// skip building them otherwise).
    fn wants(&self, _stage: &str) -> bool {
        true
    }

    /// The budget left (none by default).
    fn limits(&self) -> Limits {
        Limits::default()
    }
}

/// Ignores everything, never stops.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Observer for Silent {
    fn observe(&mut self, _: &Progress) -> Control {
        Control::Continue
    }

    fn wants(&self, _: &str) -> bool {
        false
    }
}

/// Keeps every event of the chosen stages (a convergence history).
#[derive(Clone, Debug, Default)]
pub struct History {
    pub events: Vec<Progress>,
    /// Stages to keep; empty keeps all.
    pub stages: Vec<&'static str>,
}

impl History {
    pub fn of(stages: &[&'static str]) -> Self {
        Self {
            events: Vec::new(),
            stages: stages.to_vec(),
        }
    }
}

impl Observer for History {
    fn observe(&mut self, progress: &Progress) -> Control {
        if self.wants(progress.stage) {
            self.events.push(*progress);
        }
        Control::Continue
    }

    fn wants(&self, stage: &str) -> bool {
        self.stages.is_empty() || self.stages.contains(&stage)
    }
}
