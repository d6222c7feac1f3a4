//! Views of the benchmark: the performance goals checked against the rows
//! of one run, charts of time against size, the memory of the fastest
//! solver measured in a fresh process, and the files.

use anyhow::Result;
use contactlab_solvers::registry::{self, Entry, Role};
use serde::Serialize;

use crate::io::charts::Chart;
use crate::mechanics::mesh_size::MeshSize;
use crate::settings::Settings;
use crate::study::bench::equal_accuracy::{EQUAL_ACCURACY, ORACLE_GOAL};
use crate::study::bench::exact_bound::{self, ExactBound};
use crate::study::bench::memory::{self, MemoryUse, measure_in_fresh_process};
use crate::study::bench::{BenchSpec, FastestDirect, PerfRow, bench, multigrid};
use crate::study::lab::{Artifact, Lab, Ran, RunLength, Section, Study};
use crate::study::template;

pub use crate::study::bench::charts::{
    MIN_POINTS_FOR_SLOPE, fit_slope, performance_charts, slope_label,
};

/// One goal, measured.
#[derive(Clone, Debug, Serialize)]
pub struct Goal {
    pub goal: String,
    pub measured: String,
    pub pass: Option<bool>,
}

/// The fastest certified solver of the Coulomb problem at `h`.
fn fastest<'a>(rows: &'a [PerfRow], h: &str) -> Option<&'a PerfRow> {
    rows.iter()
        .filter(|r| {
            r.what == "coulomb"
                && r.h == h
                && r.median_seconds.is_finite()
                && r.status == "converged"
        })
        .min_by(|a, b| a.median_seconds.total_cmp(&b.median_seconds))
}

/// The goals, checked against the rows of one run (and the peak memory in
/// KiB of the fastest solver on the given mesh).
pub fn goals(rows: &[PerfRow], peak: Option<(MeshSize, u64)>) -> Vec<Goal> {
    let mut out = Vec::new();
    let oracle = registry::with_role(Role::Oracle).map(|e| e.name);
    // (mesh, limit in factorizations, whether a run without the mesh must
    // say so: the large meshes are absent from quick runs).
    let meshes = [
        ("1/64", 10.0, true),
        ("1/256", 20.0, true),
        ("1/512", 3.0, false),
        ("1/1024", 3.0, false),
    ];
    for (h, limit, always) in meshes {
        if !always && !rows.iter().any(|r| r.h == h) {
            continue;
        }
        let Some(f) = fastest(rows, h) else {
            out.push(Goal {
                goal: format!("whole Coulomb problem at h = {h}, certified"),
                measured: "not measured in this run".into(),
                pass: None,
            });
            continue;
        };
        out.push(Goal {
            goal: format!(
                "whole Coulomb problem at h = {h}, fastest certified solver: at most {limit} × the best factorization (the faster of 1 and 2 threads, symbolic once)"
            ),
            measured: format!(
                "{}: {:.4} s = {:.1} × factorization",
                f.solver, f.median_seconds, f.ratio_to_factorization
            ),
            pass: Some(f.ratio_to_factorization <= limit),
        });
        if let Some(c) = rows.iter().find(|r| {
            r.what == "coulomb"
                && Some(r.solver.as_str()) == oracle
                && r.h == h
                && r.median_seconds.is_finite()
        }) {
            let ratio = c.median_seconds / f.median_seconds;
            out.push(Goal {
                goal: format!(
                    "at h = {h}, at least 10 × faster than the oracle at an equal or smaller certificate"
                ),
                measured: format!(
                    "{ratio:.1} × faster; certificate {:.1e} vs the oracle's {:.1e} ({})",
                    f.certificate, c.certificate, c.status
                ),
                pass: Some(ratio >= 10.0 && f.certificate <= c.certificate),
            });
        }
    }
    if let Some((h, kb)) = peak {
        // The aims: 2 GiB at 1/256, 6 GB at 1/1024.
        let (limit_kb, text) = if h.level() >= 10 {
            (6e9 / 1024.0, "6 GB")
        } else {
            (2.0 * 1024.0 * 1024.0, "2 GiB")
        };
        out.push(Goal {
            goal: format!("peak memory of the fastest solver at h = {h} under {text}"),
            measured: format!("{:.0} MiB", kb as f64 / 1024.0),
            pass: Some((kb as f64) < limit_kb),
        });
    }
    // Assembly against one factorization on every mesh from 1/64 on, and
    // against the floor under it: writing its output (a fresh copy of A, M).
    let assembly: Vec<(String, f64, Option<f64>)> = rows
        .iter()
        .filter(|r| r.what == "assembly" && r.unknowns >= 8000)
        .map(|r| {
            let output = rows
                .iter()
                .find(|o| o.what == "output" && o.h == r.h)
                .map(|o| r.median_seconds / o.median_seconds);
            (r.h.clone(), r.ratio_to_factorization, output)
        })
        .collect();
    if let Some((worst_h, worst, _)) = assembly.iter().max_by(|a, b| a.1.total_cmp(&b.1)).cloned() {
        let all: Vec<String> = assembly
            .iter()
            .map(|(h, r, _)| format!("{h}: {r:.2}"))
            .collect();
        let floor: Vec<String> = assembly
            .iter()
            .filter_map(|(h, _, o)| o.map(|o| format!("{h}: {o:.1}")))
            .collect();
        let floor = if floor.is_empty() {
            String::new()
        } else {
            format!(
                "; assembly ÷ writing its output (a fresh copy of A and M): {}",
                floor.join(", ")
            )
        };
        out.push(Goal {
            goal: "assembly (both matrices, loads, the problem) at most 0.2 × the best factorization at every h ≥ 1/64".into(),
            measured: format!("worst {worst:.2} × at h = {worst_h} ({}){floor}", all.join(", ")),
            pass: Some(worst <= 0.2),
        });
    }
    out.extend(oracle_goal(rows));
    out.extend(equal_accuracy_goal(rows));
    if let Some(paper) = registry::with_role(Role::PapersMethod) {
        let find = |what: &str| {
            rows.iter()
                .find(|r| r.what == what && r.solver == paper.name && r.h == "1/64")
        };
        if let (Some(k), Some(p)) = (find("kernel"), find("spmv")) {
            let ratio = k.median_seconds / p.median_seconds;
            out.push(Goal {
                goal: format!(
                    "the paper's method: one inner iteration ({}) at most 2 × one sparse matrix-vector product (h = 1/64)",
                    k.note.split(':').next().unwrap_or("kernel")
                ),
                measured: format!("{ratio:.2} ×"),
                pass: Some(ratio <= 2.0),
            });
        }
    }
    out
}

