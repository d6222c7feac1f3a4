//! The oracle: the given-friction subproblem as a conic program for Clarabel
//! (Goulart & Chen, "Clarabel: an interior-point solver for conic programs
//! with quadratic objectives", 2024),
//!
//! ```text
//! minimize ½ vᵀA v − fᵀv + Σ_i w_i g_i z_i
//! subject to t_i ≤ 0 (nonnegative cone),  (z_i, s_i) ∈ SOC(2), i.e. |s_i| ≤ z_i,
//! ```
//!
//! with A left singular (the semicoercive mode): no regularization is added.
//! The duals are the nodal contact forces: λ_i of the row t_i ≤ 0 and the
//! tail μ_i of the i-th cone, so p_i = λ_i / w_i and q_i = μ_i / w_i.
//!
//! Clarabel's relative tolerances are floored by max(1, ·), so on data of
//! any other size they act as absolute ones. By default the problem is
//! therefore written in its own scales ([`crate::Scales`]): v̂ = v/U and the
//! objective divided by F·U, i.e. ½ v̂ᵀ(A/K)v̂ − (f/F)ᵀv̂ + Σ (w_i g_i/F) ẑ_i,
//! whose data are of order one whatever the units; the duals come back as
//! λ/F.
//!
//! With `condense` the same program is written in the contact unknowns
//! y = (t_i, s_i) alone, A and f replaced by the Schur complement S and the
//! reduced load b̂ of [`crate::reduction::condensed`] (static condensation: exact, one
//! sparse factorization kept across calls), and v recovered from y. Clarabel
//! then factors KKT systems of order 6m instead of n + 4m.

use std::time::Instant;

use clarabel::solver::{DefaultSettings, DefaultSettingsBuilder};
use serde::{Deserialize, Serialize};

use crate::entry::{
    Accuracy, CONDENSED_MEMORY, Entry, FACTORED_MAX_UNKNOWNS, Knob, Memory, Role, StageInfo,
};
use crate::numerics::linalg::RowValues;
use crate::observer::{Limits, Observer};
use crate::problem::ContactProblem;
use crate::reduction::condensed::{Condensed, Kept, condense};
use crate::settings::{Kind, Validate, from_tree, to_tree};
use crate::solution::{Iterations, Solution, Status};
use crate::solver::{Friction, Law, Solver, Start};

mod program;
use program::Program;

/// The progress stage of one interior point (its unit of work).
pub(crate) const INTERIOR_POINT: &str = "interior_point";

/// The registry entry of the conic oracle.
pub(crate) const ENTRY: Entry = Entry {
    name: "clarabel",
    about: "conic oracle: interior point (Clarabel) with a second-order cone per contact node",
    source: "Goulart & Chen (2024), Clarabel; the subproblem is paper (10) as a conic program",
    laws: &[Law::GivenFriction],
    warm_starts: false,
    schedule: crate::schedule::Schedule::Revisit,
    schedule_when: None,
    stages: &[StageInfo {
        name: INTERIOR_POINT,
        about: "one interior-point iteration; residual max(primal, dual residual, gap)",
        history: true,
    }],
    work_stage: INTERIOR_POINT,
    knobs: &[
        Knob {
            name: "tol",
            fields: &["tol_gap_abs", "tol_gap_rel", "tol_feas"],
            help: "gap and feasibility tolerance (sets tol_gap_abs, tol_gap_rel, tol_feas)",
            kind: Kind::Positive,
        },
        Knob {
            name: "max_iter",
            fields: &["max_iter"],
            help: "interior-point iteration cap",
            kind: Kind::Count,
        },
        Knob {
            name: "equilibrate",
            fields: &["equilibrate"],
            help: "Clarabel's Ruiz equilibration of the data (true/false)",
            kind: Kind::Flag,
        },
        Knob {
            name: "scale_unknowns",
            fields: &["scale_unknowns"],
            help: "write the problem in its own scales, v/U and the objective over F·U (true/false)",
            kind: Kind::Flag,
        },
        Knob {
            name: "verbose",
            fields: &["verbose"],
            help: "Clarabel's own iteration log, to stdout (true/false)",
            kind: Kind::Flag,
        },
        Knob {
            name: "formulation",
            fields: &["formulation"],
            help: "the friction cone as `soc` (second-order cones) or `qp` (two half-planes)",
            kind: Kind::Word(&["soc", "qp"]),
        },
        Knob {
            name: "linear_solver",
            fields: &["linear_solver"],
            help: "Clarabel's sparse LDLᵀ: `qdldl` or `faer` (one thread)",
            kind: Kind::Word(&["qdldl", "faer"]),
        },
        Knob {
            name: "condense",
            fields: &["condense"],
            help: "give Clarabel the problem condensed onto the contact unknowns (true/false)",
            kind: Kind::Flag,
        },
    ],
    defaults: |_| to_tree(&ConicSettings::default()),
    build: crate::entry::Build::Fn(|tree| Ok(Box::new(ConicSolver::new(from_tree(tree)?)))),
    accuracy: Accuracy {
        knob: "tol",
        reference: 1e-10,
        exact: true,
    },
    role: Role::Oracle,
    kernel: None,
    max_unknowns: Some(FACTORED_MAX_UNKNOWNS),
    uses_mass: false,
    // QDLDL's factor of the KKT system: 131-134 bytes per unknown and
    // binary digit measured at 1/128, 1/256 and 1/512 (1.3 GB); the same
    // for the QP form.
    memory: Memory {
        per_unknown: 0.0,
        per_unknown_log2: 140.0,
    },
};

