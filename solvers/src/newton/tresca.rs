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

use faer::Mat;
use faer::linalg::solvers::Solve;
use serde::{Deserialize, Serialize};

use crate::entry::{Accuracy, Entry, FACTORED_MAX_UNKNOWNS, Knob, Role, StageInfo};
use crate::numerics::globalization::{Units, armijo, direction, merit};
use crate::numerics::ncp::{billups, fb};
use crate::observer::{Control, Observer, Progress};
use crate::problem::ContactProblem;
use crate::reduction::condensed::{Condensed, Kept, condense};
use crate::settings::{Kind, Validate, from_tree, to_tree};
use crate::solution::{Iterations, Solution, Status, Timing};
use crate::solver::{Friction, Law, Solver, Start};

/// The progress stage of one newton (its unit of work).
pub(crate) const NEWTON_STEP: &str = "newton";

/// The registry entry of the condensed semismooth Newton solver.
pub(crate) const ENTRY: Entry = Entry {
    name: NEWTON_STEP,
    about: "fast exact solver: condensation onto the contact unknowns (sparse Cholesky once), semismooth Newton with line search",
    source: "Fischer (1992) and Billups (1995) NCP/box functions; De Luca, Facchinei & Kanzow (1996) globalization on the merit ½‖Φ‖²",
    laws: &[Law::GivenFriction],
    warm_starts: false,
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
    build: |tree| Ok(Box::new(CondensedNewton::new(from_tree(tree)?))),
    accuracy: Accuracy {
        knob: "tolerance",
        reference: 1e-13,
        exact: true,
    },
    role: Role::Other,
    kernel: None,
    max_unknowns: Some(FACTORED_MAX_UNKNOWNS),
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

/// The state of the Newton iteration: unknowns, residuals and derivatives.
struct Kkt<'a> {
    s: &'a Mat<f64>,
    b: &'a [f64],
    /// G_i = w_i g_i.
    g: &'a [f64],
    kappa: f64,
}

struct Eval {
    /// Residuals: F (2m), Φ_N (m), Φ_F (m).
    phi: Vec<f64>,
    /// Derivatives: (∂Φ_N/∂λ, ∂Φ_N/∂(−κt)) and (∂Φ_F/∂μ, ∂Φ_F/∂(κs)) per node.
    dn: Vec<(f64, f64)>,
    df: Vec<(f64, f64)>,
}

