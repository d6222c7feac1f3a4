//! Every solver the harness knows, by name. Adding a solver means adding its
//! module and settings here and one line to [`SOLVERS`].

use serde::{Deserialize, Serialize};

use crate::conic::{ConicSettings, ConicSolver};
use crate::newton::{CondensedNewton, NewtonSettings};
use crate::relaxation::{ProxUzawa, RelaxationSettings};
use crate::solver::GivenFrictionSolver;

/// The settings of every registered solver (one section each in scene files).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverSettings {
    pub clarabel: ConicSettings,
    pub relaxation: RelaxationSettings,
    pub newton: NewtonSettings,
}

impl SolverSettings {
    /// Checks every solver's settings; the message names the field.
    pub fn validate(&self) -> Result<(), String> {
        self.clarabel.validate()?;
        self.relaxation.validate()?;
        self.newton.validate()
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
    /// Sets the solver's accuracy knob (for work-precision diagrams).
    pub set_tolerance: fn(&mut SolverSettings, f64),
    /// Values of that knob a work-precision diagram runs through.
    pub tolerances: &'static [f64],
}

/// The registry.
pub const SOLVERS: &[Entry] = &[
    Entry {
        name: "clarabel",
        about: "conic oracle: interior point (Clarabel) with SOC friction cones",
        build: |s| Box::new(ConicSolver::new(s.clarabel.clone())),
        continuation: false,
        set_tolerance: |s, t| {
            s.clarabel.tol_gap_abs = t;
            s.clarabel.tol_gap_rel = t;
            s.clarabel.tol_feas = t;
        },
        tolerances: &[1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
    },
    Entry {
        name: "relaxation",
        about: "the paper's method: prox-Uzawa on the modified Lagrangian, pointwise relaxation inside",
        build: |s| Box::new(ProxUzawa::new(s.relaxation.clone())),
        continuation: true,
        set_tolerance: |s, t| s.relaxation.epsilon = t,
        tolerances: &[1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8],
    },
    Entry {
        name: "newton",
        about: "fast exact solver: condensation onto the contact unknowns (sparse Cholesky once), semismooth Newton with line search",
        build: |s| Box::new(CondensedNewton::new(s.newton.clone())),
        continuation: false,
        set_tolerance: |s, t| s.newton.tolerance = t,
        tolerances: &[1e-4, 1e-6, 1e-8, 1e-10, 1e-12],
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
