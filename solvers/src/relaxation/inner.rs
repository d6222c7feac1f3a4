//! The inner minimization of Algorithm 1 (line 5): at fixed multipliers
//! l^k, minimize Φ(v) = M(v, l^k) + (ρ/2)‖v − v^k‖²_{L2} (paper (11), (15))
//! either by the paper's pointwise relaxation sweeps, or by truncated
//! nonsmooth Newton multigrid with those sweeps as its smoother (Gräser &
//! Sander 2019, Algorithm 1; see [`crate::multigrid`]). Φ is block-
//! separable: ½ vᵀHv − bᵀv plus, per contact node, the penalty
//! (w/(2r))((l + r t)⁺)² along t and w g |s| (or its Huber smoothing) along
//! s; both are C¹ or have a kink only at s = 0, so TNNMG truncates only
//! sticking slips. H = A + ρM is positive definite, so no kernel is left.

use crate::numerics::linalg::Csr;
use serde::{Deserialize, Serialize};

use super::pointwise::{RelaxationOperator, Smoothing, SweepData};
use crate::multigrid::iteration::{Cycle, Energy, Workspace, iterate};
use crate::multigrid::laws::Laws;
use crate::multigrid::smoother::Local;
use crate::multigrid::vcycle::Hierarchy;
use crate::problem::ContactNode;

/// How the inner minimization is done.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Inner {
    /// The paper's pointwise relaxation: one sweep per inner iteration.
    #[default]
    Sweeps,
    /// One TNNMG iteration per inner iteration (a sweep, a truncated
    /// V-cycle-preconditioned Newton step, an exact line search).
    Multigrid,
}

/// The work of one multigrid inner iteration: TNNMG's defaults
/// ([`crate::multigrid::TnnmgSettings`]), one sweep before and one after
/// the coarse correction on the finest level
/// ([`crate::multigrid::DEFAULT_FINEST_SWEEPS`]), two below it. With two on
/// the finest level too, as before, problem 1 at h = 1/1024 (target 1e-6,
/// nested schedule) took the same 13 iterations on the finest mesh and the
/// same answer (the largest pressure equal to 2e-12 of it), and 13.7,
/// 12.7, 14.9, 14.7, 16.9 s against 11.6, 12.4, 11.9, 13.6, 15.3 s with
/// one, in alternation on a noisy 2-core VM: faster in each pair, the
/// median of the pairs' ratios 0.90; the coarser levels of the schedule
/// took more iterations (100 against 84 in all, each cheaper).
pub(crate) const CYCLE: Cycle = Cycle {
    presmoothing: 1,
    linear_steps: 3,
    linear_sweeps: 2,
    finest_sweeps: crate::multigrid::DEFAULT_FINEST_SWEEPS,
};

/// An inner minimizer, ready for one Uzawa step after [`InnerSolver::begin`].
pub(crate) enum InnerSolver<'h> {
    Sweeps,
    Multigrid(Box<MultigridInner<'h>>),
}

/// TNNMG on Φ: the hierarchy of H, Φ's laws for the current l^k, and the
/// iteration's vectors.
pub(crate) struct MultigridInner<'h> {
    hierarchy: &'h mut Hierarchy,
    p: &'h [Csr],
    laws: Laws,
    contact: Vec<usize>,
    ws: Workspace,
    previous: Vec<f64>,
}

impl<'h> MultigridInner<'h> {
    pub(crate) fn new(
        hierarchy: &'h mut Hierarchy,
        p: &'h [Csr],
        n: usize,
        contacts: &[ContactNode],
    ) -> Self {
        let mut contact: Vec<usize> = contacts.iter().flat_map(|c| [c.t, c.s]).collect();
        contact.sort_unstable();
        Self {
            hierarchy,
            p,
            laws: Laws::free(n),
            contact,
            ws: Workspace::new(n),
            previous: vec![0.0; n],
        }
    }
}

impl InnerSolver<'_> {
    /// Sets Φ's laws for the multipliers and bounds of `data`.
    pub(crate) fn begin(&mut self, contacts: &[ContactNode], data: &SweepData<'_>) {
        if let InnerSolver::Multigrid(mg) = self {
            for (i, c) in contacts.iter().enumerate() {
                mg.laws.set(
                    c.t,
                    Local::Penalty {
                        w: c.weight,
                        l: data.l[i],
                        r: data.r,
                    },
                );
                let slip = match data.smoothing {
                    Smoothing::Exact => Local::Slip(data.wg[i]),
                    Smoothing::Huber { delta } => Local::Huber {
                        wg: data.wg[i],
                        delta,
                    },
                };
                mg.laws.set(c.s, slip);
            }
        }
    }

    /// One inner iteration on v; returns max_j |Δv_j| (NaN if any change
    /// is not a number).
    pub(crate) fn step(
        &mut self,
        op: &RelaxationOperator,
        v: &mut [f64],
        data: &SweepData<'_>,
    ) -> f64 {
        match self {
            InnerSolver::Sweeps => op.sweep(v, data),
            InnerSolver::Multigrid(mg) => {
                mg.previous.copy_from_slice(v);
                let energy = Energy {
                    a: &op.h,
                    b: data.b,
                    laws: &mg.laws,
                    contact: &mg.contact,
                    kernel: None,
                };
                iterate(&energy, mg.hierarchy, mg.p, CYCLE, &mut mg.ws, v);
                v.iter().zip(&mg.previous).fold(0.0f64, |m, (x, y)| {
                    let d = (x - y).abs();
                    if d.is_nan() || m.is_nan() {
                        f64::NAN
                    } else {
                        m.max(d)
                    }
                })
            }
        }
    }

    /// The name of its inner iteration, for status details.
    pub(crate) fn unit(&self) -> &'static str {
        match self {
            InnerSolver::Sweeps => "sweeps",
            InnerSolver::Multigrid(_) => "multigrid iterations",
        }
    }
}
