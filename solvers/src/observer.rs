//! One small hook through which solvers report progress (iteration, residual,
//! time). The harness turns it into logs, progress bars and convergence
//! histories; solvers never print.

/// Which loop an event comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stage {
    /// An interior-point iteration (Clarabel); residual: max(primal, dual residual).
    InteriorPoint,
    /// An Uzawa iteration of the modified Lagrangian; residual: max|Δl|.
    Uzawa,
    /// A pointwise relaxation sweep; residual: max|Δv|.
    Sweep,
    /// A Newton step; residual: the natural-map residual.
    Newton,
    /// A step of the Coulomb fixed point; residual: max|g^{m+1} − g^m|.
    Friction,
}

impl Stage {
    pub fn as_str(self) -> &'static str {
        match self {
            Stage::InteriorPoint => "interior_point",
            Stage::Uzawa => "uzawa",
            Stage::Sweep => "sweep",
            Stage::Newton => "newton",
            Stage::Friction => "friction",
        }
    }
}

/// One progress event.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    pub stage: Stage,
    /// 1-based count within the stage (for the current call).
    pub iteration: usize,
    pub residual: f64,
    /// Seconds since the reporting solver started.
    pub seconds: f64,
}

/// Receives progress events.
pub trait Observer {
    fn observe(&mut self, progress: &Progress);

    /// Whether sweep-level events are wanted (they are many; a solver may
    /// skip building them otherwise).
    fn wants(&self, _stage: Stage) -> bool {
        true
    }
}

/// Ignores everything.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Observer for Silent {
    fn observe(&mut self, _: &Progress) {}

    fn wants(&self, _: Stage) -> bool {
        false
    }
}

/// Keeps every event (a convergence history).
#[derive(Clone, Debug, Default)]
pub struct History {
    pub events: Vec<Progress>,
    /// Stages to keep; empty keeps all.
    pub stages: Vec<Stage>,
}

impl History {
    pub fn of(stages: &[Stage]) -> Self {
        Self {
            events: Vec::new(),
            stages: stages.to_vec(),
        }
    }
}

impl Observer for History {
    fn observe(&mut self, progress: &Progress) {
        if self.wants(progress.stage) {
            self.events.push(*progress);
        }
    }

    fn wants(&self, stage: Stage) -> bool {
        self.stages.is_empty() || self.stages.contains(&stage)
    }
}
