//! The paper's method in the registry: its name, source, stages, knobs,
//! sweeps and stress values, and its inner kernel (one sweep) for `bench`.

use super::pointwise::{self, RelaxationOperator, SweepData};
use super::{ProxUzawa, RelaxationSettings};
use crate::entry::{Accuracy, Entry, InnerKernel, Knob, Memory, Role, StageInfo};
use crate::problem::ContactProblem;
use crate::settings::{Kind, from_tree, to_tree};
use crate::solver::Law;

/// The knob of the certified stopping rule (a tolerance in the
/// certificate's measure; 0: the paper's rules), for studies that run the
/// method to a guaranteed accuracy.
pub const CERTIFIED_STOP_KNOB: &str = "target";
/// The knob of over-relaxation in the sweeps (1: the paper's Gauss–Seidel).
pub const OVER_RELAXATION_KNOB: &str = "omega";
/// The knob of the inner minimization at fixed l^k, and its value that
/// runs it by TNNMG ([`crate::multigrid`]) instead of the paper's sweeps.
pub const INNER_KNOB: &str = "inner";
pub const INNER_BY_MULTIGRID: &str = "multigrid";
/// The over-relaxation factor the studies compare with the paper's ω = 1:
/// one stated value for every mesh, not tuned per mesh.
pub const STUDIED_OMEGA: f64 = 1.5;

/// The progress stage of one Uzawa iteration (14).
pub(crate) const UZAWA: &str = "uzawa";
/// The progress stage of one pointwise relaxation sweep (the unit of work).
pub(crate) const SWEEP: &str = "sweep";

/// The registry entry of the paper's method.
pub(crate) const ENTRY: Entry = Entry {
    name: "relaxation",
    about: "the paper's method: prox-Uzawa on the modified Lagrangian, pointwise relaxation inside",
    source: "Zhiltsov & Namm (2019), sections 3-5: modified Lagrangian (Theorem 2), Uzawa (14), proximal regularization (15)-(16), Algorithm 1",
    laws: &[Law::GivenFriction],
    warm_starts: true,
    // The paper's method keeps the paper's reading of Algorithm 1 (every
    // level in every friction iteration), as its Table 1 is reproduced.
    schedule: crate::schedule::Schedule::Revisit,
    schedule_when: Some(("inner", "multigrid", crate::schedule::Schedule::Nested)),
    stages: &[
        StageInfo {
            name: UZAWA,
            about: "one Uzawa iteration (14); residual max|Δl|",
            history: true,
        },
        StageInfo {
            name: SWEEP,
            about: "one pointwise relaxation sweep; residual max|Δv|",
            history: false,
        },
    ],
    work_stage: SWEEP,
    knobs: &[
        Knob {
            name: "r",
            fields: &["r"],
            help: "penalty r of the modified Lagrangian; relative: in units of K/L",
            kind: Kind::Positive,
        },
        Knob {
            name: "epsilon",
            fields: &["epsilon"],
            help: "Uzawa stops when max|Δl| ≤ ε (relative: ε·P)",
            kind: Kind::Positive,
        },
        Knob {
            name: "sweep_factor",
            fields: &["sweep_factor"],
            help: "sweeps stop when max|Δv| ≤ factor·ε·U·h/L (relative) or ≤ factor·ε/64 (paper)",
            kind: Kind::Positive,
        },
        Knob {
            name: "proximal",
            fields: &["proximal"],
            help: "weight ρ of (ρ/2)‖v − v^k‖²_L2, 0 turns it off; relative: in units of K/L²",
            kind: Kind::NonNegative,
        },
        Knob {
            name: "smoothing",
            fields: &["smoothing"],
            help: "|s| along slip coordinates: `exact` (soft thresholding) or a Huber width δ; relative: in units of U",
            kind: pointwise::SMOOTHING,
        },
        Knob {
            name: OVER_RELAXATION_KNOB,
            fields: &["omega"],
            help: "over-relaxation ω of the free coordinates in each sweep, in (0, 2); 1 is the paper's Gauss–Seidel",
            kind: Kind::Between(0.0, 2.0),
        },
        Knob {
            name: INNER_KNOB,
            fields: &["inner"],
            help: "the inner minimization at fixed l^k: `sweeps` (the paper's pointwise relaxation) or `multigrid` (TNNMG with those sweeps as smoother: sweep_factor and max_sweeps then apply to its iterations, the certified rule is checked after each, omega is not used)",
            kind: Kind::Word(&["sweeps", INNER_BY_MULTIGRID]),
        },
        Knob {
            name: CERTIFIED_STOP_KNOB,
            fields: &["target"],
            help: "certified stopping: stop when the contact law's and stationarity's largest violation in the problem's scales (the certificate's measure) is ≤ target, checked after every Uzawa step and every check_every sweeps; 0: the paper's rules on max|Δl| and max|Δv|",
            kind: Kind::NonNegative,
        },
        Knob {
            name: "check_every",
            fields: &["check_every"],
            help: "sweeps between two checks of the certified stopping rule (each costs about half a sweep)",
            kind: Kind::Count,
        },
        Knob {
            name: "max_uzawa",
            fields: &["max_uzawa"],
            help: "cap on Uzawa iterations per solve",
            kind: Kind::Count,
        },
        Knob {
            name: "max_sweeps",
            fields: &["max_sweeps"],
            help: "cap on sweeps per Uzawa iteration",
            kind: Kind::Count,
        },
    ],
    defaults: |stopping| to_tree(&RelaxationSettings::defaults(stopping)),
    build: crate::entry::Build::Fn(|tree| Ok(Box::new(ProxUzawa::new(from_tree(tree)?)))),
    accuracy: Accuracy {
        knob: "epsilon",
        reference: 1e-10,
        exact: false,
    },
    role: Role::PapersMethod,
    kernel: Some(sweep_kernel),
    max_unknowns: None,
    uses_mass: true,
    memory: Memory {
        // With M and, for inner = multigrid, the hierarchies of H on every
        // level: 750-780 B per unknown measured at 1/256, 1/512 and 1/1024
        // (1.6 GB); the paper's sweeps keep less.
        per_unknown: 850.0,
        per_unknown_log2: 0.0,
    },
};

/// One relaxation sweep at the default relative settings, with multipliers
/// l = 1 and bounds g = ½ at every contact node so that every branch runs
/// (None for a problem built without the M its proximal term reads).
pub(crate) fn sweep_kernel(problem: &ContactProblem) -> Option<InnerKernel> {
    let resolved = RelaxationSettings::default().resolve(problem);
    if !RelaxationOperator::can_form(problem, resolved.proximal) {
        return None;
    }
    let op = RelaxationOperator::new(problem, resolved.proximal);
    let matrix = op.h.clone();
    let l = vec![1.0; problem.contacts().len()];
    let wg: Vec<f64> = problem.contacts().iter().map(|c| 0.5 * c.weight).collect();
    let b = problem.f().to_vec();
    let mut v = vec![0.0; problem.n()];
    Some(InnerKernel {
        name: SWEEP,
        matrix,
        step: Box::new(move || {
            let data = SweepData {
                b: &b,
                l: &l,
                wg: &wg,
                r: resolved.r,
                smoothing: resolved.smoothing,
                omega: 1.0,
            };
            std::hint::black_box(op.sweep(&mut v, &data));
        }),
    })
}
