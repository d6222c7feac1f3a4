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

/// Cattaneo–Mindlin partial slip of Hertz's line contact under a
/// tangential force Q < μP applied after P, for bodies of one material (no
/// coupling of the normal and tangential problems: the pressure stays
/// Hertz's): a stick zone |x − x₀| < c with c/a = √(1 − Q/(μP)), and the
/// traction q = μp₀ √(1 − ξ²/a²) − μp₀ (c/a) √(1 − ξ²/c²) (the second term
/// only for |ξ| < c), ξ = x − x₀, in the direction of Q (Johnson 1985,
/// §7.2; Cattaneo 1938, Mindlin 1949).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CattaneoMindlin {
    pub hertz: Hertz,
    /// The friction coefficient μ.
    pub friction: f64,
}

impl CattaneoMindlin {
    /// The stick zone's half-width c = a √(1 − |Q|/(μP)) (0 at gross slip).
    pub fn stick_half_width(&self, tangential_load: f64) -> f64 {
        let ratio = tangential_load.abs() / (self.friction * self.hertz.load);
        self.hertz.half_width() * (1.0 - ratio).max(0.0).sqrt()
    }

    /// The tangential traction q(x) under the force Q (signed as Q).
    pub fn traction(&self, x: f64, tangential_load: f64) -> f64 {
        let a = self.hertz.half_width();
        let c = self.stick_half_width(tangential_load);
        let xi = x - self.hertz.center;
        let mp0 = self.friction * self.hertz.peak_pressure();
        let slip = mp0 * (1.0 - (xi / a).powi(2)).max(0.0).sqrt();
        let stick = if xi.abs() < c {
            mp0 * (c / a) * (1.0 - (xi / c).powi(2)).sqrt()
        } else {
            0.0
        };
        (slip - stick) * tangential_load.signum()
    }
}

/// How far a computed tangential traction is from Cattaneo–Mindlin's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TractionError {
    /// The tangential force the contact carries, Q = Σ wᵢ qᵢ.
    pub tangential_load: f64,
    /// ‖q_h − q‖ / ‖q‖ in L2 over Γ_K, at the computed Q (None when the
    /// computed Q is 0, where the closed form is 0 and no relative error
    /// is defined: an answer that failed).
    pub l2: Option<f64>,
    /// max |q_h − q| over the nodes, over μp₀.
    pub max: f64,
    /// The computed stick half-width: half the span from the half-node
    /// before the first stick node to the half-node after the last, a stick
    /// node one whose friction margin μpᵢ − |qᵢ| exceeds 1e-3 μp₀ (the
    /// closed form's margin grows as √ from the stick edge, so the
    /// threshold moves the edge by under a millionth of c).
    pub stick_half_width: f64,
    /// ‖q_h − q_h(2x₀ − ·)‖ / (2‖q‖): the part of the computed traction
    /// odd about x₀, which the closed form (even) does not have. It
    /// measures what the finite bodies add (the force enters at their
    /// sides, above the contact, and the two are held differently), apart
    /// from the discretization; over the nodes whose mirror image is a node
    /// (None as for `l2`).
    pub asymmetry: Option<f64>,
}

