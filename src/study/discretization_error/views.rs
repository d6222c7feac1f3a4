//! The discretization error's views: its charts (errors against h with
//! reference slopes), its markdown table and the report's sentences.

use serde::Serialize;

use crate::io::charts::{Chart, Series};
use crate::mechanics::mesh_size::MeshSize;
use crate::study::compare::section::paper_interval;
use crate::study::template;

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

/// A row as the section's table shows it, in numbers (the row itself
/// serializes them as the CSV's text): the zone's start `None` where no
/// zone separates.
#[derive(Serialize)]
pub struct RowView<'a> {
    pub problem: u32,
    pub h: &'a str,
    pub certificate: f64,
    pub l2_error: f64,
    pub l2_rate: f64,
    pub energy_error: f64,
    pub energy_rate: f64,
    pub pressure_error: f64,
    pub pressure_rate: f64,
    pub pressure_l2_error: f64,
    pub pressure_l2_rate: f64,
    pub zone_start: Option<f64>,
    pub zone_start_error: f64,
    pub separated_fraction: f64,
}

impl<'a> From<&'a ErrorRow> for RowView<'a> {
    fn from(r: &'a ErrorRow) -> Self {
        Self {
            problem: r.problem,
            h: &r.h,
            certificate: r.certificate,
            l2_error: r.l2_error,
            l2_rate: r.l2_rate,
            energy_error: r.energy_error,
            energy_rate: r.energy_rate,
            pressure_error: r.pressure_error,
            pressure_rate: r.pressure_rate,
            pressure_l2_error: r.pressure_l2_error,
            pressure_l2_rate: r.pressure_l2_rate,
            zone_start: r.zone_start.is_finite().then_some(r.zone_start),
            zone_start_error: r.zone_start_error,
            separated_fraction: r.separated_fraction,
        }
    }
}

/// The observed orders on a problem's finest pair of meshes: from the
/// coarser `from` to the row `to`.
#[derive(Serialize)]
pub struct Orders<'a> {
    pub from: &'a str,
    pub to: RowView<'a>,
}

/// The largest nodal pressure not settling as h falls ([`unsettled_peak`]).
#[derive(Debug, Serialize)]
pub struct UnsettledPeak {
    pub first_peak: f64,
    pub first_h: String,
    pub last_peak: f64,
    pub last_h: String,
    pub last_x: f64,
    pub reference_peak: f64,
    pub reference_h: String,
    /// The rises of the trailing run that grows, one per halving.
    pub rises: Vec<f64>,
    /// log₂ of the last rise's ratio: the peak grows about as h^−growth.
    pub growth: f64,
    /// The L2 pressure error's order over the last halving, from `before_h`.
    pub l2_order: f64,
    pub before_h: String,
}

/// The separated zone at the paper's h = 1/64 of the problem the paper
/// reports an interval for ([`paper_interval`]: problem 1), against the
/// paper's start and fraction and against the reference mesh's start.
#[derive(Serialize)]
pub struct PapersZone {
    pub h: String,
    pub start: f64,
    pub separated_fraction: f64,
    pub papers_start: f64,
    pub papers_fraction: f64,
    /// |start − the reference's start|.
    pub error: f64,
    /// |start − the paper's start|.
    pub gap: f64,
}

/// What the section says of one problem.
#[derive(Serialize)]
pub struct ProblemFacts<'a> {
    pub problem: u32,
    pub orders: Option<Orders<'a>>,
    pub unsettled: Option<UnsettledPeak>,
    pub zone: Option<PapersZone>,
}

/// The largest nodal pressure when it does not settle as h falls: over the
/// last halvings (at least two) it rises by more each time, where a
/// converging peak rises, or falls, by less and less. The pressure is then
/// unbounded near that point, no maximum error can converge, and the L2
/// error along Γ_K is the one to read.
fn unsettled_peak(of: &[&ErrorRow]) -> Option<UnsettledPeak> {
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
    Some(UnsettledPeak {
        first_peak: first.peak_pressure,
        first_h: first.h.clone(),
        last_peak: last.peak_pressure,
        last_h: last.h.clone(),
        last_x: last.peak_x,
        reference_peak: last.reference_peak_pressure,
        reference_h: last.reference_h.clone(),
        rises: rises[rises.len() - run..].to_vec(),
        growth: (last.peak_pressure / before.peak_pressure).log2(),
        l2_order: last.pressure_l2_rate,
        before_h: before.h.clone(),
    })
}

