//! Pointwise relaxation (MPR): Gauss-Seidel sweeps of exact minimization
//! along each coordinate of
//!
//! ```text
//! Φ(v) = ½ vᵀH v − bᵀv + Σ_i w_i g_i φ(s_i) + Σ_i w_i/(2r) ((l_i + r t_i)⁺)²,
//! ```
//!
//! with H = A + ρM and b = f + ρ M v^k (the proximal term of paper (15)) and
//! the trapezoid rule of section 5 on Γ_K. Along a jump coordinate the
//! function is piecewise quadratic and is minimized exactly for any r; along a
//! slip coordinate φ is |·| (exact: soft thresholding) or its Huber smoothing.

use serde::{Deserialize, Serialize};

use crate::numerics::linalg::{Csr, RowValues};

/// How the non-smooth friction term w g |s| is treated along a slip
/// coordinate. In settings it is the word `exact` or a Huber width (a number;
/// the older form `{ huber = { delta = x } }` is read too).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Smoothing {
    /// |s| itself: the exact one-dimensional minimizer is soft thresholding.
    Exact,
    /// Huber smoothing with width δ (a length):
    /// φ_δ(s) = s²/(2δ) for |s| ≤ δ, |s| − δ/2 otherwise. It is C¹, within
    /// δ/2 of |s|, and its one-dimensional minimizer is in closed form. The
    /// paper smooths |s| but does not say how; this is our choice.
    Huber { delta: f64 },
}

impl Serialize for Smoothing {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Smoothing::Exact => s.serialize_str("exact"),
            Smoothing::Huber { delta } => s.serialize_f64(*delta),
        }
    }
}

impl<'de> Deserialize<'de> for Smoothing {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Width {
            delta: f64,
        }
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Repr {
            Width(f64),
            Word(String),
            Table { huber: Width },
        }
        match Repr::deserialize(d).map_err(|_| {
            serde::de::Error::custom(
                "smoothing must be `exact` or a positive Huber width such as 1e-10",
            )
        })? {
            Repr::Width(delta)
            | Repr::Table {
                huber: Width { delta },
            } => Ok(Smoothing::Huber { delta }),
            Repr::Word(w) if w.eq_ignore_ascii_case("exact") => Ok(Smoothing::Exact),
            Repr::Word(w) => Err(serde::de::Error::custom(format!(
                "smoothing = '{w}' is invalid: give `exact` or a positive Huber width such as 1e-10"
            ))),
        }
    }
}

/// A command-line smoothing: `exact` or a positive Huber width.
pub(crate) fn parse_smoothing(text: &str) -> Result<serde_json::Value, String> {
    let t = text.trim();
    if t.eq_ignore_ascii_case("exact") {
        return Ok("exact".into());
    }
    crate::settings::Kind::Positive.parse(t).map_err(|_| {
        format!("'{text}' is neither `exact` nor a positive Huber width such as 1e-10")
    })
}

/// Whether a settings value is a smoothing: `exact`, or a Huber width > 0.
fn is_smoothing(value: &serde_json::Value) -> bool {
    match serde_json::from_value::<Smoothing>(value.clone()) {
        Ok(Smoothing::Exact) => true,
        Ok(Smoothing::Huber { delta }) => delta.is_finite() && delta > 0.0,
        Err(_) => false,
    }
}

/// The kind of the `smoothing` setting.
pub(crate) const SMOOTHING: crate::settings::Kind = crate::settings::Kind::Custom {
    describe: "`exact` or a Huber width > 0",
    parse: parse_smoothing,
    check: is_smoothing,
};

impl Smoothing {
    /// Stable name for tables: `exact` or `huber(δ)`.
    pub fn label(&self) -> String {
        match self {
            Smoothing::Exact => "exact".into(),
            Smoothing::Huber { delta } => format!("huber({delta:e})"),
        }
    }
}

