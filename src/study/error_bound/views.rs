//! Views of the error-bound study's points: the sharpness table (per part,
//! law and mesh), the charts of bound against measured error, and the
//! README section. Every number is computed from the points.

use anyhow::Result;
use contactlab_solvers::Law;
use serde::Serialize;

use super::{BoundPoint, BoundSpec, LADDER_REFERENCE};
use crate::io::charts::{Chart, Series};
use crate::io::csv::fixed;
use crate::study::lab::Artifact;
use crate::study::template;
use crate::study::trial::Trial;

/// The goal: the bound within this factor of the error on 90 % of
/// the answers.
pub const SHARPNESS_GOAL: f64 = 30.0;

/// One line of the sharpness table.
#[derive(Clone, Debug, Serialize)]
pub struct SharpnessRow {
    pub part: String,
    pub law: Law,
    pub h: String,
    /// Answers, those with a bound, and those whose error is far enough
    /// above the reference's own bound to compare.
    pub answers: usize,
    pub bounded: usize,
    pub compared: usize,
    /// Answers whose bound is below their error by more than the
    /// reference's bound.
    pub below: usize,
    #[serde(serialize_with = "fixed")]
    pub ratio_median: f64,
    #[serde(serialize_with = "fixed")]
    pub ratio_p90: f64,
    #[serde(serialize_with = "fixed")]
    pub ratio_max: f64,
    /// The fraction of compared answers with bound/error ≤ [`SHARPNESS_GOAL`].
    #[serde(serialize_with = "fixed")]
    pub within_goal: f64,
    /// The same ratios for the pressure (max|p − p*| bound over max|p −
    /// p_ref|), median and 90th percentile.
    #[serde(serialize_with = "fixed")]
    pub pressure_ratio_median: f64,
    #[serde(serialize_with = "fixed")]
    pub pressure_ratio_p90: f64,
    /// Coulomb answers of a fixed point: those with an estimate of the
    /// whole error, and those whose estimate is below their error.
    pub estimated: usize,
    pub estimate_below: usize,
}

/// The q-quantile (nearest rank) of sorted values (NaN when empty).
fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let k = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[k - 1]
}

fn row(part: &str, law: Law, h: &str, points: &[&BoundPoint]) -> SharpnessRow {
    let mut ratios: Vec<f64> = points.iter().filter_map(|p| p.ratio()).collect();
    ratios.sort_by(f64::total_cmp);
    let mut pressure: Vec<f64> = points
        .iter()
        .filter(|p| p.comparable())
        .filter_map(|p| match (p.pressure_bound, p.pressure_error) {
            (Some(b), Some(e)) if e > 0.0 && b.is_finite() => Some(b / e),
            _ => None,
        })
        .collect();
    pressure.sort_by(f64::total_cmp);
    SharpnessRow {
        part: part.to_string(),
        law,
        h: h.to_string(),
        answers: points.len(),
        bounded: points.iter().filter(|p| p.bound.is_some()).count(),
        compared: ratios.len(),
        below: points.iter().filter(|p| p.below()).count(),
        ratio_median: quantile(&ratios, 0.5),
        ratio_p90: quantile(&ratios, 0.9),
        ratio_max: ratios.last().copied().unwrap_or(f64::NAN),
        within_goal: if ratios.is_empty() {
            f64::NAN
        } else {
            ratios.iter().filter(|r| **r <= SHARPNESS_GOAL).count() as f64 / ratios.len() as f64
        },
        pressure_ratio_median: quantile(&pressure, 0.5),
        pressure_ratio_p90: quantile(&pressure, 0.9),
        estimated: points.iter().filter(|p| p.estimate.is_some()).count(),
        estimate_below: points.iter().filter(|p| p.estimate_below()).count(),
    }
}

/// The sharpness table: per part and law, one row per mesh and one for
/// all meshes together.
pub fn sharpness(points: &[BoundPoint]) -> Vec<SharpnessRow> {
    let mut out = Vec::new();
    for part in ["core", "ladder"] {
        for law in [Law::GivenFriction, Law::Coulomb] {
            let of: Vec<&BoundPoint> = points
                .iter()
                .filter(|p| p.part == part && p.law == law)
                .collect();
            if of.is_empty() {
                continue;
            }
            let mut levels: Vec<(u32, String)> =
                of.iter().map(|p| (p.level, p.h.clone())).collect();
            levels.sort();
            levels.dedup();
            for (level, h) in &levels {
                let at: Vec<&BoundPoint> =
                    of.iter().copied().filter(|p| p.level == *level).collect();
                out.push(row(part, law, h, &at));
            }
            if levels.len() > 1 {
                out.push(row(part, law, "all", &of));
            }
        }
    }
    out
}

/// Bound against measured error, per solver, for answers of `law`, with
/// the line bound = error: a point below it would be a bound that fails.
fn against_error(title: &str, points: &[BoundPoint], law: Law) -> Option<Chart> {
    let pts: Vec<(String, f64, f64)> = points
        .iter()
        .filter(|p| p.law == law && p.comparable())
        .map(|p| {
            (
                p.solver.clone(),
                p.energy_error.unwrap_or(f64::NAN),
                p.bound.unwrap_or(f64::NAN),
            )
        })
        .collect();
    bound_against_error_chart(title, &pts)
}

