//! The README's sentences about the sweeps and the work-precision diagrams,
//! computed from the trials.

use contactlab_solvers::registry::{self, Role};

use crate::study::runner::Measured;
use crate::study::sweep::{WORK_PRECISION, WORK_PRECISION_COULOMB};
use crate::study::trial::Trial;

/// Ratios of time at equal accuracy, interpolated log-log along each
/// solver's work-precision curve, in both diagrams.
pub(super) fn work_precision_text(sweep: &[Measured]) -> String {
    let (Some(paper), Some(oracle)) = (
        registry::with_role(Role::PapersMethod),
        registry::with_role(Role::Oracle),
    ) else {
        return String::new();
    };
    format!(
        "Each point is one value of a solver's accuracy knob, certified; errors are measured against the reference. \
         On the given-friction subproblem at the reference's g, time at equal pressure error as a ratio (below 1: \
         faster) of each solver over the oracle; `{}` is the paper's method:\n\n{}\n\n\
         On the whole Coulomb problem (a solver run inside the fixed point through ε, every loop's; a solver of the \
         Coulomb law through its own accuracy knob), the same ratios:\n\n{}\n",
        paper.name,
        time_ratios(sweep, WORK_PRECISION, oracle.name),
        time_ratios(sweep, WORK_PRECISION_COULOMB, oracle.name),
    )
}

/// One line per solver: its time over `baseline`'s at equal pressure error
/// along the curves of `group`.
pub(super) fn time_ratios(sweep: &[Measured], group: &str, baseline: &str) -> String {
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
            let ratios: Vec<String> = (2..=11)
                .map(|k| 10f64.powi(-k))
                .filter_map(|target| {
                    let (a, b) = (time_at(&points, target)?, time_at(&base, target)?);
                    Some(format!("{:.2} at {target:.0e}", a / b))
                })
                .collect();
            format!(
                "- `{other}` over `{baseline}`: {}",
                if ratios.is_empty() {
                    "no common range of pressure errors".into()
                } else {
                    ratios.join(", ")
                }
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
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

/// For each variation: the values certified, and the cheapest certified one.
pub(super) fn variations_text(sweep: &[Measured]) -> String {
    // A variation is a group of one solver: a group that varies the same
    // setting of two solvers (the schedule) is two lines, each quoting its
    // own solver's trials, since work is counted in each solver's own unit.
    let mut groups: Vec<(&str, &str)> = Vec::new();
    for m in sweep {
        let key = (m.trial.group.as_str(), m.trial.solver.name);
        if key.0 != WORK_PRECISION && key.0 != WORK_PRECISION_COULOMB && !groups.contains(&key) {
            groups.push(key);
        }
    }
    let main_mesh = sweep.first().map(|m| m.trial.h);
    let mut lines = Vec::new();
    for (g, solver) in groups {
        let measured: Vec<&Measured> = sweep
            .iter()
            .filter(|m| m.trial.group == g && m.trial.solver.name == solver)
            .collect();
        let runs: Vec<&Trial> = measured.iter().map(|m| &m.trial).collect();
        let certified: Vec<&&Trial> = runs.iter().filter(|t| t.certified()).collect();
        let failed: Vec<String> = runs
            .iter()
            .filter(|t| !t.certified())
            .map(|t| format!("{} ({})", t.knob().1, t.status))
            .collect();
        let cheapest = certified.iter().min_by_key(|t| t.work);
        // A group on another mesh than the section's (the fine meshes)
        // says its mesh, and, measured against no reference, its times.
        let h = runs.first().map(|t| t.h);
        let elsewhere = h.filter(|h| Some(*h) != main_mesh);
        let unreferenced = runs.iter().all(|t| t.reference.is_none());
        let seconds: Vec<f64> = measured.iter().map(|m| m.timing.seconds_min).collect();
        let times = (unreferenced && !seconds.is_empty()).then(|| {
            let (lo, hi) = seconds
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
            let worst = runs.iter().map(|t| t.residual()).fold(0.0f64, f64::max);
            format!(
                "; {lo:.2}–{hi:.2} s a point, largest certificate {worst:.1e} (no reference on this mesh: the certificate measures each answer)"
            )
        });
        lines.push(format!(
            "- `{g}` ({solver}{}): certified at {}; {}{}{}",
            elsewhere.map(|h| format!(", h = {h}")).unwrap_or_default(),
            if certified.is_empty() {
                "no value".to_string()
            } else {
                certified
                    .iter()
                    .map(|t| t.knob().1.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            },
            match cheapest {
                Some(t) => format!(
                    "the least work at {} ({} work{})",
                    t.knob().1,
                    t.work,
                    match t.pressure_error() {
                        Some(e) => format!(", pressure error {e:.1e}"),
                        None if unreferenced => String::new(),
                        None => ", pressure error –".into(),
                    }
                ),
                None => String::new(),
            },
            if failed.is_empty() {
                String::new()
            } else {
                format!("; not certified at {}", failed.join(", "))
            },
            times.unwrap_or_default()
        ));
    }
    if lines.is_empty() {
        String::new()
    } else {
        format!(
            "One factor at a time around the defaults, on the whole Coulomb problem (every trial stops at a work cap):\n\n{}\n",
            lines.join("\n")
        )
    }
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
        let text = variations_text(&measured);
        for solver in ["relaxation", "tnnmg"] {
            let line = text
                .lines()
                .find(|l| l.starts_with(&format!("- `{SCHEDULE}` ({solver})")))
                .unwrap_or_else(|| panic!("no line for {solver} in\n{text}"));
            let least = measured
                .iter()
                .filter(|m| m.trial.solver.name == solver && m.trial.certified())
                .map(|m| m.trial.work)
                .min()
                .unwrap();
            assert!(line.contains(&format!("({least} work")), "{line}");
            assert!(
                line.contains("certified at revisit, finest-only;"),
                "{line}"
            );
        }
    }
}
