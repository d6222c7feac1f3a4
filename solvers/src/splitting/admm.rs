//! ADMM on the primal given-friction problem (Glowinski & Marrocco 1975;
//! Boyd, Parikh, Chu, Peleato & Eckstein 2011; the first-order family of
//! OSQP, SCS and Siconos' ADMM), splitting the contact unknowns:
//!
//! ```text
//! minimize ½ yᵀS y − b̂ᵀy + Σ w_i g_i |s_i| + I(t ≤ 0)   as   ½ yᵀS y − b̂ᵀy + G(z), y = z,
//! y ← (S + ρI)⁻¹ (b̂ + ρ(z − u)),  z ← prox_{G/ρ}(y + u),  u ← u + y − z,
//! ```
//!
//! on the contact unknowns y = (t_i, s_i) after the condensation (one sparse
//! factorization: the interior unknowns are eliminated exactly), with one
//! dense Cholesky factorization of S + ρI reused by every step. S + ρI is
//! positive definite although S is singular: the semicoercive mode is held
//! by the constraint t ≤ 0 through z, exactly. The prox of G/ρ is the
//! projection t ≤ 0 and soft thresholding of s by w g/ρ. At convergence
//! (y = z) the contact forces are r = ρu (λ = ρu_t, μ = −ρu_s).
//!
//! Penalty rule: ρ = factor × the mean of S's diagonal (the contact unknowns'
//! stiffness after condensation; factor 1 by default), fixed, so that the
//! factorization is reused. Stopping: the primal residual ‖y − z‖∞ over U
//! and the dual residual ρ‖z − z_prev‖∞ over the nodal force scale (Boyd et
//! al., section 3.3, in the problem's scales), and the balance of the
//! contact forces with the net load along the rigid mode relative to that
//! load, all below the tolerance. The last matters when the net load is
//! small against the loads themselves (near condition (13)): measured, the
//! first two alone left 1.4e-5 of the net load unbalanced there.

use std::time::Instant;

use faer::linalg::solvers::Solve;
use faer::{Mat, Side};
use serde::{Deserialize, Serialize};

use crate::entry::{
    Accuracy, CONDENSED_MEMORY, Entry, FACTORED_MAX_UNKNOWNS, Knob, Role, StageInfo,
};
use crate::numerics::linalg::max_abs;
use crate::numerics::resolution::{Resolution, WINDOW, floor};
use crate::observer::{Control, Observer, Progress};
use crate::problem::ContactProblem;
use crate::reduction::condensed::{Condensed, Ending, Kept, condense};
use crate::settings::{Kind, Validate, from_tree, to_tree};
use crate::solution::{SetupError, Solution, Status, Timing};
use crate::solver::{Friction, Law, Solver, Start};

/// The progress stage of one admm step (its unit of work).
pub(crate) const STEP: &str = "admm_step";

/// The registry entry of ADMM.
pub(crate) const ENTRY: Entry = Entry {
    name: "admm",
    about: "ADMM on the primal problem splitting the contact unknowns: condensation, one Cholesky of S + ρI reused, ρ = mean diag S",
    source: "Glowinski & Marrocco (1975); Boyd et al. (2011), Distributed optimization ... ADMM, sections 3 and 5",
    laws: &[Law::GivenFriction],
    warm_starts: false,
    schedule: crate::schedule::Schedule::Revisit,
    schedule_when: None,
    stages: &[StageInfo {
        name: STEP,
        about: "one ADMM step; residual max(primal ‖y − z‖∞/U, dual ρ‖Δz‖∞/(P·w))",
        history: true,
    }],
    work_stage: STEP,
    knobs: &[
        Knob {
            name: "tolerance",
            fields: &["tolerance"],
            help: "stop when both ADMM residuals are below tolerance (relative)",
            kind: Kind::Positive,
        },
        Knob {
            name: "rho_factor",
            fields: &["rho_factor"],
            help: "penalty ρ as a multiple of the mean diagonal of S",
            kind: Kind::Positive,
        },
        Knob {
            name: "max_iter",
            fields: &["max_iter"],
            help: "cap on steps per solve",
            kind: Kind::Count,
        },
    ],
    defaults: |_| to_tree(&AdmmSettings::default()),
    build: crate::entry::Build::Fn(|tree| Ok(Box::new(Admm::new(from_tree(tree)?)))),
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

/// Settings of ADMM (relative in both stopping modes).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct AdmmSettings {
    pub tolerance: f64,
    pub rho_factor: f64,
    pub max_iter: usize,
}

