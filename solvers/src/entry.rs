//! What a solver is to the harness: the types of a registry entry (name,
//! description and source, the laws it solves, its settings, its progress
//! stages and unit of work, its accuracy knob, its inner kernel). Each
//! solver defines its [`Entry`] beside its code; the list of solvers is in
//! [`crate::registry`], which is the only module that names them all.

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
