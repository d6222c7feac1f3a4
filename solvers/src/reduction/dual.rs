//! The condensed contact problem in the contact forces, for the dual methods
//! (nonsmooth Gauss-Seidel, accelerated projected gradient), with the
//! semicoercive mode treated exactly.
//!
//! On the contact unknowns y = (t_i, s_i) the condensed equations are
//! S y = b̂ − r, with r = (λ_i at t_i, −μ_i at s_i) the nodal contact and
//! friction forces (see [`crate::reduction::condensed`]). The usual "local" form
//! y = W(b̂ − r), W = S⁻¹ (the Delassus operator), does not exist here: the
//! upper body's vertical translation z_C (the rigid mode on the contact
//! unknowns: t_i = −1, s_i = 0) is in the kernel of S and moves every jump at
//! once. It is kept exactly, never by a spring:
//!
//! ```text
//! y = M (b̂ − r) + β ẑ,        ẑᵀ(b̂ − r) = 0,        M = (S + c ẑẑᵀ)⁻¹,
//! ```
//!
//! with ẑ = z_C/‖z_C‖. The translation β is one extra unknown and the
//! equilibrium of the contact forces with the load along the rigid mode
//! (Σ λ_i = the net load) is its equation. On vectors orthogonal to ẑ, M is
//! the pseudo-inverse of S; whatever c > 0 (c = mean S_kk, for conditioning)
//! the answer is the same once the equilibrium holds, since β absorbs the
//! component along ẑ. Measured elsewhere: a spring of stiffness k instead
//! loses a fraction ~5e3·k of the load at h = 1/64 and ruins conditioning
//! below k ≈ 1e-8.

use faer::linalg::solvers::DenseSolveCore;
use faer::{Mat, Side};

use crate::problem::ContactProblem;
use crate::reduction::condensed::Condensed;

/// The contact problem in the contact forces (2m unknowns r, plus β).
pub(crate) struct DualOperator {
    /// M = (S + c ẑẑᵀ)⁻¹, or S⁻¹ when there is no rigid mode (dense, 2m × 2m).
    pub m: Mat<f64>,
    /// b̂.
    pub b: Vec<f64>,
    /// ẑ, the rigid mode on the contact unknowns (unit length), if any.
    pub z: Option<Vec<f64>>,
}

impl DualOperator {
    /// From the condensation of `problem` (whose first rigid mode, restricted
    /// to the contact unknowns, is ẑ).
    pub fn new(problem: &ContactProblem, condensed: &Condensed) -> Result<Self, String> {
        let n2 = condensed.b.len();
        let z = problem.rigid_modes().first().map(|mode| {
            let mut z: Vec<f64> = problem
                .contacts()
                .iter()
                .flat_map(|c| [mode[c.t], mode[c.s]])
                .collect();
            let norm = z.iter().map(|x| x * x).sum::<f64>().sqrt();
            for x in &mut z {
                *x /= norm;
            }
            z
        });
        let c = (0..n2).map(|k| condensed.s[(k, k)]).sum::<f64>() / n2.max(1) as f64;
        let mut a = condensed.s.clone();
        if let Some(z) = &z {
            for i in 0..n2 {
                for j in 0..n2 {
                    a[(i, j)] += c * z[i] * z[j];
                }
            }
        }
        let llt = a.llt(Side::Lower).map_err(|e| {
            format!(
                "the condensed operator with the rigid mode added is not positive definite: {e:?}"
            )
        })?;
        Ok(Self {
            m: llt.inverse(),
            b: condensed.b.clone(),
            z,
        })
    }

    /// Number of contact unknowns (2m).
    pub fn len(&self) -> usize {
        self.b.len()
    }

