//! The nonsmooth system of [`super`] (the direct Coulomb solver) on the
//! contact unknowns x = (y, λ, μ): its residual Φ = (F, Φ_N, Φ_F), the
//! generalized Jacobian of each node's complementarity rows, and the Newton
//! direction with the merit's gradient.

use faer::Mat;
use faer::linalg::solvers::Solve;

use crate::numerics::ncp::{billups, fb};

/// The Coulomb system on the contact unknowns.
pub(super) struct System<'a> {
    pub(super) s: &'a Mat<f64>,
    pub(super) b: &'a [f64],
    /// 𝓕_i per node.
    pub(super) coefficient: &'a [f64],
    pub(super) kappa: f64,
}

impl System<'_> {
    pub(super) fn m(&self) -> usize {
        self.coefficient.len()
    }

    /// The residual Φ = (F, Φ_N, Φ_F) at x = (y, λ, μ).
    pub(super) fn residual(&self, x: &[f64]) -> Vec<f64> {
        let m = self.m();
        let (y, rest) = x.split_at(2 * m);
        let (lam, mu) = rest.split_at(m);
        let mut phi = vec![0.0; 4 * m];
        for (k, p) in phi[..2 * m].iter_mut().enumerate() {
            *p = (0..2 * m).map(|l| self.s[(k, l)] * y[l]).sum::<f64>() - self.b[k];
        }
        for i in 0..m {
            phi[2 * i] += lam[i];
            phi[2 * i + 1] -= mu[i];
            phi[2 * m + i] = fb(lam[i], -self.kappa * y[2 * i]).0;
            let g = self.coefficient[i] * lam[i].max(0.0);
            phi[3 * m + i] = billups(mu[i], self.kappa * y[2 * i + 1], g).0;
        }
        phi
    }

    /// The derivatives of node i's complementarity rows at x: Φ_N,i's
    /// (∂λ, ∂t) = (a, −κ b_N), Φ_F,i's (∂μ, ∂s, ∂λ) = (d_μ, κ d_F, c).
    fn node(&self, x: &[f64], i: usize) -> NodeDerivatives {
        let m = self.m();
        let (y, lam, mu) = (&x[..2 * m], x[2 * m + i], x[3 * m + i]);
        let (_, a, b) = fb(lam, -self.kappa * y[2 * i]);
        let g = self.coefficient[i] * lam.max(0.0);
        let (_, dmu, df, dg) = billups(mu, self.kappa * y[2 * i + 1], g);
        NodeDerivatives {
            n_lam: a,
            n_t: -self.kappa * b,
            f_mu: dmu,
            f_s: self.kappa * df,
            f_lam: if lam > 0.0 {
                dg * self.coefficient[i]
            } else {
                0.0
            },
        }
    }

    /// An element of the generalized Jacobian at x, whole (4m × 4m): only
    /// for the condition-number diagnostic.
    pub(super) fn jacobian(&self, x: &[f64]) -> Mat<f64> {
        let m = self.m();
        let mut j = Mat::<f64>::zeros(4 * m, 4 * m);
        for k in 0..2 * m {
            for l in 0..2 * m {
                j[(k, l)] = self.s[(k, l)];
            }
        }
        for i in 0..m {
            j[(2 * i, 2 * m + i)] = 1.0;
            j[(2 * i + 1, 3 * m + i)] = -1.0;
            let d = self.node(x, i);
            j[(2 * m + i, 2 * m + i)] = d.n_lam;
            j[(2 * m + i, 2 * i)] = d.n_t;
            j[(3 * m + i, 3 * m + i)] = d.f_mu;
            j[(3 * m + i, 2 * i + 1)] = d.f_s;
            j[(3 * m + i, 2 * m + i)] = d.f_lam;
        }
        j
    }

    /// The Newton direction d (None if not finite) and the gradient
    /// ∇Ψ = JᵀΦ at x, without forming J. The force rows F read
    /// S dy + E dz = −F, with E dz = (dλ_i at t_i, −dμ_i at s_i) a signed
    /// permutation, so dλ_i = −F_t − (S dy)_t and dμ_i = F_s + (S dy)_s;
    /// put into the complementarity rows they leave a 2m × 2m system in dy,
    ///
    /// ```text
    /// row t_i:  −a S_t· dy − κ b_N dy_t             = −Φ_N + a F_t
    /// row s_i:  (d_μ S_s· − c S_t·) dy + κ d_F dy_s = −Φ_F − d_μ F_s + c F_t
    /// ```
    ///
    /// whose LU costs an eighth of the whole Jacobian's (the same
    /// determinant up to sign: the eliminated block is a permutation).
    pub(super) fn direction(&self, x: &[f64], phi: &[f64]) -> (Option<Vec<f64>>, Vec<f64>) {
        let m = self.m();
        let (f, rest) = phi.split_at(2 * m);
        let (phi_n, phi_f) = rest.split_at(m);
        let nodes: Vec<NodeDerivatives> = (0..m).map(|i| self.node(x, i)).collect();
        let s = self.s;
        let mut reduced = Mat::<f64>::zeros(2 * m, 2 * m);
        let mut rhs = Mat::<f64>::zeros(2 * m, 1);
        for (i, d) in nodes.iter().enumerate() {
            let (t, sl) = (2 * i, 2 * i + 1);
            rhs[(t, 0)] = -phi_n[i] + d.n_lam * f[t];
            rhs[(sl, 0)] = -phi_f[i] - d.f_mu * f[sl] + d.f_lam * f[t];
        }
        // Column by column (faer stores columns contiguously).
        for l in 0..2 * m {
            let col = s.col(l);
            let out = reduced.col_mut(l);
            let out = out
                .try_as_col_major_mut()
                .expect("a fresh Mat is column-major");
            let out = out.as_slice_mut();
            for (i, d) in nodes.iter().enumerate() {
                let (st, ss) = (col[2 * i], col[2 * i + 1]);
                out[2 * i] = -d.n_lam * st;
                out[2 * i + 1] = d.f_mu * ss - d.f_lam * st;
            }
        }
        for (i, d) in nodes.iter().enumerate() {
            reduced[(2 * i, 2 * i)] += d.n_t;
            reduced[(2 * i + 1, 2 * i + 1)] += d.f_s;
        }
        let dy = reduced.partial_piv_lu().solve(rhs);
        let sdy = s * &dy;
        let mut dir = vec![0.0; 4 * m];
        for k in 0..2 * m {
            dir[k] = dy[(k, 0)];
        }
        for i in 0..m {
            dir[2 * m + i] = -f[2 * i] - sdy[(2 * i, 0)];
            dir[3 * m + i] = f[2 * i + 1] + sdy[(2 * i + 1, 0)];
        }
        // ∇Ψ = JᵀΦ: (S F + D_yᵀΦ_c, EᵀF + D_zᵀΦ_c), S symmetric.
        let fm = Mat::from_fn(2 * m, 1, |k, _| f[k]);
        let sf = s * &fm;
        let mut grad = vec![0.0; 4 * m];
        for (i, d) in nodes.iter().enumerate() {
            let (t, sl) = (2 * i, 2 * i + 1);
            grad[t] = sf[(t, 0)] + d.n_t * phi_n[i];
            grad[sl] = sf[(sl, 0)] + d.f_s * phi_f[i];
            grad[2 * m + i] = f[t] + d.n_lam * phi_n[i] + d.f_lam * phi_f[i];
            grad[3 * m + i] = -f[sl] + d.f_mu * phi_f[i];
        }
        (dir.iter().all(|v| v.is_finite()).then_some(dir), grad)
    }
}

/// Node i's derivatives of the complementarity rows (see [`System::node`]).
struct NodeDerivatives {
    n_lam: f64,
    n_t: f64,
    f_mu: f64,
    f_s: f64,
    f_lam: f64,
}
