//! The sweep's charts: the work-precision diagram and one-factor sweeps.

use contactlab_solvers::registry;

use crate::io::charts::{Chart, Series, suits_log_axis};
use crate::study::sweep::{SCHEDULE, WORK_PRECISION, WORK_PRECISION_COULOMB};
use crate::study::trial::{Trial, TrialTiming};

/// Errors below this are drawn at it in the work-precision diagram: the
/// reference's own resolution.
pub const WP_FLOOR: f64 = 1e-12;

/// The file-name tag of one scene and mesh in sweep charts: `problem_1_h32`.
pub fn sweep_tag(scene: &str, h: &str) -> String {
    let slug: String = scene
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .collect();
    format!("{slug}_h{}", h.replace("1/", ""))
}

/// Charts of a sweep: the work-precision diagram, and for each numeric
/// variation its iterations and its errors against the value.
pub fn sweep_charts(trials: &[(&Trial, &TrialTiming)]) -> Vec<(String, Chart)> {
    let mut out = Vec::new();
    let mut groups: Vec<(String, String)> = trials
        .iter()
        .map(|(t, _)| (t.scene.clone(), t.h.to_string()))
        .collect();
    groups.sort();
    groups.dedup();
    for (scene, h) in groups {
        let tag = sweep_tag(&scene, &h);
        let here: Vec<&(&Trial, &TrialTiming)> = trials
            .iter()
            .filter(|(t, _)| t.scene == scene && t.h.to_string() == h)
            .collect();
        for (group, file, what) in [
            (
                WORK_PRECISION,
                "work_precision",
                "given-friction subproblem",
            ),
            (
                WORK_PRECISION_COULOMB,
                "work_precision_coulomb",
                "Coulomb problem",
            ),
        ] {
            let wp = work_precision_series(&here, group);
            if !wp.is_empty() {
                out.push((
                    format!("{file}_{tag}"),
                    Chart::new(
                        format!("Work-precision, {what}, {scene}, h = {h}"),
                        "max pressure error vs reference (relative; 1e-12: at or below its resolution)",
                        "solver time [s]",
                        true,
                        true,
                        wp,
                    ),
                ));
            }
        }
        let mut variations: Vec<String> = here
            .iter()
            .map(|(t, _)| t.group.clone())
            .filter(|g| g != WORK_PRECISION && g != WORK_PRECISION_COULOMB && g != SCHEDULE)
            .collect();
        variations.dedup();
        variations.sort();
        variations.dedup();
        for group in variations {
            let runs: Vec<&Trial> = here
                .iter()
                .filter(|(t, _)| t.group == group)
                .map(|(t, _)| *t)
                .collect();
            out.extend(variation_charts(&group, &scene, &h, &tag, &runs));
        }
    }
    out
}

/// One work-precision diagram's series: per solver its certified points
/// (pressure error, fastest time) and, apart, those it claimed but the
/// certificate refused.
fn work_precision_series(here: &[&(&Trial, &TrialTiming)], group: &str) -> Vec<Series> {
    let mut wp: Vec<Series> = Vec::new();
    for e in registry::solvers() {
        // Each point labelled with the target it was run at: the
        // accuracy knob's value, or the fixed point's ε.
        let points = |certified: bool| -> Vec<((f64, f64), String)> {
            let mut pts: Vec<((f64, f64), String)> = here
                .iter()
                .filter(|(t, _)| {
                    t.group == group
                        && t.solver.name == e.name
                        && t.certified() == certified
                        && (certified || t.solver_status.is_converged())
                })
                .filter_map(|(t, tm)| {
                    t.pressure_error()
                        .map(|p| ((p.max(WP_FLOOR), tm.seconds_min), t.knob().1.to_string()))
                })
                .collect();
            pts.sort_by(|a, b| a.0.0.total_cmp(&b.0.0));
            pts
        };
        wp.extend(Series::certified_and_failed_labelled(
            e.name,
            points(true),
            points(false),
        ));
    }
    wp
}

