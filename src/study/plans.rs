//! How the studies study each solver: which settings the sweeps vary, the
//! stress conditions of the stability map, the work after which a study
//! stops it, the other starting points and diagnostics of the uniqueness
//! study, the accuracy values of a work-precision diagram. The registry
//! says what a solver is; this says how to study it, keyed by the solver's
//! name. A solver without a plan here (one registered at run time, say) is
//! studied by [`DEFAULT`]: its accuracy knob through the decades
//! down to its reference value, no sweeps, no stress, a generous work cap;
//! [`register`] gives it a plan of its own.

use std::sync::RwLock;

use contactlab_solvers::entry::Entry;

/// Values of one knob that a study runs through, one at a time around the
/// defaults (as the command line would write them).
#[derive(Clone, Copy, Debug)]
pub struct Variation {
    pub knob: &'static str,
    pub values: &'static [&'static str],
    /// A shorter list for quick runs (tests).
    pub quick: &'static [&'static str],
}

/// Another starting point of a solver of the Coulomb problem: settings
/// within the solver (name, value).
pub type Restart = &'static [(&'static str, &'static str)];

/// How a solver is tuned on a fine mesh, where its own defaults are too
/// slow to sweep: settings within the solver that keep its method and make
/// it fast there, and the one-factor sweeps run with them.
#[derive(Clone, Copy, Debug)]
pub struct Fine {
    /// Settings within the solver (name, value), as the command line
    /// writes them.
    pub settings: &'static [(&'static str, &'static str)],
    pub sweeps: &'static [Variation],
}

/// The studies' plan for one solver.
#[derive(Clone, Copy, Debug)]
pub struct Plan {
    /// One-factor sweeps of the Coulomb problem (parameter studies).
    pub sweeps: &'static [Variation],
    /// The same on a fine mesh, with the settings that make it fast there
    /// (None: not swept on fine meshes).
    pub fine: Option<Fine>,
    /// Stress conditions of the stability map.
    pub stress: &'static [Variation],
    /// Work (events of its work stage, over a whole Coulomb solve) after
    /// which a study stops it: a count, so that a study's results do not
    /// depend on the machine's speed.
    pub work: usize,
    /// Other starting points, to see whether it finds one solution or
    /// several (uniqueness study).
    pub restarts: &'static [Restart],
    /// Settings that make it report diagnostics (e.g. a condition number).
    pub diagnose: &'static [(&'static str, &'static str)],
    /// Values of its accuracy knob in a work-precision diagram, loose to
    /// tight (empty: the default decades).
    pub accuracy: &'static [f64],
}

/// The plan of a solver that has none: no sweeps, no stress, the default
/// work cap, its accuracy knob through the default decades.
pub const DEFAULT: Plan = Plan {
    sweeps: &[],
    fine: None,
    stress: &[],
    work: DEFAULT_WORK,
    restarts: &[],
    diagnose: &[],
    accuracy: &[],
};

/// The work cap of a solver without a plan.
pub const DEFAULT_WORK: usize = 1_000_000;

/// A tolerance grid of the Newton and splitting methods.
const DECADES: &[f64] = &[1e-4, 1e-6, 1e-8, 1e-10, 1e-12];

/// The oracle's tolerance in the stability map.
const ORACLE_TOL: Variation = Variation {
    knob: "tol",
    values: &["1e-4", "1e-6", "1e-8", "1e-10", "1e-12", "1e-14"],
    quick: &["1e-4", "1e-10", "1e-14"],
};

/// Line search off (full Newton steps), in the stability map.
const NO_LINE_SEARCH: Variation = Variation {
    knob: "line_search",
    values: &["false"],
    quick: &["false"],
};

