//! Complementarity functions: an equation whose roots are exactly the
//! points of a complementarity condition, so that a semismooth Newton
//! method can solve the contact law (Fischer 1992; Billups 1995; in the
//! form for frictional contact of Acary, Brémond & Huber 2018, Inria
//! RR-9118, section 3).

/// The Fischer-Burmeister function φ(a, b) = a + b − √(a² + b²), zero
/// exactly when a ≥ 0, b ≥ 0, ab = 0, and an element (∂a, ∂b) of its
/// generalized gradient (at the kink a = b = 0, the element along the
/// diagonal, 1 − 1/√2 each).
#[inline]
pub(crate) fn fb(a: f64, b: f64) -> (f64, f64, f64) {
    let r = a.hypot(b);
    if r == 0.0 {
        let d = 1.0 - std::f64::consts::FRAC_1_SQRT_2;
        (0.0, d, d)
    } else {
        (a + b - r, 1.0 - a / r, 1.0 - b / r)
    }
}

/// The Billups function of the box [−G, G]: φ(μ + G, −φ(G − μ, −F)), zero
/// exactly when μ ∈ [−G, G] is box-complementary to F (F ≥ 0 at μ = −G,
/// F ≤ 0 at μ = G, F = 0 inside): with F = κ s, the friction law for a
/// given bound G (Billups 1995). Gives its value and its partial
/// derivatives (∂μ, ∂F, ∂G); ∂G is needed where G = 𝓕λ is an unknown (the
/// Coulomb problem).
#[inline]
pub(crate) fn billups(mu: f64, f: f64, g: f64) -> (f64, f64, f64, f64) {
    let (inner, ia, ib) = fb(g - mu, -f);
    let (outer, oa, ob) = fb(mu + g, -inner);
    // ∂inner/∂μ = −ia, ∂inner/∂F = −ib, ∂inner/∂G = ia; outer's second
    // argument is −inner.
    (outer, oa + ob * ia, ob * ib, oa - ob * ia)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Roots exactly at the complementarity points, and derivatives that
    /// match finite differences away from the kinks.
    #[test]
    fn roots_are_the_complementarity_points_and_derivatives_match() {
        for (a, b, zero) in [
            (0.0, 2.0, true),
            (3.0, 0.0, true),
            (1.0, 1.0, false),
            (-1.0, 0.0, false),
        ] {
            assert_eq!(fb(a, b).0 == 0.0, zero, "fb({a}, {b})");
        }
        // Inside the box with F = 0, at a bound with F of the right sign.
        assert!(billups(0.3, 0.0, 1.0).0.abs() < 1e-15);
        assert!(billups(1.0, -2.0, 1.0).0.abs() < 1e-15);
        assert!(billups(-1.0, 2.0, 1.0).0.abs() < 1e-15);
        assert!(billups(0.3, 0.5, 1.0).0.abs() > 1e-3);
        let h = 1e-7;
        let (mu, f, g) = (0.2, 0.7, 0.5);
        let (v, dmu, df, dg) = billups(mu, f, g);
        for (d, x) in [
            (dmu, billups(mu + h, f, g).0),
            (df, billups(mu, f + h, g).0),
            (dg, billups(mu, f, g + h).0),
        ] {
            assert!((d - (x - v) / h).abs() < 1e-5, "{d} vs {}", (x - v) / h);
        }
    }
}
