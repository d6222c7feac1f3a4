//! The discretization error's views: its charts (errors against h with
//! reference slopes), its markdown table and the report's sentences.

use crate::io::charts::{Chart, Series};
use crate::mechanics::mesh_size::MeshSize;

use super::{ErrorRow, level};

/// Errors against h on log–log axes, one chart per problem.
pub fn charts(rows: &[ErrorRow]) -> Vec<(String, Chart)> {
    let mut problems: Vec<u32> = rows.iter().map(|r| r.problem).collect();
    problems.dedup();
    problems
        .into_iter()
        .map(|problem| {
            let of = |f: &dyn Fn(&ErrorRow) -> f64| -> Vec<(f64, f64)> {
                rows.iter()
                    .filter(|r| r.problem == problem)
                    .filter_map(|r| {
                        let h = r.h.parse::<MeshSize>().ok()?.h();
                        let y = f(r);
                        (y.is_finite() && y > 0.0).then_some((h, y))
                    })
                    .collect()
            };
            let reference = rows
                .iter()
                .find(|r| r.problem == problem)
                .map_or(String::new(), |r| r.reference_h.clone());
            let (l2, energy) = (of(&|r| r.l2_error), of(&|r| r.energy_error));
            let mut series = vec![
                Series::line("displacement, L2", l2.clone()).with_markers(),
                Series::line("displacement, energy norm", energy.clone()).with_markers(),
                Series::line("pressure, max on Γ_K", of(&|r| r.pressure_error)).with_markers(),
                Series::line("pressure, L2 on Γ_K", of(&|r| r.pressure_l2_error)).with_markers(),
                Series::line("start of the separated zone", of(&|r| r.zone_start_error))
                    .with_markers(),
            ];
            // Reference slopes through the coarsest point of the error each
            // order is expected of (P1 elements on a smooth solution: O(h) in
            // the energy norm, O(h²) in L2; contact may lower both).
            series.extend(guide("O(h) reference slope", &energy, 1).map(|s| s.black()));
            series.extend(guide("O(h²) reference slope", &l2, 2).map(|s| s.colored(7)));
            let mut meshes: Vec<(f64, String)> = rows
                .iter()
                .filter(|r| r.problem == problem)
                .filter_map(|r| Some((r.h.parse::<MeshSize>().ok()?.h(), r.h.clone())))
                .collect();
            meshes.dedup_by(|a, b| a.1 == b.1);
            (
                format!("discretization_error_p{problem}"),
                Chart::new(
                    format!("Discretization error, problem {problem}, against h = {reference}"),
                    "h (a tick at each mesh)",
                    "relative error (zone start: absolute)",
                    true,
                    true,
                    series,
                )
                .with_x_ticks(meshes),
            )
        })
        .collect()
}

/// A dashed line of slope `order` on log–log axes through the point of
/// `points` at the largest h, over their range of h; none without points.
fn guide(name: &str, points: &[(f64, f64)], order: i32) -> Option<Series> {
    let &(h0, e0) = points.iter().max_by(|a, b| a.0.total_cmp(&b.0))?;
    let h1 = points.iter().map(|p| p.0).fold(h0, f64::min);
    let at = |h: f64| (h, e0 * (h / h0).powi(order));
    Some(Series::line(name, vec![at(h1), at(h0)]).dashed())
}

/// A Markdown table of the rows.
pub fn markdown(rows: &[ErrorRow]) -> String {
    let num = |x: f64| {
        if x.is_finite() {
            format!("{x:.2e}")
        } else {
            "–".into()
        }
    };
    let rate = |x: f64| {
        if x.is_finite() {
            format!("{x:.2}")
        } else {
            "–".into()
        }
    };
    let mut out = String::from(
        "| problem | h | L2 error | rate | energy error | rate | pressure error (max) | rate | pressure error (L2) | rate | zone start | its error | separated | certificate |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        out.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2}% | {} |\n",
            r.problem,
            r.h,
            num(r.l2_error),
            rate(r.l2_rate),
            num(r.energy_error),
            rate(r.energy_rate),
            num(r.pressure_error),
            rate(r.pressure_rate),
            num(r.pressure_l2_error),
            rate(r.pressure_l2_rate),
            if r.zone_start.is_finite() {
                format!("{:.4}", r.zone_start)
            } else {
                "none".into()
            },
            num(r.zone_start_error),
            100.0 * r.separated_fraction,
            num(r.certificate),
        ));
    }
    out
}

