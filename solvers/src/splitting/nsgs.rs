//! Nonsmooth Gauss-Seidel on the contact forces (Jean 1999; Acary, Brémond &
//! Huber 2018, section 4, "NSGS"): sweep over the contact nodes, each time
//! solving the node's two-dimensional contact problem exactly with the other
//! nodes' forces fixed, on the condensed operator.
//!
//! With r_i = (λ_i, ν_i) the node's normal force and ν_i = −μ_i its friction
//! force (see [`crate::reduction::dual`]), the local problem at node i is
//!
//! ```text
//! (t_i, s_i) = q_i − W_ii r_i,   λ_i ≥ 0, t_i ≤ 0, λ_i t_i = 0,
//! |ν_i| ≤ G_i, ν_i = G_i sign(s_i) where s_i ≠ 0,
//! ```
//!
//! with W_ii the node's 2×2 block of M and G_i = w_i g_i (given friction) or
//! 𝓕_i λ_i (Coulomb: the method solves the Coulomb problem itself). It is
//! solved exactly by trying its six cases (closed or open × stick, slip
//! forward or slip backward) in closed form. The semicoercive mode is kept
//! exactly ([`crate::reduction::dual`]): after each sweep the translation β solves its
//! own equation, the equilibrium of the contact forces with the load, with
//! every node answering locally (a one-dimensional monotone root, found by
//! bisection).

use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::entry::{
    Accuracy, CONDENSED_MEMORY, Entry, FACTORED_MAX_UNKNOWNS, Knob, Role, StageInfo,
};
use crate::numerics::linalg::max_abs;
use crate::numerics::resolution::{Resolution, floor};
use crate::numerics::roots::monotone_root;
use crate::observer::{Control, Observer, Progress};
use crate::problem::ContactProblem;
use crate::reduction::condensed::{Condensed, Ending, Kept, condense};
use crate::reduction::dual::DualOperator;
use crate::settings::{Kind, Validate, from_tree, to_tree};
use crate::solution::{SetupError, Solution, Status, Timing};
use crate::solver::{Friction, Law, Solver, Start};

/// The progress stage of one nsgs sweep (its unit of work).
pub(crate) const SWEEP: &str = "nsgs_sweep";

/// The registry entry of nonsmooth Gauss-Seidel.
pub(crate) const ENTRY: Entry = Entry {
    name: "nsgs",
    about: "nonsmooth Gauss-Seidel on the contact forces: exact 2×2 local solves on the condensed operator, the rigid translation as an extra unknown",
    source: "Jean (1999), the non-smooth contact dynamics method; Acary, Brémond & Huber (2018), Inria RR-9118, section 4",
    laws: &[Law::GivenFriction, Law::Coulomb],
    warm_starts: false,
    schedule: crate::schedule::Schedule::Revisit,
    schedule_when: None,
    stages: &[StageInfo {
        name: SWEEP,
        about: "one sweep over the contact nodes; residual max|Δr| over the nodal force scale",
        history: true,
    }],
    work_stage: SWEEP,
    knobs: &[
        Knob {
            name: "tolerance",
            fields: &["tolerance"],
            help: "stop when a sweep changes no force by more than tolerance·P·w (relative)",
            kind: Kind::Positive,
        },
        Knob {
            name: "max_sweeps",
            fields: &["max_sweeps"],
            help: "cap on sweeps",
            kind: Kind::Count,
        },
    ],
    defaults: |_| to_tree(&NsgsSettings::default()),
    build: crate::entry::Build::Fn(|tree| Ok(Box::new(Nsgs::new(from_tree(tree)?)))),
    accuracy: Accuracy {
        knob: "tolerance",
        reference: 1e-13,
        exact: false,
    },
    role: Role::Other,
    kernel: None,
    max_unknowns: Some(FACTORED_MAX_UNKNOWNS),
    uses_mass: false,
    memory: CONDENSED_MEMORY,
};

/// Settings of nonsmooth Gauss-Seidel (the same in both stopping modes:
/// its test is relative to the problem's scales).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct NsgsSettings {
    pub tolerance: f64,
    pub max_sweeps: usize,
}

impl Default for NsgsSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_sweeps: 100_000,
        }
    }
}

impl Validate for NsgsSettings {
    /// Checked by the kinds of its registry entry's knobs.
    fn validate(&self) -> Result<(), String> {
        ENTRY.check(&to_tree(self))
    }
}

/// How the friction bound of a node is given.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Bound {
    /// G = w g (the given-friction subproblem).
    Given(f64),
    /// G = 𝓕 λ (the Coulomb problem).
    Coulomb(f64),
}

