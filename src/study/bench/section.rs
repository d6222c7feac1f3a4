//! The speed measurements' section of a run's README: the goals, the
//! memory, the paper's method at equal accuracy, the speed table and the
//! performance charts.

use contactlab_solvers::registry;

use crate::study::bench::goals::{BenchOutput, equal_accuracy_markdown, goals_markdown};
use crate::study::bench::set_up::FACTORIZATION;
use crate::study::bench::{exact_bound, memory};
use crate::study::lab::chart_markdown;

/// The whole section.
pub fn section(bench: &BenchOutput, charts: &[String]) -> String {
    let mut s = String::from(
        "## Speed (problem 1, medians after a warm-up)\n\n\
         Every time is also a ratio to one sparse Cholesky factorization and solve of the stiffness matrix with the \
         semicoercive mode removed, measured in the same run (`performance.csv`, a timing file; `contactlab bench` \
         reruns it alone), and a number of work units: the time over one product A·v with the problem's own A on \
         the same mesh (the storage the solvers get, on the machine's cores), timed in the same run, which divides \
         the machine's speed out (`work_units`; for `tnnmg` the goals split them by phase). A solver stops at a stated budget per run. The program keeps freed memory for reuse \
         (`src/allocator.rs`), so a repeated run does not fault its pages in again: medians are warm, and the rows \
         marked *once* are cold.\n\n",
    );
    s += &goals_markdown(&bench.goals);
    s += "\n";
    s += &memory::markdown(&bench.memory);
    s += &exact_bound::markdown(&bench.exact_bound, &bench.rows);
    s += "\n";
    s += &equal_accuracy_markdown(&bench.rows, bench.problem);
    s += "\n\nIn that comparison the paper's method stops by its certified rule (`relaxation.target`: the \
          certificate's largest violation, checked every `check_every` sweeps and after every Uzawa step) instead of \
          its rules on max|Δl| and max|Δv|, so that it delivers the same accuracy on every mesh; `relaxation.omega` = 1 \
          is the paper's Gauss–Seidel, 1.5 the over-relaxed sweep. The oracle runs at its own settings. Each run is \
          once and cold, without the budget; its certificate (the same code for every solver) says what accuracy it \
          reached.\n";
    s += &speed_table(&bench.rows);
    s += "\n";
    for c in charts.iter().filter(|c| c.starts_with("performance_")) {
        s += &chart_markdown(
            c,
            "How each solver's time grows with the number of unknowns (slope in the legend, fitted through three or \
             more certified runs; runs stopped or refused are crosses), beside the best sparse factorization (faer on \
             one thread or both cores, whichever is faster on the mesh, symbolic analysis once).",
        );
    }
    s
}

fn speed_table(rows: &[super::PerfRow]) -> String {
    // Each mesh once, in the order of its first row (later studies revisit
    // meshes).
    let mut meshes: Vec<&str> = Vec::new();
    for r in rows {
        if !meshes.contains(&r.h.as_str()) {
            meshes.push(&r.h);
        }
    }
    let mut s = String::from(
        "\nWhole Coulomb problem, median seconds (× the best factorization: numeric LLᵀ + one solve on the faster here of 1 and 2 threads, symbolic once; work units, WU: ÷ one product A·v), certified status:\n\n| solver |",
    );
    for h in &meshes {
        s += &format!(" {h} |");
    }
    s += "\n|---|";
    s += &"---|".repeat(meshes.len());
    s += "\n";
    let mut names = vec![FACTORIZATION];
    names.extend(registry::names());
    for name in names {
        let cells: Vec<String> = meshes
            .iter()
            .map(|h| {
                rows.iter()
                    .find(|r| {
                        r.solver == name
                            && r.h == *h
                            && (r.what == "coulomb" || r.what == "factorization")
                    })
                    .map(|r| {
                        if r.median_seconds.is_finite() {
                            let st = if r.what == "factorization" {
                                String::new()
                            } else {
                                format!(", {}", r.status)
                            };
                            let wu = if r.work_units.is_finite() {
                                format!(", {:.0} WU", r.work_units)
                            } else {
                                String::new()
                            };
                            format!(
                                "{:.4} ({:.1}×{wu}{st})",
                                r.median_seconds, r.ratio_to_factorization
                            )
                        } else {
                            r.status.clone()
                        }
                    })
                    .unwrap_or_default()
            })
            .collect();
        // A solver that ran on no mesh has no row.
        if cells.iter().all(String::is_empty) {
            continue;
        }
        s += &format!(
            "| {} |",
            if name == FACTORIZATION {
                "best factorization + solve (faster of 1 and 2 threads)"
            } else {
                name
            }
        );
        for cell in cells {
            s += &format!(" {cell} |");
        }
        s += "\n";
    }
    s
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
        let table = speed_table(&rows);
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
