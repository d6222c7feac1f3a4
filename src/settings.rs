//! All settings of a computation, with the paper's values as defaults; built
//! by serde from scene files and overridden by CLI flags.

use contactlab_solvers::registry::SolverSettings;
use serde::{Deserialize, Serialize};

use crate::coulomb::continuation::Schedule;
use crate::coulomb::fixed_point::CoulombSettings;

/// Settings of the Coulomb fixed point and of every registered solver.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Settings {
    pub coulomb: CoulombSettings,
    /// Mesh continuation schedule for solvers that warm-start.
    pub schedule: Schedule,
    pub solver: SolverSettings,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            coulomb: CoulombSettings::default(),
            schedule: Schedule::Revisit,
            solver: SolverSettings::default(),
        }
    }
}

impl Settings {
    /// Checks every field; the message names it and says what is valid.
    pub fn validate(&self) -> Result<(), String> {
        self.coulomb.validate()?;
        self.solver.validate()
    }
}
