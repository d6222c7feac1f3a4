//! What one solve gives: the one record that every report of a solve is a
//! view of.

use contactlab_solvers::entry::Entry;
use contactlab_solvers::{Law, Solution, Status, Timing};
use serde::Serialize;

use crate::certificate::Certificate;
use crate::coulomb::continuation::LevelCount;
use crate::coulomb::fixed_point::{Ending, FrictionIteration};

/// The work of a solve, however the solver counts it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Work {
    /// Main loop: interior-point, Uzawa or Newton iterations (summed over
    /// the friction iterations of a fixed point).
    pub outer: usize,
    /// Inner loop: relaxation sweeps (0 where there is none).
    pub inner: usize,
    /// Events of the solver's work stage (its registry entry names it):
    /// what a study's work cap counts.
    pub events: usize,
}

impl Work {
    /// The counts a solution reports.
    pub fn of(s: &Solution) -> Self {
        Self {
            outer: s.iterations.outer,
            inner: s.iterations.inner,
            events: 0,
        }
    }
}

/// The record of the fixed point of paper (9), when there was one.
#[derive(Clone, Debug)]
pub struct FixedPoint {
    /// Each friction iteration: its change max|Δg|, contraction, status,
    /// counts and times.
    pub history: Vec<FrictionIteration>,
    /// How it ended.
    pub ending: Ending,
    /// Its claim: converged only if every step converged and max|Δg|
    /// reached its tolerance.
    pub status: Status,
    pub detail: String,
}

impl FixedPoint {
    /// The inner solver's work summed over the friction iterations.
    pub fn work(&self) -> Work {
        self.history.iter().fold(Work::default(), |w, h| Work {
            outer: w.outer + h.iterations.outer,
            inner: w.inner + h.iterations.inner,
            events: 0,
        })
    }

    /// Its `seconds` of wall-clock time, the steps' set-up apart.
    pub fn timing(&self, seconds: f64) -> Timing {
        let setup: f64 = self.history.iter().map(|h| h.setup_seconds).sum();
        Timing {
            setup,
            solve: (seconds - setup).max(0.0),
        }
    }
}

/// One solve, certified.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub solver: &'static Entry,
    pub law: Law,
    /// The answer on the finest level.
    pub solution: Solution,
    /// The friction bound of the answer's last given-friction step: the
    /// given g, the fixed point's last g^m, or 𝓕p of a direct Coulomb
    /// solver's answer (the certificate of the Coulomb law always takes
    /// 𝓕p of the answer itself).
    pub bound: Vec<f64>,
    pub certificate: Certificate,
    /// The certified status: the claim, or `inaccurate` if a claim of
    /// convergence fails the certificate.
    pub status: Status,
    /// The solver's own claim (the fixed point's, around a given-friction
    /// solver).
    pub claim: Status,
    /// Why it stopped.
    pub detail: String,
    pub work: Work,
    /// Seconds of the solve: set-up (building, factorizing) apart.
    pub timing: Timing,
    pub fixed_point: Option<FixedPoint>,
    /// Work per mesh level (one entry without continuation).
    pub levels: Vec<LevelCount>,
}

impl Outcome {
    /// How the fixed point ended, or [`Ending::Direct`] without one.
    pub fn ending(&self) -> Ending {
        self.fixed_point
            .as_ref()
            .map_or(Ending::Direct, |fp| fp.ending)
    }

    /// The fixed point's steps (none without a fixed point).
    pub fn history(&self) -> &[FrictionIteration] {
        self.fixed_point
            .as_ref()
            .map_or(&[], |fp| fp.history.as_slice())
    }

    /// Friction iterations (0 without a fixed point).
    pub fn friction_iterations(&self) -> usize {
        self.fixed_point.as_ref().map_or(0, |fp| fp.history.len())
    }

    /// The last observed contraction factor of the fixed point.
    pub fn contraction(&self) -> Option<f64> {
        self.fixed_point
            .as_ref()
            .and_then(|fp| fp.history.last())
            .and_then(|f| f.contraction)
    }

    /// The contraction factor an estimate of the fixed point's part of the
    /// error assumes: the largest observed over the last three friction
    /// iterations (one ratio alone can be low by chance); None without a
    /// fixed point or with fewer than two iterations.
    pub fn contraction_for_estimate(&self) -> Option<f64> {
        let history = &self.fixed_point.as_ref()?.history;
        history
            .iter()
            .rev()
            .take(3)
            .filter_map(|f| f.contraction)
            .reduce(f64::max)
    }
}