/// A sentence when the largest nodal pressure does not settle as h falls:
/// over the last halvings (at least two) it rises by more each time, where
/// a converging peak rises, or falls, by less and less. The pressure is
/// then unbounded near that point, no maximum error can converge, and the
/// L2 error along Γ_K is the one to read.
fn unsettled_peak(problem: u32, of: &[&ErrorRow]) -> Option<String> {
    let rises: Vec<f64> = of
        .windows(2)
        .map(|w| w[1].peak_pressure - w[0].peak_pressure)
        .collect();
    // The rises of the trailing run that grows: positive, each at least
    // the one before.
    let mut run = 0;
    for k in (0..rises.len()).rev() {
        let grows = rises[k] > 0.0 && (k + 1 == rises.len() || rises[k] <= rises[k + 1]);
        if !grows {
            break;
        }
        run += 1;
    }
    if run < 2 {
        return None;
    }
    let first = of[of.len() - 1 - run];
    let (before, last) = (of[of.len() - 2], of[of.len() - 1]);
    let growth = (last.peak_pressure / before.peak_pressure).log2();
    let listed: Vec<String> = rises[rises.len() - run..]
        .iter()
        .map(|d| format!("{d:.1}"))
        .collect();
    Some(format!(
        "- Problem {problem}: the largest nodal pressure does not settle as h falls: from {:.1} at h = {} to {:.1} at {} (x = {:.3}) and {:.1} on the reference {}, rising by more over each halving ({}), about h^−{growth:.2} over the last. The pressure is unbounded there, so its largest nodal error cannot converge (the maximum error column), and its L2 error along Γ_K is the measure to read (order {:.2} from h = {} to {}).",
        first.peak_pressure,
        first.h,
        last.peak_pressure,
        last.h,
        last.peak_x,
        last.reference_peak_pressure,
        last.reference_h,
        listed.join(", "),
        last.pressure_l2_rate,
        before.h,
        last.h
    ))
}

/// Where the paper's problem 1 separates at h = 1/64 (paper, section 5).
pub const PAPERS_ZONE_START: f64 = 0.81;

