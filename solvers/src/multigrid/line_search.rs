//! The two exact one-dimensional minimizations that keep TNNMG monotone
//! (Gräser & Sander 2019, Algorithm 1, steps 4-5): along the multigrid
//! correction, and along the upper body's rigid mode.

use crate::multigrid::laws::Laws;
use crate::multigrid::smoother::Local;

/// Bisections of the line search: the step is then exact to 2⁻⁶⁰ of its
/// bracket.
const BISECTIONS: usize = 60;

/// Doublings of a bracket that the constraints leave open.
const DOUBLINGS: usize = 60;

/// The step α ∈ [0, α_max] minimizing J(v + α c), where
/// J(v + α c) − J(v) = ½α² cᵀAc − α cᵀr + Σ_k (φ_k(v_k + α c_k) − φ_k(v_k)),
/// r = b − A v, `cac` = cᵀAc, `cr` = cᵀr, the sum over the unknowns with a
/// law (`contact`), and α_max keeps every jump t_k + α c_k ≤ 0. J is
/// convex along the line and its right derivative nondecreasing, so the
/// minimizer is found by bisection on its sign; 0 when c is no descent
/// direction.
pub(crate) fn exact_step(
    laws: &Laws,
    contact: &[usize],
    v: &[f64],
    c: &[f64],
    cac: f64,
    cr: f64,
) -> f64 {
    let mut alpha_max = f64::INFINITY;
    for &k in contact {
        if let Local::Jump(d) = laws[k]
            && c[k] > 0.0
        {
            alpha_max = alpha_max.min((d - v[k]).max(0.0) / c[k]);
        }
    }
    // The right derivative of J(v + α c) in α.
    let slope = |alpha: f64| -> f64 {
        let mut s = alpha * cac - cr;
        for &k in contact {
            if c[k] != 0.0 {
                s += laws[k].slope(v[k] + alpha * c[k], c[k]);
            }
        }
        s
    };
    let descent = slope(0.0) < 0.0;
    if !descent {
        return 0.0;
    }
    let mut hi = if alpha_max.is_finite() {
        if slope(alpha_max) <= 0.0 {
            return alpha_max;
        }
        alpha_max
    } else {
        // From the quadratic part's own minimizer |cᵀr|/cᵀAc, so that the
        // bracket does not depend on the length of c: the rigid-mode
        // direction is O(1) while its step is of the size of the
        // displacements, and a bracket doubled from 1 stopped at 2⁶⁰ when
        // the units made displacements 1e98 (the scale-invariance test).
        let mut hi = if cac > 0.0 && cr != 0.0 {
            cr.abs() / cac
        } else {
            1.0
        };
        for _ in 0..DOUBLINGS {
            if slope(hi) > 0.0 {
                break;
            }
            hi *= 2.0;
        }
        hi
    };
    let mut lo = 0.0;
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if slope(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The translation β along the rigid mode z minimizing J(v + β z): with
/// A z = 0 and no slip in z, J(v + β z) = J(v) − β fᵀz, so when the load
/// pushes the bodies together (fᵀz < 0, paper (13)) the best β is the least
/// one that keeps every jump t_k + β z_k ≤ 0: the translation that closes
/// the gap where it is smallest. None when z moves a slip or the load does
/// not push.
pub(crate) fn closing_translation(
    laws: &Laws,
    contact: &[usize],
    v: &[f64],
    z: &[f64],
    fz: f64,
) -> Option<f64> {
    if fz >= 0.0 {
        return None;
    }
    let mut beta = f64::NEG_INFINITY;
    for &k in contact {
        let (vk, zk) = (v[k], z[k]);
        match laws[k] {
            Local::Slip(_) if zk != 0.0 => return None,
            Local::Jump(d) if zk < 0.0 => beta = beta.max((vk - d) / -zk),
            Local::Jump(_) if zk > 0.0 => return None,
            Local::Penalty { .. } | Local::Huber { .. } => return None,
            _ => {}
        }
    }
    beta.is_finite().then_some(beta)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The step is the minimizer of the sampled energy along the line.
    #[test]
    fn the_step_minimizes_the_energy_along_the_line() {
        let laws = [
            Local::Free,
            Local::Jump(0.0),
            Local::Slip(0.3),
            Local::Slip(0.0),
        ];
        let v = [0.2, -0.5, 0.1, 0.4];
        let c = [1.0, 0.4, -0.8, 0.3];
        let (cac, cr) = (2.0, 1.5);
        let energy = |a: f64| {
            let mut e = 0.5 * a * a * cac - a * cr;
            for k in 0..4 {
                if let Local::Slip(b) = laws[k] {
                    e += b * ((v[k] + a * c[k]).abs() - v[k].abs());
                }
            }
            e
        };
        let alpha = exact_step(&Laws::of(&laws), &[1, 2, 3], &v, &c, cac, cr);
        assert!(alpha <= 0.5 / 0.4 + 1e-15, "t stays ≤ 0");
        for i in 0..=1250 {
            let a = i as f64 * 1e-3;
            assert!(energy(alpha) <= energy(a) + 1e-12, "{alpha} vs {a}");
        }
    }

    /// Along a direction without a jump bound, the step does not depend on
    /// the length of the direction: with c × 1e-100 (so cᵀAc × 1e-200 and
    /// cᵀr × 1e-100) the step is × 1e100, with the laws scaled alike. A
    /// bracket doubled from 1 stopped at 2⁶⁰ and returned 1.15e18.
    #[test]
    fn the_step_scales_with_the_direction() {
        let laws = [Local::Free, Local::Slip(0.3)];
        let (v, c) = ([0.2, 0.1], [1.0, -0.8]);
        let alpha = exact_step(&Laws::of(&laws), &[1], &v, &c, 2.0, 1.5);
        assert!(alpha > 0.0);
        let s = 1e-100;
        let small = [c[0] * s, c[1] * s];
        let scaled = exact_step(&Laws::of(&laws), &[1], &v, &small, 2.0 * s * s, 1.5 * s);
        assert!(
            (scaled * s / alpha - 1.0).abs() < 1e-12,
            "{alpha} vs {scaled}·1e-100"
        );
    }
}
