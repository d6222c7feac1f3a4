//! A direct solver of the static Coulomb problem: semismooth Newton on its
//! whole condensed KKT system, the friction bound 𝓕λ being part of the
//! unknowns (no successive approximations around it):
//!
//! ```text
//! F  = S y − b̂ + Σ λ_i e_{t_i} − Σ μ_i e_{s_i} = 0,
//! Φ_N,i = φ(λ_i, −κ t_i) = 0                              (Signorini)
//! Φ_F,i = φ(μ_i + G_i, −φ(G_i − μ_i, −κ s_i)) = 0,  G_i = 𝓕_i λ_i⁺   (Coulomb)
//! ```
//!
//! with φ the Fischer-Burmeister function and the Billups box function for
//! the friction (Fischer 1992, Billups 1995; the natural-map / FB form of the
//! Coulomb problem of Acary, Brémond & Huber 2018, section 3), on the contact
//! unknowns after the condensation (reused from [`crate::reduction::condensed`]). The
//! Jacobian holds ∂Φ_F/∂λ = 𝓕 ∂Φ_F/∂G, the coupling the successive
//! approximations leave out; it is assembled densely (4m × 4m) and solved by
//! LU with partial pivoting.
//!
//! Globalization (stated, and tested): the Newton direction is taken when it
//! descends the merit Ψ = ½‖(F, Φ_N, Φ_F)‖² enough, otherwise −∇Ψ; an Armijo
//! line search on Ψ follows, so Ψ falls strictly at every step. Unlike the
//! given-friction problem the Coulomb problem is not monotone: a stationary
//! point of Ψ need not solve it, and the solution need not be unique for
//! large 𝓕. The start is the closed, sticking state (y = 0), where the
//! active contact rows hold the rigid mode (started with the contact open,
//! the Newton matrix is singular along it), or the frictionless solution, or
//! either with its forces perturbed (to look for other solutions).

use std::time::Instant;

use faer::Mat;
use serde::{Deserialize, Serialize};

use crate::entry::{
    Accuracy, CONDENSED_MEMORY, Entry, FACTORED_MAX_UNKNOWNS, Knob, Role, StageInfo,
};
use crate::numerics::globalization::{Units, armijo, direction, merit};
use crate::numerics::random::Lcg;
use crate::numerics::resolution::{Resolution, ULPS, WINDOW};
use crate::observer::{Control, Observer, Progress};
use crate::problem::ContactProblem;
use crate::reduction::condensed::{Condensed, Kept, condense};
use crate::settings::{Kind, Validate, from_tree, to_tree};
use crate::solution::{Iterations, Solution, Status, Timing};
use crate::solver::{Friction, Law, Solver, Start};

#[path = "coulomb_system.rs"]
mod system;
use system::System;

/// The progress stage of one newton step (its unit of work).
pub(crate) const NEWTON_STEP: &str = "newton_step";

/// The registry entry of the direct Coulomb solver.
pub(crate) const ENTRY: Entry = Entry {
    name: "newton-coulomb",
    about: "direct Coulomb solver: semismooth Newton on the whole Coulomb problem (the bound 𝓕λ among the unknowns), condensation, Armijo line search",
    source: "Fischer (1992), Billups (1995); the FB form of the Coulomb problem in Acary, Brémond & Huber (2018), Inria RR-9118, section 3",
    laws: &[Law::Coulomb],
    warm_starts: false,
    schedule: crate::schedule::Schedule::Revisit,
    schedule_when: None,
    stages: &[StageInfo {
        name: NEWTON_STEP,
        about: "one Newton step on the Coulomb system; residual max|Φ| / ‖b̂‖∞",
        history: true,
    }],
    work_stage: NEWTON_STEP,
    knobs: &[
        Knob {
            name: "tolerance",
            fields: &["tolerance"],
            help: "stop when max|Φ| ≤ tolerance·‖b̂‖∞ (relative)",
            kind: Kind::Positive,
        },
        Knob {
            name: "max_iter",
            fields: &["max_iter"],
            help: "cap on Newton steps",
            kind: Kind::Count,
        },
        Knob {
            name: "line_search",
            fields: &["line_search"],
            help: "Armijo line search on the merit (true/false)",
            kind: Kind::Flag,
        },
        Knob {
            name: "start",
            fields: &["start"],
            help: "starting point: `closed` (y = 0, sticking) or `frictionless` (the frictionless solution)",
            kind: Kind::Word(&["closed", "frictionless"]),
        },
        Knob {
            name: "perturbation",
            fields: &["perturbation"],
            help: "perturb the starting forces by this relative amount (pseudo-random, see seed)",
            kind: Kind::Fraction,
        },
        Knob {
            name: "seed",
            fields: &["seed"],
            help: "seed of the perturbation",
            kind: Kind::Whole,
        },
        Knob {
            name: "condition",
            fields: &["condition"],
            help: "report the condition number of the final Newton matrix (true/false; an SVD)",
            kind: Kind::Flag,
        },
    ],
    defaults: |_| to_tree(&NewtonCoulombSettings::default()),
    build: crate::entry::Build::Fn(|tree| Ok(Box::new(NewtonCoulomb::new(from_tree(tree)?)))),
    accuracy: Accuracy {
        knob: "tolerance",
        reference: 1e-13,
        exact: true,
    },
    role: Role::Other,
    kernel: None,
    max_unknowns: Some(FACTORED_MAX_UNKNOWNS),
    uses_mass: false,
    memory: CONDENSED_MEMORY,
};

