//! `contactlab reproduce`: every study on the paper's problems into one
//! output folder: Table 1 at the paper's settings, the comparison of every
//! solver (and the paper's method at the paper's settings) against the
//! earned reference, the contact-zone profiles, a sweep, the stability map,
//! the benchmark, the charts, a manifest and a README that is a view of
//! the trials ([`readme`]).

pub mod intents;
pub mod readme;
mod separation_text;
mod sweep_text;

use std::path::Path;

use anyhow::{Context, Result};
use contactlab_solvers::Law;
use contactlab_solvers::registry::{self, Role};
use serde::Serialize;

use crate::coulomb::continuation::Schedule;
use crate::io::charts::Chart;
use crate::io::csv::{fixed, to_csv};
use crate::io::latex::booktabs;
use crate::io::output::write_atomic;
use crate::mechanics::contact_zone::{PROFILE_COLUMNS, contact_profile};
use crate::mechanics::material::PlaneModel;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::bench::BenchSpec;
use crate::study::bench::goals::{BenchOutput, write_bench};
use crate::study::benchmark::{self, BenchmarkRow, BenchmarkSpec};
use crate::study::compare;
use crate::study::discretization_error::{self, ErrorRow, ErrorSpec};
use crate::study::reference::References;
use crate::study::report::{ProfilePair, convergence_charts, profile_charts, sweep_charts};
use crate::study::runner::{Keep, Measured, measure, measure_all, write_trials};
use crate::study::stability::{self, Map, StabilitySpec};
use crate::study::sweep::{self, SweepSpec};
use crate::study::table1::{self, Table1Row};
use crate::study::trial::{Trial, TrialRow, TrialSpec, intervals_text};

/// The group of the paper's method at the paper's settings in compare.csv.
pub const PAPER_SETTINGS: &str = "paper_settings";

/// What `reproduce` runs.
#[derive(Clone, Serialize)]
pub struct ReproduceSpec {
    pub quick: bool,
    /// Finest mesh of the problems (continuation from 1/8).
    pub h: MeshSize,
    pub problems: Vec<u32>,
    /// Timed runs per comparison trial, after the first.
    pub repeats: usize,
    #[serde(skip)]
    pub sweep: SweepSpec,
    pub sweep_h: MeshSize,
    pub stability: StabilitySpec,
    pub bench: BenchSpec,
    /// The benchmark over the problem collection (its solvers: all).
    #[serde(skip)]
    pub benchmark: BenchmarkSpec,
    /// The discretization-error study.
    pub errors: ErrorSpec,
}

impl ReproduceSpec {
    /// The full run.
    pub fn full() -> Self {
        let sweep_h = MeshSize::from_level(5).expect("in range");
        Self {
            quick: false,
            h: MeshSize::from_level(6).expect("in range"),
            problems: vec![1, 2, 3],
            repeats: 2,
            sweep: SweepSpec {
                meshes: vec![sweep_h],
                ..SweepSpec::default()
            },
            sweep_h,
            stability: StabilitySpec::standard(),
            bench: BenchSpec::standard(),
            benchmark: BenchmarkSpec::new(false, registry::solvers()),
            errors: ErrorSpec::standard(),
        }
    }

    /// A small run for tests (seconds).
    pub fn quick() -> Self {
        let h = MeshSize::from_level(4).expect("in range");
        Self {
            quick: true,
            h,
            problems: vec![1, 2, 3],
            repeats: 0,
            sweep: SweepSpec {
                meshes: vec![h],
                quick: true,
                repeats: 0,
                work_scale: 0.2,
                ..SweepSpec::default()
            },
            sweep_h: h,
            stability: StabilitySpec::quick(),
            bench: BenchSpec::quick(),
            benchmark: BenchmarkSpec::new(true, registry::solvers()),
            errors: ErrorSpec::quick(),
        }
    }
}

