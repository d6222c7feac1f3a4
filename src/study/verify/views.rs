//! The verification's views: the computed pressure profiles over the
//! closed form, the errors against h, and its README section.

use anyhow::Result;
use contactlab_solvers::Status;
use serde::Serialize;

use crate::io::charts::{Chart, Series, solver_color};
use crate::mechanics::contact_zone::ProfileRow;
use crate::study::template;

use super::{ClosedForm, SCENES, Verified, VerifyRow, scene};

/// The solver whose profiles the profile charts draw at every mesh (the
/// others are in `profiles/`).
pub const PROFILE_SOLVER: &str = "newton-coulomb";

/// Per scene: the pressure of `PROFILE_SOLVER` at each mesh over the closed
/// form (x within 2a of x₀), and each solver's L2 error against h.
pub fn charts(
    rows: &[VerifyRow],
    profiles: &[(String, Vec<ProfileRow>)],
) -> Result<Vec<(String, Chart)>> {
    let mut out = Vec::new();
    for (name, _) in SCENES {
        let closed = ClosedForm::of(&scene(name)?)?;
        let (c, a) = (closed.center(), closed.half_width());
        let window = |x: f64| (x - c).abs() <= 2.0 * a;
        let mut series = Vec::new();
        let samples = 400;
        let exact: Vec<(f64, f64)> = (0..=samples)
            .map(|k| c - 2.0 * a + 4.0 * a * k as f64 / samples as f64)
            .map(|x| (x, closed.pressure(x)))
            .filter(|(_, p)| p.is_finite() && *p <= 4.0 * closed.p0())
            .collect();
        series.push(Series::line(format!("closed form ({})", closed.source()), exact).black());
        series.extend(profile_series(name, profiles, window, |r| r.pressure));
        if let ClosedForm::CattaneoMindlin(cm) = &closed {
            out.push((
                format!("verify_{name}_traction"),
                traction_chart(name, cm, rows, profiles),
            ));
        }
        out.push((
            format!("verify_{name}_pressure"),
            Chart::new(
                format!("{name}: contact pressure against the closed form"),
                "x",
                "pressure p",
                false,
                false,
                series,
            ),
        ));
        let mut errors = Vec::new();
        let mut solvers: Vec<&str> = Vec::new();
        for r in rows.iter().filter(|r| r.scene == name) {
            if !solvers.contains(&r.solver) {
                solvers.push(r.solver);
            }
        }
        for s in solvers {
            let points: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.scene == name && r.solver == s && r.status == Status::Converged)
                .filter_map(|r| r.l2_error.map(|e| (r.h.h(), e)))
                .filter(|(_, e)| *e > 0.0)
                .collect();
            if !points.is_empty() {
                errors.push(
                    Series::line(s, points)
                        .with_markers()
                        .colored(solver_color(s)),
                );
            }
        }
        out.push((
            format!("verify_{name}_error"),
            Chart::new(
                format!(
                    "{name}: L2 error of the pressure against the closed form (certified answers)"
                ),
                "h",
                "‖p_h − p‖ / ‖p‖",
                true,
                true,
                errors,
            ),
        ));
    }
    Ok(out)
}

/// Cattaneo–Mindlin: the tangential traction of `PROFILE_SOLVER` at each
/// mesh over the closed form at the Q of its finest certified answer.
fn traction_chart(
    name: &str,
    cm: &crate::mechanics::closed_forms::CattaneoMindlin,
    rows: &[VerifyRow],
    profiles: &[(String, Vec<ProfileRow>)],
) -> Chart {
    let (c, a) = (cm.hertz.center, cm.hertz.half_width());
    let q_load = rows
        .iter()
        .rev()
        .filter(|r| r.scene == name && r.solver == PROFILE_SOLVER && r.status.is_converged())
        .find_map(|r| r.tangential_load);
    let mut series = Vec::new();
    if let Some(q_load) = q_load {
        let samples = 800;
        let exact: Vec<(f64, f64)> = (0..=samples)
            .map(|k| c - 1.5 * a + 3.0 * a * k as f64 / samples as f64)
            .map(|x| (x, cm.traction(x, q_load)))
            .collect();
        series.push(
            Series::line(
                format!("closed form at Q = {q_load:.4} (Cattaneo–Mindlin)"),
                exact,
            )
            .black(),
        );
    }
    series.extend(profile_series(
        name,
        profiles,
        |x| (x - c).abs() <= 1.5 * a,
        |r| r.friction_traction,
    ));
    Chart::new(
        format!("{name}: tangential traction against the closed form"),
        "x",
        "traction q",
        false,
        false,
        series,
    )
}

/// One line per mesh of `PROFILE_SOLVER`'s profiles of scene `name`: the
/// column `value` at the nodes whose x is in `window`.
fn profile_series(
    name: &str,
    profiles: &[(String, Vec<ProfileRow>)],
    window: impl Fn(f64) -> bool,
    value: impl Fn(&ProfileRow) -> f64,
) -> Vec<Series> {
    let prefix = format!("profiles/{name}_h");
    let suffix = format!("_{PROFILE_SOLVER}.csv");
    profiles
        .iter()
        .filter(|(p, _)| p.starts_with(&prefix) && p.ends_with(&suffix))
        .enumerate()
        .map(|(k, (path, profile))| {
            let h = path
                .trim_start_matches(&prefix)
                .split('_')
                .next()
                .unwrap_or("?");
            let points: Vec<(f64, f64)> = profile
                .iter()
                .filter(|r| window(r.x))
                .map(|r| (r.x, value(r)))
                .collect();
            Series::line(format!("{PROFILE_SOLVER}, h = 1/{h}"), points)
                .with_markers()
                .colored(k)
        })
        .collect()
}

/// A Cattaneo–Mindlin row of the tangential table: the row and its Q/(μP).
#[derive(Serialize)]
struct TangentialRow<'a> {
    #[serde(flatten)]
    row: &'a VerifyRow,
    load_ratio: f64,
}

/// What the section shows of one scene.
#[derive(Serialize)]
struct SceneFacts<'a> {
    name: &'a str,
    rows: Vec<&'a VerifyRow>,
    /// The rows that carry a tangential force (Cattaneo–Mindlin's).
    tangential: Vec<TangentialRow<'a>>,
    charts: Vec<&'a String>,
}

/// The README section (`templates/verify.md`): what was verified, and a
/// table per scene with its charts.
pub fn section(found: &Verified, charts: &[String]) -> Result<String> {
    let scenes: Vec<SceneFacts> = SCENES
        .iter()
        .map(|&(name, _)| {
            let rows: Vec<&VerifyRow> = found.rows.iter().filter(|r| r.scene == name).collect();
            let tangential = rows
                .iter()
                .filter_map(|&row| {
                    let q = row.tangential_load?;
                    Some(TangentialRow {
                        row,
                        load_ratio: q.abs() / (row.friction * row.load),
                    })
                })
                .collect();
            let prefix = format!("verify_{name}_");
            let charts = charts.iter().filter(|c| c.starts_with(&prefix)).collect();
            SceneFacts {
                name,
                rows,
                tangential,
                charts,
            }
        })
        .collect();
    let meshes: Vec<String> = found.spec.meshes.iter().map(|h| h.to_string()).collect();
    template::render(
        "verify",
        include_str!("../templates/verify.md"),
        template::facts! { meshes, time_limit => found.spec.time_limit, scenes },
    )
}
