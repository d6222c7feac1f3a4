//! The paper's solver of the given-friction subproblem (sections 3-5,
//! Algorithm 1, lines 4-7): Uzawa's method on the modified Lagrangian
//!
//! ```text
//! M(v, l) = ½ vᵀA v − fᵀv + Σ w_i g_i |s_i| + Σ w_i/(2r) (((l_i + r t_i)⁺)² − l_i²),
//! ```
//!
//! with iterative proximal regularization (15)-(16): step k minimizes
//! M(v, l^k) + (ρ/2)‖v − v^k‖²_{L2(Ω)} (ρ = 1 in the paper) by pointwise
//! relaxation, then updates l^{k+1} = (l^k + r t^{k+1})⁺ (14). The L2 term makes
//! every step strictly convex although A is singular.
//!
//! Stopping rules are the paper's: relaxation until max|Δv| ≤ 1e-4·ε·h_finest,
//! Uzawa until max|Δl| ≤ ε. A cap reached is a status, never a silent stop.

pub mod pointwise;

use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::observer::{Observer, Progress, Stage};
use crate::problem::GivenFrictionProblem;
use crate::solution::{Iterations, Solution, Status, Timing};
use crate::solver::{GivenFrictionSolver, Start};
use pointwise::{RelaxationOperator, Smoothing, SweepData};

/// Settings of the prox-Uzawa relaxation solver; defaults are the paper's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RelaxationSettings {
    /// Penalty r of the modified Lagrangian (paper: 1e12).
    pub r: f64,
    /// The paper's ε: Uzawa stops when max|Δl| ≤ ε (paper: 1e-4).
    pub epsilon: f64,
    /// Relaxation stops when max|Δv| ≤ sweep_factor · ε · h_finest
    /// (paper: 1e-4 · ε · 1/64).
    pub sweep_factor: f64,
    /// The finest mesh size of the run (the length in the sweep threshold).
    /// Set by the harness from the scene's levels.
    #[serde(skip)]
    pub h_finest: f64,
    /// Weight ρ of the proximal term (ρ/2)‖v − v^k‖²_{L2} (paper: 1; 0 turns
    /// the regularization off).
    pub proximal: f64,
    /// Treatment of |s| along slip coordinates.
    pub smoothing: Smoothing,
    /// Cap on Uzawa iterations per call.
    pub max_uzawa: usize,
    /// Cap on relaxation sweeps per Uzawa iteration.
    pub max_sweeps: usize,
    /// Wall-clock budget per call in seconds (default: none).
    pub time_limit: f64,
}

/// Default Huber width: below what the paper's sweep threshold resolves at
/// h = 1/64 (1e-4 · 1e-4 / 64 ≈ 1.6e-10), so the smoothing does not show.
pub const DEFAULT_HUBER_DELTA: f64 = 1e-10;

impl Default for RelaxationSettings {
    fn default() -> Self {
        Self {
            r: 1e12,
            epsilon: 1e-4,
            sweep_factor: 1e-4,
            h_finest: 1.0 / 64.0,
            proximal: 1.0,
            smoothing: Smoothing::Huber {
                delta: DEFAULT_HUBER_DELTA,
            },
            max_uzawa: 1000,
            max_sweeps: 2_000_000,
            time_limit: f64::INFINITY,
        }
    }
}

impl RelaxationSettings {
    /// The relaxation threshold on max|Δv|.
    pub fn sweep_tolerance(&self) -> f64 {
        self.sweep_factor * self.epsilon * self.h_finest
    }