/// The error of the nodal tractions `q` (pressures `p`, weights `w`, at
/// `x`, uniform spacing) against `exact`.
pub fn traction_error(
    x: &[f64],
    w: &[f64],
    p: &[f64],
    q: &[f64],
    exact: &CattaneoMindlin,
) -> TractionError {
    let tangential_load: f64 = w.iter().zip(q).map(|(w, q)| w * q).sum();
    let mp0 = exact.friction * exact.hertz.peak_pressure();
    let (mut num, mut den, mut max) = (0.0, 0.0, 0.0f64);
    for ((&xi, &wi), &qi) in x.iter().zip(w).zip(q) {
        let e = exact.traction(xi, tangential_load);
        num += wi * (qi - e) * (qi - e);
        den += wi * e * e;
        max = max.max((qi - e).abs());
    }
    let stick: Vec<f64> = x
        .iter()
        .zip(p.iter().zip(q))
        .filter(|(_, (p, q))| exact.friction * **p - q.abs() > 1e-3 * mp0)
        .map(|(x, _)| *x)
        .collect();
    let spacing = if x.len() > 1 { x[1] - x[0] } else { 0.0 };
    let center = exact.hertz.center;
    let mut odd = 0.0;
    for (i, (&xi, &wi)) in x.iter().zip(w).enumerate() {
        let mirror = 2.0 * center - xi;
        let j = ((mirror - x[0]) / spacing).round();
        if j >= 0.0 && (j as usize) < x.len() && (x[j as usize] - mirror).abs() < 1e-9 * spacing {
            let d = 0.5 * (q[i] - q[j as usize]);
            odd += wi * d * d;
        }
    }
    let stick_half_width = match (stick.first(), stick.last()) {
        (Some(lo), Some(hi)) => 0.5 * (hi - lo + spacing),
        _ => 0.0,
    };
    TractionError {
        tangential_load,
        l2: (den > 0.0).then(|| (num / den).sqrt()),
        max: max / mp0,
        stick_half_width,
        asymmetry: (den > 0.0).then(|| (odd / den).sqrt()),
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

    /// ∫q dx = Q (Johnson §7.2): the traction's sign and scale; c/a from
    /// Q/(μP), and full stick (c = a) at Q = 0 with q ≡ 0.
    #[test]
    fn cattaneo_mindlin_traction_carries_the_tangential_load() {
        let cm = CattaneoMindlin {
            hertz: Hertz {
                modulus: 41_271.0,
                load: 60.0,
                radius: 0.53,
                center: 0.5,
            },
            friction: 0.3,
        };
        let a = cm.hertz.half_width();
        for q_load in [-9.0, 4.5, 17.0] {
            let c = cm.stick_half_width(q_load);
            let expected = a * (1.0 - q_load.abs() / 18.0f64).sqrt();
            assert!((c / expected - 1.0).abs() < 1e-14);
            let n = 400_000;
            let dx = 2.0 * a / n as f64;
            let total: f64 = (0..n)
                .map(|k| cm.traction(0.5 - a + (k as f64 + 0.5) * dx, q_load) * dx)
                .sum();
            assert!((total / q_load - 1.0).abs() < 1e-5, "{q_load}: {total}");
        }
        assert_eq!(cm.stick_half_width(0.0), a);
        assert_eq!(cm.traction(0.5, 0.0), 0.0);
    }

    /// An answer carrying no tangential force (a failed one: all q = 0) has
    /// no relative traction error, not a NaN in verification.csv; a
    /// traction even about x₀ has no odd part, and one with an odd part does.
    #[test]
    fn a_zero_traction_has_no_relative_error_and_an_odd_part_is_found() {
        let cm = CattaneoMindlin {
            hertz: Hertz {
                modulus: 41_271.0,
                load: 60.0,
                radius: 0.5275732959994149,
                center: 0.5,
            },
            friction: 0.3,
        };
        let n = 257;
        let h = 1.0 / (n - 1) as f64;
        let x: Vec<f64> = (0..n).map(|i| i as f64 * h).collect();
        let w: Vec<f64> = (0..n)
            .map(|i| if i == 0 || i == n - 1 { h / 2.0 } else { h })
            .collect();
        let p: Vec<f64> = x.iter().map(|&x| cm.hertz.pressure(x)).collect();
        let zero = traction_error(&x, &w, &p, &vec![0.0; n], &cm);
        assert_eq!(zero.tangential_load, 0.0);
        assert_eq!((zero.l2, zero.asymmetry), (None, None));
        let q: Vec<f64> = x.iter().map(|&x| cm.traction(x, 8.0)).collect();
        let even = traction_error(&x, &w, &p, &q, &cm);
        assert_eq!(even.asymmetry, Some(0.0), "{even:?}");
        // An odd part of 1% of μp₀ on |x − ½| < a: its share of ‖q‖ is
        // what the mirror finds, not 0.
        let a = cm.hertz.half_width();
        let mp0 = cm.friction * cm.hertz.peak_pressure();
        let tilted: Vec<f64> = x
            .iter()
            .zip(&q)
            .map(|(&x, &q)| {
                q + if (x - 0.5).abs() < a {
                    0.01 * mp0 * (x - 0.5) / a
                } else {
                    0.0
                }
            })
            .collect();
        let odd = traction_error(&x, &w, &p, &tilted, &cm).asymmetry.unwrap();
        assert!(odd > 1e-3, "{odd}");
    }

    #[test]
    fn equal_materials_halve_the_plane_strain_modulus() {
        let m = Material::default();
        let e = effective_modulus(&m, &m);
        let expected = m.young / (2.0 * (1.0 - m.poisson * m.poisson));
        assert!((e / expected - 1.0).abs() < 1e-15);
    }
}
