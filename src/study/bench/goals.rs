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
use crate::study::catalog::{Catalogued, MAX_SECONDS, by_length};
use crate::study::lab::{Artifact, Lab, Ran, RunLength, Section, Study};
use crate::study::template;

pub use crate::study::bench::goal::Goal;
use crate::study::bench::goal::{AtMesh, EqualMesh, EqualRun, Measured};

pub use crate::study::bench::charts::{
    MIN_POINTS_FOR_SLOPE, fit_slope, performance_charts, slope_label,
};

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

/// Issue 28's limit of assembly, in best factorizations, on every mesh of
/// at least [`ASSEMBLY_UNKNOWNS`] unknowns (1/64 on).
const ASSEMBLY_GOAL: f64 = 0.2;
const ASSEMBLY_UNKNOWNS: usize = 8000;
const ASSEMBLY_FROM: &str = "1/64";

/// The fastest solver against the oracle: at least this × faster.
const ORACLE_SPEED_UP_GOAL: f64 = 10.0;

/// The oracle's Coulomb solve at 1/256 within this many seconds.
const ORACLE_GOAL_SECONDS: f64 = 60.0;

/// One inner iteration of the paper's method at most this × one product,
/// on [`KERNEL_MESH`].
const KERNEL_GOAL: f64 = 2.0;
const KERNEL_MESH: &str = "1/64";

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
                measured: Measured::CoulombNotMeasured { h: h.into() },
                pass: None,
            });
            continue;
        };
        out.push(Goal {
            measured: Measured::CoulombSpeed {
                h: h.into(),
                limit,
                solver: f.solver.clone(),
                seconds: f.median_seconds,
                ratio: f.ratio_to_factorization,
            },
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
                measured: Measured::FasterThanOracle {
                    h: h.into(),
                    limit: ORACLE_SPEED_UP_GOAL,
                    ratio,
                    certificate: f.certificate,
                    oracle_certificate: c.certificate,
                    oracle_status: c.status.clone(),
                },
                pass: Some(ratio >= ORACLE_SPEED_UP_GOAL && f.certificate <= c.certificate),
            });
        }
    }
    if let Some((h, kb)) = peak {
        // The aims: 2 GiB at 1/256, 6 GB at 1/1024.
        let (limit_kb, limit) = if h.level() >= 10 {
            (6e9 / 1024.0, "6 GB")
        } else {
            (2.0 * 1024.0 * 1024.0, "2 GiB")
        };
        out.push(Goal {
            measured: Measured::PeakMemory {
                h: h.to_string(),
                limit,
                mib: kb as f64 / 1024.0,
            },
            pass: Some((kb as f64) < limit_kb),
        });
    }
    // Assembly against one factorization on every mesh from 1/64 on, and
    // against the floor under it: writing its output (a fresh copy of A, M).
    let assembly: Vec<(String, f64, Option<f64>)> = rows
        .iter()
        .filter(|r| r.what == "assembly" && r.unknowns >= ASSEMBLY_UNKNOWNS)
        .map(|r| {
            let output = rows
                .iter()
                .find(|o| o.what == "output" && o.h == r.h)
                .map(|o| r.median_seconds / o.median_seconds);
            (r.h.clone(), r.ratio_to_factorization, output)
        })
        .collect();
    if let Some((worst_h, worst, _)) = assembly.iter().max_by(|a, b| a.1.total_cmp(&b.1)).cloned() {
        out.push(Goal {
            measured: Measured::Assembly {
                from: ASSEMBLY_FROM,
                limit: ASSEMBLY_GOAL,
                worst,
                worst_h,
                ratios: assembly
                    .iter()
                    .map(|(h, r, _)| AtMesh {
                        h: h.clone(),
                        value: *r,
                    })
                    .collect(),
                over_output: assembly
                    .iter()
                    .filter_map(|(h, _, o)| {
                        o.map(|o| AtMesh {
                            h: h.clone(),
                            value: o,
                        })
                    })
                    .collect(),
            },
            pass: Some(worst <= ASSEMBLY_GOAL),
        });
    }
    out.extend(oracle_goal(rows));
    out.extend(equal_accuracy_goal(rows));
    if let Some(paper) = registry::with_role(Role::PapersMethod) {
        let find = |what: &str| {
            rows.iter()
                .find(|r| r.what == what && r.solver == paper.name && r.h == KERNEL_MESH)
        };
        if let (Some(k), Some(p)) = (find("kernel"), find("spmv")) {
            let ratio = k.median_seconds / p.median_seconds;
            out.push(Goal {
                measured: Measured::PaperKernel {
                    kernel: k.note.split(':').next().unwrap_or("kernel").to_string(),
                    h: KERNEL_MESH,
                    limit: KERNEL_GOAL,
                    ratio,
                },
                pass: Some(ratio <= KERNEL_GOAL),
            });
        }
    }
    out
}