    /// Checks ranges; the message names the field and what is valid.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |name: &str, v: f64, hint: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!(
                    "relaxation.{name} = {v} is invalid: it must be a positive number ({hint})"
                ))
            }
        };
        positive("r", self.r, "the paper: 1e12")?;
        positive("epsilon", self.epsilon, "the paper: 1e-4")?;
        positive("sweep_factor", self.sweep_factor, "the paper: 1e-4")?;
        positive("h_finest", self.h_finest, "the finest mesh size")?;
        if !(self.proximal.is_finite() && self.proximal >= 0.0) {
            return Err(format!(
                "relaxation.proximal = {} is invalid: the proximal weight must be ≥ 0 (the paper: 1; 0 is off)",
                self.proximal
            ));
        }
        if let Smoothing::Huber { delta } = self.smoothing {
            positive("smoothing.huber.delta", delta, "e.g. 1e-10")?;
        }
        if self.max_uzawa == 0 {
            return Err("relaxation.max_uzawa = 0 is invalid: allow at least 1 Uzawa iteration (default 1000)".into());
        }
        if self.time_limit.is_nan() || self.time_limit <= 0.0 {
            return Err(format!(
                "relaxation.time_limit = {} is invalid: give a positive number of seconds (default: none)",
                self.time_limit
            ));
        }
        if self.max_sweeps == 0 {
            return Err(
                "relaxation.max_sweeps = 0 is invalid: allow at least 1 sweep (default 2000000)"
                    .into(),
            );
        }
        Ok(())
    }
}

/// The prox-Uzawa relaxation solver. Keeps H = A + ρM across calls on the
/// same operator (the steps of the Coulomb fixed point).
#[derive(Clone, Debug, Default)]
pub struct ProxUzawa {
    pub settings: RelaxationSettings,
    cache: Option<(u64, f64, RelaxationOperator)>,
}

impl ProxUzawa {
    pub fn new(settings: RelaxationSettings) -> Self {
        Self {
            settings,
            cache: None,
        }
    }

    fn operator(&mut self, problem: &GivenFrictionProblem) -> &RelaxationOperator {
        let key = (problem.operator_id(), self.settings.proximal);
        let stale = self
            .cache
            .as_ref()
            .is_none_or(|(id, rho, _)| (*id, *rho) != key);
        if stale {
            let op =
                RelaxationOperator::new(problem.a(), problem.mass(), key.1, problem.contacts());
            self.cache = Some((key.0, key.1, op));
        }
        &self.cache.as_ref().expect("just filled").2
    }
}