/// A chart of error bounds against measured errors (both over √K·U), one
/// scatter series per solver (solver, error, bound), with the lines bound
/// = error and bound = 30 × error (None: no point with both positive).
pub fn bound_against_error_chart(title: &str, points: &[(String, f64, f64)]) -> Option<Chart> {
    let of: Vec<&(String, f64, f64)> = points
        .iter()
        .filter(|(_, e, b)| e.is_finite() && b.is_finite() && *e > 0.0 && *b > 0.0)
        .collect();
    if of.is_empty() {
        return None;
    }
    let mut names: Vec<&str> = of.iter().map(|p| p.0.as_str()).collect();
    names.sort();
    names.dedup();
    let mut series: Vec<Series> = names
        .iter()
        .map(|name| {
            let pts = of
                .iter()
                .filter(|p| p.0 == *name)
                .map(|p| (p.1, p.2))
                .collect();
            Series::line(*name, pts).scatter().of_solver(name)
        })
        .collect();
    let (lo, hi) = of.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| {
        (lo.min(p.1), hi.max(p.1))
    });
    // One legend entry for both lines: with every solver listed, two would
    // pass the legend's limit.
    series.push(
        Series::line(
            format!("bound = error (dashed: {SHARPNESS_GOAL}×)"),
            vec![(lo, lo), (hi, hi)],
        )
        .black(),
    );
    let mut goal = Series::line(
        format!("bound = {SHARPNESS_GOAL}× error"),
        vec![(lo, SHARPNESS_GOAL * lo), (hi, SHARPNESS_GOAL * hi)],
    )
    .dashed()
    .black();
    goal.legend = false;
    series.push(goal);
    Some(Chart::new(
        title,
        "measured error ‖v − v_ref‖_A / (√K·U)",
        "error bound / (√K·U)",
        true,
        true,
        series,
    ))
}

/// The measured trials' (solver, error, bound) where both exist: the
/// points of [`bound_against_error_chart`].
pub fn trial_points<'a>(trials: impl IntoIterator<Item = &'a Trial>) -> Vec<(String, f64, f64)> {
    trials
        .into_iter()
        .filter_map(|t| {
            Some((
                t.solver.name.to_string(),
                t.agreement?.energy,
                t.error_bound()?.displacement,
            ))
        })
        .collect()
}

/// The median and the largest ratio bound/error over the solvers'
/// answers at each mesh of the ladder, one pair of lines per target.
fn ratio_against_h(points: &[BoundPoint], law: Law) -> Option<Chart> {
    let of: Vec<&BoundPoint> = points
        .iter()
        .filter(|p| p.part == "ladder" && p.law == law)
        .collect();
    let mut targets: Vec<f64> = of.iter().map(|p| p.target).collect();
    targets.sort_by(f64::total_cmp);
    targets.dedup();
    let mut levels: Vec<(u32, String)> = of.iter().map(|p| (p.level, p.h.clone())).collect();
    levels.sort();
    levels.dedup();
    let mut series = Vec::new();
    for (k, &target) in targets.iter().enumerate() {
        let (mut median, mut max) = (Vec::new(), Vec::new());
        for (level, _) in &levels {
            let mut ratios: Vec<f64> = of
                .iter()
                .filter(|p| p.level == *level && p.target == target)
                .filter_map(|p| p.ratio())
                .collect();
            ratios.sort_by(f64::total_cmp);
            if let Some(&last) = ratios.last() {
                let x = 2f64.powi(*level as i32);
                median.push((x, quantile(&ratios, 0.5)));
                max.push((x, last));
            }
        }
        if !median.is_empty() {
            series.push(
                Series::line(format!("target {target:e}: median"), median)
                    .with_markers()
                    .colored(k),
            );
            series.push(
                Series::line(format!("target {target:e}: largest"), max)
                    .dashed()
                    .colored(k),
            );
        }
    }
    if series.is_empty() {
        return None;
    }
    let ticks = levels
        .iter()
        .map(|(level, h)| (2f64.powi(*level as i32), h.clone()))
        .collect();
    Some(
        Chart::new(
            format!(
                "Error bound over measured error against h, problem 1 ({})",
                law.as_str()
            ),
            "mesh size h",
            "bound / error over the solvers' answers",
            true,
            true,
            series,
        )
        .with_x_ticks(ticks),
    )
}

/// The study's charts.
pub fn charts(points: &[BoundPoint]) -> Vec<Artifact> {
    let mut out = Vec::new();
    if let Some(c) = against_error(
        "Error bound against measured error, given friction (rigorous)",
        points,
        Law::GivenFriction,
    ) {
        out.push(Artifact::chart("error_bound_given_friction", c));
    }
    if let Some(c) = against_error(
        "Error bound at g = 𝓕p against error from the Coulomb reference",
        points,
        Law::Coulomb,
    ) {
        out.push(Artifact::chart("error_bound_coulomb", c));
    }
    for law in [Law::GivenFriction, Law::Coulomb] {
        if let Some(c) = ratio_against_h(points, law) {
            out.push(Artifact::chart(
                &format!("error_bound_ratio_{}", law.as_str()),
                c,
            ));
        }
    }
    out
}

/// The README section (`templates/error_bound.md`): what was measured, the
/// table, the charts.
pub fn section(spec: &BoundSpec, points: &[BoundPoint], charts: &[String]) -> Result<String> {
    let mesh = |h: Option<&crate::mechanics::mesh_size::MeshSize>| {
        h.map(|h| h.to_string()).unwrap_or_default()
    };
    template::render(
        "error_bound",
        include_str!("../templates/error_bound.md"),
        template::facts! {
            collection => if spec.quick { "quick" } else { "core" },
            targets => spec.targets,
            ladder_problem => spec.ladder_problem,
            ladder_from => mesh(spec.ladder_meshes.first()),
            ladder_to => mesh(spec.ladder_meshes.last()),
            ladder_targets => spec.ladder_targets,
            ladder_reference => LADDER_REFERENCE,
            budget => spec.budget,
            rows => sharpness(points),
            charts,
        },
    )
}
