//! The speed measurements' section of a run's README (`templates/bench.md`):
//! the goals, the memory, the paper's method at equal accuracy, the speed
//! table and the performance charts.

use anyhow::Result;
use contactlab_solvers::registry;
use serde::Serialize;

use crate::study::bench::goals::{BenchOutput, equal_accuracy_markdown, goals_markdown};
use crate::study::bench::set_up::FACTORIZATION;
use crate::study::bench::{exact_bound, memory};
use crate::study::template;

/// The whole section.
pub fn section(bench: &BenchOutput, charts: &[String]) -> Result<String> {
    let performance: Vec<&String> = charts
        .iter()
        .filter(|c| c.starts_with("performance_"))
        .collect();
    let goals = goals_markdown(&bench.goals)?;
    let memory = memory::markdown(&bench.memory, &[])?;
    let exact_bound = exact_bound::markdown(&bench.exact_bound, &bench.rows)?;
    let equal_accuracy = equal_accuracy_markdown(&bench.rows, bench.problem)?;
    let speed = speed_table(&bench.rows)?;
    template::render(
        "bench",
        include_str!("../templates/bench.md"),
        template::facts! {
            goals,
            memory,
            exact_bound,
            equal_accuracy,
            speed,
            charts => performance,
        },
    )
}

/// A cell of the speed table: the run's median seconds (none: not
/// finite, the status is shown instead), its ratio to the factorization,
/// its work units (none: not measured) and its certified status.
#[derive(Serialize)]
struct Cell<'a> {
    seconds: Option<f64>,
    ratio: f64,
    work_units: Option<f64>,
    status: &'a str,
}

/// A line of the speed table: a solver (or the factorization) and its
/// cell on each mesh (none: no run there).
#[derive(Serialize)]
struct Line<'a> {
    name: &'a str,
    factorization: bool,
    cells: Vec<Option<Cell<'a>>>,
}

/// The whole-Coulomb speed table (`templates/bench_speed.md`).
fn speed_table(rows: &[super::PerfRow]) -> Result<String> {
    // Each mesh once, in the order of its first row (later studies revisit
    // meshes).
    let mut meshes: Vec<&str> = Vec::new();
    for r in rows {
        if !meshes.contains(&r.h.as_str()) {
            meshes.push(&r.h);
        }
    }
    let mut names = vec![FACTORIZATION];
    names.extend(registry::names());
    let lines: Vec<Line> = names
        .into_iter()
        .map(|name| Line {
            name,
            factorization: name == FACTORIZATION,
            cells: meshes
                .iter()
                .map(|h| {
                    rows.iter()
                        .find(|r| {
                            r.solver == name
                                && r.h == *h
                                && (r.what == "coulomb" || r.what == "factorization")
                        })
                        .map(|r| Cell {
                            seconds: r.median_seconds.is_finite().then_some(r.median_seconds),
                            ratio: r.ratio_to_factorization,
                            work_units: r.work_units.is_finite().then_some(r.work_units),
                            status: &r.status,
                        })
                })
                .collect(),
        })
        // A solver that ran on no mesh has no row.
        .filter(|l| l.cells.iter().any(Option::is_some))
        .collect();
    template::render(
        "bench_speed",
        include_str!("../templates/bench_speed.md"),
        template::facts! { meshes, lines },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::bench::PerfRow;

    /// The factorization's row is found by the name the benchmark gives it
    /// (it was once empty: the table looked for another name), and a solver
    /// that ran on no mesh has no row.
    #[test]
    fn the_speed_table_has_the_factorization_and_no_empty_row() {
        let mut rows = vec![
            PerfRow::sample("factorization", FACTORIZATION, 100, 0.5, "done"),
            PerfRow::sample("coulomb", "tnnmg", 100, 0.25, "converged"),
        ];
        for r in &mut rows {
            r.h = "1/8".into();
        }
        rows[1].work_units = 12.4;
        let table = speed_table(&rows).unwrap();
        let body: Vec<&str> = table.lines().filter(|l| l.starts_with("| ")).collect();
        assert_eq!(body.len(), 3, "{table}");
        assert!(body[1].contains("best factorization") && body[1].contains("0.5000"));
        assert!(body[2].starts_with("| tnnmg |") && body[2].contains("0.2500"));
        assert!(
            body[2].contains("12 WU") && !body[1].contains("WU"),
            "{table}"
        );
    }
}