/// The registry entry of the oracle in its second formulation: in two
/// dimensions the cone |s_i| ≤ z_i is the two half-planes s_i − z_i ≤ 0 and
/// −s_i − z_i ≤ 0, so the subproblem is a quadratic program with
/// nonnegative cones only.
pub(crate) const ENTRY_QP: Entry = Entry {
    name: "clarabel-qp",
    about: "the conic oracle as a QP: the friction cone of each node as two half-planes (nonnegative cones only)",
    source: "Goulart & Chen (2024), Clarabel; paper (10) with |s| ≤ z written as s − z ≤ 0, −s − z ≤ 0",
    defaults: |_| {
        to_tree(&ConicSettings {
            formulation: Formulation::Qp,
            ..ConicSettings::default()
        })
    },
    role: Role::Other,
    ..ENTRY
};

/// The registry entry of the oracle with Clarabel's other linear solver:
/// the same second-order cone program, its KKT systems factored by faer's
/// supernodal LDLᵀ (Clarabel's `faer-sparse` feature) instead of QDLDL, on
/// one thread like every timed solver here.
pub(crate) const ENTRY_FAER: Entry = Entry {
    name: "clarabel-faer",
    about: "the conic oracle (second-order cones) with faer's sparse LDLᵀ instead of QDLDL inside Clarabel",
    source: "Goulart & Chen (2024), Clarabel, direct_solve_method = \"faer\"; paper (10) as a conic program",
    defaults: |_| {
        to_tree(&ConicSettings {
            linear_solver: LinearSolver::Faer,
            ..ConicSettings::default()
        })
    },
    role: Role::Other,
    // faer's LDLᵀ inside Clarabel: 119 bytes per unknown and binary
    // digit measured at 1/256 and 1/512.
    memory: Memory {
        per_unknown: 0.0,
        per_unknown_log2: 125.0,
    },
    ..ENTRY
};

/// The registry entry of the oracle on the condensed problem: the interior
/// unknowns eliminated exactly by one sparse Cholesky factorization (kept
/// across the friction iterations, see [`crate::reduction::condensed`]); Clarabel then
/// solves the subproblem in the 2m contact unknowns, with the dense Schur
/// complement as its quadratic form and its KKT systems factored by faer.
/// The cone of each node is given as two half-planes: measured on problem 1
/// at h = 1/16 and 1/32, the second-order-cone form of the condensed program
/// ended some given-friction steps in `AlmostSolved` (the primal residual
/// rose from 6e-13 to 3e-8 while μ fell to 1e-15, past where the full
/// program stops) and its iteration counts changed with the units; the
/// half-planes did neither.
pub(crate) const ENTRY_CONDENSED: Entry = Entry {
    name: "clarabel-condensed",
    about: "the conic oracle on the problem condensed onto the contact unknowns (dense Schur complement; cone as two half-planes; faer's LDLᵀ)",
    source: "Goulart & Chen (2024), Clarabel; paper (10) as a QP in the contact unknowns after static condensation (Schur complement of the interior unknowns)",
    defaults: |_| {
        to_tree(&ConicSettings {
            linear_solver: LinearSolver::Faer,
            formulation: Formulation::Qp,
            condense: true,
            ..ConicSettings::default()
        })
    },
    role: Role::Other,
    memory: CONDENSED_MEMORY,
    ..ENTRY
};