/// argmin_x ½ a x² + c x + (w/(2r)) ((l + r x)⁺)² along a jump coordinate
/// (a > 0, w > 0, r > 0). The derivative a x + c + w (l + r x)⁺ is continuous
/// and increasing: its root lies in the active piece (l + r x > 0) or in the
/// inactive one, and the pieces are tried in that order.
#[inline]
pub(crate) fn minimize_jump(a: f64, c: f64, w: f64, l: f64, r: f64) -> f64 {
    let active = -(c + w * l) / (a + w * r);
    if l + r * active > 0.0 { active } else { -c / a }
}

/// argmin_x ½ a x² + c x + wg |x| (soft thresholding), a > 0, wg ≥ 0.
#[inline]
pub(crate) fn minimize_slip_exact(a: f64, c: f64, wg: f64) -> f64 {
    if c < -wg {
        -(c + wg) / a
    } else if c > wg {
        (wg - c) / a
    } else {
        0.0
    }
}

/// argmin_x ½ a x² + c x + wg φ_δ(x) for the Huber function φ_δ.
#[inline]
pub(crate) fn minimize_slip_huber(a: f64, c: f64, wg: f64, delta: f64) -> f64 {
    let knee = wg + a * delta;
    if c < -knee {
        -(c + wg) / a
    } else if c > knee {
        (wg - c) / a
    } else {
        -c / (a + wg / delta)
    }
}

/// Role of an unknown in the sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coordinate {
    /// A displacement away from the contact terms.
    Free,
    /// The jump t_i of contact node i.
    Jump(u32),
    /// The slip s_i of contact node i.
    Slip(u32),
}

/// H = A + ρM with what a sweep needs precomputed: its CSR arrays, the
/// diagonal, and the role of each unknown.
#[derive(Clone, Debug)]
pub(crate) struct RelaxationOperator {
    pub h: Csr,
    pub diag: Vec<f64>,
    /// 1 / diag, so that free coordinates cost a multiplication.
    pub inv_diag: Vec<f64>,
    pub role: Vec<Coordinate>,
    /// Trapezoid weights per contact node.
    pub weight: Vec<f64>,
}

/// Per-call data of a sweep: the right-hand side, the multipliers, the
/// friction bounds (times weights) and the treatment of the terms.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SweepData<'a> {
    pub b: &'a [f64],
    /// Uzawa multipliers l_i (per contact node).
    pub l: &'a [f64],
    /// w_i g_i per contact node.
    pub wg: &'a [f64],
    pub r: f64,
    pub smoothing: Smoothing,
    /// Over-relaxation ω of the free coordinates (1: Gauss–Seidel, the
    /// paper's pointwise relaxation).
    pub omega: f64,
}

impl RelaxationOperator {
    /// Whether H = A + ρ M can be formed for a problem: ρ = 0, or the
    /// problem carries M (one built for a solver that does not read it has
    /// none).
    pub fn can_form(problem: &crate::ContactProblem, rho: f64) -> bool {
        rho == 0.0 || problem.has_mass()
    }

    /// Prepares H = A + ρ M for a problem: on A's pattern when M lives there
    /// ([`RelaxationOperator::can_form`] first).
    pub fn new(problem: &crate::ContactProblem, rho: f64) -> Self {
        let (a, contacts) = (problem.a(), problem.contacts());
        let h = match problem.mass_on_stiffness_pattern() {
            _ if rho == 0.0 => a.clone(),
            Some(m) => {
                let mut h = a.clone();
                for (h, m) in h.values_mut().iter_mut().zip(m) {
                    *h += m * rho;
                }
                h
            }
            None => {
                let m = problem
                    .mass()
                    .expect("the relaxation refuses a problem without M before it gets here");
                Csr::try_from(&a.to_nalgebra() + &(&*m * rho))
                    .expect("A + ρM has A's size, which a Csr holds")
            }
        };
        let diag: Vec<f64> = (0..h.nrows())
            .map(|i| h.position(i, i).map_or(0.0, |p| h.value_at(i, p)))
            .collect();
        let inv_diag = diag.iter().map(|a| 1.0 / a).collect();
        let mut role = vec![Coordinate::Free; h.nrows()];
        for (i, c) in contacts.iter().enumerate() {
            role[c.t] = Coordinate::Jump(i as u32);
            role[c.s] = Coordinate::Slip(i as u32);
        }
        let weight = contacts.iter().map(|c| c.weight).collect();
        Self {
            h,
            diag,
            inv_diag,
            role,
            weight,
        }
    }

