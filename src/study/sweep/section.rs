//! The facts the sweep's README section states (`templates/sweep.md`):
//! the work-precision ratios and the one-factor variations, computed from
//! the trials.

use contactlab_solvers::registry::{self, Role};
use serde::Serialize;

use crate::study::runner::Measured;
use crate::study::sweep::{WORK_PRECISION, WORK_PRECISION_COULOMB};
use crate::study::trial::Trial;

/// A solver's time over the baseline's at one pressure error.
#[derive(Debug, Serialize)]
pub struct Ratio {
    pub ratio: f64,
    pub target: f64,
}

/// One solver's line of a work-precision comparison: its time over
/// `baseline`'s at equal pressure error, at each target both curves reach
/// (empty: no common range).
#[derive(Debug, Serialize)]
pub struct RatioLine {
    pub solver: &'static str,
    pub baseline: &'static str,
    pub ratios: Vec<Ratio>,
}

/// Ratios of time at equal accuracy, interpolated log-log along each
/// solver's work-precision curve, in both diagrams.
#[derive(Debug, Serialize)]
pub struct WorkPrecision {
    pub paper: &'static str,
    pub given_friction: Vec<RatioLine>,
    pub coulomb: Vec<RatioLine>,
}

/// The work-precision ratios (none without a paper's method and an oracle).
pub(super) fn work_precision(sweep: &[Measured]) -> Option<WorkPrecision> {
    let paper = registry::with_role(Role::PapersMethod)?;
    let oracle = registry::with_role(Role::Oracle)?;
    Some(WorkPrecision {
        paper: paper.name,
        given_friction: time_ratios(sweep, WORK_PRECISION, oracle.name),
        coulomb: time_ratios(sweep, WORK_PRECISION_COULOMB, oracle.name),
    })
}

/// One line per solver: its time over `baseline`'s at equal pressure error
/// along the curves of `group`, at 1e-2 ... 1e-11.
pub(super) fn time_ratios(
    sweep: &[Measured],
    group: &str,
    baseline: &'static str,
) -> Vec<RatioLine> {
    let curve = |solver: &str| -> Vec<(f64, f64)> {
        let mut pts: Vec<(f64, f64)> = sweep
            .iter()
            .filter(|m| {
                m.trial.group == group && m.trial.solver.name == solver && m.trial.certified()
            })
            .filter_map(|m| {
                m.trial.pressure_error().map(|e| {
                    (
                        e.max(crate::study::sweep::charts::WP_FLOOR),
                        m.timing.seconds_min,
                    )
                })
            })
            .filter(|(_, t)| *t > 0.0)
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        pts
    };
    let base = curve(baseline);
    registry::names()
        .into_iter()
        .filter(|n| {
            *n != baseline
                && sweep
                    .iter()
                    .any(|m| m.trial.group == group && m.trial.solver.name == *n)
        })
        .map(|other| {
            let points = curve(other);
            RatioLine {
                solver: other,
                baseline,
                ratios: (2..=11)
                    .map(|k| 10f64.powi(-k))
                    .filter_map(|target| {
                        let (a, b) = (time_at(&points, target)?, time_at(&base, target)?);
                        Some(Ratio {
                            ratio: a / b,
                            target,
                        })
                    })
                    .collect(),
            }
        })
        .collect()
}

/// The time a solver needs for `target` error, interpolated log-log between
/// its points (errors increasing); None outside its range.
pub(super) fn time_at(points: &[(f64, f64)], target: f64) -> Option<f64> {
    points.windows(2).find_map(|w| {
        let ((e0, t0), (e1, t1)) = (w[0], w[1]);
        (e0 <= target && target <= e1 && e1 > e0).then(|| {
            let a = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
            (t0.ln() + a * (t1.ln() - t0.ln())).exp()
        })
    })
}

/// The cheapest certified value of a variation.
#[derive(Debug, Serialize)]
pub struct Cheapest {
    pub value: String,
    pub work: usize,
    pub pressure_error: Option<f64>,
}

/// A value that was not certified, with its status.
#[derive(Debug, Serialize)]
pub struct Failed {
    pub value: String,
    pub status: String,
}

/// The times of a variation measured against no reference (a fine mesh),
/// fastest and slowest point, with its largest certificate violation.
#[derive(Debug, Serialize)]
pub struct Times {
    pub fastest: f64,
    pub slowest: f64,
    pub certificate: f64,
}

