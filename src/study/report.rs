//! Charts drawn from trials: contact-zone profiles (the paper's figures 2-5),
//! convergence histories, the work-precision diagram and one-factor sweeps.

use std::path::{Path, PathBuf};

use anyhow::Result;
use contactlab_solvers::registry;

use crate::coulomb::fixed_point::STAGE;
use crate::io::charts::{Chart, Legend, Series};
use crate::mechanics::contact_zone::ProfileRow;
use crate::study::runner::Measured;
use crate::study::sweep::{SCHEDULE, WORK_PRECISION, WORK_PRECISION_COULOMB};
use crate::study::trial::{Trial, TrialTiming};

fn chart(
    title: impl Into<String>,
    x: &str,
    y: &str,
    log_x: bool,
    log_y: bool,
    series: Vec<Series>,
) -> Chart {
    Chart {
        title: title.into(),
        x_label: x.into(),
        y_label: y.into(),
        log_x,
        log_y,
        series,
        legend: Legend::default(),
    }
}

/// Writes each chart as `dir/name.svg`; returns the paths.
pub fn write_all(dir: &Path, charts: &[(String, Chart)]) -> Result<Vec<PathBuf>> {
    charts
        .iter()
        .map(|(name, c)| {
            let path = dir.join(format!("{name}.svg"));
            c.write(&path)?;
            Ok(path)
        })
        .collect()
}

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
        .map(|(t, _)| (t.scene.clone(), t.h.clone()))
        .collect();
    groups.sort();
    groups.dedup();
    for (scene, h) in groups {
        let tag = sweep_tag(&scene, &h);
        let here: Vec<&(&Trial, &TrialTiming)> = trials
            .iter()
            .filter(|(t, _)| t.scene == scene && t.h == h)
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
                    chart(
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
        let points = |certified: bool| -> Vec<(f64, f64)> {
            let mut pts: Vec<(f64, f64)> = here
                .iter()
                .filter(|(t, _)| {
                    t.group == group
                        && t.solver == e.name
                        && t.certified() == certified
                        && (certified || t.solver_status.is_converged())
                })
                .filter_map(|(t, tm)| t.pressure_error.map(|p| (p.max(WP_FLOOR), tm.seconds_min)))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            pts
        };
        let (good, failed) = (points(true), points(false));
        if !good.is_empty() {
            wp.push(Series::line(e.name, good).with_markers());
        }
        if !failed.is_empty() {
            wp.push(Series::line(format!("{}: claimed, not certified", e.name), failed).scatter());
        }
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
    let numeric = |t: &Trial| t.value.parse::<f64>().ok().filter(|v| *v > 0.0);
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
    let metric = |name: &str, f: &dyn Fn(&Trial) -> Option<f64>| -> Vec<Series> {
        let mut v = Vec::new();
        let pts: Vec<(f64, f64)> = runs
            .iter()
            .filter(|t| t.certified())
            .filter_map(|t| Some((numeric(t)?, f(t)?)))
            .collect();
        v.push(Series::line(name, pts).with_markers());
        let failed: Vec<(f64, f64)> = runs
            .iter()
            .filter(|t| !t.certified())
            .filter_map(|t| Some((numeric(t)?, f(t)?)))
            .collect();
        if !failed.is_empty() {
            v.push(Series::line(format!("{name}, not certified"), failed).scatter());
        }
        for t in runs.iter().filter(|t| numeric(t).is_none()) {
            if let Some(y) = f(t) {
                v.push(
                    Series::line(format!("{name} at {}", t.value), vec![(lo, y), (hi, y)]).dashed(),
                );
            }
        }
        v
    };
    let count = |f: fn(&Trial) -> usize| move |t: &Trial| Some(f(t).max(1) as f64);
    let mut iterations = metric("inner iterations", &count(|t| t.inner_iterations));
    iterations.extend(metric("outer iterations", &count(|t| t.outer_iterations)));
    iterations.extend(metric(
        "friction iterations",
        &count(|t| t.friction_iterations),
    ));
    let mut errors = metric("max displacement error", &|t| t.displacement_error);
    errors.extend(metric("max pressure error", &|t| t.pressure_error));
    errors.extend(metric("certificate", &|t| Some(t.certificate)));
    let slug = group.replace('.', "_");
    vec![
        (
            format!("sweep_{slug}_iterations_{tag}"),
            chart(
                format!("Iterations against {group}, {scene}, h = {h}"),
                group,
                "iterations (count)",
                true,
                true,
                iterations,
            ),
        ),
        (
            format!("sweep_{slug}_error_{tag}"),
            chart(
                format!("Error against {group}, vs reference, {scene}, h = {h}"),
                group,
                "relative error / certificate (dimensionless)",
                true,
                true,
                errors,
            ),
        ),
    ]
}

/// The profile of one solver with and without friction.
pub struct ProfilePair<'a> {
    pub solver: &'a str,
    pub friction: &'a [ProfileRow],
    pub frictionless: &'a [ProfileRow],
}

