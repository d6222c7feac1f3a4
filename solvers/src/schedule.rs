//! The schedule of a mesh continuation (paper, Algorithm 1, lines 2-8):
//! which levels of the nested meshes a solver that warm-starts runs in each
//! friction iteration. It is named here, beside the registry's entries,
//! because each such solver has its own fastest one ([`crate::entry::Entry`]
//! `schedule`); the continuation itself is the harness's.

use serde::{Deserialize, Serialize};

/// Whether coarse levels are revisited in every friction iteration.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Schedule {
    /// All levels in every friction iteration (the paper's reading).
    #[default]
    Revisit,
    /// All levels in the first friction iteration, then the finest only.
    FinestOnly,
    /// The fixed point on each level in turn, each started from the level
    /// below (nested iteration of the whole Coulomb problem).
    Nested,
}

impl Schedule {
    pub const ALL: [Self; 3] = [Self::Revisit, Self::FinestOnly, Self::Nested];

    /// Its name in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Schedule::Revisit => "revisit",
            Schedule::FinestOnly => "finest-only",
            Schedule::Nested => "nested",
        }
    }

    /// The schedule of a name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.name() == name.trim())
    }
}

impl std::fmt::Display for Schedule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