/// One setting of one solver varied around the defaults.
#[derive(Debug, Serialize)]
pub struct Variation {
    pub group: String,
    pub solver: &'static str,
    /// Its mesh when it is not the section's (the fine meshes).
    pub h: Option<String>,
    pub certified: Vec<String>,
    pub cheapest: Option<Cheapest>,
    pub failed: Vec<Failed>,
    /// Whether no trial had a reference, and then the times.
    pub unreferenced: bool,
    pub times: Option<Times>,
}

/// For each variation: the values certified, and the cheapest certified one.
pub(super) fn variations(sweep: &[Measured]) -> Vec<Variation> {
    // A variation is a group of one solver: a group that varies the same
    // setting of two solvers (the schedule) is two lines, each quoting its
    // own solver's trials, since work is counted in each solver's own unit.
    let mut groups: Vec<(&str, &'static str)> = Vec::new();
    for m in sweep {
        let key = (m.trial.group.as_str(), m.trial.solver.name);
        if key.0 != WORK_PRECISION && key.0 != WORK_PRECISION_COULOMB && !groups.contains(&key) {
            groups.push(key);
        }
    }
    let main_mesh = sweep.first().map(|m| m.trial.h);
    let mut out = Vec::new();
    for (g, solver) in groups {
        let measured: Vec<&Measured> = sweep
            .iter()
            .filter(|m| m.trial.group == g && m.trial.solver.name == solver)
            .collect();
        let runs: Vec<&Trial> = measured.iter().map(|m| &m.trial).collect();
        let certified: Vec<&&Trial> = runs.iter().filter(|t| t.certified()).collect();
        // A group on another mesh than the section's (the fine meshes)
        // says its mesh, and, measured against no reference, its times.
        let h = runs.first().map(|t| t.h).filter(|h| Some(*h) != main_mesh);
        let unreferenced = runs.iter().all(|t| t.reference.is_none());
        let seconds: Vec<f64> = measured.iter().map(|m| m.timing.seconds_min).collect();
        let times = (unreferenced && !seconds.is_empty()).then(|| {
            let (fastest, slowest) = seconds
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
            Times {
                fastest,
                slowest,
                certificate: runs.iter().map(|t| t.residual()).fold(0.0f64, f64::max),
            }
        });
        out.push(Variation {
            group: g.to_string(),
            solver,
            h: h.map(|h| h.to_string()),
            certified: certified.iter().map(|t| t.knob().1.to_string()).collect(),
            cheapest: certified.iter().min_by_key(|t| t.work).map(|t| Cheapest {
                value: t.knob().1.to_string(),
                work: t.work,
                pressure_error: t.pressure_error(),
            }),
            failed: runs
                .iter()
                .filter(|t| !t.certified())
                .map(|t| Failed {
                    value: t.knob().1.to_string(),
                    status: t.status.to_string(),
                })
                .collect(),
            unreferenced,
            times,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::Settings;
    use crate::study::runner::{Keep, measure};
    use crate::study::sweep::{SCHEDULE, SweepSpec, plan};
    use contactlab_solvers::registry;

    /// The schedule varies one setting of every solver that warm-starts:
    /// each solver gets its own line, quoting its own trials' work. (The
    /// README once quoted tnnmg's least work under relaxation's name.)
    #[test]
    fn each_solver_of_a_shared_variation_quotes_its_own_trials() {
        let spec = SweepSpec {
            meshes: vec![crate::mechanics::mesh_size::MeshSize::from_level(3).unwrap()],
            solvers: ["relaxation", "tnnmg"]
                .map(|n| registry::by_name(n).unwrap())
                .to_vec(),
            work_precision: false,
            quick: true,
            ..SweepSpec::default()
        };
        let keep = Keep {
            history: false,
            solution: false,
        };
        let measured: Vec<Measured> = plan(&spec, &Settings::default())
            .unwrap()
            .iter()
            .filter(|t| t.group == SCHEDULE)
            .map(|t| measure(t, None, keep).unwrap())
            .collect();
        assert_eq!(measured.len(), 4);
        let found = variations(&measured);
        for solver in ["relaxation", "tnnmg"] {
            let line = found
                .iter()
                .find(|v| v.group == SCHEDULE && v.solver == solver)
                .unwrap_or_else(|| panic!("no line for {solver} in {found:?}"));
            let least = measured
                .iter()
                .filter(|m| m.trial.solver.name == solver && m.trial.certified())
                .map(|m| m.trial.work)
                .min()
                .unwrap();
            assert_eq!(
                line.cheapest.as_ref().map(|c| c.work),
                Some(least),
                "{line:?}"
            );
            assert_eq!(line.certified, ["revisit", "finest-only"], "{line:?}");
        }
    }
}
