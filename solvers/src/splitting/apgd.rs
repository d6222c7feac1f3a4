//! Accelerated projected gradient descent on the contact forces (APGD: the
//! FISTA of Beck & Teboulle (2009) with the adaptive restart of O'Donoghue &
//! Candès (2015), as Mazhar, Heyn, Negrut & Tasora (2015) use it for
//! frictional contact in multibody codes).
//!
//! The given-friction subproblem's dual, with the semicoercive mode kept
//! exactly ([`crate::reduction::dual`]): the forces r = (λ_i, ν_i) minimize
//!
//! ```text
//! D(r) = ½ (b̂ − r)ᵀ M (b̂ − r)   over  λ_i ≥ 0, |ν_i| ≤ G_i,  ẑᵀ(b̂ − r) = 0,
//! ```
//!
//! the last constraint being the equilibrium of the contact forces with the
//! load along the rigid mode (without it the dual is unbounded: S is
//! singular). The projection onto the boxes intersected with that
//! hyperplane is exact: r = clamp(x − θẑ) with θ the root of a monotone
//! function (bisection). The gradient step is 1/L with L the largest
//! eigenvalue of M (power iteration). The translation β is recovered as the
//! one that closes the gap where the contact carries load. It stops on the
//! natural-map residual of the contact law in the problem's scales (the
//! certificate's measure), checked every tenth step.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::entry::{
    Accuracy, CONDENSED_MEMORY, Entry, FACTORED_MAX_UNKNOWNS, Knob, Role, StageInfo,
};
use crate::numerics::resolution::Resolution;
use crate::numerics::roots::monotone_root;
use crate::observer::{Control, Observer, Progress};
use crate::problem::ContactProblem;
use crate::reduction::condensed::{Condensed, Ending, Kept, condense};
use crate::reduction::dual::DualOperator;
use crate::settings::{Kind, Validate, from_tree, to_tree};
use crate::solution::{SetupError, Solution, Status, Timing};
use crate::solver::{Friction, Law, Solver, Start};

/// The progress stage of one apgd step (its unit of work).
pub(crate) const STEP: &str = "apgd_step";

/// The registry entry of APGD.
pub(crate) const ENTRY: Entry = Entry {
    name: "apgd",
    about: "accelerated projected gradient (FISTA with restart) on the contact forces, the equilibrium along the rigid mode as an exact constraint",
    source: "Beck & Teboulle (2009), FISTA; O'Donoghue & Candès (2015), adaptive restart; Mazhar et al. (2015), APGD for frictional contact",
    laws: &[Law::GivenFriction],
    warm_starts: false,
    schedule: crate::schedule::Schedule::Revisit,
    schedule_when: None,
    stages: &[StageInfo {
        name: STEP,
        about: "one accelerated projected gradient step; residual: the natural map of the contact law in the problem's scales (every tenth step)",
        history: true,
    }],
    work_stage: STEP,
    knobs: &[
        Knob {
            name: "tolerance",
            fields: &["tolerance"],
            help: "stop when the natural-map residual of the contact law, in the problem's scales, is below tolerance",
            kind: Kind::Positive,
        },
        Knob {
            name: "max_iter",
            fields: &["max_iter"],
            help: "cap on steps per solve",
            kind: Kind::Count,
        },
        Knob {
            name: "restart",
            fields: &["restart"],
            help: "adaptive restart of the momentum (true/false)",
            kind: Kind::Flag,
        },
    ],
    defaults: |_| to_tree(&ApgdSettings::default()),
    build: crate::entry::Build::Fn(|tree| Ok(Box::new(Apgd::new(from_tree(tree)?)))),
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

/// Settings of APGD (relative in both stopping modes).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct ApgdSettings {
    pub tolerance: f64,
    pub max_iter: usize,
    pub restart: bool,
}

impl Default for ApgdSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iter: 1_000_000,
            restart: true,
        }
    }
}

impl Validate for ApgdSettings {
    /// Checked by the kinds of its registry entry's knobs.
    fn validate(&self) -> Result<(), String> {
        ENTRY.check(&to_tree(self))
    }
}

/// APGD. Keeps the condensation, M and its largest eigenvalue across calls
/// on the same problem operator.
#[derive(Default)]
pub(crate) struct Apgd {
    pub settings: ApgdSettings,
    cache: Kept<u64, (Condensed, DualOperator, f64)>,
}

impl Apgd {
    pub fn new(settings: ApgdSettings) -> Self {
        Self {
            settings,
            cache: Kept::default(),
        }
    }
}

