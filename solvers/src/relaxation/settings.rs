//! The settings of the paper's solver: its r, ε, sweep threshold, proximal
//! weight and smoothing, the additions that keep to the method (target,
//! over-relaxation, multigrid inside), and how each is read in the paper's
//! absolute units or in the problem's own scales.

use serde::{Deserialize, Serialize};

use super::ENTRY;
use super::inner::Inner;
use super::pointwise::Smoothing;
use crate::problem::ContactProblem;
use crate::settings::{Stopping, Validate, to_tree};

/// The paper's finest mesh, 1/64: its sweep threshold is 1e-4·ε·(1/64)
/// (section 5), a length written into the rule.
pub(crate) const PAPER_SWEEP_LENGTH: f64 = 1.0 / 64.0;

/// Settings of the prox-Uzawa relaxation solver.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RelaxationSettings {
    /// How the values below are read (set from the harness's stopping mode).
    pub stopping: Stopping,
    /// Penalty r of the modified Lagrangian.
    pub r: f64,
    /// Uzawa stops when max|Δl| ≤ ε (the paper's ε).
    pub epsilon: f64,
    /// Factor of the sweep threshold on max|Δv|.
    pub sweep_factor: f64,
    /// Weight ρ of the proximal term (ρ/2)‖v − v^k‖²_{L2} (0 turns it off).
    pub proximal: f64,
    /// Treatment of |s| along slip coordinates.
    pub smoothing: Smoothing,
    /// Over-relaxation ω ∈ (0, 2) of the free coordinates (1: the paper).
    pub omega: f64,
    /// The inner minimization: the paper's sweeps, or TNNMG with them as
    /// its smoother.
    pub inner: Inner,
    /// Certified stopping: stop once [`residual::contact_residual`] ≤ target
    /// (0: the paper's rules).
    pub target: f64,
    /// Sweeps between two checks of the certified rule.
    pub check_every: usize,
    /// Cap on Uzawa iterations per call.
    pub max_uzawa: usize,
    /// Cap on relaxation sweeps per Uzawa iteration.
    pub max_sweeps: usize,
}

/// The paper's Huber width (our choice: the paper smooths |s| without saying
/// how): below what its sweep threshold resolves at h = 1/64
/// (1e-4 · 1e-4 / 64 ≈ 1.6e-10), so the smoothing does not show.
pub(crate) const DEFAULT_HUBER_DELTA: f64 = 1e-10;

impl Default for RelaxationSettings {
    fn default() -> Self {
        Self::defaults(Stopping::Relative)
    }
}

/// Absolute values of the settings for one problem.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolved {
    pub r: f64,
    /// Threshold on max|Δl|.
    pub uzawa_tolerance: f64,
    /// Threshold on max|Δv|.
    pub sweep_tolerance: f64,
    pub proximal: f64,
    pub smoothing: Smoothing,
}

impl RelaxationSettings {
    /// The defaults of a stopping mode: the paper's values (section 5), or
    /// relative ones. On the paper's problem 1 (K = 2.79e5, L = 1, P = 20,
    /// U = 7.16e-5) the paper's values are r ≈ 3.6e6 K/L, ρ ≈ 3.6e-6 K/L²,
    /// δ ≈ 1.4e-6 U, ε = 5e-6 P and a sweep factor of about 28; the relative
    /// defaults keep r and ρ at those decades and tighten ε, the sweeps and δ
    /// until the answers pass the certificate at its default tolerance 1e-5
    /// (measured at h = 1/64: largest violation 9e-7, the force balance).
    pub fn defaults(stopping: Stopping) -> Self {
        match stopping {
            Stopping::Paper => Self {
                stopping,
                r: 1e12,
                epsilon: 1e-4,
                sweep_factor: 1e-4,
                proximal: 1.0,
                smoothing: Smoothing::Huber {
                    delta: DEFAULT_HUBER_DELTA,
                },
                omega: 1.0,
                inner: Inner::Sweeps,
                target: 0.0,
                check_every: 10,
                max_uzawa: 1000,
                max_sweeps: 2_000_000,
            },
            Stopping::Relative => Self {
                stopping,
                r: 1e7,
                epsilon: 1e-6,
                sweep_factor: 1.0,
                proximal: 1e-5,
                smoothing: Smoothing::Huber { delta: 1e-7 },
                omega: 1.0,
                inner: Inner::Sweeps,
                target: 0.0,
                check_every: 10,
                max_uzawa: 1000,
                max_sweeps: 2_000_000,
            },
        }
    }

    /// The paper's defaults.
    pub fn paper() -> Self {
        Self::defaults(Stopping::Paper)
    }

    /// The absolute values for `problem`. Relative mode reads every value in
    /// the problem's scales (K stiffness, L length of Γ_K, P = F/L pressure,
    /// U = F/K displacement; see [`crate::Scales`]):
    ///
    /// - r in K/L (a penalty is a pressure per displacement);
    /// - ρ in K/L² (ρM has the units of A, M those of an area);
    /// - the Huber width δ in U;
    /// - Uzawa: max|Δl| ≤ ε·P;
    /// - sweeps: max|Δv| ≤ sweep_factor·ε·U·w/L with w the largest weight
    ///   (h on a uniform mesh): along a jump the Uzawa update makes l the
    ///   nodal force over w, so a displacement error δv moves l by about
    ///   K·δv/w, and this threshold keeps that below sweep_factor·ε·P.
    ///
    /// Paper mode takes them as they are, with the sweep threshold
    /// sweep_factor·ε·(1/64) of section 5.
    pub fn resolve(&self, problem: &ContactProblem) -> Resolved {
        match self.stopping {
            Stopping::Paper => Resolved {
                r: self.r,
                uzawa_tolerance: self.epsilon,
                sweep_tolerance: self.sweep_factor * self.epsilon * PAPER_SWEEP_LENGTH,
                proximal: self.proximal,
                smoothing: self.smoothing,
            },
            Stopping::Relative => {
                let s = problem.scales();
                let w = problem
                    .contacts()
                    .iter()
                    .fold(0.0f64, |m, c| m.max(c.weight));
                Resolved {
                    r: self.r * s.stiffness / s.length,
                    uzawa_tolerance: self.epsilon * s.pressure,
                    sweep_tolerance: self.sweep_factor * self.epsilon * s.displacement * w
                        / s.length,
                    proximal: self.proximal * s.stiffness / (s.length * s.length),
                    smoothing: match self.smoothing {
                        Smoothing::Exact => Smoothing::Exact,
                        Smoothing::Huber { delta } => Smoothing::Huber {
                            delta: delta * s.displacement,
                        },
                    },
                }
            }
        }
    }
}

impl Validate for RelaxationSettings {
    /// Checked by the kinds of its registry entry's knobs.
    fn validate(&self) -> Result<(), String> {
        ENTRY.check(&to_tree(self))
    }
}