/// Files every reproduce run writes (relative to the output folder),
/// besides the per-problem profiles and the charts.
pub const FILES: [&str; 27] = [
    "README.md",
    "manifest.json",
    "table1.csv",
    "table1.tex",
    "table1_trials.csv",
    "compare.csv",
    "compare.tex",
    "compare_timing.csv",
    "references.csv",
    "separation.csv",
    "sweep.csv",
    "sweep_timing.csv",
    "sweep_references.csv",
    "stability.csv",
    "stability_friction.csv",
    "stability_uniqueness.csv",
    "stability_references.csv",
    "performance.csv",
    "performance_goals.md",
    "benchmark.csv",
    "benchmark.md",
    "benchmark_trials.csv",
    "benchmark_trials_timing.csv",
    "benchmark_summary.csv",
    "benchmark_1e-4.tex",
    "benchmark_1e-8.tex",
    "discretization_error.csv",
];

/// One problem's separation with one solver.
#[derive(Clone, Debug, Serialize)]
pub struct SeparationRow {
    pub problem: u32,
    pub solver: String,
    #[serde(serialize_with = "fixed")]
    pub friction_coefficient: f64,
    pub status: String,
    pub separated: String,
    #[serde(serialize_with = "fixed")]
    pub separated_fraction: f64,
}

/// Everything a run measured.
pub struct Outputs {
    pub table1: Vec<Table1Row>,
    /// Per problem: its comparison trials, then the paper's method at the
    /// paper's settings.
    pub compare: Vec<(u32, Vec<Measured>)>,
    pub separation: Vec<SeparationRow>,
    /// Separated fraction of problem 1 in plane stress (the reference's).
    pub plane_stress_fraction: Option<f64>,
    pub sweep: Vec<Measured>,
    pub stability: Map,
    pub bench: BenchOutput,
    /// The benchmark's rows.
    pub benchmark: Vec<BenchmarkRow>,
    /// The discretization-error study's rows.
    pub errors: Vec<ErrorRow>,
    pub references: References,
    pub charts: Vec<(String, Chart)>,
}

