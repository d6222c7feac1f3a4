//! The benchmark's tables and charts, views of its rows (one run's, or the
//! merged rows of several shards): per target accuracy, each solver's
//! success rate, the shifted geometric mean of its time (a failure counts
//! at the time limit), the runs it claimed but the certificate refused, and
//! performance profiles (Dolan & Moré 2002).

use anyhow::Result;
use serde::Serialize;

use crate::io::charts::{Chart, Series};
use crate::io::csv::fixed;
use crate::study::benchmark::BenchmarkRow;
use crate::study::lab::Artifact;
use crate::study::template;

/// The shift of the shifted geometric mean, seconds: times well below it
/// count as about equal (a 1 ms and a 10 ms solve are both fast), so the
/// mean is not ruled by the smallest instances.
pub const SHIFT: f64 = 0.1;

/// One solver at one target accuracy.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    #[serde(serialize_with = "fixed")]
    pub target: f64,
    pub solver: String,
    pub runs: usize,
    pub successes: usize,
    #[serde(serialize_with = "fixed")]
    pub success_rate: f64,
    /// Runs whose solver claimed convergence on an answer the certificate
    /// refused at the target.
    pub claimed_but_failed: usize,
    /// exp(mean log(t + SHIFT)) − SHIFT over all instances, a failure at
    /// the time limit.
    #[serde(serialize_with = "fixed")]
    pub shifted_geometric_mean: f64,
    /// The same over the best solver's (1: the best).
    #[serde(serialize_with = "fixed")]
    pub relative_to_best: f64,
}

fn targets(rows: &[BenchmarkRow]) -> Vec<f64> {
    let mut t: Vec<f64> = rows.iter().map(|r| r.target).collect();
    t.sort_by(|a, b| b.total_cmp(a));
    t.dedup();
    t
}

fn solvers(rows: &[BenchmarkRow]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in rows {
        if !out.contains(&r.solver) {
            out.push(r.solver.clone());
        }
    }
    out
}

/// A run's time as the profile and the mean count it: its time if it
/// succeeded, else the time limit (the mean) or infinity (the profile).
/// A failure counts at the limit exactly, also one that ran past it (a
/// Python function, which cannot be interrupted): the report says so.
fn charged(r: &BenchmarkRow) -> f64 {
    if r.success { r.seconds } else { r.time_limit }
}

/// The per-solver summaries at every target.
pub fn summaries(rows: &[BenchmarkRow]) -> Vec<Summary> {
    let mut out = Vec::new();
    for target in targets(rows) {
        let here: Vec<&BenchmarkRow> = rows.iter().filter(|r| r.target == target).collect();
        let mut block: Vec<Summary> = solvers(rows)
            .into_iter()
            .map(|solver| {
                let mine: Vec<&&BenchmarkRow> =
                    here.iter().filter(|r| r.solver == solver).collect();
                let successes = mine.iter().filter(|r| r.success).count();
                let sgm = (mine.iter().map(|r| (charged(r) + SHIFT).ln()).sum::<f64>()
                    / mine.len().max(1) as f64)
                    .exp()
                    - SHIFT;
                Summary {
                    target,
                    solver,
                    runs: mine.len(),
                    successes,
                    success_rate: successes as f64 / mine.len().max(1) as f64,
                    claimed_but_failed: mine.iter().filter(|r| r.claimed_but_failed).count(),
                    shifted_geometric_mean: sgm,
                    relative_to_best: f64::NAN,
                }
            })
            .collect();
        let best = block
            .iter()
            .map(|s| s.shifted_geometric_mean + SHIFT)
            .fold(f64::INFINITY, f64::min);
        for s in &mut block {
            s.relative_to_best = (s.shifted_geometric_mean + SHIFT) / best;
        }
        out.extend(block);
    }
    out
}