    /// y = M (b̂ − r) + β ẑ.
    pub fn displacements(&self, r: &[f64], beta: f64) -> Vec<f64> {
        let n2 = self.len();
        let d: Vec<f64> = self.b.iter().zip(r).map(|(b, r)| b - r).collect();
        (0..n2)
            .map(|i| {
                let my: f64 = (0..n2).map(|j| self.m[(i, j)] * d[j]).sum();
                my + self.z.as_ref().map_or(0.0, |z| beta * z[i])
            })
            .collect()
    }

    /// The gradient of the dual energy ½(b̂ − r)ᵀM(b̂ − r) in r, −M(b̂ − r),
    /// written to `out` (M is symmetric: read by columns, in memory order).
    pub fn gradient(&self, r: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            let column = self.m.col(i);
            let mut sum = 0.0;
            for (j, (b, rj)) in self.b.iter().zip(r).enumerate() {
                sum += column[j] * (b - rj);
            }
            *o = -sum;
        }
    }

    /// The translation that closes the gap: given y⁰ = M(b̂ − r), the β for
    /// which the largest jump is zero (t_i = y⁰_{t_i} + β ẑ_{t_i} ≤ 0 at every
    /// node, with equality at one). None without a rigid mode.
    pub(crate) fn closing_translation(&self, y0: &[f64]) -> Option<f64> {
        let z = self.z.as_ref()?;
        let mut beta = f64::NEG_INFINITY;
        let mut upper = f64::INFINITY;
        for i in (0..self.len()).step_by(2) {
            // t_i ≤ 0  ⇔  β ≥ −y⁰/ẑ where ẑ < 0, β ≤ −y⁰/ẑ where ẑ > 0.
            if z[i] < 0.0 {
                beta = beta.max(-y0[i] / z[i]);
            } else if z[i] > 0.0 {
                upper = upper.min(-y0[i] / z[i]);
            }
        }
        Some(if beta.is_finite() { beta } else { upper })
    }

    /// The largest eigenvalue of M by power iteration (a step size for
    /// gradient methods on the forces).
    pub(crate) fn largest_eigenvalue(&self) -> f64 {
        let n2 = self.len();
        let mut x = vec![1.0 / (n2.max(1) as f64).sqrt(); n2];
        let mut lambda = 0.0;
        for _ in 0..100 {
            let y: Vec<f64> = (0..n2)
                .map(|i| (0..n2).map(|j| self.m[(i, j)] * x[j]).sum())
                .collect();
            let norm = y.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm == 0.0 {
                break;
            }
            let next = norm;
            x = y.iter().map(|v| v / norm).collect();
            if (next - lambda).abs() <= 1e-6 * next {
                lambda = next;
                break;
            }
            lambda = next;
        }
        lambda
    }
}

/// The displacements of a problem whose contact forces are given (nodal
/// pressures p_i and friction tractions q_i per unit length): the elastic
/// response y = M(b̂ − r) + βẑ on the contact unknowns, r = (w_i p_i,
/// −w_i q_i), with the rigid translation β that closes the gap where the
/// contact carries load, then the interior unknowns. For checking an answer
/// given as forces alone (the certificate needs the displacements too).
pub fn displacements_from_forces(
    problem: &ContactProblem,
    p: &[f64],
    q: &[f64],
) -> Result<Vec<f64>, String> {
    let m = problem.contacts().len();
    if p.len() != m || q.len() != m {
        return Err(format!(
            "expected {m} pressures and friction tractions, got {} and {}",
            p.len(),
            q.len()
        ));
    }
    let condensed = crate::reduction::condensed::condense(problem).map_err(|e| e.detail)?;
    let op = DualOperator::new(problem, &condensed)?;
    let r: Vec<f64> = problem
        .contacts()
        .iter()
        .enumerate()
        .flat_map(|(i, c)| [c.weight * p[i], -c.weight * q[i]])
        .collect();
    let y0 = op.displacements(&r, 0.0);
    let beta = op.closing_translation(&y0).unwrap_or(0.0);
    Ok(condensed.expand(problem, &op.displacements(&r, beta)))
}
