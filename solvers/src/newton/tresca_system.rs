//! The condensed KKT system of the given-friction subproblem (see
//! [`super::tresca`]) and its globalized semismooth Newton iteration: the
//! residuals F, Φ_N, Φ_F and their derivatives, the Newton direction with
//! the multipliers eliminated node by node, and the Armijo line search on
//! the merit Ψ = ½‖Φ‖².

use std::time::Instant;

use faer::Mat;
use faer::linalg::solvers::Solve;

use super::tresca::{NEWTON_STEP, NewtonSettings};
use crate::numerics::globalization::{Units, armijo, direction, merit};
use crate::numerics::ncp::{billups, fb};
use crate::numerics::resolution::{Resolution, ULPS, WINDOW};
use crate::observer::{Control, Observer, Progress};
use crate::solution::Status;

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
    let mut stall = Resolution::default();
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
        // The residual, relative to the problem's scale, at rounding for
        // several steps: no Newton step can take it to the tolerance.
        if stall.stalled(r, 1.0) {
            let detail = format!(
                "residual {r:.2e} > {:e} after {} Newton steps: stalled at floating-point resolution (within {ULPS} roundoffs of the problem's scale for {WINDOW} steps)",
                settings.tolerance,
                step - 1
            );
            return finish(
                y,
                lam,
                mu,
                Status::InsufficientProgress,
                detail,
                step - 1,
                merits,
            );
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