/// The paper's figures 2-5 for one problem: both bodies' vertical
/// displacements, the jump, the multiplier l, and a zoom on the separation zone.
pub fn profile_charts(
    problem: u32,
    h: &str,
    pairs: &[ProfilePair<'_>],
    zoom_from: f64,
) -> Vec<(String, Chart)> {
    let col = |rows: &[ProfileRow], f: fn(&ProfileRow) -> f64, from: f64| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|r| r.x >= from)
            .map(|r| (r.x, f(r)))
            .collect()
    };
    let styled = |s: Series, i: usize| if i == 0 { s } else { s.scatter() };
    let mut displacement = Vec::new();
    let mut zoom = Vec::new();
    let mut jump = Vec::new();
    let mut pressure = Vec::new();
    for (i, p) in pairs.iter().enumerate() {
        for (body, f) in [
            (
                "lower u'₂",
                (|r: &ProfileRow| r.u2_lower) as fn(&ProfileRow) -> f64,
            ),
            ("upper u''₂", |r: &ProfileRow| r.u2_upper),
        ] {
            displacement.push(styled(
                Series::line(format!("{body}, {}", p.solver), col(p.friction, f, 0.0)),
                i,
            ));
            zoom.push(styled(
                Series::line(
                    format!("{body}, friction, {}", p.solver),
                    col(p.friction, f, zoom_from),
                ),
                i,
            ));
            zoom.push(styled(
                Series::line(
                    format!("{body}, no friction, {}", p.solver),
                    col(p.frictionless, f, zoom_from),
                )
                .dashed(),
                i,
            ));
        }
        jump.push(styled(
            Series::line(
                format!("friction, {}", p.solver),
                col(p.friction, |r| r.jump, 0.0),
            ),
            i,
        ));
        jump.push(styled(
            Series::line(
                format!("no friction, {}", p.solver),
                col(p.frictionless, |r| r.jump, 0.0),
            )
            .dashed(),
            i,
        ));
        pressure.push(styled(
            Series::line(
                format!("friction, {}", p.solver),
                col(p.friction, |r| r.pressure, 0.0),
            ),
            i,
        ));
        pressure.push(styled(
            Series::line(
                format!("no friction, {}", p.solver),
                col(p.frictionless, |r| r.pressure, 0.0),
            )
            .dashed(),
            i,
        ));
    }
    let x = "x along Γ_K";
    vec![
        (
            format!("profile_p{problem}_displacement"),
            chart(
                format!(
                    "Vertical displacements on Γ_K, problem {problem}, h = {h} (with friction)"
                ),
                x,
                "u₂ [length]",
                false,
                false,
                displacement,
            ),
        ),
        (
            format!("profile_p{problem}_zoom"),
            chart(
                format!("Separation zone, problem {problem}, h = {h}: with and without friction"),
                x,
                "u₂ [length]",
                false,
                false,
                zoom,
            ),
        ),
        (
            format!("profile_p{problem}_jump"),
            chart(
                format!("Jump [u] = u'₂ − u''₂ on Γ_K, problem {problem}, h = {h}"),
                x,
                "[u] [length]",
                false,
                false,
                jump,
            ),
        ),
        (
            format!("profile_p{problem}_pressure"),
            chart(
                format!("Multiplier l (contact pressure), problem {problem}, h = {h}"),
                x,
                "l [force/length]",
                false,
                false,
                pressure,
            ),
        ),
    ]
}

/// Residual against iteration for each solver's Coulomb solve, the fixed
/// point included, from a comparison's measured trials of one problem.
pub fn convergence_chart(problem: u32, h: &str, measured: &[Measured]) -> (String, Chart) {
    let mut series = Vec::new();
    for m in measured
        .iter()
        .filter(|m| m.trial.law == contactlab_solvers::Law::Coulomb)
    {
        let mut stages = vec![(STAGE, "friction max|Δg|".to_string())];
        if let Some(e) = registry::by_name(&m.trial.solver) {
            stages.extend(
                e.stages
                    .iter()
                    .filter(|s| s.history)
                    .map(|s| (s.name, s.name.to_string())),
            );
        }
        let before = series.len();
        for (stage, what) in stages {
            let pts: Vec<(f64, f64)> = m
                .history
                .iter()
                .filter(|p| p.stage == stage)
                .enumerate()
                .map(|(i, p)| ((i + 1) as f64, p.residual))
                .collect();
            if !pts.is_empty() {
                series
                    .push(Series::line(format!("{}: {what}", m.trial.solver), pts).with_markers());
            }
        }
        if series.len() == before {
            // Nothing to draw, but said in the legend rather than left out.
            series.push(Series::line(
                format!(
                    "{}: no iterations (its start passed its test)",
                    m.trial.solver
                ),
                Vec::new(),
            ));
        }
    }
    (
        format!("convergence_p{problem}"),
        chart(
            format!("Convergence histories, Coulomb problem {problem}, h = {h}"),
            "iteration (counted over the whole run, per loop)",
            "residual of that loop",
            false,
            true,
            series,
        ),
    )
}
