//! Every solver the harness knows, by name. Adding a solver means adding its
//! module and settings here and one line to [`SOLVERS`].

use serde::{Deserialize, Serialize};

use crate::conic::{ConicSettings, ConicSolver};
use crate::relaxation::{ProxUzawa, RelaxationSettings};
use crate::solver::GivenFrictionSolver;

/// The settings of every registered solver (one section each in scene files).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverSettings {
    pub clarabel: ConicSettings,
    pub relaxation: RelaxationSettings,
}

impl SolverSettings {
    /// Checks every solver's settings; the message names the field.
    pub fn validate(&self) -> Result<(), String> {
        self.clarabel.validate()?;
        self.relaxation.validate()
    }
}

/// A registered solver.
pub struct Entry {
    pub name: &'static str,
    pub about: &'static str,
    /// Builds the solver from the settings.
    pub build: fn(&SolverSettings) -> Box<dyn GivenFrictionSolver>,
    /// Whether it warm-starts, so that mesh continuation (coarse levels
    /// first) pays off; otherwise it is run on the finest level only.
    pub continuation: bool,
}

/// The registry.
pub const SOLVERS: &[Entry] = &[
    Entry {
        name: "clarabel",
        about: "conic oracle: interior point (Clarabel) with SOC friction cones",
        build: |s| Box::new(ConicSolver::new(s.clarabel.clone())),
        continuation: false,
    },
    Entry {
        name: "relaxation",
        about: "the paper's method: prox-Uzawa on the modified Lagrangian, pointwise relaxation inside",
        build: |s| Box::new(ProxUzawa::new(s.relaxation.clone())),
        continuation: true,
    },
];

/// Looks a solver up by name.
pub fn by_name(name: &str) -> Option<&'static Entry> {
    SOLVERS.iter().find(|e| e.name == name)
}

/// The registered names, for messages.
pub fn names() -> Vec<&'static str> {
    SOLVERS.iter().map(|e| e.name).collect()
}
