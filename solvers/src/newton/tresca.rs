//! A fast exact solver: condensation onto the contact unknowns, then a
//! semismooth Newton method on the condensed KKT system
//!
//! ```text
//! F  = S y − b̂ + Σ λ_i e_{t_i} − Σ μ_i e_{s_i} = 0,
//! Φ_N,i = φ(λ_i, −κ t_i) = 0                       (Signorini: λ ≥ 0, t ≤ 0, λt = 0)
//! Φ_F,i = φ(μ_i + G_i, −φ(G_i − μ_i, −κ s_i)) = 0   (Tresca: μ ∈ [−G, G], the box
//!                                                    complementarity to κ s; Billups)
//! ```
//!
//! with φ(a, b) = a + b − √(a² + b²) (Fischer-Burmeister), G_i = w_i g_i, λ and
//! μ the nodal contact and friction forces, κ a stiffness scale. The system is
//! a monotone mixed complementarity problem, so every stationary point of the
//! merit Ψ = ½‖(F, Φ_N, Φ_F)‖² solves it.
//!
//! Globalization: a Newton direction is taken when it descends Ψ enough,
//! otherwise −∇Ψ, and an Armijo line search on Ψ follows. Ψ decreases strictly
//! at every step, so the iterates cannot cycle between active sets (the plain
//! primal-dual active set method can: see the tests). The multipliers are
//! eliminated node by node, so each step solves one dense 2m × 2m system.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::entry::{
    Accuracy, CONDENSED_MEMORY, Entry, FACTORED_MAX_UNKNOWNS, Knob, Role, StageInfo,
};
use crate::observer::Observer;
use crate::problem::ContactProblem;
use crate::reduction::condensed::{Condensed, Kept, condense};
use crate::settings::{Kind, Validate, from_tree, to_tree};
use crate::solution::{Iterations, Solution, Timing};
use crate::solver::{Friction, Law, Solver, Start};

pub use super::tresca_system::{NewtonOutcome, semismooth_newton};

/// The progress stage of one newton (its unit of work).
pub(crate) const NEWTON_STEP: &str = "newton";

/// The registry entry of the condensed semismooth Newton solver.
pub(crate) const ENTRY: Entry = Entry {
    name: NEWTON_STEP,
    about: "fast exact solver: condensation onto the contact unknowns (sparse Cholesky once), semismooth Newton with line search",
    source: "Fischer (1992) and Billups (1995) NCP/box functions; De Luca, Facchinei & Kanzow (1996) globalization on the merit ½‖Φ‖²",
    laws: &[Law::GivenFriction],
    warm_starts: false,
    schedule: crate::schedule::Schedule::Revisit,
    schedule_when: None,
    stages: &[StageInfo {
        name: NEWTON_STEP,
        about: "one Newton step; residual max|Φ| / ‖b̂‖∞ (condensed KKT system)",
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
            help: "cap on Newton steps per solve",
            kind: Kind::Count,
        },
        Knob {
            name: "line_search",
            fields: &["line_search"],
            help: "Armijo line search on the merit (true/false; false: plain full steps)",
            kind: Kind::Flag,
        },
    ],
    defaults: |_| to_tree(&NewtonSettings::default()),
    build: crate::entry::Build::Fn(|tree| Ok(Box::new(CondensedNewton::new(from_tree(tree)?)))),
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

/// Settings of the condensed semismooth Newton solver. The same in both
/// stopping modes: its test is relative to the condensed load already.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NewtonSettings {
    /// Stop when max(‖F‖∞, ‖Φ_N‖∞, ‖Φ_F‖∞) ≤ tolerance · ‖b̂‖∞.
    pub tolerance: f64,
    /// Cap on Newton steps per call.
    pub max_iter: usize,
    /// Armijo line search on the merit (off: plain full steps).
    pub line_search: bool,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-12,
            max_iter: 200,
            line_search: true,
        }
    }
}

impl Validate for NewtonSettings {
    /// Checked by the kinds of its registry entry's knobs.
    fn validate(&self) -> Result<(), String> {
        ENTRY.check(&to_tree(self))
    }
}

/// The condensed semismooth Newton solver. Keeps the condensation (the
/// factor of A_II, S and b̂) across calls on the same problem operator.
#[derive(Default)]
pub struct CondensedNewton {
    pub settings: NewtonSettings,
    cache: Kept<u64, Condensed>,
}

impl CondensedNewton {
    pub fn new(settings: NewtonSettings) -> Self {
        Self {
            settings,
            cache: Kept::default(),
        }
    }
}

impl Solver for CondensedNewton {
    fn solve(
        &mut self,
        problem: &ContactProblem,
        friction: Friction<'_>,
        start: Option<Start<'_>>,
        observer: &mut dyn Observer,
    ) -> Solution {
        let (n, contacts) = (problem.n(), problem.contacts());
        let m = contacts.len();
        let bound = match Solution::given_bound(problem, friction, self.settings.validate()) {
            Ok(g) => g,
            Err(refused) => return *refused,
        };
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
        let g: Vec<f64> = contacts
            .iter()
            .zip(bound)
            .map(|(c, g)| c.weight * g)
            .collect();
        // Start: the given iterate, or all contacts closed and sticking (y = 0)
        // with the forces that hold that state.
        let y0: Vec<f64> = match &start {
            Some(s) if s.v.len() == n => {
                contacts.iter().flat_map(|c| [s.v[c.t], s.v[c.s]]).collect()
            }
            _ => vec![0.0; 2 * m],
        };
        let force = |k: usize| -> f64 {
            (0..2 * m).map(|l| condensed.s[(k, l)] * y0[l]).sum::<f64>() - condensed.b[k]
        };
        let lam0: Vec<f64> = match &start {
            Some(s) if s.pressure.len() == m => contacts
                .iter()
                .zip(s.pressure)
                .map(|(c, p)| c.weight * p.max(0.0))
                .collect(),
            _ => (0..m).map(|i| (-force(2 * i)).max(0.0)).collect(),
        };
        let mu0: Vec<f64> = (0..m)
            .map(|i| force(2 * i + 1).clamp(-g[i], g[i]))
            .collect();
        let out = semismooth_newton(
            &condensed.s,
            &condensed.b,
            &g,
            (y0, lam0, mu0),
            &self.settings,
            observer,
        );
        let v = condensed.expand(problem, &out.y);
        let solution = Solution {
            v,
            pressure: contacts
                .iter()
                .zip(&out.lambda)
                .map(|(c, l)| l / c.weight)
                .collect(),
            friction_traction: contacts
                .iter()
                .zip(&out.mu)
                .map(|(c, mu)| mu / c.weight)
                .collect(),
            status: out.status,
            detail: out.detail,
            iterations: Iterations {
                outer: out.steps,
                inner: 0,
            },
            timing: Timing {
                setup,
                solve: t1.elapsed().as_secs_f64(),
            },
            diagnostics: Vec::new(),
        };
        solution.flag_non_finite()
    }
}
