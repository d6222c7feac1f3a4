//! The comparison's charts: contact-zone profiles (the paper's figures
//! 2-5) and convergence histories.

use contactlab_solvers::registry;

use crate::coulomb::fixed_point::STAGE;
use crate::io::charts::{Chart, Panels, Series};
use crate::mechanics::contact_zone::ProfileRow;
use crate::study::runner::Measured;

/// The profile of one solver with and without friction.
pub struct ProfilePair<'a> {
    pub solver: &'a str,
    pub friction: &'a [ProfileRow],
    pub frictionless: &'a [ProfileRow],
}

/// The paper's figures 2-5 for one problem: both bodies' vertical
/// displacements, the jump, the multiplier l, and a zoom on the separation
/// zone. `lines` (the oracle) is drawn as lines, friction solid and
/// frictionless dashed; `dots` (the paper's method) as dots on top, with
/// friction: every solver's profile is in `profiles/`, and these two agree
/// to the plotted resolution. Values below 1e-9 of the largest displacement
/// (or pressure) are round-off, drawn as zero.
pub fn profile_charts(
    problem: u32,
    h: &str,
    lines: &ProfilePair<'_>,
    dots: Option<&ProfilePair<'_>>,
    zoom_from: f64,
) -> Vec<(String, Chart)> {
    let col = |rows: &[ProfileRow], f: fn(&ProfileRow) -> f64, from: f64| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|r| r.x >= from)
            .map(|r| (r.x, f(r)))
            .collect()
    };
    let largest = |f: fn(&ProfileRow) -> f64| {
        [lines.friction, lines.frictionless]
            .iter()
            .flat_map(|rows| rows.iter().map(f))
            .fold(0.0f64, |m, v| m.max(v.abs()))
    };
    let u_scale = largest(|r| r.u2_lower).max(largest(|r| r.u2_upper));
    let p_scale = largest(|r| r.pressure);
    // One metric: series of the oracle (friction, frictionless) and the
    // paper's method (friction).
    let curves = |f: fn(&ProfileRow) -> f64, from: f64, label: &str| -> Vec<Series> {
        let mut v = vec![
            Series::line(
                format!("{label}friction, {}", lines.solver),
                col(lines.friction, f, from),
            )
            .of_solver(lines.solver),
            Series::line(
                format!("{label}no friction, {}", lines.solver),
                col(lines.frictionless, f, from),
            )
            .dashed()
            .of_solver(lines.solver),
        ];
        if let Some(d) = dots {
            v.push(
                Series::line(
                    format!("{label}friction, {}", d.solver),
                    col(d.friction, f, from),
                )
                .scatter()
                .of_solver(d.solver),
            );
        }
        v
    };
    // Both bodies with friction: the lower body solid, the upper dashed,
    // the paper's method as dots on both.
    let lower = |r: &ProfileRow| r.u2_lower;
    let upper = |r: &ProfileRow| r.u2_upper;
    let mut bodies = vec![
        Series::line(
            format!("lower u'₂, {}", lines.solver),
            col(lines.friction, lower, 0.0),
        )
        .of_solver(lines.solver),
        Series::line(
            format!("upper u''₂, {}", lines.solver),
            col(lines.friction, upper, 0.0),
        )
        .dashed()
        .of_solver(lines.solver),
    ];
    if let Some(d) = dots {
        for (body, f) in [
            ("lower u'₂", lower as fn(&ProfileRow) -> f64),
            ("upper u''₂", upper),
        ] {
            bodies.push(
                Series::line(format!("{body}, {}", d.solver), col(d.friction, f, 0.0))
                    .scatter()
                    .of_solver(d.solver),
            );
        }
    }
    // The separation zone, the oracle with and without friction: lower
    // body lines (solid, dashed), upper body dots (with a line: friction).
    let zoom = vec![
        Series::line(
            format!("lower, friction, {}", lines.solver),
            col(lines.friction, lower, zoom_from),
        )
        .of_solver(lines.solver),
        Series::line(
            format!("lower, no friction, {}", lines.solver),
            col(lines.frictionless, lower, zoom_from),
        )
        .dashed()
        .of_solver(lines.solver),
        Series::line(
            format!("upper, friction, {}", lines.solver),
            col(lines.friction, upper, zoom_from),
        )
        .with_markers()
        .of_solver(lines.solver),
        Series::line(
            format!("upper, no friction, {}", lines.solver),
            col(lines.frictionless, upper, zoom_from),
        )
        .scatter()
        .of_solver(lines.solver),
    ];
    let x = "x along Γ_K";
    let resolution_u = 1e-9 * u_scale;
    vec![
        (
            format!("profile_p{problem}_displacement"),
            Chart::new(
                format!("Vertical displacements on Γ_K with friction, problem {problem}, h = {h}"),
                x,
                "u₂ [length]",
                false,
                false,
                bodies,
            )
            .with_y_resolution(resolution_u),
        ),
        (
            format!("profile_p{problem}_zoom"),
            Chart::new(
                format!("Separation zone, problem {problem}, h = {h}: with and without friction"),
                x,
                "u₂ [length]",
                false,
                false,
                zoom,
            )
            .with_y_resolution(resolution_u),
        ),
        (
            format!("profile_p{problem}_jump"),
            Chart::new(
                format!("Jump [u] = u'₂ − u''₂ on Γ_K, problem {problem}, h = {h}"),
                x,
                "[u] [length]",
                false,
                false,
                curves(|r| r.jump, 0.0, ""),
            )
            .with_y_resolution(resolution_u),
        ),
        (
            format!("profile_p{problem}_pressure"),
            Chart::new(
                format!("Multiplier l (contact pressure), problem {problem}, h = {h}"),
                x,
                "l [force/length]",
                false,
                false,
                curves(|r| r.pressure, 0.0, ""),
            )
            .with_y_resolution(1e-9 * p_scale),
        ),
    ]
}

