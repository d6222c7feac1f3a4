//! Sums of products as accurate as if computed in twice the working
//! precision, with a bound on their error: Dot2 of Ogita, Rump & Oishi,
//! "Accurate sum and dot product", SIAM J. Sci. Comput. 26(6), 2005
//! (Algorithm 5.3, error bound Proposition 5.5), with TwoSum (Knuth) and
//! TwoProduct by the fused multiply-add (their Algorithm 3.5).
//!
//! The error bound needs them where a residual A v − f is far smaller than
//! its terms: computed plainly, its rounding (about ε Σ|A_ij v_j| per row)
//! grows with the stiffness's condition and becomes the bound's floor at
//! fine h; computed by Dot2 it is about ε times the residual itself.

/// u = 2⁻⁵³, the unit roundoff of f64.
const UNIT: f64 = f64::EPSILON / 2.0;

/// a + b = s + e exactly (Knuth's TwoSum, no branch).
#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let z = s - a;
    (s, (a - (s - z)) + (b - z))
}

/// a·b = p + e exactly (the fused multiply-add rounds once).
#[inline]
fn two_product(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

/// A running Dot2 sum Σ a_k b_k, with what its error bound needs.
#[derive(Clone, Copy, Debug, Default)]
pub struct Dot2 {
    sum: f64,
    tail: f64,
    /// Σ |a_k b_k| (computed plainly: it only scales a tiny term).
    size: f64,
    terms: usize,
}

impl Dot2 {
    /// Adds a·b.
    #[inline]
    pub fn add(&mut self, a: f64, b: f64) {
        let (h, r) = two_product(a, b);
        let (s, q) = two_sum(self.sum, h);
        self.sum = s;
        self.tail += q + r;
        self.size += h.abs();
        self.terms += 1;
    }

    /// The sum, and a bound on its error: u |Σ| + γ_n² Σ|a_k b_k| with γ_n =
    /// n u / (1 − n u) (Proposition 5.5; the first term taken at the
    /// computed sum, with a factor (1 + 2u) for the difference), without
    /// underflow.
    pub fn value(&self) -> (f64, f64) {
        let value = self.sum + self.tail;
        let n = (self.terms.max(1)) as f64;
        let gamma = n * UNIT / (1.0 - n * UNIT);
        let error = UNIT * value.abs() * (1.0 + 2.0 * UNIT) + gamma * gamma * self.size * 1.01;
        (value, error)
    }
}

#[cfg(test)]
mod tests {
    use super::Dot2;

    /// A sum whose terms cancel to 1 out of 1e16: computed plainly it is
    /// 0, by Dot2 it is exact, and the stated error covers the truth.
    #[test]
    fn cancelling_terms_sum_as_in_twice_the_precision() {
        let terms = [(1e16, 1.0), (1.0, 1.0), (-1e16, 1.0)];
        let plain: f64 = terms.iter().map(|(a, b)| a * b).sum();
        assert_eq!(plain, 0.0);
        let mut d = Dot2::default();
        for (a, b) in terms {
            d.add(a, b);
        }
        let (v, e) = d.value();
        assert_eq!(v, 1.0);
        // u·1 + γ₃²·(2e16 + 1) ≈ 2.3e-15: the stated error is tiny, where
        // the plain sum is off by 1.
        assert!(e > 0.0 && e < 1e-14, "{e}");
    }

    /// Products whose low parts matter: (1 + 2⁻³⁰)² − 1 − 2⁻²⁹ = 2⁻⁶⁰,
    /// exactly, which a plain product loses.
    #[test]
    fn the_low_part_of_a_product_is_kept() {
        let x = 1.0 + 2f64.powi(-30);
        let mut d = Dot2::default();
        d.add(x, x);
        d.add(-1.0, 1.0);
        d.add(-(2f64.powi(-29)), 1.0);
        assert_eq!(x * x - 1.0 - 2f64.powi(-29), 0.0);
        assert_eq!(d.value().0, 2f64.powi(-60));
    }
}
