//! Charts drawn from the harness's rows: work-precision, r and ε sweeps,
//! contact-zone profiles (the paper's figures 2-5), convergence histories.

use std::path::{Path, PathBuf};

use anyhow::Result;
use contactlab_solvers::{Progress, registry};

use crate::io::charts::{Chart, Series};
use crate::mechanics::contact_zone::ProfileRow;
use crate::study::compare::{CompareRow, Mode};
use crate::study::sweep::SweepRow;

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
        legend: Default::default(),
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

fn parse_value(v: &str) -> f64 {
    v.parse().unwrap_or(f64::NAN)
}

/// Errors below this are drawn at it in the work-precision diagram: the
/// reference's own resolution (its residuals are ~1e-13).
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

/// Charts of a sweep: work-precision, and iterations and errors against r and ε.
pub fn sweep_charts(rows: &[SweepRow]) -> Vec<(String, Chart)> {
    let mut out = Vec::new();
    let groups: Vec<(String, String)> = {
        let mut g: Vec<(String, String)> = rows
            .iter()
            .map(|r| (r.problem.clone(), r.h.clone()))
            .collect();
        g.dedup();
        g.sort();
        g.dedup();
        g
    };
    for (problem, h) in groups {
        let tag = sweep_tag(&problem, &h);
        let rows: Vec<&SweepRow> = rows
            .iter()
            .filter(|r| r.problem == problem && r.h == h)
            .collect();
        let of = |f: &'static str| rows.iter().copied().filter(move |r| r.factor == f);
        // Work-precision: one curve per solver, one point per tolerance.
        let mut solvers: Vec<&str> = of("tolerance").map(|r| r.solver.as_str()).collect();
        solvers.dedup();
        let wp: Vec<Series> = solvers
            .iter()
            .map(|&s| {
                // Errors below the reference's resolution are drawn at it.
                let mut pts: Vec<(f64, f64)> = of("tolerance")
                    .filter(|r| r.solver == s && r.converged)
                    .filter_map(|r| {
                        r.seconds
                            .map(|t| (r.agreement.pressure_max.max(WP_FLOOR), t))
                    })
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                Series::line(s, pts).with_markers()
            })
            .collect();
        if wp.iter().any(|s| !s.points.is_empty()) {
            out.push((
                format!("work_precision_{tag}"),
                chart(
                    format!("Work-precision, given-friction subproblem, {problem}, h = {h}"),
                    "max pressure error vs reference (relative; 1e-12: at or below its resolution)",
                    "solver time [s]",
                    true,
                    true,
                    wp,
                ),
            ));
        }
        for factor in ["r", "epsilon"] {
            let runs: Vec<&SweepRow> = of(factor).collect();
            if runs.is_empty() {
                continue;
            }
            let name = if factor == "r" {
                "penalty r"
            } else {
                "ε (the paper's tolerance)"
            };
            let pick = |f: &dyn Fn(&SweepRow) -> f64, converged: bool| -> Vec<(f64, f64)> {
                runs.iter()
                    .filter(|r| r.converged == converged)
                    .map(|r| (parse_value(&r.value), f(r)))
                    .collect()
            };
            let mut iters = vec![
                Series::line("relaxation sweeps (MPR)", pick(&|r| r.inner as f64, true))
                    .with_markers(),
                Series::line("Uzawa iterations (MU)", pick(&|r| r.outer as f64, true))
                    .with_markers(),
                Series::line(
                    "friction iterations (MPP)",
                    pick(&|r| r.friction_iterations as f64, true),
                )
                .with_markers(),
            ];
            let failed = pick(&|r| r.inner as f64, false);
            if !failed.is_empty() {
                iters.push(Series::line("sweeps of runs that did not converge", failed).scatter());
            }
            out.push((
                format!("sweep_{factor}_iterations_{tag}"),
                chart(
                    format!("Iterations against {name}, relaxation, {problem}, h = {h}"),
                    name,
                    "iterations (count)",
                    true,
                    true,
                    iters,
                ),
            ));
            let mut errors = vec![
                Series::line(
                    "max displacement error",
                    pick(&|r| r.agreement.displacement_max, true),
                )
                .with_markers(),
                Series::line(
                    "max pressure error",
                    pick(&|r| r.agreement.pressure_max, true),
                )
                .with_markers(),
                Series::line("KKT residual", pick(&|r| r.kkt, true))
                    .with_markers()
                    .dashed(),
            ];
            let failed = pick(&|r| r.agreement.pressure_max, false);
            if !failed.is_empty() {
                errors.push(
                    Series::line("pressure error of runs that did not converge", failed).scatter(),
                );
            }
            out.push((
                format!("sweep_{factor}_error_{tag}"),
                chart(
                    format!("Error against {name}, relaxation vs reference, {problem}, h = {h}"),
                    name,
                    "relative error / residual (dimensionless)",
                    true,
                    true,
                    errors,
                ),
            ));
        }
        let smooth: Vec<&SweepRow> = of("smoothing").collect();
        if !smooth.is_empty() {
            let huber: Vec<(f64, f64)> = smooth
                .iter()
                .filter(|r| r.converged && r.smoothing.starts_with("huber"))
                .map(|r| {
                    (
                        parse_value(
                            r.smoothing
                                .trim_start_matches("huber(")
                                .trim_end_matches(')'),
                        ),
                        r.agreement.pressure_max,
                    )
                })
                .collect();
            let mut series =
                vec![Series::line("Huber smoothing of width δ", huber.clone()).with_markers()];
            if let Some(exact) = smooth
                .iter()
                .find(|r| r.converged && r.smoothing == "exact")
            {
                let xs: Vec<f64> = huber.iter().map(|p| p.0).collect();
                let (lo, hi) = xs
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                        (a.min(x), b.max(x))
                    });
                if lo.is_finite() {
                    series.push(
                        Series::line(
                            "exact soft thresholding",
                            vec![
                                (lo, exact.agreement.pressure_max),
                                (hi, exact.agreement.pressure_max),
                            ],
                        )
                        .dashed(),
                    );
                }
            }
            out.push((
                format!("sweep_smoothing_{tag}"),
                chart(
                    format!("Smoothing of |s|: pressure error vs reference, {problem}, h = {h}"),
                    "Huber width δ [length]",
                    "max pressure error (relative)",
                    true,
                    true,
                    series,
                ),
            ));
        }
    }
    out
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

/// Residual against iteration for each method, the Coulomb loop included,
/// from the comparison's Coulomb rows of one problem.
pub fn convergence_chart(problem: u32, h: &str, rows: &[&CompareRow]) -> (String, Chart) {
    let mut series = Vec::new();
    for r in rows.iter().filter(|r| r.mode == Mode::Coulomb) {
        let mut by_stage = |stage: &str, what: &str| {
            let pts: Vec<(f64, f64)> = r
                .history
                .iter()
                .filter(|p: &&Progress| p.stage == stage)
                .enumerate()
                .map(|(i, p)| ((i + 1) as f64, p.residual))
                .collect();
            if !pts.is_empty() {
                series.push(Series::line(format!("{}: {what}", r.solver), pts).with_markers());
            }
        };
        by_stage(crate::coulomb::fixed_point::STAGE, "friction max|Δg|");
        for e in registry::SOLVERS {
            for s in e.stages.iter().filter(|s| s.history) {
                by_stage(s.name, s.name);
            }
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
