//! The globalization of the semismooth Newton methods on the merit
//! Ψ = ½‖Φ‖² (De Luca, Facchinei & Kanzow, Math. Programming 75, 1996,
//! Algorithm 3.1): take the Newton direction d when it descends Ψ enough,
//! ∇Ψᵀd ≤ −ρ‖d‖^p, otherwise the steepest descent −∇Ψ; then backtrack
//! along it until Ψ decreases sufficiently (Armijo). Ψ then falls strictly
//! at every step, so the iterates cannot cycle between active sets.

/// ρ of the descent test: small, so that the Newton direction is refused
/// only when it is nearly orthogonal to −∇Ψ (DFK's numerical experiments
/// take 1e-8; the test is made in the problem's units, see [`Units`]).
pub(crate) const DESCENT_RHO: f64 = 1e-10;
/// p of the descent test: p > 2 is what the convergence theory needs (DFK
/// Theorem 3.1); 2.1 is their choice.
pub(crate) const DESCENT_P: f64 = 2.1;
/// σ of the sufficient decrease Ψ(x + αd) ≤ Ψ(x) + σα∇Ψᵀd (Armijo; DFK
/// take 1e-4, the usual value, Nocedal & Wright (3.4)).
pub(crate) const ARMIJO_SIGMA: f64 = 1e-4;
/// The factor by which a refused step is shortened.
pub(crate) const BACKTRACK: f64 = 0.5;
/// The shortest step tried before the search gives up: below it, in double
/// precision, x + αd no longer differs from x in any but the last bits (a
/// stationary point of Ψ that is not a zero).
pub(crate) const MIN_STEP: f64 = 1e-14;

/// The merit Ψ = ½‖Φ‖² of a residual Φ.
pub fn merit(phi: &[f64]) -> f64 {
    0.5 * phi.iter().map(|x| x * x).sum::<f64>()
}

/// The units of a Newton system's unknowns, so that the descent test does
/// not depend on the units the user chose: the first `displacements`
/// components are displacements, scaled to forces by the stiffness `kappa`
/// (κ: the mean diagonal of the condensed operator S, so that κ·t and a
/// contact force λ are commensurate), the others are forces; all are
/// measured against the load `scale` (‖b̂‖∞). With ‖d‖^p in raw units,
/// E = 1e-30 or loads × 1e100 turned every step into a gradient step.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Units {
    pub displacements: usize,
    pub kappa: f64,
    pub scale: f64,
}

impl Units {
    /// The units of a system on the condensed contact unknowns (2m
    /// displacements, then forces) with operator `s` and load `b`: κ the
    /// mean |S_kk| (1 for an empty or zero S), the scale ‖b‖∞ (at least the
    /// smallest normal number).
    pub(crate) fn of_condensed(s: &faer::Mat<f64>, b: &[f64]) -> Self {
        let n = s.nrows();
        let mean = (0..n).map(|k| s[(k, k)].abs()).sum::<f64>() / n.max(1) as f64;
        Self {
            displacements: n,
            kappa: if mean > 0.0 { mean } else { 1.0 },
            scale: b
                .iter()
                .fold(0.0f64, |a, x| a.max(x.abs()))
                .max(f64::MIN_POSITIVE),
        }
    }

    /// Whether the Newton direction `d` descends Ψ enough to be taken:
    /// ∇Ψᵀd ≤ −ρ‖d‖^p in these units (`slope` is ∇Ψᵀd).
    pub(crate) fn descends(&self, slope: f64, d: &[f64]) -> bool {
        let size: f64 = d
            .iter()
            .enumerate()
            .map(|(k, x)| {
                let unit = if k < self.displacements {
                    self.kappa * x
                } else {
                    *x
                } / self.scale;
                unit * unit
            })
            .sum();
        slope / (self.scale * self.scale) <= -DESCENT_RHO * size.powf(DESCENT_P / 2.0)
    }
}

/// The direction of a step: Newton's (`newton`, None where its system could
/// not be solved) if it descends enough or the search is off, else −∇Ψ.
/// Gives the direction and its slope ∇Ψᵀd.
pub fn direction(
    newton: Option<Vec<f64>>,
    grad: &[f64],
    units: &Units,
    line_search: bool,
) -> (Vec<f64>, f64) {
    let slope = |d: &[f64]| d.iter().zip(grad).map(|(a, b)| a * b).sum::<f64>();
    let d = match newton {
        Some(d) if !line_search => d,
        Some(d) if units.descends(slope(&d), &d) => d,
        _ => grad.iter().map(|x| -x).collect(),
    };
    let s = slope(&d);
    (d, s)
}

/// The backtracking search along a direction of slope `slope` from a point
/// of merit `psi`: `trial(α)` evaluates the point x + αd and gives its
/// merit and whatever the caller keeps of it. The first α = 1, ½, ¼, ...
/// with sufficient decrease (any α = 1 when the search is off) is taken;
/// None once α falls below [`MIN_STEP`].
pub(crate) fn armijo<T>(
    psi: f64,
    slope: f64,
    line_search: bool,
    mut trial: impl FnMut(f64) -> (f64, T),
) -> Option<(f64, T)> {
    let mut alpha = 1.0;
    loop {
        let (psi1, kept) = trial(alpha);
        if !line_search || (psi1.is_finite() && psi1 <= psi + ARMIJO_SIGMA * alpha * slope) {
            return Some((psi1, kept));
        }
        alpha *= BACKTRACK;
        if alpha < MIN_STEP {
            return None;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On Ψ(x) = ½x², the search takes the full Newton step; a direction
    /// that ascends is refused for −∇Ψ; the test does not depend on units.
    #[test]
    fn newton_steps_are_taken_when_they_descend_in_any_units() {
        let units = Units {
            displacements: 1,
            kappa: 1.0,
            scale: 1.0,
        };
        let (d, slope) = direction(Some(vec![-2.0]), &[2.0], &units, true);
        assert_eq!((d, slope), (vec![-2.0], -4.0));
        let (d, _) = direction(Some(vec![1.0]), &[2.0], &units, true);
        assert_eq!(d, vec![-2.0]);
        let (psi1, x1) = armijo(2.0, -4.0, true, |a| {
            let x = 2.0 - 2.0 * a;
            (0.5 * x * x, x)
        })
        .unwrap();
        assert_eq!((psi1, x1), (0.0, 0.0));
        // The same system with displacements × 1e30 and forces × 1e-10:
        // the same decision.
        for (kappa, scale) in [(1e-30, 1e-10), (1e30, 1e20)] {
            let u = Units {
                displacements: 1,
                kappa,
                scale,
            };
            let d = [1e-3 * scale / kappa, 2e-3 * scale];
            let slope = -1e-12 * scale * scale;
            let base = Units {
                displacements: 1,
                kappa: 1.0,
                scale: 1.0,
            };
            assert_eq!(u.descends(slope, &d), base.descends(-1e-12, &[1e-3, 2e-3]));
        }
        // A search that never decreases gives up.
        assert!(armijo(1.0, -1.0, true, |_| (2.0, ())).is_none());
    }
}
