//! The benchmark's charts of time against the number of unknowns: one
//! series per solver with its fitted slope (only through certified runs,
//! and only from three points on), one factorization for scale.

use contactlab_solvers::registry;

use crate::io::charts::{Chart, Series};
use crate::study::bench::PerfRow;

/// The two families the performance charts are split into, so that each
/// legend stays readable: the solvers that factor a matrix (their memory
/// grows as n log n, `Entry::memory`) and the iterative ones.
const FAMILIES: [(&str, &str, bool); 2] = [
    ("factored", "solvers that factor a matrix", true),
    ("iterative", "iterative solvers", false),
];

/// Time against unknowns (log-log), one series per solver with its fitted
/// slope, and one factorization for scale: per law, one chart per family.
pub fn performance_charts(rows: &[PerfRow]) -> Vec<(String, Chart)> {
    let mut out = Vec::new();
    for what in ["coulomb", "given_friction"] {
        for (tag, family, factors) in FAMILIES {
            out.push(chart(rows, what, tag, family, factors));
        }
    }
    out
}

/// One law's chart of one family.
fn chart(rows: &[PerfRow], what: &str, tag: &str, family: &str, factors: bool) -> (String, Chart) {
    {
        let mut series = Vec::new();
        let factor: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.what == "factorization")
            .map(|r| (r.unknowns as f64, r.median_seconds))
            .collect();
        for e in registry::solvers()
            .into_iter()
            .filter(|e| (e.memory.per_unknown_log2 > 0.0) == factors)
        {
            let here = |certified: bool| -> Vec<(f64, f64)> {
                rows.iter()
                    .filter(|r| {
                        r.solver == e.name && r.what == what && r.median_seconds.is_finite()
                    })
                    .filter(|r| (r.status == "converged") == certified)
                    .map(|r| (r.unknowns as f64, r.median_seconds))
                    .collect()
            };
            // The slope is fitted through certified runs only: a run stopped
            // by the time limit or refused by the certificate is drawn as a
            // cross and never bends the fit.
            let (certified, failed) = (here(true), here(false));
            if !certified.is_empty() {
                series.push(
                    Series::line(
                        format!("{} ({})", e.name, slope_label(&certified)),
                        certified,
                    )
                    .with_markers()
                    .of_solver(e.name),
                );
            }
            if !failed.is_empty() {
                series.push(
                    Series::line(format!("{}: not certified", e.name), failed)
                        .failed()
                        .of_solver(e.name),
                );
            }
        }
        series.push(
            Series::line(
                format!(
                    "best factorization + solve, faster of 1 and 2 threads ({})",
                    slope_label(&factor)
                ),
                factor,
            )
            .dashed()
            .black(),
        );
        let title = if what == "coulomb" {
            format!("Whole Coulomb problem, {family}: time against unknowns (problem 1)")
        } else {
            format!("Given-friction subproblem, {family}: time against unknowns (problem 1)")
        };
        (
            format!("performance_{what}_{tag}"),
            Chart {
                title,
                x_label: "unknowns".into(),
                y_label:
                    "median time [s] (solvers one thread, factorization two; large meshes once)"
                        .into(),
                log_x: true,
                log_y: true,
                series,
                y_resolution: None,
                x_ticks: None,
            },
        )
    }
}

/// A fitted slope for a legend, only through at least
/// [`MIN_POINTS_FOR_SLOPE`] points (two points always give a line).
pub fn slope_label(points: &[(f64, f64)]) -> String {
    match fit_slope(points) {
        Some(s) if points.len() >= MIN_POINTS_FOR_SLOPE => format!("slope {s:.2}"),
        _ => format!("no slope: {} points", points.len()),
    }
}

/// The fewest points a slope in a legend is fitted through.
pub const MIN_POINTS_FOR_SLOPE: usize = 3;

/// Least-squares slope of log y against log x.
pub fn fit_slope(points: &[(f64, f64)]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}