/// Where the Newton iteration starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum StartingPoint {
    /// y = 0 (every node closed and sticking), the forces that hold it.
    Closed,
    /// The frictionless solution (𝓕 = 0), from the closed state.
    Frictionless,
}

/// Settings of the direct Coulomb solver (relative in both stopping modes).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct NewtonCoulombSettings {
    pub tolerance: f64,
    pub max_iter: usize,
    pub line_search: bool,
    pub start: StartingPoint,
    pub perturbation: f64,
    pub seed: u64,
    pub condition: bool,
}

impl Default for NewtonCoulombSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-12,
            max_iter: 500,
            line_search: true,
            start: StartingPoint::Closed,
            perturbation: 0.0,
            seed: 1,
            condition: false,
        }
    }
}

impl Validate for NewtonCoulombSettings {
    /// Checked by the kinds of its registry entry's knobs.
    fn validate(&self) -> Result<(), String> {
        ENTRY.check(&to_tree(self))
    }
}

fn norm_inf(x: &[f64]) -> f64 {
    crate::numerics::linalg::max_abs(x)
}

/// The outcome of the Newton iteration.
struct Outcome {
    x: Vec<f64>,
    status: Status,
    detail: String,
    steps: usize,
    jacobian: Option<Mat<f64>>,
}

/// Globalized semismooth Newton from `x` (see the module's documentation).
fn newton(
    sys: &System<'_>,
    mut x: Vec<f64>,
    settings: &NewtonCoulombSettings,
    units: &Units,
    observer: &mut dyn Observer,
    t0: Instant,
) -> Outcome {
    let scale = units.scale;
    let mut phi = sys.residual(&x);
    let mut psi = merit(&phi);
    let finish = |x, status, detail, steps, jacobian| Outcome {
        x,
        status,
        detail,
        steps,
        jacobian,
    };
    let mut stall = Resolution::default();
    for step in 1..=settings.max_iter {
        let r = norm_inf(&phi) / scale;
        if !r.is_finite() {
            return finish(
                x,
                Status::NonFinite,
                format!("non-finite residual at step {step}"),
                step - 1,
                None,
            );
        }
        if r <= settings.tolerance {
            let detail = format!(
                "residual {r:.2e} ≤ {:e} after {} Newton steps",
                settings.tolerance,
                step - 1
            );
            let j = settings.condition.then(|| sys.jacobian(&x));
            return finish(x, Status::Converged, detail, step - 1, j);
        }
        // The residual, relative to the problem's scale, at rounding for
        // several steps: no Newton step can take it to the tolerance.
        if stall.stalled(r, 1.0) {
            let detail = format!(
                "residual {r:.2e} > {:e} after {} Newton steps: stalled at floating-point resolution (within {ULPS} roundoffs of the problem's scale for {WINDOW} steps)",
                settings.tolerance,
                step - 1
            );
            let j = settings.condition.then(|| sys.jacobian(&x));
            return finish(x, Status::InsufficientProgress, detail, step - 1, j);
        }
        let (newton_dir, grad) = sys.direction(&x, &phi);
        let (dir, slope) = direction(newton_dir, &grad, units, settings.line_search);
        let trial = |alpha: f64| {
            let x1: Vec<f64> = x.iter().zip(&dir).map(|(a, d)| a + alpha * d).collect();
            let phi1 = sys.residual(&x1);
            (merit(&phi1), (x1, phi1))
        };
        match armijo(psi, slope, settings.line_search, trial) {
            Some((psi1, (x1, phi1))) => {
                x = x1;
                phi = phi1;
                psi = psi1;
            }
            None => {
                let detail = format!(
                    "line search failed at Newton step {step} (residual {r:.2e}): a stationary point of the merit that is not a solution"
                );
                let j = settings.condition.then(|| sys.jacobian(&x));
                return finish(x, Status::InsufficientProgress, detail, step, j);
            }
        }
        let control = observer.observe(&Progress {
            stage: NEWTON_STEP,
            iteration: step,
            residual: norm_inf(&phi) / scale,
            seconds: t0.elapsed().as_secs_f64(),
        });
        if let Control::Stop(s) = control {
            return finish(
                x,
                s,
                format!("stopped by the harness after {step} Newton steps"),
                step,
                None,
            );
        }
    }
    let r = norm_inf(&phi) / scale;
    let status = if r <= settings.tolerance {
        Status::Converged
    } else {
        Status::MaxIterations
    };
    let detail = format!(
        "Newton step cap {} reached with residual {r:.2e}",
        settings.max_iter
    );
    finish(x, status, detail, settings.max_iter, None)
}