/// Runs `prox_uzawa` (Algorithm 1, lines 4-7) on one problem.
pub fn prox_uzawa(
    op: &RelaxationOperator,
    problem: &GivenFrictionProblem,
    settings: &RelaxationSettings,
    start: Option<Start<'_>>,
    observer: &mut dyn Observer,
) -> Solution {
    let t0 = Instant::now();
    let n = problem.n();
    let contacts = problem.contacts();
    let m = contacts.len();
    let mut v = match start {
        Some(s) if s.v.len() == n => s.v.to_vec(),
        _ => vec![0.0; n],
    };
    let mut l = match start {
        Some(s) if s.pressure.len() == m => s.pressure.iter().map(|p| p.max(0.0)).collect(),
        _ => vec![0.0; m],
    };
    let wg: Vec<f64> = contacts.iter().map(|c| c.weight * c.g).collect();
    let rho = settings.proximal;
    let mut b = problem.f().to_vec();
    let mut mv = vec![0.0; n];
    let sweep_tol = settings.sweep_tolerance();
    let want_sweeps = observer.wants(Stage::Sweep);
    let (mut sweeps, mut uzawa) = (0usize, 0usize);
    let mut status = Status::MaxIterations;
    let mut detail = format!("Uzawa iteration cap {} reached", settings.max_uzawa);
    'uzawa: for k in 1..=settings.max_uzawa {
        uzawa = k;
        // b = f + ρ M v^k: the proximal centre is the previous iterate.
        if rho != 0.0 {
            crate::linalg::spmv_into(problem.mass(), &v, &mut mv);
            for ((bi, fi), mi) in b.iter_mut().zip(problem.f()).zip(&mv) {
                *bi = fi + rho * mi;
            }
        }
        let data = SweepData {
            b: &b,
            l: &l,
            wg: &wg,
            r: settings.r,
            smoothing: settings.smoothing,
        };
        let mut converged_inner = false;
        for q in 1..=settings.max_sweeps {
            let change = op.sweep(&mut v, &data);
            sweeps += 1;
            if want_sweeps {
                observer.observe(&Progress {
                    stage: Stage::Sweep,
                    iteration: q,
                    residual: change,
                    seconds: t0.elapsed().as_secs_f64(),
                });
            }
            if !change.is_finite() {
                status = Status::NonFinite;
                detail = format!("non-finite iterate in sweep {q} of Uzawa iteration {k}");
                break 'uzawa;
            }
            if change <= sweep_tol {
                converged_inner = true;
                break;
            }
            if q % 256 == 0 && t0.elapsed().as_secs_f64() > settings.time_limit {
                status = Status::TimeLimit;
                detail = format!(
                    "time limit {} s reached in Uzawa iteration {k} after {sweeps} sweeps (max|Δv| = {change:.3e})",
                    settings.time_limit
                );
                break 'uzawa;
            }
        }
        if !converged_inner {
            status = Status::MaxIterations;
            detail = format!(
                "relaxation sweep cap {} reached in Uzawa iteration {k} (max|Δv| > {sweep_tol:.3e})",
                settings.max_sweeps
            );
            break;
        }
        // l^{k+1} = (l^k + r t^{k+1})⁺, paper (14).
        let mut dl = 0.0f64;
        for (li, c) in l.iter_mut().zip(contacts) {
            let new = (*li + settings.r * v[c.t]).max(0.0);
            dl = dl.max((new - *li).abs());
            *li = new;
        }
        observer.observe(&Progress {
            stage: Stage::Uzawa,
            iteration: k,
            residual: dl,
            seconds: t0.elapsed().as_secs_f64(),
        });
        if !dl.is_finite() {
            status = Status::NonFinite;
            detail = format!("non-finite multiplier in Uzawa iteration {k}");
            break;
        }
        if dl <= settings.epsilon {
            status = Status::Converged;
            detail = format!(
                "max|Δl| = {dl:.3e} ≤ ε = {:e} after {k} Uzawa iterations, {sweeps} sweeps",
                settings.epsilon
            );
            break;
        }
    }
    // Friction traction from the one-dimensional optimality condition along
    // each slip coordinate: (Hv − b)_s + w g ξ = 0 with ξ ∈ ∂φ(s).
    let friction_traction = contacts
        .iter()
        .map(|c| {
            let g = c.g;
            match settings.smoothing {
                Smoothing::Huber { delta } => -g * (v[c.s] / delta).clamp(-1.0, 1.0),
                Smoothing::Exact => (op.gradient_at(&v, &b, c.s) / c.weight).clamp(-g, g),
            }
        })
        .collect();
    let mut out = Solution {
        v,
        pressure: l,
        friction_traction,
        status,
        detail,
        iterations: Iterations {
            outer: uzawa,
            inner: sweeps,
        },
        timing: Timing {
            setup: 0.0,
            solve: t0.elapsed().as_secs_f64(),
        },
    };
    if !out.is_finite() {
        out.status = Status::NonFinite;
    }
    out
}

impl GivenFrictionSolver for ProxUzawa {
    fn name(&self) -> &'static str {
        "relaxation"
    }

    fn solve(
        &mut self,
        problem: &GivenFrictionProblem,
        start: Option<Start<'_>>,
        observer: &mut dyn Observer,
    ) -> Solution {
        let (n, m) = (problem.n(), problem.contacts().len());
        if let Err(e) = self.settings.validate() {
            return Solution::failed(n, m, Status::NotRun, e);
        }
        let t0 = Instant::now();
        let settings = self.settings.clone();
        let op = self.operator(problem);
        let setup = t0.elapsed().as_secs_f64();
        let mut out = prox_uzawa(op, problem, &settings, start, observer);
        out.timing.setup = setup;
        out
    }
}