/// Runs everything, writing the data files into `out` (charts, manifest and
/// README are the caller's). `log` receives one line per stage.
pub fn run(
    out: &Path,
    spec: &ReproduceSpec,
    settings: &Settings,
    log: &dyn Fn(&str),
) -> Result<Outputs> {
    let none = &|_: &TrialSpec| {};
    let mut charts = Vec::new();
    log(&format!(
        "Table 1 at h = {} (the paper's settings, both schedules)",
        spec.h
    ));
    let mut paper = Settings::paper();
    paper.certificate = settings.certificate;
    let t1_specs = table1::plan(
        &[1, 2, 3],
        &[Schedule::Revisit, Schedule::FinestOnly],
        &paper,
        spec.h,
        PlaneModel::Strain,
    )?;
    let (t1_measured, t1) = table1::run(&t1_specs, &[1, 2, 3], none)?;
    write_atomic(&out.join("table1.csv"), &to_csv(&t1, &[])?)?;
    write_atomic(
        &out.join("table1.tex"),
        booktabs(&table1::markdown(&t1), "Table 1 of Zhiltsov & Namm (2019): iteration counts of the paper's method, ours beside the paper's (contactlab reproduce)").as_bytes(),
    )?;
    let t1_trials: Vec<TrialRow> = t1_measured.iter().map(|m| m.trial.row()).collect();
    write_atomic(&out.join("table1_trials.csv"), &to_csv(&t1_trials, &[])?)?;

    let solvers = registry::solvers();
    let paper_method =
        registry::with_role(Role::PapersMethod).context("no paper's method registered")?;
    let mut references = References::default();
    let mut compared = Vec::new();
    let mut separation = Vec::new();
    for &problem in &spec.problems {
        log(&format!(
            "problem {problem}: every solver at h = {}",
            spec.h
        ));
        let sc = Scene::paper_problem_to(problem, spec.h)?;
        let mut measured =
            compare::run(&sc, settings, &solvers, spec.repeats, &mut references, none)?;
        let at_paper = TrialSpec::new(
            PAPER_SETTINGS,
            PAPER_SETTINGS,
            &sc,
            paper_method,
            Law::Coulomb,
            &paper,
        )
        .with_repeats(spec.repeats);
        let reference = references.get(&sc, settings)?;
        measured.push(measure(&at_paper, reference, Keep::default())?);
        // Profiles with and without friction.
        let mut frictionless = sc.clone();
        frictionless.friction = 0.0;
        frictionless.name = format!("{}, frictionless", sc.name);
        let specs: Vec<TrialSpec> = solvers
            .iter()
            .map(|&e| {
                TrialSpec::new(
                    "profiles",
                    "frictionless",
                    &frictionless,
                    e,
                    Law::Coulomb,
                    settings,
                )
            })
            .collect();
        let without = measure_all(
            &specs,
            &mut References::none(),
            Keep {
                history: false,
                solution: true,
            },
            none,
        )?;
        let mut profiles = Vec::new();
        for (&e, w) in solvers.iter().zip(&without) {
            let with = measured
                .iter()
                .find(|m| {
                    m.trial.solver.name == e.name
                        && m.trial.law == Law::Coulomb
                        && m.trial.study == compare::STUDY
                })
                .context("a Coulomb trial per solver")?;
            let profile = |m: &Measured| {
                m.solution()
                    .map(|(d, s, g)| contact_profile(d, s, g, m.trial.status))
                    .unwrap_or_default()
            };
            let (pw, pwo) = (profile(with), profile(w));
            for (kind, rows) in [("friction", &pw), ("frictionless", &pwo)] {
                let path = out.join(format!("profiles/p{problem}_{}_{kind}.csv", e.name));
                write_atomic(&path, &to_csv(rows, &PROFILE_COLUMNS)?)?;
            }
            for (m, f) in [(with, sc.friction), (w, 0.0)] {
                separation.push(SeparationRow {
                    problem,
                    solver: e.name.into(),
                    friction_coefficient: f,
                    status: m.trial.status.to_string(),
                    separated: intervals_text(&m.trial.separated),
                    separated_fraction: m.trial.separated_fraction,
                });
            }
            profiles.push((e.name, pw, pwo));
        }
        let zoom_from = separation
            .iter()
            .filter(|r| r.problem == problem)
            .filter_map(|r| first_start(&r.separated))
            .fold(1.0f64, f64::min)
            - 0.1;
        let pair = |role: Role| {
            let name = registry::with_role(role)?.name;
            profiles
                .iter()
                .find(|(s, ..)| *s == name)
                .map(|(s, w, wo)| ProfilePair {
                    solver: s,
                    friction: w,
                    frictionless: wo,
                })
        };
        if let Some(oracle) = pair(Role::Oracle) {
            charts.extend(profile_charts(
                problem,
                &spec.h.to_string(),
                &oracle,
                pair(Role::PapersMethod).as_ref(),
                zoom_from.clamp(0.0, 0.9),
            ));
        }
        charts.extend(convergence_charts(
            problem,
            &spec.h.to_string(),
            &measured
                .iter()
                .filter(|m| m.trial.study == compare::STUDY)
                .map(clone_for_chart)
                .collect::<Vec<_>>(),
        ));
        compared.push((problem, measured));
    }
    let all: Vec<Measured> = compared
        .iter()
        .flat_map(|(_, m)| m.iter().map(clone_for_chart))
        .collect();
    crate::commands::compare::write_files(out, &all, &references)?;
    let trials: Vec<Trial> = all.iter().map(|m| m.trial.clone()).collect();
    let seconds: Vec<f64> = all.iter().map(|m| m.timing.seconds_min).collect();
    write_atomic(
        &out.join("compare.tex"),
        booktabs(&compare::markdown(&trials, &seconds), "every solver on the paper's problems against the earned reference (contactlab reproduce)").as_bytes(),
    )?;
    write_atomic(&out.join("separation.csv"), &to_csv(&separation, &[])?)?;
    let mut stress = Scene::paper_problem_to(1, spec.h)?;
    stress.material.plane = PlaneModel::Stress;
    stress.name = "problem 1, plane stress".into();
    let plane_stress_fraction = references
        .get(&stress, settings)?
        .map(|r| r.coulomb.separation().fraction);

    log(&format!("sweep at h = {}", spec.sweep_h));
    let mut sweep_refs = References::default();
    let swept = sweep::run(&spec.sweep, settings, &mut sweep_refs, none)?;
    write_trials(out, "sweep", &swept)?;
    write_atomic(
        &out.join("sweep_references.csv"),
        &to_csv(&sweep_refs.candidates(), &[])?,
    )?;
    charts.extend(sweep_charts(&crate::commands::sweep::pairs(&swept)));

    log("stability map");
    let mut stab_refs = References::default();
    let map = stability::run(
        &spec.stability,
        settings,
        &mut stab_refs,
        &|l| log(&format!("stability: {l}")),
        none,
    )?;
    crate::commands::stability::write_tables(out, &map)?;
    write_atomic(
        &out.join("stability_references.csv"),
        &to_csv(&stab_refs.candidates(), &[])?,
    )?;
    charts.extend(stability::views::charts(&map.trials, &map.steps));

    log("speed");
    let bench = write_bench(out, &spec.bench, settings, &|l| log(&format!("bench: {l}")))?;
    charts.extend(bench.charts.clone());

    let plan = benchmark::plan(&spec.benchmark, settings)?;
    log(&format!(
        "benchmark over the problem collection: {} runs",
        plan.len()
    ));
    let progress = crate::commands::StudyProgress::new(plan.len() as u64, "reproduce: benchmark")
        .with_costs(benchmark::expected_costs(&plan), spec.benchmark.time_limit);
    let done = benchmark::run(plan, &|t| progress.tick(t))?;
    progress.finish();
    let (rows, measured): (Vec<BenchmarkRow>, Vec<Measured>) = done.into_iter().unzip();
    write_atomic(&out.join("benchmark.csv"), &to_csv(&rows, &[])?)?;
    write_trials(out, "benchmark_trials", &measured)?;
    charts.extend(benchmark::views::write(out, &rows)?);

    log(&format!(
        "discretization error against h = {}",
        spec.errors.reference
    ));
    let mut error_spec = spec.errors.clone();
    let finest = spec
        .bench
        .meshes
        .last()
        .map(|h| h.to_string())
        .unwrap_or_default();
    // The direct solver certified on the reference mesh in the speed study,
    // else the fastest certified on its finest mesh.
    error_spec.solver =
        crate::study::bench::certified_direct(&bench.rows, &spec.errors.reference.to_string())
            .or_else(|| crate::study::bench::certified_direct(&bench.rows, &finest));
    let errors = discretization_error::run(&error_spec, settings, &|l| {
        log(&format!("discretization error: {l}"))
    })?;
    write_atomic(
        &out.join("discretization_error.csv"),
        &to_csv(&errors, &[])?,
    )?;
    charts.extend(discretization_error::charts(&errors));
    Ok(Outputs {
        table1: t1,
        compare: compared,
        separation,
        plane_stress_fraction,
        sweep: swept,
        stability: map,
        bench,
        benchmark: rows,
        errors,
        references,
        charts,
    })
}

/// A measured trial without its finest level (charts need trials and
/// histories).
fn clone_for_chart(m: &Measured) -> Measured {
    Measured {
        trial: m.trial.clone(),
        timing: m.timing.clone(),
        outcome: m.outcome.clone(),
        history: m.history.clone(),
        finest: None,
    }
}

/// The start of the first interval of `[a;b] [c;d]`.
fn first_start(text: &str) -> Option<f64> {
    text.trim_start_matches('[').split(';').next()?.parse().ok()
}