impl Kkt<'_> {
    fn m(&self) -> usize {
        self.g.len()
    }

    fn eval(&self, y: &[f64], lam: &[f64], mu: &[f64]) -> Eval {
        let m = self.m();
        let mut phi = vec![0.0; 4 * m];
        for (k, (p, bk)) in phi[..2 * m].iter_mut().zip(self.b).enumerate() {
            *p = y
                .iter()
                .enumerate()
                .map(|(l, yl)| self.s[(k, l)] * yl)
                .sum::<f64>()
                - bk;
        }
        let mut dn = Vec::with_capacity(m);
        let mut df = Vec::with_capacity(m);
        for i in 0..m {
            phi[2 * i] += lam[i];
            phi[2 * i + 1] -= mu[i];
            let (v, a, b) = fb(lam[i], -self.kappa * y[2 * i]);
            phi[2 * m + i] = v;
            dn.push((a, b));
            let (v, c, d, _) = billups(mu[i], self.kappa * y[2 * i + 1], self.g[i]);
            phi[3 * m + i] = v;
            df.push((c, d));
        }
        Eval { phi, dn, df }
    }

    /// ∇Ψ = Jᵀ Φ, in the order (y, λ, μ).
    fn gradient(&self, e: &Eval) -> Vec<f64> {
        let m = self.m();
        let mut grad = vec![0.0; 4 * m];
        for (k, gk) in grad[..2 * m].iter_mut().enumerate() {
            *gk = e.phi[..2 * m]
                .iter()
                .enumerate()
                .map(|(l, pl)| self.s[(l, k)] * pl)
                .sum();
        }
        for i in 0..m {
            let (pn, pf) = (e.phi[2 * m + i], e.phi[3 * m + i]);
            let (na, nb) = e.dn[i];
            let (fc, fd) = e.df[i];
            grad[2 * i] += -self.kappa * nb * pn;
            grad[2 * i + 1] += self.kappa * fd * pf;
            grad[2 * m + i] = e.phi[2 * i] + na * pn;
            grad[3 * m + i] = -e.phi[2 * i + 1] + fc * pf;
        }
        grad
    }

    /// The Newton direction (dy, dλ, dμ) of J d = −Φ, with dλ_i or dt_i and
    /// dμ_i or ds_i eliminated per node (whichever has the larger
    /// coefficient), so that one dense 2m × 2m system is solved.
    fn newton_direction(&self, e: &Eval) -> Option<Vec<f64>> {
        let m = self.m();
        let kappa = self.kappa;
        let mut mat = self.s.clone();
        let mut rhs: Vec<f64> = e.phi[..2 * m].iter().map(|x| -x).collect();
        let mut keep_t = vec![true; m];
        let mut keep_s = vec![true; m];
        for i in 0..m {
            let (t, sx) = (2 * i, 2 * i + 1);
            let (a, b) = e.dn[i];
            let pn = e.phi[2 * m + i];
            if a >= b {
                // dλ = (−Φ_N + κ b dt)/a
                mat[(t, t)] += kappa * b / a;
                rhs[t] += pn / a;
            } else {
                // dt = (Φ_N + a dλ)/(κ b); column t holds dλ.
                keep_t[i] = false;
                for r in 0..2 * m {
                    let col = self.s[(r, t)];
                    mat[(r, t)] = col * a / (kappa * b);
                    rhs[r] -= col * pn / (kappa * b);
                }
                mat[(t, t)] += 1.0;
            }
            let (c, d) = e.df[i];
            let pf = e.phi[3 * m + i];
            if c >= d {
                // dμ = (−Φ_F − d κ ds)/c
                mat[(sx, sx)] += d * kappa / c;
                rhs[sx] -= pf / c;
            } else {
                // ds = (−Φ_F − c dμ)/(d κ); column s holds dμ.
                keep_s[i] = false;
                for r in 0..2 * m {
                    let col = self.s[(r, sx)];
                    mat[(r, sx)] = -col * c / (d * kappa);
                    rhs[r] += col * pf / (d * kappa);
                }
                mat[(sx, sx)] -= 1.0;
            }
        }
        let lu = mat.partial_piv_lu();
        let x = lu.solve(Mat::from_fn(2 * m, 1, |r, _| rhs[r]));
        let mut dir = vec![0.0; 4 * m];
        for i in 0..m {
            let (t, sx) = (2 * i, 2 * i + 1);
            let (a, b) = e.dn[i];
            let pn = e.phi[2 * m + i];
            if keep_t[i] {
                dir[t] = x[(t, 0)];
                dir[2 * m + i] = (-pn + kappa * b * dir[t]) / a;
            } else {
                dir[2 * m + i] = x[(t, 0)];
                dir[t] = (pn + a * dir[2 * m + i]) / (kappa * b);
            }
            let (c, d) = e.df[i];
            let pf = e.phi[3 * m + i];
            if keep_s[i] {
                dir[sx] = x[(sx, 0)];
                dir[3 * m + i] = (-pf - d * kappa * dir[sx]) / c;
            } else {
                dir[3 * m + i] = x[(sx, 0)];
                dir[sx] = (-pf - c * dir[3 * m + i]) / (d * kappa);
            }
        }
        dir.iter().all(|v| v.is_finite()).then_some(dir)
    }
}

/// Outcome of the condensed Newton iteration.
pub struct NewtonOutcome {
    pub y: Vec<f64>,
    pub lambda: Vec<f64>,
    pub mu: Vec<f64>,
    pub status: Status,
    pub detail: String,
    pub steps: usize,
    /// The merit Ψ after each step (strictly decreasing with the line search).
    pub merit: Vec<f64>,
}