/// Iterations and errors against one knob's value; values that are not
/// numbers (`exact`) are drawn as dashed levels.
fn variation_charts(
    group: &str,
    scene: &str,
    h: &str,
    tag: &str,
    runs: &[&Trial],
) -> Vec<(String, Chart)> {
    let numeric = |t: &Trial| {
        t.setting
            .as_ref()
            .and_then(|s| s.number)
            .filter(|v| *v > 0.0)
    };
    if runs.iter().filter(|t| numeric(t).is_some()).count() < 2 {
        return Vec::new();
    }
    let lo = runs
        .iter()
        .filter_map(|t| numeric(t))
        .fold(f64::INFINITY, f64::min);
    let hi = runs
        .iter()
        .filter_map(|t| numeric(t))
        .fold(f64::NEG_INFINITY, f64::max);
    // Each metric in one colour (its index on the chart): its line, its
    // failed points' crosses and its level at a non-numeric value.
    let metric = |color: usize, name: &str, f: &dyn Fn(&Trial) -> Option<f64>| -> Vec<Series> {
        let mut v = Vec::new();
        let pts: Vec<(f64, f64)> = runs
            .iter()
            .filter(|t| t.certified())
            .filter_map(|t| Some((numeric(t)?, f(t)?)))
            .collect();
        v.push(Series::line(name, pts).with_markers().colored(color));
        let failed: Vec<(f64, f64)> = runs
            .iter()
            .filter(|t| !t.certified())
            .filter_map(|t| Some((numeric(t)?, f(t)?)))
            .collect();
        if !failed.is_empty() {
            v.push(
                Series::line(format!("{name}, not certified"), failed)
                    .failed()
                    .colored(color),
            );
        }
        for t in runs.iter().filter(|t| numeric(t).is_none()) {
            if let Some(y) = f(t) {
                v.push(
                    Series::line(format!("{name} at {}", t.knob().1), vec![(lo, y), (hi, y)])
                        .dashed()
                        .colored(color),
                );
            }
        }
        v
    };
    let count = |f: fn(&Trial) -> usize| move |t: &Trial| Some(f(t).max(1) as f64);
    let mut iterations = metric(0, "inner iterations", &count(|t| t.inner_iterations));
    iterations.extend(metric(
        1,
        "outer iterations",
        &count(|t| t.outer_iterations),
    ));
    iterations.extend(metric(
        2,
        "friction iterations",
        &count(|t| t.friction_iterations),
    ));
    let mut errors = metric(0, "max displacement error", &|t| t.displacement_error());
    errors.extend(metric(1, "max pressure error", &|t| t.pressure_error()));
    errors.extend(metric(2, "certificate", &|t| Some(t.residual())));
    // Without a reference the errors have no points: not in the legend.
    errors.retain(|s| !s.points.is_empty());
    let slug = file_slug(group);
    let measured_against = if runs.iter().any(|t| t.reference.is_some()) {
        "vs reference"
    } else {
        "certificate only (no reference on this mesh)"
    };
    // A log axis for values over a decade or more, linear otherwise (ω).
    let log_x = suits_log_axis([lo, hi]);
    vec![
        (
            format!("sweep_{slug}_iterations_{tag}"),
            Chart::new(
                format!("Iterations against {group}, {scene}, h = {h}"),
                group,
                "iterations (count)",
                log_x,
                true,
                iterations,
            ),
        ),
        (
            format!("sweep_{slug}_error_{tag}"),
            Chart::new(
                format!("Error against {group}, {measured_against}, {scene}, h = {h}"),
                group,
                "relative error / certificate (dimensionless)",
                log_x,
                true,
                errors,
            ),
        ),
    ]
}

/// A group's name in file names: letters and digits kept, every run of
/// anything else one `_` (`relaxation.r (inner = multigrid)` →
/// `relaxation_r_inner_multigrid`).
fn file_slug(group: &str) -> String {
    let mut slug = String::new();
    for c in group.chars() {
        if c.is_ascii_alphanumeric() {
            slug.push(c);
        } else if !slug.ends_with('_') {
            slug.push('_');
        }
    }
    slug.trim_matches('_').to_string()
}

#[cfg(test)]
mod tests {
    use super::file_slug;

    /// A group's name becomes a file name the old groups keep
    /// (`relaxation.r` → `relaxation_r`) and a fine group's is readable.
    #[test]
    fn file_slugs() {
        assert_eq!(file_slug("relaxation.r"), "relaxation_r");
        assert_eq!(file_slug("admm.rho_factor"), "admm_rho_factor");
        assert_eq!(
            file_slug("relaxation.r (inner = multigrid)"),
            "relaxation_r_inner_multigrid"
        );
    }
}