/// Performance profiles, one chart per target: ρ_s(τ), the fraction of
/// instances that solver s solves within τ times the fastest solver's time
/// on each.
pub fn profile_charts(rows: &[BenchmarkRow]) -> Vec<(String, Chart)> {
    let mut out = Vec::new();
    for target in targets(rows) {
        let here: Vec<&BenchmarkRow> = rows.iter().filter(|r| r.target == target).collect();
        let mut instances: Vec<&str> = here.iter().map(|r| r.instance.as_str()).collect();
        instances.sort();
        instances.dedup();
        let best = |inst: &str| {
            here.iter()
                .filter(|r| r.instance == inst && r.success)
                .map(|r| r.seconds.max(1e-9))
                .fold(f64::INFINITY, f64::min)
        };
        let bests: Vec<(&str, f64)> = instances.iter().map(|i| (*i, best(i))).collect();
        let mut ratios_of = Vec::new();
        for solver in solvers(rows) {
            let mut ratios: Vec<f64> = bests
                .iter()
                .map(|(inst, b)| {
                    here.iter()
                        .find(|r| r.instance == *inst && r.solver == solver)
                        .filter(|r| r.success)
                        .map_or(f64::INFINITY, |r| r.seconds.max(1e-9) / b)
                })
                .collect();
            ratios.sort_by(f64::total_cmp);
            ratios_of.push((solver, ratios));
        }
        let tau_max = ratios_of
            .iter()
            .flat_map(|(_, r)| r.iter().copied().filter(|x| x.is_finite()))
            .fold(1.0f64, f64::max)
            * 1.5;
        let n = instances.len().max(1) as f64;
        let series = ratios_of
            .iter()
            .map(|(solver, ratios)| {
                // A step function: up by 1/n at each ratio.
                let mut pts = vec![(1.0, 0.0)];
                let mut solved = 0usize;
                for &r in ratios.iter().filter(|r| r.is_finite()) {
                    let last = solved as f64 / n;
                    solved += 1;
                    pts.push((r.max(1.0), last));
                    pts.push((r.max(1.0), solved as f64 / n));
                }
                pts.push((tau_max, solved as f64 / n));
                Series::line(solver.clone(), pts).of_solver(solver)
            })
            .collect();
        out.push((
            format!("benchmark_profile_{}", tag(target)),
            Chart::new(
                format!(
                    "Performance profile at target accuracy {target:.0e} ({} instances)",
                    instances.len()
                ),
                "τ: time within τ × the fastest solver's on the instance",
                "fraction of instances solved (certified)",
                true,
                false,
                series,
            ),
        ));
    }
    out
}

/// `1e-4` as a file-name tag: `1e-4`.
pub fn tag(target: f64) -> String {
    format!("{target:.0e}")
}

/// The LaTeX table at one target: the Markdown table's columns, headed
/// short enough to fit a page's width and defined in the caption.
pub fn latex(summaries: &[Summary], target: f64) -> anyhow::Result<String> {
    use crate::io::latex::{Tabular, text};
    let caption = crate::study::template::render(
        "benchmark_caption",
        include_str!("../templates/benchmark_caption.tex"),
        crate::study::template::facts! { target, shift => SHIFT },
    )?;
    let mut t = Tabular::new(
        &caption,
        &format!("benchmark_{}", tag(target)),
        vec![
            "solver".into(),
            "solved".into(),
            "refused".into(),
            "SGM (s)".into(),
            "ratio".into(),
        ],
    );
    for x in summaries.iter().filter(|x| x.target == target) {
        t.row(vec![
            text(&x.solver),
            text(&format!(
                "{}/{} ({:.0}%)",
                x.successes,
                x.runs,
                100.0 * x.success_rate
            )),
            x.claimed_but_failed.to_string(),
            format!("{:.3}", x.shifted_geometric_mean),
            format!("{:.2}", x.relative_to_best),
        ]);
    }
    Ok(t.render())
}