/// Clarabel's linear solver for its KKT systems.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LinearSolver {
    /// QDLDL, Clarabel's default.
    #[default]
    Qdldl,
    /// faer's sparse LDLᵀ, sequential.
    Faer,
}

impl LinearSolver {
    fn name(self) -> &'static str {
        match self {
            Self::Qdldl => "qdldl",
            Self::Faer => "faer",
        }
    }
}

/// How the friction cone |s_i| ≤ z_i is given to Clarabel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Formulation {
    /// One second-order cone per node.
    #[default]
    Soc,
    /// Two half-planes per node (nonnegative cones only).
    Qp,
}

/// Clarabel's settings that matter here; the rest keep Clarabel's defaults.
/// The same in both stopping modes: its tolerances act on the problem
/// written in its own scales.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ConicSettings {
    /// Absolute duality gap tolerance.
    pub tol_gap_abs: f64,
    /// Relative duality gap tolerance.
    pub tol_gap_rel: f64,
    /// Feasibility tolerance.
    pub tol_feas: f64,
    /// Interior-point iteration cap.
    pub max_iter: u32,
    /// Clarabel's Ruiz equilibration of the data.
    pub equilibrate: bool,
    /// Solve for v/U with the objective over F·U (the problem's own scales).
    pub scale_unknowns: bool,
    /// Clarabel's own console output.
    pub verbose: bool,
    /// The friction cone as second-order cones or as half-planes.
    pub formulation: Formulation,
    /// The linear solver of its KKT systems.
    pub linear_solver: LinearSolver,
    /// Solve the problem condensed onto the contact unknowns.
    pub condense: bool,
}

impl Default for ConicSettings {
    fn default() -> Self {
        Self::with_tolerance(DEFAULT_TOLERANCE)
    }
}

/// Default gap and feasibility tolerance: the tightest of 1e-8, 1e-10, 1e-12
/// that solves the paper's three problems reliably (see the closing study in
/// `results/`): 1e-12 ends in reduced accuracy or insufficient progress.
pub const DEFAULT_TOLERANCE: f64 = 1e-10;

/// The tightest tolerance [`Solver::tighten`] goes to. Clarabel certifies
/// problem 1 at h = 1/128 from 1e-11 on (3e-11 still stalls the friction
/// fixed point), and 1e-12 is the tightest at which it still ends
/// `Solved` rather than `AlmostSolved` on the paper's problems.
pub const TIGHTEST_TOLERANCE: f64 = 1e-12;

impl ConicSettings {
    /// All three tolerances set to `tol`, everything else default.
    pub(crate) fn with_tolerance(tol: f64) -> Self {
        Self {
            tol_gap_abs: tol,
            tol_gap_rel: tol,
            tol_feas: tol,
            max_iter: 200,
            equilibrate: true,
            scale_unknowns: true,
            verbose: false,
            formulation: Formulation::Soc,
            linear_solver: LinearSolver::Qdldl,
            condense: false,
        }
    }

    fn clarabel(&self, limits: &Limits) -> DefaultSettings<f64> {
        let max_iter = limits.work.map_or(self.max_iter, |w| {
            self.max_iter.min(w.min(u32::MAX as usize) as u32)
        });
        let time_limit = limits.deadline.map_or(f64::INFINITY, |d| {
            d.saturating_duration_since(Instant::now()).as_secs_f64()
        });
        DefaultSettingsBuilder::default()
            .verbose(self.verbose)
            .max_iter(max_iter)
            .time_limit(time_limit)
            .tol_gap_abs(self.tol_gap_abs)
            .tol_gap_rel(self.tol_gap_rel)
            .tol_feas(self.tol_feas)
            .equilibrate_enable(self.equilibrate)
            .direct_solve_method(self.linear_solver.name().to_string())
            .max_threads(1)
            .build()
            .expect("all settings have defaults")
    }
}

impl Validate for ConicSettings {
    /// Checked by the kinds of its registry entry's knobs.
    fn validate(&self) -> Result<(), String> {
        ENTRY.check(&to_tree(self))
    }
}

/// The conic oracle. Keeps the condensation (when it condenses) across
/// calls on the same problem operator.
#[derive(Default)]
pub struct ConicSolver {
    pub settings: ConicSettings,
    condensation: Kept<u64, Condensed>,
}

impl ConicSolver {
    pub fn new(settings: ConicSettings) -> Self {
        Self {
            settings,
            condensation: Kept::default(),
        }
    }
}