/// The oracle's time goal: its Coulomb solve at 1/256 within 60 s, certified.
fn oracle_goal(rows: &[PerfRow]) -> Option<Goal> {
    let r = rows.iter().find(|r| r.what == ORACLE_GOAL)?;
    Some(Goal {
        goal: format!(
            "the oracle's whole Coulomb problem at h = {} within 60 s, certified (its fastest variant, {})",
            r.h, r.solver
        ),
        measured: format!(
            "{:.1} s = {:.0} × factorization, {} (certificate {:.1e}); {}",
            r.median_seconds, r.ratio_to_factorization, r.status, r.certificate, r.note
        ),
        pass: Some(r.median_seconds <= 60.0 && r.status == "converged"),
    })
}

/// The paper's method to a certified accuracy, with and without
/// over-relaxation, against the oracle: measured on every mesh of the
/// comparison, passed when every run of the paper's method is certified.
fn equal_accuracy_goal(rows: &[PerfRow]) -> Option<Goal> {
    let paper = registry::with_role(Role::PapersMethod)?;
    let compared: Vec<&PerfRow> = rows.iter().filter(|r| r.what == EQUAL_ACCURACY).collect();
    let ours: Vec<&PerfRow> = compared
        .iter()
        .copied()
        .filter(|r| r.solver == paper.name)
        .collect();
    let target = ours.first()?.variant.clone();
    let mut meshes: Vec<&str> = compared.iter().map(|r| r.h.as_str()).collect();
    meshes.dedup();
    let per_mesh: Vec<String> = meshes
        .iter()
        .map(|h| {
            let runs: Vec<String> = compared
                .iter()
                .filter(|r| r.h == *h)
                .map(|r| {
                    let (label, stage) = paper_label(r, paper);
                    format!(
                        "{label} {:.2} s, {} × {stage} ({}, {:.1e})",
                        r.median_seconds, r.work, r.status, r.certificate
                    )
                })
                .collect();
            format!("{h}: {}", runs.join(", "))
        })
        .collect();
    let worst = ours.iter().map(|r| r.certificate).fold(0.0, f64::max);
    Some(Goal {
        goal: format!(
            "the paper's method to a certified accuracy ({}), with and without over-relaxation and with its inner minimization by multigrid, against the oracle at its own settings: time and work (status, certificate)",
            target.split(' ').next().unwrap_or_default()
        ),
        measured: format!(
            "{}; the paper's method's largest certificate {worst:.1e}",
            per_mesh.join("; ")
        ),
        pass: Some(ours.iter().all(|r| r.status == "converged")),
    })
}