impl Default for AdmmSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            rho_factor: 1.0,
            max_iter: 1_000_000,
        }
    }
}

impl Validate for AdmmSettings {
    /// Checked by the kinds of its registry entry's knobs.
    fn validate(&self) -> Result<(), String> {
        ENTRY.check(&to_tree(self))
    }
}

/// ADMM. Keeps the condensation and the factor of S + ρI across calls on
/// the same problem operator and penalty.
#[derive(Default)]
pub(crate) struct Admm {
    pub settings: AdmmSettings,
    cache: Kept<(u64, f64), (Condensed, faer::linalg::solvers::Llt<f64>, f64)>,
}

impl Admm {
    pub fn new(settings: AdmmSettings) -> Self {
        Self {
            settings,
            cache: Kept::default(),
        }
    }
}

impl Solver for Admm {
    /// Two rigid modes, measured: Cattaneo–Mindlin with the upper body free
    /// to slide (`scenes/cattaneo_mindlin_sliding.toml`) certifies.
    fn rigid_modes_handled(&self) -> usize {
        2
    }

    fn solve(
        &mut self,
        problem: &ContactProblem,
        friction: Friction<'_>,
        _start: Option<Start<'_>>,
        observer: &mut dyn Observer,
    ) -> Solution {
        let (n, contacts) = (problem.n(), problem.contacts());
        let m = contacts.len();
        let bound = match Solution::given_bound(problem, friction, self.settings.validate()) {
            Ok(g) => g,
            Err(refused) => return *refused,
        };
        let t0 = Instant::now();
        let factor = self.settings.rho_factor;
        let kept = self
            .cache
            .get_or_build((problem.operator_id(), factor), || {
                let condensed = condense(problem)?;
                let n2 = condensed.b.len();
                let mean = (0..n2).map(|k| condensed.s[(k, k)]).sum::<f64>() / n2.max(1) as f64;
                let rho = factor * mean;
                let mut a = condensed.s.clone();
                for k in 0..n2 {
                    a[(k, k)] += rho;
                }
                let llt = a.llt(Side::Lower).map_err(|e| {
                    SetupError::from(format!("S + ρI is not positive definite: {e:?}"))
                })?;
                Ok::<_, SetupError>((condensed, llt, rho))
            });
        let (condensed, llt, rho) = match kept {
            Ok((c, l, r)) => (c, l, *r),
            Err(e) => return Solution::failed(n, m, e.status, e.detail),
        };
        let setup = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let n2 = 2 * m;
        let scales = problem.scales();
        let w_max = contacts.iter().fold(0.0f64, |a, c| a.max(c.weight));
        let (u_scale, f_scale) = (scales.displacement, scales.pressure * w_max);
        // prox_{G/ρ} of one component: t ≤ 0, soft thresholding of s.
        let prox = |k: usize, v: f64| -> f64 {
            if k.is_multiple_of(2) {
                v.min(0.0)
            } else {
                let c = &contacts[k / 2];
                let kappa = c.weight * bound[k / 2] / rho;
                v.signum() * (v.abs() - kappa).max(0.0)
            }
        };
        // The rigid mode on the contact unknowns and the net load along it,
        // z_Cᵀ b̂ = zᵀf: the forces must balance it, and ADMM's iterates do
        // so only as y → z (z_Cᵀ(b̂ − ρu) = ρ z_Cᵀ(y − z) by the y-step, as
        // z_Cᵀ S = 0), so its stopping test checks it relative to that load.
        let mode: Option<Vec<f64>> = problem
            .rigid_modes()
            .first()
            .map(|z| contacts.iter().flat_map(|c| [z[c.t], z[c.s]]).collect());
        let net = mode.as_ref().map_or(0.0, |z| {
            z.iter()
                .zip(&condensed.b)
                .map(|(z, b)| z * b)
                .sum::<f64>()
                .abs()
        });
        // Buffers allocated once.
        let (mut z, mut u, mut z_next) = (vec![0.0; n2], vec![0.0; n2], vec![0.0; n2]);
        let mut y = Mat::<f64>::zeros(n2, 1);
        let mut status = Status::MaxIterations;
        let mut detail = format!("step cap {} reached", self.settings.max_iter);
        let mut steps = 0;
        let mut stall = Resolution::default();
        for k in 1..=self.settings.max_iter {
            steps = k;
            for i in 0..n2 {
                y[(i, 0)] = condensed.b[i] + rho * (z[i] - u[i]);
            }
            llt.solve_in_place(y.as_mut());
            for (i, zn) in z_next.iter_mut().enumerate() {
                *zn = prox(i, y[(i, 0)] + u[i]);
            }
            let primal =
                (0..n2).fold(0.0f64, |a, i| a.max((y[(i, 0)] - z_next[i]).abs())) / u_scale;
            let dual = rho
                * z_next
                    .iter()
                    .zip(&z)
                    .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()))
                / f_scale;
            for i in 0..n2 {
                u[i] += y[(i, 0)] - z_next[i];
            }
            std::mem::swap(&mut z, &mut z_next);
            let equilibrium = match &mode {
                Some(mode) if net > 0.0 => {
                    let carried: f64 = mode.iter().zip(&u).map(|(z, u)| z * rho * u).sum();
                    let load: f64 = mode.iter().zip(&condensed.b).map(|(z, b)| z * b).sum();
                    (load - carried).abs() / net
                }
                _ => 0.0,
            };
            let residual = primal.max(dual).max(equilibrium);
            let control = observer.observe(&Progress {
                stage: STEP,
                iteration: k,
                residual,
                seconds: t1.elapsed().as_secs_f64(),
            });
            if !residual.is_finite() {
                status = Status::NonFinite;
                detail = format!("non-finite iterate at step {k}");
                break;
            }
            if residual <= self.settings.tolerance {
                status = Status::Converged;
                detail = format!(
                    "residuals {primal:.2e} (primal), {dual:.2e} (dual), {equilibrium:.2e} (equilibrium) ≤ {:e} after {k} steps, ρ = {rho:.3e}",
                    self.settings.tolerance
                );
                break;
            }
            // The iterate (z, u) moved by rounding only: a fixed point of
            // the arithmetic short of the tolerance.
            let (dz, du) = (dual * f_scale / rho, primal * u_scale);
            if stall.step(dz <= floor(max_abs(&z)) && du <= floor(max_abs(&u))) {
                status = Status::InsufficientProgress;
                detail = format!(
                    "residual {residual:.2e} > {:e} after {k} steps: stalled at floating-point resolution (z and u moved by rounding only in {WINDOW} steps in a row: {dz:.1e} and {du:.1e})",
                    self.settings.tolerance
                );
                break;
            }
            if let Control::Stop(s) = control {
                status = s;
                detail = format!("stopped by the harness after {k} steps");
                break;
            }
        }
        condensed.solution(
            problem,
            &z,
            &u.iter().map(|u| rho * u).collect::<Vec<f64>>(),
            Ending {
                status,
                detail,
                steps,
                timing: Timing {
                    setup,
                    solve: t1.elapsed().as_secs_f64(),
                },
            },
        )
    }
}