/// The restart test's threshold on cos∠(y − r⁺, r⁺ − r).
const RESTART_COSINE: f64 = 1e-9;

/// The largest violation of the contact law at forces r and contact
/// displacements y, node by node in the problem's scales (forces over F_w,
/// the nodal force scale; displacements over U): the natural map
/// min(λ/F_w, −t/U) of the normal law, and ν − clamp(ν + s·F_w/U, ±G) over
/// F_w of the friction law (zero exactly when |ν| ≤ G, with ν = G sign(s)
/// where s ≠ 0). The same measure as the certificate's, so that the
/// tolerance means the same thing (the projected-gradient step residual,
/// scaled by 1/L, stopped 1e-5 runs with a certificate of 2e-4).
fn natural_residual(r: &[f64], y: &[f64], g: &[f64], fw: f64, u: f64) -> f64 {
    let mut worst = 0.0f64;
    for (i, gi) in g.iter().enumerate() {
        let (lam, nu, t, s) = (r[2 * i], r[2 * i + 1], y[2 * i], y[2 * i + 1]);
        let normal = (lam / fw).min(-t / u).abs();
        let friction = (nu - (nu + s * fw / u).clamp(-gi, *gi)).abs() / fw;
        worst = worst.max(normal).max(friction);
    }
    worst
}

/// The dual is infeasible, so the primal is unbounded: the body flies off.
const NO_EQUILIBRIUM: &str = "no contact forces in the friction bounds balance the load along the rigid mode (it pulls the body off)";

/// One component of the box {λ ≥ 0, |ν| ≤ G}: even k a pressure, odd k a
/// friction force.
fn clamp_component(k: usize, v: f64, g: &[f64]) -> f64 {
    if k.is_multiple_of(2) {
        v.max(0.0)
    } else {
        v.clamp(-g[k / 2], g[k / 2])
    }
}

/// The projection of `x` onto {λ ≥ 0, |ν| ≤ G} ∩ {ẑᵀ r = c}, written to
/// `out`: clamp(x − θẑ) with θ the root of the nonincreasing
/// θ ↦ ẑᵀ clamp(x − θẑ) − c (each term is −ẑ_k² times a clamp's slope, 0 or
/// 1). False when there is no root: the boxes miss the hyperplane (the
/// load pulls the body off), so the subproblem has no solution.
fn project(x: &[f64], g: &[f64], z: Option<&[f64]>, c: f64, scale: f64, out: &mut [f64]) -> bool {
    let theta = match z {
        None => 0.0,
        Some(z) => {
            let f = |theta: f64| {
                x.iter()
                    .zip(z)
                    .enumerate()
                    .map(|(k, (&xk, &zk))| zk * clamp_component(k, xk - theta * zk, g))
                    .sum::<f64>()
                    - c
            };
            match monotone_root(f, 0.0, scale) {
                Some(theta) => theta,
                None => return false,
            }
        }
    };
    for (k, o) in out.iter_mut().enumerate() {
        *o = clamp_component(k, x[k] - z.map_or(0.0, |z| theta * z[k]), g);
    }
    true
}