/// The views of `rows`: benchmark_summary.csv, a LaTeX table per target,
/// benchmark.md, and the performance profiles.
pub fn artifacts(rows: &[BenchmarkRow]) -> Result<Vec<Artifact>> {
    let sums = summaries(rows);
    let mut out = vec![Artifact::csv("benchmark_summary.csv", &sums, &[])?];
    for t in targets(rows) {
        out.push(Artifact::text(
            &format!("benchmark_{}.tex", tag(t)),
            &latex(&sums, t)?,
        ));
    }
    out.push(Artifact::text("benchmark.md", &report(rows)?));
    out.extend(Artifact::charts(profile_charts(rows)));
    Ok(out)
}

/// The fastest solver at a target and the next, with how much slower it
/// is in shifted geometric mean.
#[derive(Serialize)]
struct Fastest<'a> {
    first: &'a Summary,
    second: &'a Summary,
    slower: f64,
}

/// One target of the report: the table, the winner, the runs claimed but
/// refused.
#[derive(Serialize)]
struct TargetFacts<'a> {
    target: f64,
    summaries: Vec<&'a Summary>,
    fastest: Option<Fastest<'a>>,
    refused: Vec<&'a BenchmarkRow>,
}

/// The benchmark's report (`templates/benchmark_report.md`): per target
/// the table, which solver wins by how much, and the runs claimed but
/// refused.
pub fn report(rows: &[BenchmarkRow]) -> Result<String> {
    let sums = summaries(rows);
    let mut instances: Vec<&str> = rows.iter().map(|r| r.instance.as_str()).collect();
    instances.sort();
    instances.dedup();
    let targets: Vec<TargetFacts> = targets(rows)
        .into_iter()
        .map(|t| {
            let summaries: Vec<&Summary> = sums.iter().filter(|x| x.target == t).collect();
            let mut ranked = summaries.clone();
            ranked.sort_by(|a, b| a.relative_to_best.total_cmp(&b.relative_to_best));
            let fastest = match ranked.as_slice() {
                [first, second, ..] => Some(Fastest {
                    first,
                    second,
                    slower: second.relative_to_best / first.relative_to_best,
                }),
                _ => None,
            };
            TargetFacts {
                target: t,
                summaries,
                fastest,
                refused: rows
                    .iter()
                    .filter(|r| r.target == t && r.claimed_but_failed)
                    .collect(),
            }
        })
        .collect();
    template::render(
        "benchmark_report",
        include_str!("../templates/benchmark_report.md"),
        template::facts! {
            instances => instances.len(),
            solvers => solvers(rows).len(),
            runs => rows.len(),
            limit => rows.iter().map(|r| r.time_limit).fold(0.0f64, f64::max),
            shift => SHIFT,
            targets,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(solver: &str, success: bool, seconds: f64) -> BenchmarkRow {
        BenchmarkRow {
            instance: "p".into(),
            family: "paper".into(),
            h: "1/8".into(),
            unknowns: 158,
            friction_coefficient: 0.5,
            solver: solver.into(),
            target: 1e-4,
            status: if success { "converged" } else { "time_limit" }.into(),
            solver_status: "converged".into(),
            success,
            claimed_but_failed: false,
            certificate: 1e-6,
            failing: String::new(),
            seconds,
            time_limit: 10.0,
            work: 0,
            detail: String::new(),
        }
    }

    /// A failure counts at the time limit exactly, as the report says,
    /// also one that ran past it (a Python function is not interrupted):
    /// before, a run of 100 s against a limit of 10 counted as 100 s.
    #[test]
    fn a_failure_counts_at_the_time_limit_even_past_it() {
        let rows = [
            row("a", true, 1.0),
            row("a", false, 100.0),
            row("b", false, 10.0),
            row("b", true, 1.0),
        ];
        let s = summaries(&rows);
        let mean = |name: &str| {
            s.iter()
                .find(|x| x.solver == name)
                .unwrap()
                .shifted_geometric_mean
        };
        assert_eq!(mean("a"), mean("b"));
        let expected = ((1.0 + SHIFT) * (10.0 + SHIFT)).sqrt() - SHIFT;
        assert!(
            (mean("a") - expected).abs() < 1e-12,
            "{} vs {expected}",
            mean("a")
        );
    }
}