/// The exact solution of one node's problem (t, s) = q − W r with
/// r = (λ, ν): the first of the six cases whose conditions hold, or the one
/// that violates them least.
pub(crate) fn local_solve(w: [[f64; 2]; 2], q: [f64; 2], bound: Bound) -> [f64; 2] {
    let [[wtt, wts], [wst, wss]] = w;
    let mut best = ([0.0, 0.0], f64::INFINITY);
    let mut consider = |r: [f64; 2], violation: f64| {
        if violation < best.1 {
            best = (r, violation);
        }
    };
    let g_of = |lambda: f64| match bound {
        Bound::Given(g) => g,
        Bound::Coulomb(f) => f * lambda.max(0.0),
    };
    // Closed and sticking: W r = q.
    let det = wtt * wss - wts * wst;
    if det != 0.0 {
        let lambda = (wss * q[0] - wts * q[1]) / det;
        let nu = (wtt * q[1] - wst * q[0]) / det;
        let v = (-lambda).max(0.0) + (nu.abs() - g_of(lambda)).max(0.0);
        consider([lambda, nu], v);
    }
    for sigma in [1.0, -1.0] {
        // Closed and slipping: t = 0, ν = σG.
        let lambda = match bound {
            Bound::Given(g) => (q[0] - wts * sigma * g) / wtt,
            Bound::Coulomb(f) => {
                let d = wtt + sigma * f * wts;
                if d > 0.0 { q[0] / d } else { f64::NAN }
            }
        };
        if lambda.is_finite() {
            let nu = sigma * g_of(lambda);
            let s = q[1] - wst * lambda - wss * nu;
            consider([lambda, nu], (-lambda).max(0.0) + (-sigma * s).max(0.0));
        }
        // Open and slipping: λ = 0, ν = σG(0).
        let nu = sigma * g_of(0.0);
        let t = q[0] - wts * nu;
        let s = q[1] - wss * nu;
        let v = t.max(0.0)
            + if nu != 0.0 {
                (-sigma * s).max(0.0)
            } else {
                0.0
            };
        consider([0.0, nu], v);
    }
    // Open and sticking: λ = 0, s = 0.
    let nu = q[1] / wss;
    let t = q[0] - wts * nu;
    consider([0.0, nu], t.max(0.0) + (nu.abs() - g_of(0.0)).max(0.0));
    // No case may hold exactly (round-off): the least violation is kept.
    best.0
}

/// Nonsmooth Gauss-Seidel. Keeps the condensation and the operator M
/// across calls on the same problem operator.
#[derive(Default)]
pub(crate) struct Nsgs {
    pub settings: NsgsSettings,
    cache: Kept<u64, (Condensed, DualOperator)>,
}

impl Nsgs {
    pub fn new(settings: NsgsSettings) -> Self {
        Self {
            settings,
            cache: Kept::default(),
        }
    }
}

/// The sum Σ ẑ_k r_k of all nodes answering locally to the translation β
/// (given y at β0 and the current forces r).
fn equilibrium_at(
    op: &DualOperator,
    y: &[f64],
    r: &[f64],
    beta: f64,
    beta0: f64,
    bounds: &[Bound],
) -> f64 {
    let z = op.z.as_ref().expect("called with a rigid mode");
    let mut e = 0.0;
    for (i, &bound) in bounds.iter().enumerate() {
        let k = 2 * i;
        let w = block(op, k);
        let q = [
            y[k] + w[0][0] * r[k] + w[0][1] * r[k + 1] + (beta - beta0) * z[k],
            y[k + 1] + w[1][0] * r[k] + w[1][1] * r[k + 1] + (beta - beta0) * z[k + 1],
        ];
        let local = local_solve(w, q, bound);
        e += z[k] * (op.b[k] - local[0]) + z[k + 1] * (op.b[k + 1] - local[1]);
    }
    e
}

fn block(op: &DualOperator, k: usize) -> [[f64; 2]; 2] {
    [
        [op.m[(k, k)], op.m[(k, k + 1)]],
        [op.m[(k + 1, k)], op.m[(k + 1, k + 1)]],
    ]
}