/// The study's findings per problem, computed from the rows: the observed
/// orders on the finest pair of meshes, a pressure peak that does not
/// settle, and where the zone of the paper's reported interval starts at
/// the paper's h = 1/64 against the reference ([`paper_interval`]).
pub fn findings(rows: &[ErrorRow]) -> Vec<ProblemFacts<'_>> {
    let papers_h = level(6).to_string();
    let paper = paper_interval();
    let mut problems: Vec<u32> = rows.iter().map(|r| r.problem).collect();
    problems.dedup();
    problems
        .into_iter()
        .map(|problem| {
            let of: Vec<&ErrorRow> = rows.iter().filter(|r| r.problem == problem).collect();
            let orders = of
                .last()
                .filter(|r| r.l2_rate.is_finite())
                .map(|&last| Orders {
                    from: &of[of.len() - 2].h,
                    to: RowView::from(last),
                });
            let zone = of
                .iter()
                .find(|r| r.h == papers_h)
                .filter(|r| r.zone_start.is_finite())
                .zip(paper.filter(|p| p.problem == problem))
                .map(|(r, paper)| PapersZone {
                    h: r.h.clone(),
                    start: r.zone_start,
                    separated_fraction: r.separated_fraction,
                    papers_start: paper.start,
                    papers_fraction: paper.fraction,
                    error: r.zone_start_error,
                    gap: (r.zone_start - paper.start).abs(),
                });
            ProblemFacts {
                problem,
                orders,
                unsettled: unsettled_peak(&of),
                zone,
            }
        })
        .collect()
}

/// The section (`templates/discretization_error.md`): the table, the
/// findings and the charts.
pub fn section(rows: &[ErrorRow], reference: &str, charts: &[String]) -> anyhow::Result<String> {
    let solver = rows.first().map_or("", |r| r.solver.as_str());
    let problems = findings(rows);
    let any = problems
        .iter()
        .any(|p| p.orders.is_some() || p.unsettled.is_some() || p.zone.is_some());
    template::render(
        "discretization_error",
        include_str!("../templates/discretization_error.md"),
        template::facts! {
            reference,
            solver,
            multigrid => solver == super::MULTIGRID,
            rows => rows.iter().map(RowView::from).collect::<Vec<_>>(),
            problems,
            findings => any,
            charts,
        },
    )
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
        let unsettled = |peaks: &[f64]| {
            let rows = with_peaks(peaks);
            unsettled_peak(&rows.iter().collect::<Vec<_>>())
        };
        // Problem 3's peaks at 1/32 to 1/256 in the study: the first
        // halving moves the peak to the end of Γ_K without a rise.
        let u = unsettled(&[62.7, 62.7, 65.2, 72.0]).expect("reported");
        assert_eq!((u.first_h.as_str(), u.last_h.as_str()), ("1/32", "1/128"));
        assert_eq!(
            (u.first_peak, u.last_peak, u.reference_peak),
            (62.7, 72.0, 95.0)
        );
        assert_eq!(u.rises.len(), 2);
        assert!((u.rises[0] - 2.5).abs() < 1e-12 && (u.rises[1] - 6.8).abs() < 1e-12);
        assert!((u.growth - (72.0f64 / 65.2).log2()).abs() < 1e-15);
        assert_eq!((u.l2_order, u.before_h.as_str()), (0.6, "1/64"));
        // Converging: rises of 2, 1, 0.5.
        assert!(unsettled(&[52.0, 54.0, 55.0, 55.5]).is_none());
        // Nor is one whose last rise is smaller, or that stops.
        assert!(unsettled(&[62.7, 65.2, 72.0, 75.0]).is_none());
        assert!(unsettled(&[62.7, 65.2, 72.0, 72.0]).is_none());
    }

    /// The template renders every fact: the orders, the unsettled peak with
    /// its rises, the paper's zone with the verdict the numbers give, a
    /// missing zone as `none`, and no blank lines inside the table.
    #[test]
    fn the_section_renders_the_facts() {
        let mut rows = vec![
            ErrorRow {
                peak_pressure: 62.7,
                ..row("1/16", 0.1)
            },
            ErrorRow {
                peak_pressure: 65.2,
                zone_start: f64::NAN,
                ..row("1/32", 0.05)
            },
            ErrorRow {
                peak_pressure: 72.0,
                ..row("1/64", 0.025)
            },
        ];
        rows[0].l2_rate = f64::NAN;
        let s = section(&rows, "1/256", &["discretization_error_p1".into()]).unwrap();
        assert!(
            s.contains("observed orders 2.00 (L2), 1.00 (energy)"),
            "{s}"
        );
        assert!(
            s.contains("rising by more over each halving (2.5, 6.8)"),
            "{s}"
        );
        assert!(s.contains("| 1 | 1/32 | 2.50e-3 |"), "{s}");
        assert!(s.contains("| none | 5.00e-2 | 20.00% |"), "{s}");
        // 0.8 against the paper's 0.81 is 1e-2 away; the reference's 2.5e-2.
        assert!(
            s.contains("the separated zone starts at 0.8000 (20.0% of Γ_K; the paper: 0.81, 19%)"),
            "{s}"
        );
        assert!(
            s.contains("the mesh can explain the difference (1.0e-2)"),
            "{s}"
        );
        assert!(!s.contains("|\n\n|"), "{s}");
        assert!(s.ends_with("slope is the observed order.*\n\n"), "{s:?}");
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