/// The oracle's time goal: its Coulomb solve at 1/256 within 60 s, certified.
fn oracle_goal(rows: &[PerfRow]) -> Option<Goal> {
    let r = rows.iter().find(|r| r.what == ORACLE_GOAL)?;
    Some(Goal {
        measured: Measured::OracleTime {
            h: r.h.clone(),
            solver: r.solver.clone(),
            limit_seconds: ORACLE_GOAL_SECONDS,
            seconds: r.median_seconds,
            ratio: r.ratio_to_factorization,
            status: r.status.clone(),
            certificate: r.certificate,
            note: r.note.clone(),
        },
        pass: Some(r.median_seconds <= ORACLE_GOAL_SECONDS && r.status == "converged"),
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
    let meshes = meshes
        .iter()
        .map(|h| EqualMesh {
            h: h.to_string(),
            runs: compared
                .iter()
                .filter(|r| r.h == *h)
                .map(|r| {
                    let (label, stage) = paper_label(r, paper);
                    EqualRun {
                        label,
                        seconds: r.median_seconds,
                        work: r.work,
                        stage,
                        status: r.status.clone(),
                        certificate: r.certificate,
                    }
                })
                .collect(),
        })
        .collect();
    let worst = ours.iter().map(|r| r.certificate).fold(0.0, f64::max);
    Some(Goal {
        measured: Measured::EqualAccuracy {
            target: target.split(' ').next().unwrap_or_default().to_string(),
            meshes,
            worst,
        },
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

impl Catalogued for Bench {
    const COMMAND: &'static str = "bench";
    const ABOUT: &'static str = "Speed on problem 1 from h = 1/8 to 1/256, as medians after a warm-up and as ratios \
        to the best sparse factorization here (faer, symbolic analysis once); at 1/512 and 1/1024 assembly, the \
        factorization and the fastest certified solvers; the paper's method at a certified accuracy beside the \
        fastest oracle variant; where the fastest solver's memory goes, in a fresh process; the multigrid goals \
        (tnnmg's iterations from zero, its whole Coulomb problem in a fresh process, in work units by phase and on one \
        thread, and with --long alone at 1/2048 to 1/8192); every time also in work units (÷ one product A·v). \
        The main job's budget takes about 4 min, --long about 2 h. Writes performance.csv, performance_goals.md \
        and charts into --out (a fresh process is this binary, or CONTACTLAB_BIN).";
    type Spec = BenchSpec;

    fn spec(length: RunLength) -> BenchSpec {
        by_length(length, BenchSpec::quick, BenchSpec::main, BenchSpec::long)
    }

    fn of(spec: BenchSpec) -> Result<Self> {
        anyhow::ensure!(
            (1..=100).contains(&spec.runs),
            "runs = {} (--runs) is invalid: give 1 to 100 timed runs after the warm-up",
            spec.runs
        );
        for (budget, name) in [
            (spec.budget, "--time-limit"),
            (spec.large_budget, "large_budget"),
        ] {
            anyhow::ensure!(
                budget > 0.0 && budget <= MAX_SECONDS,
                "{name} = {} is invalid: give a positive number of seconds up to a week ({MAX_SECONDS})",
                crate::mechanics::scene::Shown::shown(&budget)
            );
        }
        crate::study::catalog::check_paper_problems(&[spec.problem])?;
        anyhow::ensure!(
            !spec.meshes.is_empty(),
            "meshes: give at least one mesh, such as 1/64"
        );
        Ok(Self { spec })
    }
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

    /// The goals of a run with the main job's meshes read as the committed
    /// tables do: the fastest certified solver against the factorization
    /// and the oracle, assembly against both floors, the paper's kernel
    /// against a product; a failed run is not the fastest, and a goal
    /// past its limit falls short. A template branch that words a kind
    /// wrongly, or a limit or format changed, fails it.
    #[test]
    fn the_goals_read_as_the_tables_do() {
        let oracle = registry::with_role(Role::Oracle).unwrap().name;
        let paper = registry::with_role(Role::PapersMethod).unwrap().name;
        let at = |mut r: PerfRow, h: &str, ratio: f64, certificate: f64| {
            r.h = h.into();
            r.ratio_to_factorization = ratio;
            r.certificate = certificate;
            r
        };
        let mut kernel = at(
            PerfRow::sample("kernel", paper, 9000, 1.5e-3, "done"),
            "1/64",
            0.1,
            f64::NAN,
        );
        kernel.note = "sweep: one pass".into();
        let rows = vec![
            at(
                row("newton-coulomb", 9000, 0.0136, "converged"),
                "1/64",
                3.2,
                2.8e-13,
            ),
            at(
                row("tnnmg", 9000, 0.001, "max_iterations"),
                "1/64",
                0.2,
                1e-3,
            ),
            at(row(oracle, 9000, 2.345, "converged"), "1/64", 500.0, 1.7e-7),
            at(
                PerfRow::sample("assembly", "", 9000, 0.77, "done"),
                "1/64",
                0.77,
                f64::NAN,
            ),
            at(
                PerfRow::sample("output", "", 9000, 0.77 / 128.5, "done"),
                "1/64",
                0.0,
                f64::NAN,
            ),
            at(
                PerfRow::sample("assembly", "", 36000, 0.49, "done"),
                "1/128",
                0.49,
                f64::NAN,
            ),
            kernel,
            at(
                PerfRow::sample("spmv", paper, 9000, 1e-3, "done"),
                "1/64",
                0.1,
                f64::NAN,
            ),
        ];
        let text = goals_markdown(&goals(
            &rows,
            Some((MeshSize::from_level(10).unwrap(), 298_000)),
        ))
        .unwrap();
        for line in [
            "| whole Coulomb problem at h = 1/64, fastest certified solver: at most 10 × the best factorization (the faster of 1 and 2 threads, symbolic once) | newton-coulomb: 0.0136 s = 3.2 × factorization | pass |",
            "| at h = 1/64, at least 10 × faster than the oracle at an equal or smaller certificate | 172.4 × faster; certificate 2.8e-13 vs the oracle's 1.7e-7 (converged) | pass |",
            "| whole Coulomb problem at h = 1/256, certified | not measured in this run | not measured |",
            "| peak memory of the fastest solver at h = 1/1024 under 6 GB | 291 MiB | pass |",
            "| assembly (both matrices, loads, the problem) at most 0.2 × the best factorization at every h ≥ 1/64 | worst 0.77 × at h = 1/64 (1/64: 0.77, 1/128: 0.49); assembly ÷ writing its output (a fresh copy of A and M): 1/64: 128.5 | falls short |",
            "| the paper's method: one inner iteration (sweep) at most 2 × one sparse matrix-vector product (h = 1/64) | 1.50 × | pass |",
        ] {
            assert!(text.contains(line), "{line}\nnot in\n{text}");
        }
        assert!(!text.contains("1/512"), "{text}");
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