impl Solver for Nsgs {
    fn solve(
        &mut self,
        problem: &ContactProblem,
        friction: Friction<'_>,
        _start: Option<Start<'_>>,
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
        let (condensed, op) = match self.cache.get_or_build(problem.operator_id(), || {
            let c = condense(problem)?;
            let d = DualOperator::new(problem, &c).map_err(SetupError::from)?;
            Ok::<_, SetupError>((c, d))
        }) {
            Ok((c, d)) => (c, d),
            Err(e) => return Solution::failed(n, m, e.status, e.detail),
        };
        let setup = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let bounds: Vec<Bound> = contacts
            .iter()
            .enumerate()
            .map(|(i, c)| match friction {
                Friction::Given(g) => Bound::Given(c.weight * g[i]),
                Friction::Coulomb => Bound::Coulomb(c.coefficient),
            })
            .collect();
        let scales = problem.scales();
        let w_max = contacts.iter().fold(0.0f64, |a, c| a.max(c.weight));
        let force_tol = self.settings.tolerance * scales.pressure * w_max;
        let mut r = vec![0.0; 2 * m];
        let mut beta = 0.0;
        let mut y = op.displacements(&r, beta);
        let mut status = Status::MaxIterations;
        let mut detail = format!("sweep cap {} reached", self.settings.max_sweeps);
        let mut sweeps = 0;
        let mut stall = Resolution::default();
        for sweep in 1..=self.settings.max_sweeps {
            sweeps = sweep;
            let mut change = 0.0f64;
            for (i, &bound) in bounds.iter().enumerate() {
                let k = 2 * i;
                let w = block(op, k);
                let q = [
                    y[k] + w[0][0] * r[k] + w[0][1] * r[k + 1],
                    y[k + 1] + w[1][0] * r[k] + w[1][1] * r[k + 1],
                ];
                let local = local_solve(w, q, bound);
                let d = [local[0] - r[k], local[1] - r[k + 1]];
                if d[0] != 0.0 || d[1] != 0.0 {
                    for (row, yr) in y.iter_mut().enumerate() {
                        *yr -= op.m[(row, k)] * d[0] + op.m[(row, k + 1)] * d[1];
                    }
                    r[k] = local[0];
                    r[k + 1] = local[1];
                    change = change.max(d[0].abs()).max(d[1].abs());
                }
            }
            // The translation: its equation is the equilibrium.
            let mut beta_change = 0.0;
            if let Some(z) = &op.z {
                let e = |b: f64| equilibrium_at(op, &y, &r, b, beta, &bounds);
                let step0 = scales.displacement * (m as f64).sqrt();
                if let Some(b) = monotone_root(e, beta, step0) {
                    beta_change = b - beta;
                    for (yk, zk) in y.iter_mut().zip(z) {
                        *yk += beta_change * zk;
                    }
                    beta = b;
                } else {
                    // No translation balances the load: the nodes' forces
                    // cannot carry it (it pulls the body off), so the
                    // problem is unbounded.
                    status = Status::Unbounded;
                    detail = format!(
                        "sweep {sweep}: no rigid translation balances the load along the rigid mode (it pulls the body off)"
                    );
                    break;
                }
            }
            let residual = change / (scales.pressure * w_max);
            let control = observer.observe(&Progress {
                stage: SWEEP,
                iteration: sweep,
                residual,
                seconds: t1.elapsed().as_secs_f64(),
            });
            if !change.is_finite() {
                status = Status::NonFinite;
                detail = format!("non-finite force in sweep {sweep}");
                break;
            }
            let moved = beta_change.abs() <= self.settings.tolerance * scales.displacement;
            if change <= force_tol && moved {
                status = Status::Converged;
                detail = format!("max|Δr| = {change:.3e} ≤ {force_tol:.3e} after {sweep} sweeps");
                break;
            }
            let size = max_abs(&r);
            if stall.step(change <= floor(size) && beta_change.abs() <= floor(beta.abs())) {
                status = Status::InsufficientProgress;
                detail = format!(
                    "max|Δr| = {change:.3e} > {force_tol:.3e} after {sweep} sweeps: {}",
                    Resolution::detail("the contact forces r", change, size)
                );
                break;
            }
            if let Control::Stop(s) = control {
                status = s;
                detail = format!("stopped by the harness after {sweep} sweeps");
                break;
            }
        }
        // Recompute y from the forces (no drift from the incremental updates).
        let y = op.displacements(&r, beta);
        condensed.solution(
            problem,
            &y,
            &r,
            Ending {
                status,
                detail,
                steps: sweeps,
                timing: Timing {
                    setup,
                    solve: t1.elapsed().as_secs_f64(),
                },
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Checks the local law at r for (t, s) = q − W r.
    fn holds(w: [[f64; 2]; 2], q: [f64; 2], r: [f64; 2], bound: Bound) -> bool {
        let t = q[0] - w[0][0] * r[0] - w[0][1] * r[1];
        let s = q[1] - w[1][0] * r[0] - w[1][1] * r[1];
        let g = match bound {
            Bound::Given(g) => g,
            Bound::Coulomb(f) => f * r[0],
        };
        let e = 1e-10;
        r[0] >= -e
            && t <= e
            && (r[0] * t).abs() <= e
            && r[1].abs() <= g + e
            && (s.abs() <= e || (r[1] - g * s.signum()).abs() <= e)
    }

    #[test]
    fn the_local_solve_satisfies_the_law_in_every_case() {
        let w = [[2.0, 0.3], [0.3, 1.0]];
        let mut random = crate::numerics::random::Lcg::new(3);
        let mut rnd = || 2.0 * random.symmetric();
        for _ in 0..2000 {
            let q = [rnd(), rnd()];
            for bound in [Bound::Given(rnd().abs()), Bound::Coulomb(rnd().abs() * 0.8)] {
                let r = local_solve(w, q, bound);
                assert!(holds(w, q, r, bound), "q = {q:?}, {bound:?}: r = {r:?}");
            }
        }
    }
}
