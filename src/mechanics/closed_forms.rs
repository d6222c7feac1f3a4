//! Closed-form answers of classical plane contact problems, to verify the
//! discretization and every solver against (`contactlab verify`). Plane
//! strain or stress per unit thickness; loads P are forces per unit length.

use crate::mechanics::material::{Material, PlaneModel};

/// The effective modulus E* of two bodies in contact: in plane strain
/// 1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂, in plane stress 1/E₁ + 1/E₂
/// (Johnson, *Contact Mechanics*, 1985, ch. 4).
pub fn effective_modulus(lower: &Material, upper: &Material) -> f64 {
    let compliance = |m: &Material| match m.plane {
        PlaneModel::Strain => (1.0 - m.poisson * m.poisson) / m.young,
        PlaneModel::Stress => 1.0 / m.young,
    };
    1.0 / (compliance(lower) + compliance(upper))
}

/// Hertz's line contact of two bodies whose initial gap is the parabola
/// (x − x₀)²/2R (Johnson 1985, §4.3, two-dimensional contact of
/// cylinders; the half-plane idealization: bodies large against the
/// contact half-width a, which finite bodies miss by terms in (a/size)²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hertz {
    /// The effective modulus E*.
    pub modulus: f64,
    /// The normal load P per unit length.
    pub load: f64,
    /// The relative radius of curvature R.
    pub radius: f64,
    /// Where the bodies first touch, x₀.
    pub center: f64,
}

impl Hertz {
    /// The half-width a = √(4PR/(πE*)).
    pub fn half_width(&self) -> f64 {
        (4.0 * self.load * self.radius / (std::f64::consts::PI * self.modulus)).sqrt()
    }

    /// The peak pressure p₀ = 2P/(πa).
    pub fn peak_pressure(&self) -> f64 {
        2.0 * self.load / (std::f64::consts::PI * self.half_width())
    }

    /// p(x) = p₀ √(1 − (x − x₀)²/a²) inside the contact, 0 outside.
    pub fn pressure(&self, x: f64) -> f64 {
        let xi = (x - self.center) / self.half_width();
        self.peak_pressure() * (1.0 - xi * xi).max(0.0).sqrt()
    }
}

/// A flat rigid punch of half-width b pressed by P into a half-plane, or
/// two half-planes of one material touching on |x − x₀| ≤ b (the pressure
/// does not depend on the moduli): p(x) = P / (π √(b² − (x − x₀)²))
/// (Sadowsky 1928; Johnson 1985, §2.8), infinite at the edges.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatPunch {
    pub load: f64,
    pub half_width: f64,
    pub center: f64,
}

impl FlatPunch {
    /// p(x) inside the punch (infinite at its edges), 0 outside.
    pub fn pressure(&self, x: f64) -> f64 {
        let xi = x - self.center;
        let b = self.half_width;
        if xi.abs() > b {
            0.0
        } else {
            self.load / (std::f64::consts::PI * (b * b - xi * xi).sqrt())
        }
    }
}

/// How far a computed pressure profile is from a closed form: the measures
/// of `verification.csv`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PressureError {
    /// ‖p_h − p‖ / ‖p‖ in L2 over the compared part of Γ_K, by the
    /// trapezoid weights.
    pub l2: f64,
    /// max |p_h − p| over the nodes of the compared part inside the closed
    /// form's contact zone, over p₀.
    pub max: f64,
    /// The computed half-width: half the distance between the outermost
    /// nodes carrying a pressure above 1e-6 p₀.
    pub half_width: f64,
    /// The computed peak pressure, max p_h.
    pub peak: f64,
    /// The computed pressure at the node nearest the center.
    pub at_center: f64,
}

/// The error of the nodal pressures `p` at `x` (weights `w`) against
/// `exact`, compared on |x − center| ≤ `within` (infinite: all of Γ_K; the
/// max only where the closed form is positive), measured in p₀.
pub fn pressure_error(
    x: &[f64],
    w: &[f64],
    p: &[f64],
    exact: impl Fn(f64) -> f64,
    center: f64,
    within: f64,
    p0: f64,
) -> PressureError {
    let (mut num, mut den, mut max) = (0.0, 0.0, 0.0f64);
    let mut at_center = (f64::INFINITY, 0.0);
    for ((&xi, &wi), &pi) in x.iter().zip(w).zip(p) {
        if (xi - center).abs() < at_center.0 {
            at_center = ((xi - center).abs(), pi);
        }
        if (xi - center).abs() > within {
            continue;
        }
        let e = exact(xi);
        num += wi * (pi - e) * (pi - e);
        den += wi * e * e;
        if e > 0.0 {
            max = max.max((pi - e).abs());
        }
    }
    let carrying: Vec<f64> = x
        .iter()
        .zip(p)
        .filter(|(_, pi)| **pi > 1e-6 * p0)
        .map(|(xi, _)| *xi)
        .collect();
    let half_width = match (carrying.first(), carrying.last()) {
        (Some(lo), Some(hi)) => 0.5 * (hi - lo),
        _ => 0.0,
    };
    PressureError {
        l2: (num / den).sqrt(),
        max: max / p0,
        half_width,
        peak: p.iter().copied().fold(0.0, f64::max),
        at_center: at_center.1,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// p₀ = √(PE*/(πR)) (Johnson §4.3) and ∫p dx = P: the two
    /// forms of the peak agree, and the pressure carries the load.
    #[test]
    fn hertz_pressure_carries_the_load() {
        let h = Hertz {
            modulus: 41_271.0,
            load: 60.0,
            radius: 0.53,
            center: 0.5,
        };
        let direct = (h.load * h.modulus / (std::f64::consts::PI * h.radius)).sqrt();
        assert!((h.peak_pressure() / direct - 1.0).abs() < 1e-14);
        let n = 200_000;
        let (lo, hi) = (h.center - h.half_width(), h.center + h.half_width());
        let dx = (hi - lo) / n as f64;
        let total: f64 = (0..n)
            .map(|k| h.pressure(lo + (k as f64 + 0.5) * dx) * dx)
            .sum();
        assert!((total / h.load - 1.0).abs() < 1e-6, "{total}");
        assert_eq!(h.pressure(hi + 1e-9), 0.0);
    }

    #[test]
    fn equal_materials_halve_the_plane_strain_modulus() {
        let m = Material::default();
        let e = effective_modulus(&m, &m);
        let expected = m.young / (2.0 * (1.0 - m.poisson * m.poisson));
        assert!((e / expected - 1.0).abs() < 1e-15);
    }
}