    /// One Gauss-Seidel sweep in natural order: each coordinate is set to the
    /// exact minimizer of Φ along it (free coordinates over-relaxed by ω). Returns max_j |Δv_j|. Walks the CSR rows
    /// once and allocates nothing.
    pub fn sweep(&self, v: &mut [f64], data: &SweepData<'_>) -> f64 {
        assert_eq!(v.len(), self.h.ncols(), "sweep: v has the wrong length");
        crate::with_values!(self.h.values(), vals => self.sweep_with(vals, v, data))
    }

    /// [`Self::sweep`] for one kind of stored values.
    fn sweep_with<'v>(
        &'v self,
        vals: impl RowValues<'v>,
        v: &mut [f64],
        data: &SweepData<'_>,
    ) -> f64 {
        let cols = self.h.columns();
        let mut max_change = 0.0f64;
        for j in 0..v.len() {
            let (lo, hi) = self.h.row_range(j);
            // SAFETY: a Csr keeps its column indices below ncols = v.len().
            let row = vals.row(j, lo, hi);
            let sum = unsafe { crate::numerics::linalg::row_dot_at(cols.row(j, lo, hi), row, v) };
            let a = self.diag[j];
            let old = v[j];
            // Gradient of the quadratic part without the diagonal term.
            let c = sum - a * old - data.b[j];
            let new = match self.role[j] {
                // Over-relaxed: along a free coordinate Φ is quadratic, so
                // old + ω(x* − old) lowers it by ω(2 − ω)/2 · a(x* − old)²,
                // a descent for every ω in (0, 2) (Glowinski, Lions &
                // Trémolières 1976, ch. 2: point over-relaxation). Contact
                // coordinates keep their exact minimizers.
                // ω = 1 is taken as is, so Gauss–Seidel stays bit for bit.
                Coordinate::Free => {
                    let exact = -c * self.inv_diag[j];
                    if data.omega == 1.0 {
                        exact
                    } else {
                        old + data.omega * (exact - old)
                    }
                }
                Coordinate::Jump(i) => {
                    let i = i as usize;
                    minimize_jump(a, c, self.weight[i], data.l[i], data.r)
                }
                Coordinate::Slip(i) => {
                    let wg = data.wg[i as usize];
                    match data.smoothing {
                        Smoothing::Exact => minimize_slip_exact(a, c, wg),
                        Smoothing::Huber { delta } => minimize_slip_huber(a, c, wg, delta),
                    }
                }
            };
            v[j] = new;
            let change = (new - old).abs();
            // A NaN must not be lost by max().
            max_change = if change.is_nan() {
                f64::NAN
            } else {
                max_change.max(change)
            };
        }
        max_change
    }

    /// (H v − b)_j: the gradient of the quadratic part at coordinate j.
    pub(crate) fn gradient_at(&self, v: &[f64], b: &[f64], j: usize) -> f64 {
        let (cols, vals) = self.h.row(j);
        cols.iter().zip(vals).map(|(c, a)| a * v[c]).sum::<f64>() - b[j]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Minimizes a convex function on [lo, hi] by golden section, to machine
    /// precision in x (brute force for the closed forms).
    fn golden(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
        let ratio = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..300 {
            let x1 = hi - ratio * (hi - lo);
            let x2 = lo + ratio * (hi - lo);
            if f(x1) <= f(x2) { hi = x2 } else { lo = x1 }
        }
        0.5 * (lo + hi)
    }

    fn check(x: f64, f: &impl Fn(f64) -> f64, brute: f64, what: &str) {
        // The closed form must be at least as good as brute force and close to it.
        let scale = 1.0 + brute.abs();
        assert!(
            f(x) <= f(brute) + 1e-12 * (1.0 + f(brute).abs()),
            "{what}: f({x}) > f({brute})"
        );
        assert!(
            (x - brute).abs() <= 1e-6 * scale,
            "{what}: {x} vs brute force {brute}"
        );
    }

    #[test]
    fn jump_minimizer_matches_brute_force_on_random_data() {
        let mut s = crate::numerics::random::Lcg::new(7);
        for case in 0..2000 {
            let a = 0.1 + 10.0 * s.uniform();
            let c = 20.0 * (s.uniform() - 0.5);
            let w = 0.01 + s.uniform();
            let l = if case % 3 == 0 {
                0.0
            } else {
                30.0 * s.uniform()
            };
            let r = 10f64.powf(-2.0 + 6.0 * s.uniform());
            let f = |x: f64| 0.5 * a * x * x + c * x + w / (2.0 * r) * (l + r * x).max(0.0).powi(2);
            let x = minimize_jump(a, c, w, l, r);
            let bound = 10.0 * (c.abs() + w * l + 1.0) / a;
            check(
                x,
                &f,
                golden(f, -bound, bound),
                &format!("jump case {case}"),
            );
        }
    }

    #[test]
    fn jump_minimizer_is_exact_for_a_huge_penalty() {
        // r = 1e12 as in the paper: the active root is −(c + w l)/(a + w r).
        let (a, c, w, l, r) = (1e5, -3.0, 1.0 / 64.0, 50.0, 1e12);
        let x = minimize_jump(a, c, w, l, r);
        assert_eq!(x, -(c + w * l) / (a + w * r));
        assert!(l + r * x > 0.0);
        // The Uzawa update l + r t is (l a − r c)/(a + w r): the nodal force
        // −c/w up to a relative a/(w r) (≈ 6e-6 here).
        let updated = l + r * x;
        assert!((updated - (l * a - r * c) / (a + w * r)).abs() < 1e-12 * updated.abs());
        let limit = -c / w;
        assert!((updated - limit).abs() <= 2.0 * a / (w * r) * (limit.abs() + l));
    }

    #[test]
    fn slip_minimizers_match_brute_force_on_random_data() {
        let mut s = crate::numerics::random::Lcg::new(11);
        for case in 0..2000 {
            let a = 0.1 + 10.0 * s.uniform();
            let c = 20.0 * (s.uniform() - 0.5);
            let wg = if case % 5 == 0 {
                0.0
            } else {
                10.0 * s.uniform()
            };
            let delta = 10f64.powf(-4.0 + 3.0 * s.uniform());
            let bound = 10.0 * (c.abs() + wg + 1.0) / a;
            let exact = |x: f64| 0.5 * a * x * x + c * x + wg * x.abs();
            check(
                minimize_slip_exact(a, c, wg),
                &exact,
                golden(exact, -bound, bound),
                &format!("exact {case}"),
            );
            let huber = |x: f64| {
                let phi = if x.abs() <= delta {
                    x * x / (2.0 * delta)
                } else {
                    x.abs() - delta / 2.0
                };
                0.5 * a * x * x + c * x + wg * phi
            };
            let x = minimize_slip_huber(a, c, wg, delta);
            check(
                x,
                &huber,
                golden(huber, -bound, bound),
                &format!("huber {case}"),
            );
            // Smoothing moves the minimizer by at most δ.
            assert!((x - minimize_slip_exact(a, c, wg)).abs() <= delta * (1.0 + 1e-12));
        }
    }
}
