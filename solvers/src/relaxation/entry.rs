//! The paper's method in the registry: its name, source, stages, knobs,
//! sweeps and stress values, and its inner kernel (one sweep) for `bench`.

use super::pointwise::{self, RelaxationOperator, SweepData};
use super::{ProxUzawa, RelaxationSettings};
use crate::entry::{Accuracy, Entry, InnerKernel, Knob, Role, StageInfo, Variation};
use crate::problem::ContactProblem;
use crate::settings::{from_tree, parse_positive, parse_scalar, to_tree};
use crate::solver::Law;

/// The knob of the certified stopping rule (a tolerance in the
/// certificate's measure; 0: the paper's rules), for studies that run the
/// method to a guaranteed accuracy.
pub const CERTIFIED_STOP_KNOB: &str = "target";
/// The knob of over-relaxation in the sweeps (1: the paper's Gauss–Seidel).
pub const OVER_RELAXATION_KNOB: &str = "omega";
/// The over-relaxation factor the studies compare with the paper's ω = 1:
/// one stated value for every mesh, not tuned per mesh.
pub const STUDIED_OMEGA: f64 = 1.5;

/// The registry entry of the paper's method.
pub const ENTRY: Entry = Entry {
    name: "relaxation",
    about: "the paper's method: prox-Uzawa on the modified Lagrangian, pointwise relaxation inside",
    source: "Zhiltsov & Namm (2019), sections 3-5: modified Lagrangian (Theorem 2), Uzawa (14), proximal regularization (15)-(16), Algorithm 1",
    laws: &[Law::GivenFriction],
    warm_starts: true,
    stages: &[
        StageInfo {
            name: "uzawa",
            about: "one Uzawa iteration (14); residual max|Δl|",
            history: true,
        },
        StageInfo {
            name: "sweep",
            about: "one pointwise relaxation sweep; residual max|Δv|",
            history: false,
        },
    ],
    work_stage: "sweep",
    knobs: &[
        Knob {
            name: "r",
            fields: &["r"],
            help: "penalty r of the modified Lagrangian; relative: in units of K/L [default 1e7; paper: 1e12]",
            parse: parse_positive,
        },
        Knob {
            name: "epsilon",
            fields: &["epsilon"],
            help: "Uzawa stops when max|Δl| ≤ ε (relative: ε·P) [default 1e-6; paper: 1e-4]",
            parse: parse_positive,
        },
        Knob {
            name: "sweep_factor",
            fields: &["sweep_factor"],
            help: "sweeps stop when max|Δv| ≤ factor·ε·U·h/L (relative) or ≤ factor·ε/64 (paper) [default 1; paper: 1e-4]",
            parse: parse_positive,
        },
        Knob {
            name: "proximal",
            fields: &["proximal"],
            help: "weight ρ of (ρ/2)‖v − v^k‖²_L2, 0 turns it off; relative: in units of K/L² [default 1e-5; paper: 1]",
            parse: parse_scalar,
        },
        Knob {
            name: "smoothing",
            fields: &["smoothing"],
            help: "|s| along slip coordinates: `exact` (soft thresholding) or a Huber width δ; relative: in units of U [default 1e-7; paper: 1e-10]",
            parse: pointwise::parse_smoothing,
        },
        Knob {
            name: OVER_RELAXATION_KNOB,
            fields: &["omega"],
            help: "over-relaxation ω of the free coordinates in each sweep, in (0, 2); 1 is the paper's Gauss–Seidel [default 1]",
            parse: parse_positive,
        },
        Knob {
            name: CERTIFIED_STOP_KNOB,
            fields: &["target"],
            help: "certified stopping: stop when the contact law's and stationarity's largest violation in the problem's scales (the certificate's measure) is ≤ target, checked after every Uzawa step and every check_every sweeps; 0: the paper's rules on max|Δl| and max|Δv| [default 0]",
            parse: parse_scalar,
        },
        Knob {
            name: "check_every",
            fields: &["check_every"],
            help: "sweeps between two checks of the certified stopping rule (each costs about half a sweep) [default 10]",
            parse: parse_scalar,
        },
        Knob {
            name: "max_uzawa",
            fields: &["max_uzawa"],
            help: "cap on Uzawa iterations per solve [default 1000]",
            parse: parse_scalar,
        },
        Knob {
            name: "max_sweeps",
            fields: &["max_sweeps"],
            help: "cap on sweeps per Uzawa iteration [default 2000000]",
            parse: parse_scalar,
        },
    ],
    defaults: |stopping| to_tree(&RelaxationSettings::defaults(stopping)),
    build: |tree| Ok(Box::new(ProxUzawa::new(from_tree(tree)?))),
    accuracy: Accuracy {
        knob: "epsilon",
        values: &[1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8],
        reference: 1e-10,
        exact: false,
    },
    role: Role::PapersMethod,
    sweeps: &[
        Variation {
            knob: "r",
            values: &[
                "1e-3", "1e-2", "1e-1", "1", "1e1", "1e3", "1e5", "1e7", "1e9", "1e11",
            ],
            quick: &["1e-1", "1e3", "1e7"],
        },
        Variation {
            knob: "epsilon",
            values: &["1e-2", "1e-3", "1e-4", "1e-5", "1e-6", "1e-7", "1e-8"],
            quick: &["1e-2", "1e-4", "1e-6"],
        },
        Variation {
            knob: "smoothing",
            values: &["exact", "1e-3", "1e-5", "1e-7", "1e-9"],
            quick: &["exact", "1e-3"],
        },
    ],
    stress: &[
        Variation {
            knob: "r",
            values: &[
                "1e-8", "1e-6", "1e-4", "1e-2", "1", "1e2", "1e4", "1e6", "1e8", "1e10",
            ],
            quick: &["1e-8", "1e7"],
        },
        Variation {
            knob: "epsilon",
            values: &[
                "1e-2", "1e-3", "1e-4", "1e-5", "1e-6", "1e-7", "1e-8", "1e-9", "1e-10",
            ],
            quick: &["1e-6", "1e-15"],
        },
        Variation {
            knob: "smoothing",
            values: &["exact", "1e-2", "1e-4", "1e-6", "1e-8", "1e-10"],
            quick: &["exact", "1e-2"],
        },
        Variation {
            knob: "proximal",
            values: &["0", "1e-5"],
            quick: &["0"],
        },
    ],
    study_work: 2_000_000,
    kernel: Some(sweep_kernel),
    restarts: &[],
    diagnose: &[],
};

/// One relaxation sweep at the default relative settings, with multipliers
/// l = 1 and bounds g = ½ at every contact node so that every branch runs.
pub fn sweep_kernel(problem: &ContactProblem) -> InnerKernel {
    let resolved = RelaxationSettings::default().resolve(problem);
    let op = RelaxationOperator::new(problem, resolved.proximal);
    let matrix = op.h.clone();
    let l = vec![1.0; problem.contacts().len()];
    let wg: Vec<f64> = problem.contacts().iter().map(|c| 0.5 * c.weight).collect();
    let b = problem.f().to_vec();
    let mut v = vec![0.0; problem.n()];
    InnerKernel {
        name: "sweep",
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
    }
}