/// The study's findings as sentences computed from the rows: the observed
/// orders on the finest pair of meshes, and where problem 1's zone starts at
/// the paper's h = 1/64 against the reference (the paper reports 0.81, 19 %).
pub fn findings(rows: &[ErrorRow]) -> String {
    let papers_h = level(6);
    let mut lines = Vec::new();
    let mut problems: Vec<u32> = rows.iter().map(|r| r.problem).collect();
    problems.dedup();
    for problem in problems {
        let of: Vec<&ErrorRow> = rows.iter().filter(|r| r.problem == problem).collect();
        if let Some(last) = of.last().filter(|r| r.l2_rate.is_finite()) {
            lines.push(format!(
                "- Problem {problem}, from h = {} to {}: observed orders {:.2} (L2), {:.2} (energy), {:.2} (pressure, max) and {:.2} (pressure, L2); at h = {} the errors are {:.1e}, {:.1e}, {:.1e} and {:.1e}.",
                of[of.len() - 2].h,
                last.h,
                last.l2_rate,
                last.energy_rate,
                last.pressure_rate,
                last.pressure_l2_rate,
                last.h,
                last.l2_error,
                last.energy_error,
                last.pressure_error,
                last.pressure_l2_error
            ));
        }
        lines.extend(unsettled_peak(problem, &of));
        let at = of.iter().find(|r| r.h == papers_h.to_string());
        if let Some(r) = at.filter(|r| r.zone_start.is_finite() && problem == 1) {
            let gap = (r.zone_start - PAPERS_ZONE_START).abs();
            let verdict = if r.zone_start_error < gap {
                "smaller than its distance from the paper's start: the mesh does not explain the difference"
            } else {
                "as large as its distance from the paper's start: the mesh can explain the difference"
            };
            lines.push(format!(
                "- Problem 1 at the paper's h = {}: the separated zone starts at {:.4} ({:.1}% of Γ_K; the paper: {PAPERS_ZONE_START}, 19%). Its distance from the reference mesh's start, {:.1e}, is {verdict} ({gap:.1e}).",
                r.h,
                r.zone_start,
                100.0 * r.separated_fraction,
                r.zone_start_error
            ));
        }
    }
    lines.join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(h: &str, e: f64) -> ErrorRow {
        ErrorRow {
            problem: 1,
            h: h.into(),
            reference_h: "1/256".into(),
            solver: "newton-coulomb".into(),
            status: "converged".into(),
            certificate: 1e-9,
            l2_error: e * e,
            energy_error: e,
            pressure_error: e,
            pressure_l2_error: e,
            peak_pressure: 60.0,
            peak_x: 0.0,
            reference_peak_pressure: 60.0,
            zone_start: 0.8,
            zone_start_error: e,
            separated_fraction: 0.2,
            l2_rate: 2.0,
            energy_rate: 1.0,
            pressure_rate: 1.0,
            pressure_l2_rate: 1.0,
        }
    }

    /// A peak that rises by more and more is reported, with the L2 order;
    /// one that rises by less and less (converging), or falls, is not.
    #[test]
    fn an_unbounded_pressure_is_reported_and_a_converging_one_is_not() {
        let with_peaks = |peaks: &[f64]| -> Vec<ErrorRow> {
            let hs = ["1/16", "1/32", "1/64", "1/128"];
            peaks
                .iter()
                .zip(hs)
                .map(|(&p, h)| ErrorRow {
                    peak_pressure: p,
                    peak_x: 1.0,
                    reference_peak_pressure: 95.0,
                    pressure_l2_rate: 0.6,
                    ..row(h, 0.1)
                })
                .collect()
        };
        // Problem 3's peaks at 1/32 to 1/256 in the study: the first
        // halving moves the peak to the end of Γ_K without a rise.
        let singular = findings(&with_peaks(&[62.7, 62.7, 65.2, 72.0]));
        assert!(singular.contains("does not settle"), "{singular}");
        assert!(
            singular.contains("order 0.60 from h = 1/64 to 1/128"),
            "{singular}"
        );
        assert!(
            singular.contains(
                "from 62.7 at h = 1/32 to 72.0 at 1/128 (x = 1.000) and 95.0 on the reference 1/256, rising by more over each halving (2.5, 6.8)"
            ),
            "{singular}"
        );
        // Converging: rises of 2, 1, 0.5.
        let converging = findings(&with_peaks(&[52.0, 54.0, 55.0, 55.5]));
        assert!(!converging.contains("does not settle"), "{converging}");
        // Nor is one whose last rise is smaller, or that stops.
        let slowing = findings(&with_peaks(&[62.7, 65.2, 72.0, 75.0]));
        assert!(!slowing.contains("does not settle"), "{slowing}");
        let flat = findings(&with_peaks(&[62.7, 65.2, 72.0, 72.0]));
        assert!(!flat.contains("does not settle"), "{flat}");
    }

    #[test]
    fn the_chart_has_reference_slopes_and_a_tick_at_each_mesh() {
        let rows = [row("1/16", 0.1), row("1/32", 0.05), row("1/64", 0.025)];
        let (name, chart) = charts(&rows).remove(0);
        assert_eq!(name, "discretization_error_p1");
        let slope = |label: &str| {
            let s = chart.series.iter().find(|s| s.name == label).unwrap();
            let (a, b) = (s.points[0], s.points[1]);
            (b.1 / a.1).ln() / (b.0 / a.0).ln()
        };
        assert!((slope("O(h) reference slope") - 1.0).abs() < 1e-12);
        assert!((slope("O(h²) reference slope") - 2.0).abs() < 1e-12);
        // Through the coarsest point of the error it is compared with.
        let o2 = chart
            .series
            .iter()
            .find(|s| s.name.starts_with("O(h²)"))
            .unwrap();
        assert!(o2.points.contains(&(1.0 / 16.0, 0.1 * 0.1)));
        let ticks: Vec<String> = chart
            .x_ticks
            .clone()
            .unwrap()
            .into_iter()
            .map(|t| t.1)
            .collect();
        assert_eq!(ticks, ["1/16", "1/32", "1/64"]);
        let svg = chart.to_svg().unwrap();
        for t in &ticks {
            assert!(svg.contains(&format!("\n{t}\n")), "no tick label {t}");
        }
    }
}