/// The direct Coulomb solver. Keeps the condensation across calls on the
/// same problem operator.
#[derive(Default)]
pub(crate) struct NewtonCoulomb {
    pub settings: NewtonCoulombSettings,
    cache: Kept<u64, Condensed>,
}

impl NewtonCoulomb {
    pub fn new(settings: NewtonCoulombSettings) -> Self {
        Self {
            settings,
            cache: Kept::default(),
        }
    }
}

/// The closed, sticking state y = 0 with the forces that hold it.
fn closed_start(b: &[f64], m: usize) -> Vec<f64> {
    let mut x = vec![0.0; 4 * m];
    for i in 0..m {
        // F = −b̂ + λ e_t − μ e_s = 0 at y = 0.
        x[2 * m + i] = b[2 * i].max(0.0);
        x[3 * m + i] = -b[2 * i + 1];
    }
    x
}

/// Multiplies every force by (1 + p·u), u pseudo-random in [−1, 1).
fn perturb(x: &mut [f64], m: usize, p: f64, seed: u64) {
    let mut random = Lcg::new(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    for v in &mut x[2 * m..] {
        *v *= 1.0 + p * random.symmetric();
    }
}

impl Solver for NewtonCoulomb {
    /// Two rigid modes, measured: Cattaneo–Mindlin with the upper body free
    /// to slide (`scenes/cattaneo_mindlin_sliding.toml`) certifies.
    fn rigid_modes_handled(&self) -> usize {
        2
    }

    fn solve(
        &mut self,
        problem: &ContactProblem,
        friction: Friction<'_>,
        start: Option<Start<'_>>,
        observer: &mut dyn Observer,
    ) -> Solution {
        let (n, contacts) = (problem.n(), problem.contacts());
        let m = contacts.len();
        if let Some(refused) =
            Solution::refusal(problem, ENTRY.laws, friction, self.settings.validate())
        {
            return refused;
        }
        let t0 = Instant::now();
        let condensed = match self
            .cache
            .get_or_build(problem.operator_id(), || condense(problem))
        {
            Ok(c) => c,
            Err(e) => return Solution::failed(n, m, e.status, e.detail),
        };
        let setup = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let units = Units::of_condensed(&condensed.s, &condensed.b);
        let coefficient: Vec<f64> = contacts.iter().map(|c| c.coefficient).collect();
        let sys = System {
            s: &condensed.s,
            b: &condensed.b,
            coefficient: &coefficient,
            kappa: units.kappa,
        };
        let mut x = match &start {
            Some(st) if st.v.len() == n && st.pressure.len() == m => {
                let mut x = closed_start(&condensed.b, m);
                for (i, c) in contacts.iter().enumerate() {
                    x[2 * i] = st.v[c.t];
                    x[2 * i + 1] = st.v[c.s];
                    x[2 * m + i] = c.weight * st.pressure[i].max(0.0);
                }
                x
            }
            _ => closed_start(&condensed.b, m),
        };
        let mut extra_steps = 0;
        if self.settings.start == StartingPoint::Frictionless && start.is_none() {
            let zero = vec![0.0; m];
            let frictionless = System {
                s: sys.s,
                b: sys.b,
                coefficient: &zero,
                kappa: sys.kappa,
            };
            let out = newton(
                &frictionless,
                x.clone(),
                &self.settings,
                &units,
                &mut crate::observer::Silent,
                t1,
            );
            extra_steps = out.steps;
            if out.status.is_converged() {
                x = out.x;
            }
        }
        if self.settings.perturbation > 0.0 {
            perturb(&mut x, m, self.settings.perturbation, self.settings.seed);
        }
        let out = newton(&sys, x, &self.settings, &units, observer, t1);
        let mut diagnostics = condensed.memory_diagnostics().to_vec();
        if let Some(j) = &out.jacobian
            && let Ok(sv) = j.singular_values()
        {
            let (hi, lo) = sv
                .iter()
                .fold((0.0f64, f64::INFINITY), |(a, b), &s| (a.max(s), b.min(s)));
            diagnostics.push(("condition", if lo > 0.0 { hi / lo } else { f64::INFINITY }));
        }
        let (y, rest) = out.x.split_at(2 * m);
        let (lam, mu) = rest.split_at(m);
        let v = condensed.expand(problem, y);
        let solution = Solution {
            v,
            pressure: contacts
                .iter()
                .zip(lam)
                .map(|(c, l)| l / c.weight)
                .collect(),
            friction_traction: contacts.iter().zip(mu).map(|(c, u)| u / c.weight).collect(),
            status: out.status,
            detail: out.detail,
            iterations: Iterations {
                outer: out.steps + extra_steps,
                inner: 0,
            },
            timing: Timing {
                setup,
                solve: t1.elapsed().as_secs_f64(),
            },
            diagnostics,
        };
        solution.flag_non_finite()
    }
}

#[cfg(test)]
#[path = "coulomb_tests.rs"]
mod tests;
