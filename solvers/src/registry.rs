//! Every solver the harness knows, and everything solver-specific about it:
//! name, description and source, the laws it solves, its settings (paths,
//! help, defaults), its progress stages and unit of work, its accuracy knob.
//! The harness reads only this; adding a solver is its own file (which
//! defines an [`Entry`]) plus one line in [`SOLVERS`].

use std::sync::RwLock;

use nalgebra_sparse::CsrMatrix;
use serde_json::Value;

use crate::problem::ContactProblem;
use crate::settings::Stopping;
use crate::solver::{Law, Solver};

/// What a solver is to this testbed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// The paper's method: Table 1 counts its iterations.
    PapersMethod,
    /// The independent conic oracle the paper's method is verified against.
    Oracle,
    /// Any other solver.
    Other,
}

/// Values of one knob that a study runs through, one at a time around the
/// defaults (as the command line would write them).
#[derive(Clone, Copy, Debug)]
pub struct Variation {
    pub knob: &'static str,
    pub values: &'static [&'static str],
    /// A shorter list for quick runs (tests).
    pub quick: &'static [&'static str],
}

/// One iteration of a solver's inner loop, ready to be timed against one
/// product with `matrix` (the operator it iterates with).
pub struct InnerKernel {
    pub name: &'static str,
    pub matrix: CsrMatrix<f64>,
    pub step: Box<dyn FnMut()>,
}

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
    pub role: Role,
    /// One-factor sweeps of the Coulomb problem (parameter studies).
    pub sweeps: &'static [Variation],
    /// Stress conditions of the stability map.
    pub stress: &'static [Variation],
    /// Work (events of its work stage, over a whole Coulomb solve) after
    /// which a study stops it: a count, so that a study's results do not
    /// depend on the machine's speed.
    pub study_work: usize,
    /// Its inner iteration for the speed benchmark (None: it has none).
    pub kernel: Option<fn(&ContactProblem) -> InnerKernel>,
    /// Other starting points, each a set of settings (path within the
    /// solver, value): a study runs them all to see whether the solver
    /// finds one solution or several.
    pub restarts: &'static [&'static [(&'static str, &'static str)]],
    /// Settings that make it report diagnostics (e.g. a condition number).
    pub diagnose: &'static [(&'static str, &'static str)],
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
    &crate::conic::ENTRY_QP,
    &crate::conic::ENTRY_FAER,
    &crate::conic::ENTRY_CONDENSED,
    &crate::nsgs::ENTRY,
    &crate::apgd::ENTRY,
    &crate::admm::ENTRY,
    &crate::newton_coulomb::ENTRY,
];

/// Solvers registered at run time (by a program that embeds contactlab, or
/// a test), after the built-in ones.
static REGISTERED: RwLock<Vec<&'static Entry>> = RwLock::new(Vec::new());

/// Registers a solver at run time; every command and study sees it from
/// then on. Names must be unique.
pub fn register(entry: &'static Entry) -> Result<(), String> {
    if by_name(entry.name).is_some() {
        return Err(format!(
            "a solver named '{}' is registered already",
            entry.name
        ));
    }
    REGISTERED
        .write()
        .map_err(|_| "the registry lock is poisoned".to_string())?
        .push(entry);
    Ok(())
}

/// Every registered solver: the built-in ones, then those registered at run time.
pub fn solvers() -> Vec<&'static Entry> {
    let mut all: Vec<&'static Entry> = SOLVERS.to_vec();
    if let Ok(extra) = REGISTERED.read() {
        all.extend(extra.iter().copied());
    }
    all
}

/// The solver with a role (the paper's method, the oracle), if registered.
pub fn with_role(role: Role) -> Option<&'static Entry> {
    solvers().into_iter().find(|e| e.role == role)
}

/// The oracle and its registered variants: the entries with the oracle's
/// laws and knobs (the same program with other defaults: another
/// formulation, linear solver or condensation). Empty without an oracle.
pub fn oracle_family() -> Vec<&'static Entry> {
    let Some(oracle) = with_role(Role::Oracle) else {
        return Vec::new();
    };
    let knobs = |e: &Entry| e.knobs.iter().map(|k| k.name).collect::<Vec<_>>();
    solvers()
        .into_iter()
        .filter(|e| e.laws == oracle.laws && knobs(e) == knobs(oracle))
        .collect()
}

/// Looks a solver up by name.
pub fn by_name(name: &str) -> Option<&'static Entry> {
    solvers().into_iter().find(|e| e.name == name)
}

/// The registered names, for messages.
pub fn names() -> Vec<&'static str> {
    solvers().iter().map(|e| e.name).collect()
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
        for role in [Role::PapersMethod, Role::Oracle] {
            let n = SOLVERS.iter().filter(|e| e.role == role).count();
            assert!(n <= 1, "at most one solver has role {role:?}");
        }
    }

    #[test]
    fn the_oracle_family_is_the_oracle_and_its_variants_only() {
        let family: Vec<&str> = oracle_family().iter().map(|e| e.name).collect();
        let oracle = with_role(Role::Oracle).expect("registered");
        let paper = with_role(Role::PapersMethod).expect("registered");
        assert!(family.contains(&oracle.name), "{family:?}");
        assert!(!family.contains(&paper.name), "{family:?}");
        for name in &family {
            let e = by_name(name).expect("registered");
            assert_eq!(e.laws, oracle.laws, "{name} solves other laws");
        }
    }
}