/// Semismooth Newton on the condensed KKT system from (y, λ, μ).
#[allow(clippy::too_many_arguments)]
pub fn semismooth_newton(
    s: &Mat<f64>,
    b: &[f64],
    g: &[f64],
    start: (Vec<f64>, Vec<f64>, Vec<f64>),
    settings: &NewtonSettings,
    observer: &mut dyn Observer,
) -> NewtonOutcome {
    let m = g.len();
    let units = Units::of_condensed(s, b);
    let kkt = Kkt {
        s,
        b,
        g,
        kappa: units.kappa,
    };
    let scale = units.scale;
    let (mut y, mut lam, mut mu) = start;
    let t0 = Instant::now();
    let mut e = kkt.eval(&y, &lam, &mu);
    let mut psi = merit(&e.phi);
    let mut merits = Vec::new();
    let residual = |e: &Eval| e.phi.iter().fold(0.0f64, |a, x| a.max(x.abs())) / scale;
    for step in 1..=settings.max_iter {
        let r = residual(&e);
        if !r.is_finite() {
            return finish(
                y,
                lam,
                mu,
                Status::NonFinite,
                format!("non-finite residual at Newton step {step}"),
                step - 1,
                merits,
            );
        }
        if r <= settings.tolerance {
            let detail = format!(
                "residual {r:.2e} ≤ {:e} after {} Newton steps",
                settings.tolerance,
                step - 1
            );
            return finish(y, lam, mu, Status::Converged, detail, step - 1, merits);
        }
        let grad = kkt.gradient(&e);
        let (dir, slope) = direction(
            kkt.newton_direction(&e),
            &grad,
            &units,
            settings.line_search,
        );
        let trial = |alpha: f64| {
            let along = |x: &[f64], d: &[f64]| -> Vec<f64> {
                x.iter().zip(d).map(|(a, d)| a + alpha * d).collect()
            };
            let (y1, l1, m1) = (
                along(&y, &dir[..2 * m]),
                along(&lam, &dir[2 * m..3 * m]),
                along(&mu, &dir[3 * m..]),
            );
            let e1 = kkt.eval(&y1, &l1, &m1);
            (merit(&e1.phi), (y1, l1, m1, e1))
        };
        let Some((psi1, (y1, l1, m1, e1))) = armijo(psi, slope, settings.line_search, trial) else {
            let detail = format!(
                "line search failed at Newton step {step} (residual {:.2e})",
                residual(&e)
            );
            return finish(
                y,
                lam,
                mu,
                Status::InsufficientProgress,
                detail,
                step,
                merits,
            );
        };
        e = e1;
        psi = psi1;
        y = y1;
        lam = l1;
        mu = m1;
        merits.push(psi);
        let control = observer.observe(&Progress {
            stage: NEWTON_STEP,
            iteration: step,
            residual: residual(&e),
            seconds: t0.elapsed().as_secs_f64(),
        });
        if let Control::Stop(status) = control {
            let detail = format!(
                "stopped by the harness after {step} Newton steps (residual {:.2e})",
                residual(&e)
            );
            return finish(y, lam, mu, status, detail, step, merits);
        }
    }
    let r = residual(&e);
    if r <= settings.tolerance {
        let detail = format!(
            "residual {r:.2e} ≤ {:e} after {} Newton steps",
            settings.tolerance, settings.max_iter
        );
        return finish(
            y,
            lam,
            mu,
            Status::Converged,
            detail,
            settings.max_iter,
            merits,
        );
    }
    let detail = format!(
        "Newton step cap {} reached with residual {r:.2e}",
        settings.max_iter
    );
    finish(
        y,
        lam,
        mu,
        Status::MaxIterations,
        detail,
        settings.max_iter,
        merits,
    )
}

fn finish(
    y: Vec<f64>,
    lambda: Vec<f64>,
    mu: Vec<f64>,
    status: Status,
    detail: String,
    steps: usize,
    merit: Vec<f64>,
) -> NewtonOutcome {
    NewtonOutcome {
        y,
        lambda,
        mu,
        status,
        detail,
        steps,
        merit,
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
            Err(e) => return Solution::failed(n, m, Status::NumericalError, e),
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
        let y0: Vec<f64> = match start {
            Some(s) if s.v.len() == n => {
                contacts.iter().flat_map(|c| [s.v[c.t], s.v[c.s]]).collect()
            }
            _ => vec![0.0; 2 * m],
        };
        let force = |k: usize| -> f64 {
            (0..2 * m).map(|l| condensed.s[(k, l)] * y0[l]).sum::<f64>() - condensed.b[k]
        };
        let lam0: Vec<f64> = match start {
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
