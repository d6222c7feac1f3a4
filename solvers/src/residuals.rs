//! Solver-independent KKT residuals of the given-friction subproblem, computed
//! from (v, p, q) alone, so that every solver, Clarabel included, is judged by
//! the same measure instead of by its own status.
//!
//! With nodal forces λ_i = w_i p_i (contact) and μ_i = w_i q_i (friction on the
//! lower body) the optimality conditions of paper (10) are
//!
//! ```text
//! A v − f + Σ_i λ_i e_{t_i} − Σ_i μ_i e_{s_i} = 0          (stationarity)
//! t_i ≤ 0,  p_i ≥ 0,  t_i p_i = 0                          (Signorini, (5)-(6))
//! |q_i| ≤ g_i,  q_i s_i + g_i |s_i| = 0                    (Tresca: at the bound and
//!                                                           opposing the slip where s_i ≠ 0)
//! ```
//!
//! Scales (stated, so the numbers can be read), each floored by a scale of
//! the data so that a solution that is rightly zero (a closed node, an open
//! node) does not divide noise by noise:
//! displacements by u = max(‖v‖∞, ‖f‖∞ / max_i A_ii),
//! pressures by p = max(max_i |p_i|, ‖f‖∞ / max_i w_i) (the load intensity),
//! forces by F = ‖f‖∞. Every residual below is dimensionless.

use serde::{Deserialize, Serialize};

use crate::linalg::{max_abs, spmv};
use crate::problem::GivenFrictionProblem;

/// Dimensionless KKT residuals (0 at an exact solution).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Residuals {
    /// max_i max(t_i, 0) / u: penetration.
    pub primal: f64,
    /// max_i max(−p_i, 0) / p: adhesive pressure.
    pub dual: f64,
    /// max_i |t_i p_i| / (u p).
    pub complementarity: f64,
    /// max_i max(|q_i| − g_i, 0) / p: friction outside its cone.
    pub cone: f64,
    /// max_i |q_i s_i + g_i |s_i|| / (u p): where s_i ≠ 0, q_i = −g_i sign(s_i).
    pub slip: f64,
    /// ‖A v − f + Σ λ_i e_t − Σ μ_i e_s‖∞ / F.
    pub stationarity: f64,
    /// Natural map of the complementarity conditions in scaled variables
    /// (t̂ = t/u, p̂ = p/p, ŝ = s/u, q̂ = q/p, ĝ = g/p):
    /// max_i max(|p̂_i − max(0, p̂_i + t̂_i)|, |q̂_i − proj_[−ĝ_i, ĝ_i](q̂_i − ŝ_i)|).
    pub natural_map: f64,
    /// The scales u, p, F used above.
    pub displacement_scale: f64,
    pub pressure_scale: f64,
    pub force_scale: f64,
}

impl Residuals {
    /// Computes every residual of (v, p, q) for `problem`.
    /// Sizes that do not fit the problem give infinite residuals.
    pub fn compute(problem: &GivenFrictionProblem, v: &[f64], p: &[f64], q: &[f64]) -> Self {
        let contacts = problem.contacts();
        if v.len() != problem.n() || p.len() != contacts.len() || q.len() != contacts.len() {
            let inf = f64::INFINITY;
            return Residuals {
                stationarity: inf,
                natural_map: inf,
                displacement_scale: 1.0,
                pressure_scale: 1.0,
                force_scale: 1.0,
                ..Default::default()
            };
        }
        let f_scale = nonzero(max_abs(problem.f()), 1.0);
        let max_diag = max_abs(problem.a().diagonal_as_csr().values());
        let max_w = contacts.iter().fold(0.0f64, |m, c| m.max(c.weight));
        let u_scale = nonzero(max_abs(v).max(f_scale / nonzero(max_diag, 1.0)), 1.0);
        let p_scale = nonzero(max_abs(p).max(f_scale / nonzero(max_w, 1.0)), 1.0);

        let mut r = spmv(problem.a(), v);
        for (ri, fi) in r.iter_mut().zip(problem.f()) {
            *ri -= fi;
        }
        let mut out = Residuals {
            displacement_scale: u_scale,
            pressure_scale: p_scale,
            force_scale: f_scale,
            ..Default::default()
        };
        for (i, c) in contacts.iter().enumerate() {
            let (t, s, pi, qi, g) = (v[c.t], v[c.s], p[i], q[i], c.g);
            r[c.t] += c.weight * pi;
            r[c.s] -= c.weight * qi;
            out.primal = out.primal.max(t.max(0.0) / u_scale);
            out.dual = out.dual.max((-pi).max(0.0) / p_scale);
            out.complementarity = out
                .complementarity
                .max((t * pi).abs() / (u_scale * p_scale));
            out.cone = out.cone.max((qi.abs() - g).max(0.0) / p_scale);
            out.slip = out
                .slip
                .max((qi * s + g * s.abs()).abs() / (u_scale * p_scale));
            let (th, ph, sh, qh, gh) = (
                t / u_scale,
                pi / p_scale,
                s / u_scale,
                qi / p_scale,
                g / p_scale,
            );
            let contact = (ph - (ph + th).max(0.0)).abs();
            let friction = (qh - (qh - sh).clamp(-gh, gh)).abs();
            out.natural_map = out.natural_map.max(contact).max(friction);
        }
        out.stationarity = max_abs(&r) / f_scale;
        // A NaN anywhere must not read as a small residual.
        if v.iter().chain(p).chain(q).any(|x| !x.is_finite()) {
            out.stationarity = f64::INFINITY;
            out.natural_map = f64::INFINITY;
        }
        out
    }

    /// The largest of all residuals: one number to judge a solution by.
    pub fn kkt(&self) -> f64 {
        [
            self.primal,
            self.dual,
            self.complementarity,
            self.cone,
            self.slip,
            self.stationarity,
            self.natural_map,
        ]
        .into_iter()
        .fold(0.0, f64::max)
    }
}

fn nonzero(x: f64, fallback: f64) -> f64 {
    if x > 0.0 && x.is_finite() {
        x
    } else {
        fallback
    }
}
