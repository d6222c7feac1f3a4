//! Every solver the harness knows, and everything solver-specific about it:
//! name, description and source, the laws it solves, its settings (paths,
//! help, defaults), its progress stages and unit of work, its accuracy knob.
//! The harness reads only this; adding a solver is its own file (which
//! defines an [`Entry`]) plus one line in [`SOLVERS`].

use serde_json::Value;

use crate::settings::Stopping;
use crate::solver::{Law, Solver};

/// A progress stage a solver reports (see [`crate::Progress`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StageInfo {
    pub name: &'static str,
    /// What one event is and what its residual measures.
    pub about: &'static str,
    /// Whether convergence histories keep it (not for the many inner sweeps).
    pub history: bool,
}

/// A setting reachable by path (`name.knob`) from scene files, `--set` and
/// a command-line flag `--name-knob`.
#[derive(Clone, Copy, Debug)]
pub struct Knob {
    /// The knob's name within the solver's settings.
    pub name: &'static str,
    /// The settings fields it sets: itself, or several for a shorthand
    /// (Clarabel's `tol` sets its three tolerances).
    pub fields: &'static [&'static str],
    pub help: &'static str,
    /// Parses a command-line value.
    pub parse: fn(&str) -> Result<Value, String>,
}

/// The knob that trades time for accuracy (work-precision diagrams,
/// benchmarks at a target accuracy, references).
#[derive(Clone, Copy, Debug)]
pub struct Accuracy {
    pub knob: &'static str,
    /// Values a work-precision diagram runs through, loose to tight.
    pub values: &'static [f64],
    /// The value for the most accurate solve it offers (a reference).
    pub reference: f64,
    /// Whether its answers can serve as a reference at all (exact solvers:
    /// interior point, Newton; not a method whose error is set by its
    /// stopping rule, like the relaxation).
    pub exact: bool,
}

/// A registered solver.
pub struct Entry {
    pub name: &'static str,
    pub about: &'static str,
    /// Where the method comes from (paper, section, equations).
    pub source: &'static str,
    /// The laws it solves directly. A solver without [`Law::Coulomb`] is run
    /// inside the successive approximations of paper (9).
    pub laws: &'static [Law],
    /// Whether it uses a starting point, so that mesh continuation (coarse
    /// levels first) pays off.
    pub warm_starts: bool,
    pub stages: &'static [StageInfo],
    /// The stage whose events count as its work (for budgets and "slow").
    pub work_stage: &'static str,
    pub knobs: &'static [Knob],
    /// The settings tree for a stopping mode.
    pub defaults: fn(Stopping) -> Value,
    /// Builds the solver from a settings tree (unknown fields and ranges are
    /// errors that name the field).
    pub build: fn(&Value) -> Result<Box<dyn Solver>, String>,
    pub accuracy: Accuracy,
}

impl Entry {
    /// Whether it solves `law` directly.
    pub fn solves(&self, law: Law) -> bool {
        self.laws.contains(&law)
    }

    pub fn knob(&self, name: &str) -> Option<&'static Knob> {
        self.knobs.iter().find(|k| k.name == name)
    }

    pub fn stage(&self, name: &str) -> Option<&'static StageInfo> {
        self.stages.iter().find(|s| s.name == name)
    }
}

/// The registry.
pub const SOLVERS: &[&Entry] = &[
    &crate::conic::ENTRY,
    &crate::relaxation::ENTRY,
    &crate::newton::ENTRY,
];

/// Looks a solver up by name.
pub fn by_name(name: &str) -> Option<&'static Entry> {
    SOLVERS.iter().copied().find(|e| e.name == name)
}

/// The registered names, for messages.
pub fn names() -> Vec<&'static str> {
    SOLVERS.iter().map(|e| e.name).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_entry_is_consistent() {
        for e in SOLVERS {
            assert!(e.stage(e.work_stage).is_some(), "{}: work stage", e.name);
            for stopping in [Stopping::Relative, Stopping::Paper] {
                let tree = (e.defaults)(stopping);
                (e.build)(&tree).unwrap_or_else(|m| panic!("{}: defaults: {m}", e.name));
                for k in e.knobs {
                    for f in k.fields {
                        assert!(tree.get(f).is_some(), "{}.{}: no field {f}", e.name, k.name);
                    }
                }
            }
            assert!(
                e.knob(e.accuracy.knob).is_some(),
                "{}: accuracy knob",
                e.name
            );
        }
        let mut names = names();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), SOLVERS.len(), "names are unique");
    }
}