/// Residual against iteration for each solver's Coulomb solve, from a
/// comparison's measured trials of one problem: the chart that
/// shows the outer loop: the friction fixed point's max|Δg| (a direct
/// Coulomb solver's own steps stand in its place); the inner loops are
/// small multiples of their own ([`inner_convergence_panels`]).
pub fn convergence_charts(problem: u32, h: &str, measured: &[Measured]) -> Vec<(String, Chart)> {
    let mut outer = Vec::new();
    for m in measured
        .iter()
        .filter(|m| m.trial.law == contactlab_solvers::Law::Coulomb)
    {
        let solver = m.trial.solver.name;
        let direct =
            registry::by_name(solver).is_some_and(|e| e.solves(contactlab_solvers::Law::Coulomb));
        let stages: Vec<&str> = registry::by_name(solver)
            .map(|e| {
                e.stages
                    .iter()
                    .filter(|s| s.history)
                    .map(|s| s.name)
                    .collect()
            })
            .unwrap_or_default();
        let points = |stage: &str| -> Vec<(f64, f64)> {
            m.history
                .iter()
                .filter(|p| p.stage == stage)
                .enumerate()
                .map(|(i, p)| ((i + 1) as f64, p.residual))
                .collect()
        };
        let friction = points(STAGE);
        if !friction.is_empty() {
            outer.push(
                Series::line(format!("{solver}: friction max|Δg|"), friction)
                    .with_markers()
                    .of_solver(solver),
            );
        }
        for stage in stages {
            let pts = points(stage);
            if pts.is_empty() {
                continue;
            }
            let line = Series::line(format!("{solver}: {stage}"), pts).of_solver(solver);
            // The inner loops are drawn apart ([`inner_convergence_panels`]).
            if direct {
                outer.push(line.with_markers());
            }
        }
        if direct && m.history.is_empty() {
            // Nothing to draw, but said in the legend rather than left out.
            outer.push(
                Series::line(
                    format!("{solver}: no iterations (its start passed its test)"),
                    Vec::new(),
                )
                .of_solver(solver),
            );
        }
    }
    vec![(
        format!("convergence_p{problem}"),
        Chart::new(
            format!("Convergence of the Coulomb problem {problem}, h = {h}: the outer loop"),
            "iteration (friction fixed point; a direct solver's own steps)",
            "residual: max|Δg| (or the solver's own)",
            false,
            true,
            outer,
        ),
    )]
}

/// The inner loops' histories as small multiples, one panel per solver:
/// on one axis nine histories from ten to ten thousand iterations could
/// not be told apart.
pub fn inner_convergence_panels(problem: u32, h: &str, measured: &[Measured]) -> Panels {
    let mut panels = Vec::new();
    for m in measured
        .iter()
        .filter(|m| m.trial.law == contactlab_solvers::Law::Coulomb)
    {
        let solver = m.trial.solver.name;
        let Some(entry) = registry::by_name(solver) else {
            continue;
        };
        if entry.solves(contactlab_solvers::Law::Coulomb) {
            continue;
        }
        let series: Vec<Series> = entry
            .stages
            .iter()
            .filter(|s| s.history)
            .filter_map(|stage| {
                let pts: Vec<(f64, f64)> = m
                    .history
                    .iter()
                    .filter(|p| p.stage == stage.name)
                    .enumerate()
                    .map(|(i, p)| ((i + 1) as f64, p.residual))
                    .collect();
                (!pts.is_empty()).then(|| {
                    Series::line(format!("{solver}: {}", stage.name), pts).of_solver(solver)
                })
            })
            .collect();
        if series.is_empty() {
            continue;
        }
        let stage = entry.work_stage;
        panels.push(Chart::new(
            format!("{solver} ({stage})"),
            "inner iteration, over the whole run",
            "residual",
            true,
            true,
            series,
        ));
    }
    Panels {
        title: format!(
            "Convergence histories of the inner loops, Coulomb problem {problem}, h = {h}: each solver's residual over all its friction iterations"
        ),
        panels,
        columns: 3,
    }
}