/// The plans of the built-in solvers.
const PLANS: &[(&str, Plan)] = &[
    (
        "clarabel",
        Plan {
            stress: &[
                ORACLE_TOL,
                Variation {
                    knob: "equilibrate",
                    values: &["false"],
                    quick: &["false"],
                },
                Variation {
                    knob: "scale_unknowns",
                    values: &["false"],
                    quick: &["false"],
                },
            ],
            work: 2000,
            accuracy: &[1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
            ..DEFAULT
        },
    ),
    (
        "clarabel-qp",
        Plan {
            stress: &[Variation {
                knob: "tol",
                values: &["1e-4", "1e-6", "1e-8", "1e-12", "1e-14"],
                quick: &["1e-14"],
            }],
            work: 2000,
            accuracy: &[1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
            ..DEFAULT
        },
    ),
    (
        "clarabel-faer",
        Plan {
            work: 2000,
            accuracy: &[1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
            ..DEFAULT
        },
    ),
    (
        "clarabel-condensed",
        Plan {
            work: 2000,
            accuracy: &[1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
            ..DEFAULT
        },
    ),
    (
        "relaxation",
        Plan {
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
            // Algorithm 1 with its inner minimization by TNNMG (issue 28:
            // "this is how a researcher tunes r and ε at 1/256"). r below
            // 1e3 is left out: at 1/256, r = 1 took 115 s (3718 Uzawa
            // steps) against 2.4 s at r = 1e7, one run each.
            fine: Some(Fine {
                settings: &[("inner", "multigrid")],
                sweeps: &[
                    Variation {
                        knob: "r",
                        values: &["1e3", "1e5", "1e7", "1e9", "1e11"],
                        quick: &["1e3", "1e7"],
                    },
                    Variation {
                        knob: "epsilon",
                        values: &["1e-4", "1e-5", "1e-6", "1e-7", "1e-8"],
                        quick: &["1e-4", "1e-6"],
                    },
                ],
            }),
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
            work: 2_000_000,
            accuracy: &[1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8],
            ..DEFAULT
        },
    ),
    (
        "newton",
        Plan {
            stress: &[NO_LINE_SEARCH],
            work: 5000,
            accuracy: DECADES,
            ..DEFAULT
        },
    ),
    (
        "nsgs",
        Plan {
            stress: &[Variation {
                knob: "tolerance",
                values: &["1e-2", "1e-14"],
                quick: &["1e-14"],
            }],
            work: 200_000,
            accuracy: DECADES,
            ..DEFAULT
        },
    ),
    (
        "apgd",
        Plan {
            stress: &[Variation {
                knob: "restart",
                values: &["false"],
                quick: &["false"],
            }],
            work: 2_000_000,
            accuracy: DECADES,
            ..DEFAULT
        },
    ),
    (
        "tnnmg",
        Plan {
            // One bare V-cycle per iteration (Gräser & Sander's choice):
            // slower here, see the solver's documentation.
            stress: &[Variation {
                knob: "linear_steps",
                values: &["1"],
                quick: &["1"],
            }],
            work: 100_000,
            accuracy: DECADES,
            ..DEFAULT
        },
    ),
    (
        "admm",
        Plan {
            sweeps: &[Variation {
                knob: "rho_factor",
                values: &["0.01", "0.1", "1", "10", "100"],
                quick: &["0.1", "10"],
            }],
            stress: &[Variation {
                knob: "rho_factor",
                values: &["1e-4", "1e4"],
                quick: &["1e4"],
            }],
            work: 2_000_000,
            accuracy: DECADES,
            ..DEFAULT
        },
    ),
    (
        "newton-coulomb",
        Plan {
            stress: &[NO_LINE_SEARCH],
            work: 5000,
            restarts: &[
                &[("start", "frictionless")],
                &[("perturbation", "0.5"), ("seed", "1")],
                &[("perturbation", "0.5"), ("seed", "2")],
                &[
                    ("start", "frictionless"),
                    ("perturbation", "0.5"),
                    ("seed", "3"),
                ],
            ],
            diagnose: &[("condition", "true")],
            accuracy: DECADES,
            ..DEFAULT
        },
    ),
];

/// Plans given at run time, after the built-in ones.
static REGISTERED: RwLock<Vec<(&'static str, Plan)>> = RwLock::new(Vec::new());

/// Gives a solver (by name) a plan of its own; a later one replaces an
/// earlier one of the same name.
pub fn register(name: &'static str, plan: Plan) {
    if let Ok(mut plans) = REGISTERED.write() {
        plans.retain(|(n, _)| *n != name);
        plans.push((name, plan));
    }
}

impl Plan {
    /// The values of the accuracy knob in a work-precision diagram: the
    /// plan's, or the decades 1e-2, 1e-4, ... down to (not past) the
    /// entry's reference value.
    pub fn accuracy_values(&self, entry: &Entry) -> Vec<f64> {
        if !self.accuracy.is_empty() {
            return self.accuracy.to_vec();
        }
        (1..=8)
            .map(|k| 10f64.powi(-2 * k))
            .filter(|&x| x >= entry.accuracy.reference)
            .collect()
    }
}

/// The studies' plan for `entry`: registered at run time, built in, or the
/// default.
pub fn plan(entry: &Entry) -> Plan {
    let registered = REGISTERED.read().ok().and_then(|plans| {
        plans
            .iter()
            .find(|(n, _)| *n == entry.name)
            .map(|(_, p)| *p)
    });
    registered
        .or_else(|| {
            PLANS
                .iter()
                .find(|(n, _)| *n == entry.name)
                .map(|(_, p)| *p)
        })
        .unwrap_or(DEFAULT)
}

#[cfg(test)]
mod tests {
    use super::*;
    use contactlab_solvers::registry;

    /// Every built-in solver has a plan, and every knob a plan names is one
    /// of the solver's.
    #[test]
    fn plans_name_registered_solvers_and_their_knobs() {
        for (name, p) in PLANS {
            let entry = registry::by_name(name).unwrap_or_else(|| panic!("{name}: no solver"));
            for v in p.sweeps.iter().chain(p.stress) {
                assert!(entry.knob(v.knob).is_some(), "{name}.{}", v.knob);
            }
            for v in p.fine.iter().flat_map(|f| f.sweeps) {
                assert!(entry.knob(v.knob).is_some(), "{name}.{} (fine)", v.knob);
            }
            let fine_settings = p.fine.iter().flat_map(|f| f.settings);
            for (knob, _) in p
                .restarts
                .iter()
                .flat_map(|r| r.iter())
                .chain(p.diagnose)
                .chain(fine_settings)
            {
                assert!(entry.knob(knob).is_some(), "{name}.{knob}");
            }
        }
        for e in registry::SOLVERS {
            assert!(
                PLANS.iter().any(|(n, _)| *n == e.name),
                "{}: no plan",
                e.name
            );
        }
    }
}