/// How the goal names a run of the comparison, and its unit of work: the
/// paper's method by the setting that tells its runs apart (the inner
/// minimization if it is multigrid, whose work is counted in TNNMG
/// iterations; else ω), another solver by its name.
fn paper_label(r: &PerfRow, paper: &Entry) -> (String, &'static str) {
    use contactlab_solvers::relaxation::{INNER_KNOB, OVER_RELAXATION_KNOB};
    let stage = registry::by_name(&r.solver).map_or("work", |e| e.work_stage);
    if r.solver != paper.name {
        return (r.solver.clone(), stage);
    }
    let setting = |knob: &str| {
        r.variant
            .split(' ')
            .find(|v| v.contains(&format!(".{knob}=")))
    };
    match setting(INNER_KNOB) {
        Some(inner) => (inner.to_string(), "TNNMG iteration"),
        None => (
            setting(OVER_RELAXATION_KNOB)
                .unwrap_or(&r.variant)
                .to_string(),
            stage,
        ),
    }
}

/// A row of the equal-accuracy table: the run and its work as the table
/// gives it (the note without its `once; `).
#[derive(Serialize)]
struct EqualRow<'a> {
    #[serde(flatten)]
    row: &'a PerfRow,
    work_text: &'a str,
}

/// The equal-accuracy comparison as a table: one row per run.
pub fn equal_accuracy_markdown(rows: &[PerfRow], problem: u32) -> Result<String> {
    let compared: Vec<EqualRow> = rows
        .iter()
        .filter(|r| r.what == EQUAL_ACCURACY)
        .map(|row| EqualRow {
            row,
            work_text: row.note.trim_start_matches("once; "),
        })
        .collect();
    template::render(
        "bench_equal_accuracy",
        include_str!("../templates/bench_equal_accuracy.md"),
        template::facts! { rows => compared, problem },
    )
}

/// The goals as a table (`templates/bench_goals.md`).
pub fn goals_markdown(goals: &[Goal]) -> Result<String> {
    template::render(
        "bench_goals",
        include_str!("../templates/bench_goals.md"),
        template::facts! { goals },
    )
}

/// What one benchmark run wrote.
pub struct BenchOutput {
    /// The paper's problem the benchmark ran on, and its meshes (the
    /// large ones aside).
    pub problem: u32,
    pub meshes: Vec<MeshSize>,
    pub rows: Vec<PerfRow>,
    pub goals: Vec<Goal>,
    /// Each large mesh's fastest solver, measured in a fresh process.
    pub memory: Vec<MemoryUse>,
    /// `performance_goals.md`: the goals, where the memory goes, the
    /// paper's method at equal accuracy.
    pub goals_markdown: String,
    pub charts: Vec<(String, Chart)>,
    /// The friction fixed point against TNNMG at the exact bound.
    pub exact_bound: Vec<ExactBound>,
}

/// The speed measurements as a study: performance.csv,
/// performance_goals.md and the charts.
pub struct Bench {
    pub spec: BenchSpec,
}

impl Study for Bench {
    /// Its rows, goals and memory measurements.
    type Findings = BenchOutput;

    fn name(&self) -> &'static str {
        "bench"
    }

    fn estimated_seconds(&self, length: RunLength) -> f64 {
        match length {
            RunLength::Quick => 5.3,
            // The main job's, measured alone on 7ffa5e6 (267 s).
            RunLength::Standard => 270.0,
            RunLength::Long => 5700.0,
        }
    }

    fn section(&self, out: &BenchOutput, _: &Lab, charts: &[String]) -> Result<Section> {
        Ok(Section {
            markdown: crate::study::bench::section::section(out, charts)?,
        })
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<BenchOutput>> {
        lab.log("speed");
        let log = lab.logger();
        let out = measure_bench(&self.spec, &lab.settings, &|l| log(&format!("bench: {l}")))?;
        let mut artifacts = vec![
            Artifact::csv("performance.csv", &out.rows, &[])?,
            Artifact::text("performance_goals.md", &out.goals_markdown),
        ];
        artifacts.extend(Artifact::charts(out.charts.clone()));
        lab.handoff.put(&FastestDirect::of(&out))?;
        Ok(Ran {
            findings: out,
            artifacts,
        })
    }
}

