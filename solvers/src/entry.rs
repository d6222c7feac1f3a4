//! What a solver is to the harness: the types of a registry entry (name,
//! description and source, the laws it solves, its settings, its progress
//! stages and unit of work, its accuracy knob, its inner kernel). Each
//! solver defines its [`Entry`] beside its code; the list of solvers is in
//! [`crate::registry`], which is the only module that names them all.

use serde_json::Value;

use crate::problem::ContactProblem;
pub use crate::settings::Knob;
use crate::settings::{Stopping, check_tree};
use crate::solver::{Law, Solver};

/// What builds a solver from its settings tree.
pub type BuildFn = dyn Fn(&Value) -> Result<Box<dyn Solver>, String> + Send + Sync;

/// How an entry builds its solver: a function (every solver of this
/// crate), or a closure made at run time, for a solver registered by a
/// program (a Python function through the binding: the closure holds it).
#[derive(Clone, Copy)]
pub enum Build {
    Fn(fn(&Value) -> Result<Box<dyn Solver>, String>),
    Closure(&'static BuildFn),
}

impl Build {
    /// The solver for `tree`, meeting a problem with an initial gap in
    /// the closed unknowns ([`crate::reduction::gap`]): every solver,
    /// built in or registered, solves gaps without code of its own.
    pub fn call(&self, tree: &Value) -> Result<Box<dyn Solver>, String> {
        let inner = match self {
            Build::Fn(f) => f(tree),
            Build::Closure(f) => f(tree),
        }?;
        Ok(Box::new(crate::reduction::gap::ClosingGap::new(inner)))
    }
}

impl std::fmt::Debug for Build {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Build::Fn(_) => "Build::Fn",
            Build::Closure(_) => "Build::Closure",
        })
    }
}

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

/// One iteration of a solver's inner loop, ready to be timed against one
/// product with `matrix` (the operator it iterates with).
pub struct InnerKernel {
    pub name: &'static str,
    pub matrix: crate::numerics::linalg::Csr,
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

/// The knob that trades time for accuracy (work-precision diagrams,
/// benchmarks at a target accuracy, references).
#[derive(Clone, Copy, Debug)]
pub struct Accuracy {
    pub knob: &'static str,
    /// The value for the most accurate solve it offers (a reference).
    pub reference: f64,
    /// Whether its answers can serve as a reference at all (exact solvers:
    /// interior point, Newton; not a method whose error is set by its
    /// stopping rule, like the relaxation).
    pub exact: bool,
}

/// A registered solver: what it is. How the studies study it (which
/// settings they sweep, the stress conditions, the work caps) is the
/// studies' business, keyed by the solver's name.
#[derive(Debug)]
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
    /// The mesh continuation it runs unless the user names one: its
    /// fastest certified schedule, measured (for a solver that does not
    /// warm-start it is never used).
    pub schedule: crate::schedule::Schedule,
    /// Another default schedule when one of its settings (a path in its
    /// settings tree) holds a given value: (path, value, schedule). The
    /// paper's method runs the paper's continuation with its own sweeps
    /// inside, and the nested one with multigrid inside, its fastest.
    pub schedule_when: Option<(&'static str, &'static str, crate::schedule::Schedule)>,
    pub stages: &'static [StageInfo],
    /// The stage whose events count as its work (for budgets and "slow").
    pub work_stage: &'static str,
    pub knobs: &'static [Knob],
    /// The settings tree for a stopping mode: its settings struct's defaults.
    pub defaults: fn(Stopping) -> Value,
    /// Builds the solver from a settings tree (unknown fields and values
    /// that its knobs' kinds refuse are errors that name the field).
    pub build: Build,
    pub accuracy: Accuracy,
    pub role: Role,
    /// Its inner iteration for the speed benchmark (None: it has none; the
    /// function's None: not for this problem).
    pub kernel: Option<fn(&ContactProblem) -> Option<InnerKernel>>,
    /// The most unknowns it is given (None: no cap). A solver that factors
    /// A, or a matrix of its size, holds a factor that grows faster than
    /// the problem; [`FACTORED_MAX_UNKNOWNS`] refuses the meshes on which
    /// it would exhaust the machine's memory mid-run.
    pub max_unknowns: Option<usize>,
    /// Whether it reads the mass matrix M (the proximal term of paper
    /// (15)). A problem assembled for a solver that does not is built
    /// without M ([`crate::problem::Mass::Omitted`]): a third of the
    /// assembled problem, 235 MB at h = 1/1024.
    pub uses_mass: bool,
    /// The peak memory of a whole solve (the problem assembled as the
    /// solver needs it, and solved), per unknown of the finest mesh: the
    /// harness estimates a run's memory from it before anything is
    /// allocated, and refuses a run that would not fit.
    pub memory: Memory,
}

/// The peak memory of a whole solve per unknown, n·(a + b·log₂ n) bytes
/// for n unknowns: measured (peak resident memory of `contactlab solve`,
/// problem 1, from h = 1/128 to the finest mesh the solver runs) and
/// rounded up, so that the estimate is at or above every measurement. A
/// solver that factors a sparse matrix grows as n log n (the fill of a
/// factor of a 2D mesh); one that keeps vectors and matrices of the mesh,
/// as n.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Memory {
    /// a: bytes per unknown.
    pub per_unknown: f64,
    /// b: bytes per unknown and binary digit of the unknown count.
    pub per_unknown_log2: f64,
}

impl Memory {
    /// The estimate for `n` unknowns, in bytes.
    pub fn bytes(&self, n: usize) -> f64 {
        let n = n as f64;
        n * (self.per_unknown + self.per_unknown_log2 * n.max(2.0).log2())
    }
}

/// The condensation onto the contact unknowns (one sparse Cholesky factor
/// of A without them, [`crate::reduction::condensed`]) with the problem
/// assembled around it: 96 bytes per unknown and binary digit measured at
/// h = 1/256 (1640 B per unknown), 90 at 1/512 and 88 at 1/1024 (3.7 GB),
/// the same for every solver that condenses (newton, newton-coulomb,
/// clarabel-condensed, nsgs, apgd, admm) and for `export`.
pub const CONDENSED_MEMORY: Memory = Memory {
    per_unknown: 0.0,
    per_unknown_log2: 100.0,
};

/// The cap of the solvers that factor A: 2²² unknowns, between h = 1/1024
/// of the paper's scenes (2.1 million, where newton-coulomb peaks at 4.3
/// GiB) and 1/2048 (8.4 million, about four times the unknowns and more
/// than four times the factor: beyond a 24 GiB machine).
pub const FACTORED_MAX_UNKNOWNS: usize = 1 << 22;

impl Entry {
    /// The schedule it runs unless the user names one, for its settings
    /// tree `tree` ([`Entry::schedule`], or [`Entry::schedule_when`]'s).
    pub fn default_schedule(&self, tree: &serde_json::Value) -> crate::schedule::Schedule {
        match self.schedule_when {
            Some((path, value, schedule))
                if tree.pointer(&format!("/{}", path.replace('.', "/")))
                    == Some(&serde_json::Value::from(value)) =>
            {
                schedule
            }
            _ => self.schedule,
        }
    }

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

    /// A knob's help with its default: `what it does [default 1e-10]`.
    pub fn help(&self, knob: &Knob) -> String {
        knob.help_with_default(self.defaults)
    }

    /// Checks a settings tree against the knobs' kinds (see [`check_tree`]).
    pub fn check(&self, tree: &Value) -> Result<(), String> {
        check_tree(self.name, self.knobs, self.defaults, tree)
    }
}