impl Solver for Apgd {
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
        let (condensed, op, l) = match self.cache.get_or_build(problem.operator_id(), || {
            let c = condense(problem)?;
            let d = DualOperator::new(problem, &c).map_err(SetupError::from)?;
            let l = d.largest_eigenvalue();
            Ok::<_, SetupError>((c, d, l))
        }) {
            Ok((c, d, l)) => (c, d, *l),
            Err(e) => return Solution::failed(n, m, e.status, e.detail),
        };
        let setup = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let g: Vec<f64> = contacts
            .iter()
            .zip(bound)
            .map(|(c, g)| c.weight * g)
            .collect();
        let z = op.z.as_deref();
        // The equilibrium ẑᵀ r = ẑᵀ b̂.
        let c = z.map_or(0.0, |z| z.iter().zip(&op.b).map(|(a, b)| a * b).sum());
        let scales = problem.scales();
        let w_max = contacts.iter().fold(0.0f64, |a, c| a.max(c.weight));
        let force = scales.pressure * w_max;
        let tol = self.settings.tolerance;
        let step = 1.0 / l;
        let n2 = 2 * m;
        // The iteration's vectors, allocated once: forces r, extrapolated
        // point y, gradient, trial point x, next forces, probe.
        let mut r = vec![0.0; n2];
        let mut x = vec![0.0; n2];
        if !project(&x, &g, z, c, force, &mut r) {
            return Solution::failed(n, m, Status::Unbounded, NO_EQUILIBRIUM);
        }
        let mut yk = r.clone();
        let mut gradient = vec![0.0; n2];
        let mut next = vec![0.0; n2];
        let mut probe = vec![0.0; n2]; // the contact displacements at a check
        let mut tk = 1.0f64;
        let mut status = Status::MaxIterations;
        let mut detail = format!("step cap {} reached", self.settings.max_iter);
        let mut steps = 0;
        let mut stall = Resolution::default();
        for k in 1..=self.settings.max_iter {
            steps = k;
            op.gradient(&yk, &mut gradient);
            for ((xi, y), gi) in x.iter_mut().zip(&yk).zip(&gradient) {
                *xi = y - step * gi;
            }
            if !project(&x, &g, z, c, force, &mut next) {
                return Solution::failed(n, m, Status::Unbounded, NO_EQUILIBRIUM);
            }
            // Restart when the momentum points uphill, in the composite
            // form of O'Donoghue & Candès (2015), section 3.2: the gradient
            // mapping y − r⁺ against the step r⁺ − r, (y − r⁺)ᵀ(r⁺ − r) > 0.
            // (The plain gradient ∇D(y) is not small at a constrained
            // solution, so its sign test reads roundoff near convergence.)
            // It is read as a cosine above a roundoff-level threshold, so that
            // the decision does not hinge on the last bits.
            let (mut uphill, mut gg, mut dd) = (0.0, 0.0, 0.0);
            let (mut moved, mut size) = (0.0f64, 0.0f64);
            for ((y, a), b) in yk.iter().zip(&next).zip(&r) {
                let (g, d) = (y - a, a - b);
                uphill += g * d;
                gg += g * g;
                dd += d * d;
                moved = moved.max(d.abs());
                size = size.max(a.abs());
            }
            let uphill = uphill > RESTART_COSINE * (gg * dd).sqrt();
            // Forces that move by rounding only: a fixed point of the
            // arithmetic, converged or stalled, which the residual decides.
            let at_rest = stall.stalled(moved, size);
            // The natural-map residual of the contact law at the new forces,
            // every tenth step (it costs a product with M), and at rest.
            let residual = if k % 10 == 0 || k == self.settings.max_iter || at_rest {
                op.gradient(&next, &mut gradient);
                for (p, gi) in probe.iter_mut().zip(&gradient) {
                    *p = -gi;
                }
                let beta = op.closing_translation(&probe).unwrap_or(0.0);
                if let Some(z) = z {
                    for (p, zk) in probe.iter_mut().zip(z) {
                        *p += beta * zk;
                    }
                }
                natural_residual(&next, &probe, &g, force, scales.displacement)
            } else {
                f64::INFINITY
            };
            let t_next = 0.5 * (1.0 + (1.0 + 4.0 * tk * tk).sqrt());
            if self.settings.restart && uphill {
                yk.copy_from_slice(&next);
                tk = 1.0;
            } else {
                let beta = (tk - 1.0) / t_next;
                for ((y, a), b) in yk.iter_mut().zip(&next).zip(&r) {
                    *y = a + beta * (a - b);
                }
                tk = t_next;
            }
            let finite = next.iter().all(|x| x.is_finite());
            std::mem::swap(&mut r, &mut next);
            let control = observer.observe(&Progress {
                stage: STEP,
                iteration: k,
                residual: if residual.is_finite() {
                    residual / force
                } else {
                    f64::NAN
                },
                seconds: t1.elapsed().as_secs_f64(),
            });
            if !finite {
                status = Status::NonFinite;
                detail = format!("non-finite force at step {k}");
                break;
            }
            if residual <= tol {
                status = Status::Converged;
                detail = format!("natural-map residual {residual:.3e} ≤ {tol:.0e} after {k} steps");
                break;
            }
            if at_rest {
                status = Status::InsufficientProgress;
                detail = format!(
                    "the natural-map residual is above {tol:.0e} after {k} steps: {}",
                    Resolution::detail("the contact forces r", moved, size)
                );
                break;
            }
            if let Control::Stop(s) = control {
                status = s;
                detail = format!("stopped by the harness after {k} steps");
                break;
            }
        }
        let y0 = op.displacements(&r, 0.0);
        let beta = op.closing_translation(&y0).unwrap_or(0.0);
        let y = op.displacements(&r, beta);
        condensed.solution(
            problem,
            &y,
            &r,
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