/// Runs the benchmark and measures the memory of the fastest solver on
/// each large mesh (the finest mesh if there are none) in a fresh process.
pub fn measure_bench(
    spec: &BenchSpec,
    settings: &Settings,
    log: &dyn Fn(&str),
) -> Result<BenchOutput> {
    let rows = bench(spec, settings, log)?;
    let measured_meshes = if spec.large.is_empty() {
        spec.meshes.last().into_iter().copied().collect()
    } else {
        spec.large.clone()
    };
    // A probe that fails costs its line in the report, not the run.
    let (mut memory, mut unmeasured) = (Vec::new(), Vec::new());
    for h in measured_meshes {
        let Some(fastest) = fastest(&rows, &h.to_string()) else {
            continue;
        };
        log(&format!(
            "memory of {} at h = {h} (fresh process)",
            fastest.solver
        ));
        let schedule = registry::by_name(&fastest.solver)
            .map_or(settings.schedule.unwrap_or_default(), |e| {
                settings.schedule_of(e)
            });
        match measure_in_fresh_process(spec.problem, h, &fastest.solver, schedule, &[]) {
            Ok(used) => memory.push(used),
            Err(e) => {
                log(&format!("memory at h = {h} not measured: {e:#}"));
                unmeasured.push(memory::Unmeasured {
                    h: h.to_string(),
                    error: format!("{e:#}"),
                });
            }
        }
    }
    let finest = memory.last().map(|u| (u.h, u.peak_kb));
    let mut goals = goals(&rows, finest);
    let multigrid = multigrid::measure(spec, log)?;
    goals.extend(multigrid::goals(&multigrid, &rows));
    // The multigrid goals' runs at a mesh and solver the table already has
    // would only repeat its row (the fastest solver is often tnnmg).
    for used in &multigrid.coulomb {
        if !memory
            .iter()
            .any(|u| u.h == used.h && u.solver == used.solver)
        {
            memory.push(used.clone());
        }
    }
    let md = [
        goals_markdown(&goals)?,
        memory::markdown(&memory, &unmeasured)?,
        exact_bound::markdown(&multigrid.exact_bound, &rows)?,
        equal_accuracy_markdown(&rows, spec.problem)?,
    ]
    .concat();
    Ok(BenchOutput {
        problem: spec.problem,
        meshes: spec.meshes.clone(),
        charts: performance_charts(&rows),
        rows,
        goals,
        memory,
        goals_markdown: md,
        exact_bound: multigrid.exact_bound,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(solver: &str, unknowns: usize, seconds: f64, status: &str) -> PerfRow {
        PerfRow::sample("coulomb", solver, unknowns, seconds, status)
    }

    /// The goal names each run of the paper's method by what tells it
    /// apart, and counts a multigrid run's work in TNNMG iterations, not in
    /// the sweeps it does not make.
    #[test]
    fn the_paper_s_runs_are_named_by_their_inner_minimization_or_omega() {
        let paper = registry::with_role(Role::PapersMethod).unwrap();
        let p = paper.name;
        let run = |solver: &str, variant: String| {
            let mut r = PerfRow::sample(EQUAL_ACCURACY, solver, 100, 1.0, "converged");
            r.variant = variant;
            r
        };
        let by_multigrid = run(p, format!("{p}.target=1e-6 {p}.inner=multigrid"));
        assert_eq!(
            paper_label(&by_multigrid, paper),
            (format!("{p}.inner=multigrid"), "TNNMG iteration")
        );
        let by_sweeps = run(p, format!("{p}.target=1e-6 {p}.omega=1.5"));
        assert_eq!(
            paper_label(&by_sweeps, paper),
            (format!("{p}.omega=1.5"), paper.work_stage)
        );
        let other = registry::solvers()
            .into_iter()
            .find(|e| e.name != p)
            .unwrap();
        let oracle = run(other.name, String::new());
        assert_eq!(
            paper_label(&oracle, paper),
            (other.name.to_string(), other.work_stage)
        );
    }

    #[test]
    fn failed_runs_are_crosses_outside_the_fit_and_two_points_give_no_slope() {
        // Two solvers of one family (the charts are split by family).
        let factoring: Vec<&str> = registry::solvers()
            .iter()
            .filter(|e| e.memory.per_unknown_log2 > 0.0)
            .map(|e| e.name)
            .collect();
        let (solver, other) = (factoring[0], factoring[1]);
        let rows = vec![
            // Time ∝ n on three certified meshes, then a run stopped by the
            // time limit far above the line.
            row(solver, 100, 1.0, "converged"),
            row(solver, 1000, 10.0, "converged"),
            row(solver, 10000, 100.0, "converged"),
            row(solver, 100000, 5.0e4, "stopped"),
            // Two certified points only.
            row(other, 100, 1.0, "converged"),
            row(other, 1000, 100.0, "converged"),
        ];
        let charts = performance_charts(&rows);
        let (_, chart) = charts
            .iter()
            .find(|(n, _)| n == "performance_coulomb_factored")
            .unwrap();
        let names: Vec<&str> = chart.series.iter().map(|s| s.name.as_str()).collect();
        assert!(
            names.contains(&format!("{solver} (slope 1.00)").as_str()),
            "{names:?}"
        );
        let crosses = chart
            .series
            .iter()
            .find(|s| s.name == format!("{solver}: not certified"))
            .expect("the stopped run is drawn");
        assert_eq!(crosses.points, vec![(100000.0, 5.0e4)]);
        assert!(
            names.contains(&format!("{other} (no slope: 2 points)").as_str()),
            "{names:?}"
        );
    }
}
