//! The classes of the stability map, decided from a trial's certified
//! status, its outcome, its agreement with the reference and its work.
//!
//! - refused: the problem has no solution (condition (13) fails) and this
//!   is said: by our check before any solve, or by a solver that reports the
//!   problem unbounded or infeasible; or the solver declines, before any
//!   work, a problem it was not built for and says why (a second rigid
//!   mode, a hierarchy it cannot use);
//! - diverged: a NaN or infinity, a numerical breakdown, a fixed point whose
//!   max|Δg| grows (contraction factor > 1), or a solver that reports a
//!   problem unbounded or infeasible although condition (13) holds;
//! - stalled: stopped by a work cap, at reduced accuracy, at
//!   floating-point resolution short of its tolerance
//!   (`insufficient_progress`), or by a fixed point that stopped
//!   contracting without growing;
//! - wrong: converged by its own test, but the certificate fails
//!   (status `inaccurate`) or the pressure differs from the reference's by
//!   more than [`WRONG_PRESSURE`] of its largest value;
//! - slow: certified and right, but its work exceeds [`SLOW_FACTOR`] times
//!   that of the same solver at its default settings on the same problem
//!   (or, in the friction scan, its friction iterations those at 𝓕 = ½);
//! - converged: everything else.

use contactlab_solvers::Status;

use crate::study::trial::{Trial, TrialOutcome};

pub use crate::study::class::{Class, SLOW_FACTOR, WRONG_PRESSURE};

/// What classification needs beside the trial.
#[derive(Clone, Copy, Debug, Default)]
pub struct Context {
    /// Whether the problem has a solution (condition (13) holds).
    pub solvable: bool,
    /// The same solver's work at its default settings on the same problem.
    pub default_work: Option<usize>,
    /// The same solver's friction iterations at 𝓕 = ½ (friction scan).
    pub default_friction_iterations: Option<usize>,
    /// The contraction factor of the fixed point's late steps ([`trend`]).
    pub trend: Option<f64>,
}

/// The class of a trial and the reason, in words.
pub fn classify(t: &Trial, cx: &Context) -> (Class, String) {
    let claim = t.solver_status;
    let says_no_solution = matches!(claim, Status::Unbounded | Status::Infeasible);
    if !cx.solvable {
        if t.status == Status::NotRun {
            return (Class::Refused, t.detail.clone());
        }
        if says_no_solution {
            return (
                Class::Refused,
                format!(
                    "the solver reports the problem {claim} (there is no solution): {}",
                    t.detail
                ),
            );
        }
    } else if says_no_solution {
        return (
            Class::Diverged,
            format!(
                "the solver reports the problem {claim} although condition (13) holds (a solution exists): {}",
                t.detail
            ),
        );
    }
    match t.status {
        // The machine's memory, not the method: refused before or at set-up.
        Status::OutOfMemory => (Class::Refused, t.detail.clone()),
        // The solver declined the problem before any work, saying why.
        Status::NotRun => (Class::Refused, t.detail.clone()),
        Status::NonFinite | Status::NumericalError => (Class::Diverged, t.detail.clone()),
        _ if t.outcome == TrialOutcome::NotContracting => match cx.trend {
            Some(q) if q > 1.0 => (
                Class::Diverged,
                format!("{} (contraction factor {q:.2} > 1)", t.detail),
            ),
            _ => (Class::Stalled, t.detail.clone()),
        },
        Status::Inaccurate => (
            Class::Wrong,
            format!(
                "converged by its own test but the certificate fails ({} > {:e})",
                t.failing()
                    .iter()
                    .map(|c| c.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                t.tolerance
            ),
        ),
        Status::Converged => {
            if let Some(e) = t.pressure_error().filter(|e| *e > WRONG_PRESSURE) {
                return (
                    Class::Wrong,
                    format!(
                        "certified, but its pressure differs from the reference ({}) by {e:.1e} > {WRONG_PRESSURE:e}",
                        t.reference.unwrap_or_default()
                    ),
                );
            }
            if let Some(d) = cx
                .default_work
                .filter(|&d| t.work as f64 > SLOW_FACTOR * d as f64)
            {
                return (
                    Class::Slow,
                    format!("work {} > {SLOW_FACTOR} × {d} of the default run", t.work),
                );
            }
            if let Some(d) = cx
                .default_friction_iterations
                .filter(|&d| t.friction_iterations as f64 > SLOW_FACTOR * d as f64)
            {
                return (
                    Class::Slow,
                    format!(
                        "{} friction iterations > {SLOW_FACTOR} × {d} at 𝓕 = ½",
                        t.friction_iterations
                    ),
                );
            }
            (Class::Converged, t.detail.clone())
        }
        s => (Class::Stalled, format!("{s}: {}", t.detail)),
    }
}

/// The contraction factor of a fixed point's late steps: the geometric
/// mean of the factors over the second half of its steps (at least the
/// last two). A fixed way of taking "the last four" mixed a fast start
/// into a stalled end: steps contracting by 0.09 and 0.13 and then stalling
/// at 1.0 gave 0.33, and a stalled solver looked contracting.
pub fn trend(contractions: &[Option<f64>]) -> Option<f64> {
    let known: Vec<f64> = contractions
        .iter()
        .filter_map(|q| *q)
        .filter(|q| *q > 0.0 && q.is_finite())
        .collect();
    let late = &known[known.len() - (known.len() / 2).max(2).min(known.len())..];
    (!late.is_empty()).then(|| (late.iter().map(|q| q.ln()).sum::<f64>() / late.len() as f64).exp())
}

#[cfg(test)]
mod tests {
    use super::trend;

    #[test]
    fn the_trend_is_the_late_steps_contraction() {
        // A fast start, then a stall: the trend is the stall's, not a mix.
        let stalled = [None, Some(0.086), Some(0.129), Some(1.056), Some(1.0)];
        let q = trend(&stalled).unwrap();
        assert!((q - (1.056f64).sqrt()).abs() < 1e-12, "{q}");
        let mut longer = stalled.to_vec();
        longer.extend([Some(1.0), Some(1.0), Some(1.0)]);
        assert!((trend(&longer).unwrap() - 1.0).abs() < 0.01);
        // A steady contraction is itself.
        let steady = [None, Some(0.5), Some(0.5), Some(0.5), Some(0.5), Some(0.5)];
        assert!((trend(&steady).unwrap() - 0.5).abs() < 1e-12);
        assert_eq!(trend(&[None]), None);
        assert_eq!(trend(&[None, Some(0.2)]), Some(0.2));
    }
}
