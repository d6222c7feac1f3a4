//! The benchmark's performance goals as data: each goal is a kind with
//! its limit and what was measured, typed; `templates/bench_goals.md`
//! words them (issue 76: no prose in Rust). [`super::goals`] and
//! [`super::multigrid`] compute them from the rows of one run.

use serde::Serialize;

/// One goal, measured: what was measured, by kind, and whether it passed
/// (none: not measured in this run).
#[derive(Clone, Debug, Serialize)]
pub struct Goal {
    pub measured: Measured,
    pub pass: Option<bool>,
}

/// A mesh and a number measured on it (a ratio, a gap).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AtMesh {
    pub h: String,
    pub value: f64,
}

/// Iterations on one mesh, and whether the answer was certified.
#[derive(Clone, Debug, Serialize)]
pub struct Count {
    pub h: String,
    pub iterations: usize,
    pub certified: bool,
}

/// One run of the equal-accuracy comparison, as the goal names it.
#[derive(Clone, Debug, Serialize)]
pub struct EqualRun {
    /// The setting that tells the paper's method's runs apart, or another
    /// solver's name.
    pub label: String,
    pub seconds: f64,
    pub work: usize,
    /// The unit of `work` (a sweep, a TNNMG iteration, ...).
    pub stage: &'static str,
    pub status: String,
    pub certificate: f64,
}

/// The runs of the equal-accuracy comparison on one mesh.
#[derive(Clone, Debug, Serialize)]
pub struct EqualMesh {
    pub h: String,
    pub runs: Vec<EqualRun>,
}

/// One of the multigrid solver's phases in work units.
#[derive(Clone, Debug, Serialize)]
pub struct Phase {
    pub name: String,
    pub units: f64,
}

/// The medians of the products timed before and after a solve.
#[derive(Clone, Debug, Serialize)]
pub struct ProductSides {
    /// How many products both medians are of.
    pub products: usize,
    pub before_ms: f64,
    pub after_ms: f64,
}

/// A solve in work units: its seconds over one product A·v.
#[derive(Clone, Debug, Serialize)]
pub struct WorkUnits {
    pub total: f64,
    pub seconds: f64,
    /// One product, ms.
    pub unit_ms: f64,
    pub sides: Option<ProductSides>,
    /// The solver's own phases.
    pub phases: Vec<Phase>,
    /// What the solver's own total leaves: the friction fixed point's
    /// updates, the continuation's transfers, the harness.
    pub rest: Option<f64>,
    pub status: String,
}

/// One fresh-process run of the multigrid solver on a fine mesh.
#[derive(Clone, Debug, Serialize)]
pub struct FineRun {
    pub h: String,
    pub seconds: f64,
    pub peak_gib: f64,
    pub status: String,
}

/// The limit a fine mesh's run is held to.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum FineLimit {
    /// Its peak memory at most `gib`, certified.
    Peak { gib: f64 },
    /// Certified, its peak at most `gib`, at most `seconds`.
    PeakAndTime { gib: f64, seconds: f64 },
}

/// What a run exceeded of its [`FineLimit`].
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Exceeded {
    /// The peak limit, GiB, if the peak was above it.
    pub peak_gib: Option<f64>,
    /// The time limit, s, if the run took longer.
    pub seconds: Option<f64>,
}

impl Exceeded {
    pub fn nothing(&self) -> bool {
        self.peak_gib.is_none() && self.seconds.is_none()
    }
}

/// What became of the goal's fine mesh.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum FineOutcome {
    /// The mesh is beyond the accepted range.
    Refused { why: String },
    /// Run, and what it exceeded.
    Run { run: FineRun, exceeded: Exceeded },
    /// Not run: too little memory here.
    Skipped { h: String, why: String },
    /// Not planned in this run: the long run's.
    NotPlanned { h: String },
    /// Planned, but not measured: its measurement failed.
    NotMeasured { h: String },
}

/// What a goal measured, by kind, with its limit.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Measured {
    /// No certified solver of the whole Coulomb problem at `h`.
    CoulombNotMeasured { h: String },
    /// The fastest certified solver of the Coulomb problem at `h` against
    /// at most `limit` × the best factorization.
    CoulombSpeed {
        h: String,
        limit: f64,
        solver: String,
        seconds: f64,
        ratio: f64,
    },
    /// The fastest against the oracle at `h`: at least `limit` × faster at
    /// an equal or smaller certificate.
    FasterThanOracle {
        h: String,
        limit: f64,
        ratio: f64,
        certificate: f64,
        oracle_certificate: f64,
        oracle_status: String,
    },
    /// Peak memory of the fastest solver at `h` under `limit`.
    PeakMemory {
        h: String,
        limit: &'static str,
        mib: f64,
    },
    /// Assembly against the best factorization on the meshes from
    /// `from`, and against writing its output.
    Assembly {
        from: &'static str,
        limit: f64,
        worst: f64,
        worst_h: String,
        ratios: Vec<AtMesh>,
        over_output: Vec<AtMesh>,
    },
    /// The oracle's fastest variant's whole Coulomb problem at `h`.
    OracleTime {
        h: String,
        solver: String,
        limit_seconds: f64,
        seconds: f64,
        ratio: f64,
        status: String,
        certificate: f64,
        note: String,
    },
    /// The paper's method to a certified accuracy against the oracle.
    EqualAccuracy {
        target: String,
        meshes: Vec<EqualMesh>,
        worst: f64,
    },
    /// One inner iteration of the paper's method against one sparse
    /// matrix-vector product at `h`.
    PaperKernel {
        kernel: String,
        h: &'static str,
        limit: f64,
        ratio: f64,
    },
    /// The multigrid solver's iterations from zero on the given-friction
    /// subproblem.
    Iterations {
        solver: &'static str,
        tolerance: f64,
        bound_of_scale: f64,
        limit: usize,
        counts: Vec<Count>,
    },
    /// The multigrid solver's default solve against the best
    /// factorization.
    DefaultSolve {
        solver: &'static str,
        h: String,
        limit: f64,
        seconds: f64,
        ratio: f64,
        factorization: Option<f64>,
        peak_gib: f64,
        status: String,
        runs: usize,
    },
    /// The multigrid solver's whole Coulomb problem in work units
    /// (none: the product was not timed).
    WorkUnits {
        solver: String,
        h: String,
        limit: f64,
        units: Option<WorkUnits>,
    },
    /// The multigrid solver's speed-up from one thread to the machine's.
    ThreadSpeedUp {
        solver: &'static str,
        cores: usize,
        h: String,
        limit: f64,
        speed_up: f64,
        one_seconds: f64,
        one_status: String,
        all_seconds: f64,
        all_status: String,
        runs: usize,
    },
    /// The multigrid solver on a fine mesh, held to `limit`.
    Fine {
        solver: &'static str,
        h: String,
        limit: FineLimit,
        outcome: FineOutcome,
        coarser: Vec<FineRun>,
    },
    /// The paper's method with multigrid inside.
    PaperMultigrid {
        h: String,
        limit_seconds: f64,
        seconds: f64,
        status: String,
    },
    /// The multigrid solver's pressures against another's.
    Agreement {
        solver: &'static str,
        against: &'static str,
        limit: f64,
        gaps: Vec<AtMesh>,
    },
}
