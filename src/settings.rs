//! All settings of a computation, with the paper's values as defaults; built
//! by serde from scene files and overridden by CLI flags.

use contactlab_solvers::registry::SolverSettings;
use serde::{Deserialize, Serialize};

use crate::friction::CoulombSettings;

/// Settings of the Coulomb fixed point and of every registered solver.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Settings {
    pub coulomb: CoulombSettings,
    pub solver: SolverSettings,
}

impl Settings {
    /// Checks every field; the message names it and says what is valid.
    pub fn validate(&self) -> Result<(), String> {
        self.coulomb.validate()?;
        self.solver.validate()
    }
}
