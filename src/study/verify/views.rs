//! The verification's views: the computed pressure profiles over the
//! closed form, the errors against h, and its README section.

use anyhow::Result;
use contactlab_solvers::Status;

use crate::io::charts::{Chart, Series, solver_color};
use crate::mechanics::contact_zone::ProfileRow;

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

fn opt(x: Option<f64>) -> String {
    x.map_or("–".to_string(), |v| format!("{v:.2e}"))
}

/// The README section: what was verified, and a table per scene.
pub fn section(found: &Verified, charts: &[String]) -> String {
    // Its own heading: without it the scenes' tables read as the section
    // before's (a run's README had them under the last tuning map).
    let mut md = String::from("## Verification against closed forms: the classical scenes\n\n");
    md.push_str(&format!(
        "Each classical scene of `scenes/` at h = {}, every registered solver at its defaults, the Coulomb law (frictionless, 𝓕 = 0, but for Cattaneo–Mindlin's 0.3), a time limit of {:.0} s a solve. Errors are those of the nodal pressures against the half-plane closed form: L2 relative over Γ_K (the punch: over |x − x₀| ≤ 0.8 b, away from its singular edges), max over p₀. `order` is log₂ of the L2 error's fall from the next coarser mesh. The bodies are 16 half-widths wide on either side and deep: the closed forms, for half-planes, differ from them by a finite-size error, the floor the errors fall towards.\n\n",
        found.spec.meshes.iter().map(|h| h.to_string()).collect::<Vec<_>>().join(", "),
        found.spec.time_limit
    ));
    for (name, _) in SCENES {
        md.push_str(&format!("### {name}\n\n"));
        md.push_str("| h | solver | status | L2 error | order | max error | half-width (exact) | p₀ (exact) | seconds |\n|---|---|---|---|---|---|---|---|---|\n");
        for r in found.rows.iter().filter(|r| r.scene == name) {
            md.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} | {} ({:.4e}) | {} ({:.4e}) | {} |\n",
                r.h,
                r.solver,
                r.status,
                opt(r.l2_error),
                r.l2_order.map_or("–".to_string(), |o| format!("{o:.2}")),
                opt(r.max_error),
                opt(r.half_width),
                r.half_width_exact,
                opt(r.p0),
                r.p0_exact,
                r.seconds.map_or("–".to_string(), |s| format!("{s:.2}")),
            ));
        }
        md.push('\n');
        if found
            .rows
            .iter()
            .any(|r| r.scene == name && r.tangential_load.is_some())
        {
            md.push_str("The tangential side: the force Q the contact carries, the stick half-width c against a √(1 − Q/(μP)), the traction's errors against Cattaneo–Mindlin's at that Q (L2 relative over Γ_K, max over μp₀), and its odd part about x₀ over ‖q‖ (the closed form is even: this part is what the finite bodies, sheared from their sides, add, apart from the discretization).\n\n| h | solver | Q | Q/(μP) | c (exact) | traction L2 error | traction max error | odd part |\n|---|---|---|---|---|---|---|---|\n");
            for r in found.rows.iter().filter(|r| r.scene == name) {
                let Some(q) = r.tangential_load else { continue };
                md.push_str(&format!(
                    "| {} | {} | {:.4} | {:.4} | {} ({}) | {} | {} | {} |\n",
                    r.h,
                    r.solver,
                    q,
                    q.abs() / (r.friction * r.load),
                    opt(r.stick_half_width),
                    opt(r.stick_half_width_exact),
                    opt(r.traction_l2_error),
                    opt(r.traction_max_error),
                    opt(r.traction_asymmetry),
                ));
            }
            md.push('\n');
        }
        for c in charts
            .iter()
            .filter(|c| c.starts_with(&format!("verify_{name}_")))
        {
            md.push_str(&crate::study::lab::chart_markdown(
                c,
                if c.ends_with("_pressure") {
                    "The computed contact pressure at each mesh over the closed form: the profile should close on it as h falls."
                } else if c.ends_with("_traction") {
                    "The computed tangential traction at each mesh over Cattaneo–Mindlin's at the finest mesh's Q: the stick zone in the middle, μp in the slip zones at its sides."
                } else {
                    "The L2 error of each solver's certified pressure against h: it falls with h until the finite-size floor."
                },
            ));
        }
    }
    md
}