impl Solver for ConicSolver {
    /// Two rigid modes, measured: Cattaneo–Mindlin with the upper body free
    /// to slide (`scenes/cattaneo_mindlin_sliding.toml`) certifies.
    fn rigid_modes_handled(&self) -> usize {
        2
    }

    /// The gap is the right-hand side of the rows t_i + slack = d_i.
    fn poses_gaps(&self) -> bool {
        true
    }

    /// The slip offset is the right-hand side of the cone's rows on s_i.
    fn poses_slip_offsets(&self) -> bool {
        true
    }

    /// All three tolerances a tenth of the tightest of them, down to
    /// [`TIGHTEST_TOLERANCE`]. A tolerance looser than the default was
    /// chosen (a work-precision point, a quick look) and is kept.
    fn tighten(&mut self) -> Option<String> {
        let s = &mut self.settings;
        let tol = s.tol_gap_abs.min(s.tol_gap_rel).min(s.tol_feas);
        let chosen_looser =
            s.tol_gap_abs.max(s.tol_gap_rel).max(s.tol_feas) > DEFAULT_TOLERANCE * (1.0 + 1e-9);
        if chosen_looser || tol <= TIGHTEST_TOLERANCE * (1.0 + 1e-9) {
            return None;
        }
        let next = (tol / 10.0).max(TIGHTEST_TOLERANCE);
        (s.tol_gap_abs, s.tol_gap_rel, s.tol_feas) = (next, next, next);
        Some(format!("tol {tol:.0e} → {next:.0e}"))
    }

    fn solve(
        &mut self,
        problem: &ContactProblem,
        friction: Friction<'_>,
        _start: Option<Start<'_>>,
        observer: &mut dyn Observer,
    ) -> Solution {
        let (n, m) = (problem.n(), problem.contacts().len());
        let g = match Solution::given_bound(problem, friction, Ok(())) {
            Ok(g) => g,
            Err(refused) => return *refused,
        };
        let t0 = Instant::now();
        if self.settings.condense {
            let condensed = match self
                .condensation
                .get_or_build(problem.operator_id(), || condense(problem))
            {
                Ok(c) => c,
                Err(e) => return Solution::failed(n, m, e.status, e.detail),
            };
            let s = &condensed.s;
            let program = Program {
                unknowns: 2 * m,
                upper: (0..2 * m)
                    .flat_map(|j| (0..=j).map(move |i| (i, j, s[(i, j)])))
                    .collect(),
                load: &condensed.b,
                contact: (0..m).map(|i| (2 * i, 2 * i + 1)).collect(),
                bound: g,
            };
            let answer = match program.solve(&self.settings, problem, t0, observer) {
                Ok(a) => a,
                Err(e) => return Solution::failed(n, m, Status::NumericalError, e),
            };
            // The condensed forces are r = (λ_i, ν_i) with ν_i = −μ_i.
            let r: Vec<f64> = answer.forces.iter().flat_map(|&(l, mu)| [l, -mu]).collect();
            let t2 = Instant::now();
            let mut out = condensed.solution(problem, &answer.unknowns, &r, answer.end);
            out.timing.solve += t2.elapsed().as_secs_f64();
            return out;
        }
        let contacts = problem.contacts();
        let a = problem.a();
        let (offsets, cols, vals) = a.csr_data();
        let cols = &*cols;
        let program = Program {
            unknowns: n,
            upper: (0..n)
                .flat_map(|j| {
                    let (lo, hi) = a.row_range(j);
                    (lo..hi)
                        .filter(move |&k| cols[k] as usize <= j)
                        .map(move |k| (cols[k] as usize, j, vals.at(offsets, j, k)))
                })
                .collect(),
            load: problem.f(),
            contact: contacts.iter().map(|c| (c.t, c.s)).collect(),
            bound: g,
        };
        let answer = match program.solve(&self.settings, problem, t0, observer) {
            Ok(a) => a,
            Err(e) => return Solution::failed(n, m, Status::NumericalError, e),
        };
        let out = Solution {
            pressure: contacts
                .iter()
                .zip(&answer.forces)
                .map(|(c, r)| r.0 / c.weight)
                .collect(),
            friction_traction: contacts
                .iter()
                .zip(&answer.forces)
                .map(|(c, r)| r.1 / c.weight)
                .collect(),
            v: answer.unknowns,
            status: answer.end.status,
            detail: answer.end.detail,
            iterations: Iterations {
                outer: answer.end.steps,
                inner: 0,
            },
            timing: answer.end.timing,
            diagnostics: Vec::new(),
        };
        out.flag_non_finite()
    }
}
