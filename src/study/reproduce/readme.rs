//! The README of a results folder: a template (`readme.md`) filled with
//! findings computed from the trials, never typed in. Each finding is a
//! threshold crossed, a ratio or a best value; explanations appear only
//! beside the data that support them.

use anyhow::{Context as _, Result};
use contactlab_solvers::registry::{self, Role};
use serde::Serialize;

use crate::io::manifest::Manifest;
use crate::study::reproduce::ReproduceSpec;
use crate::study::reproduce::intents::{ChartRef, named};
use crate::study::reproduce::sections::{
    BenchSection, BenchmarkSection, CompareSection, ErrorsSection, Sections, StabilitySection,
    SweepSection, Table1Section,
};
use crate::study::stability::classify::WRONG_PRESSURE;

pub use crate::study::reproduce::separation_text::PAPER_SEPARATION;

const TEMPLATE: &str = include_str!("readme.md");

#[derive(Serialize)]
struct SolverInfo {
    name: &'static str,
    role: &'static str,
    about: &'static str,
    source: &'static str,
}

#[derive(Serialize)]
struct Context<'a> {
    quick: bool,
    long: bool,
    seconds: String,
    /// The studies an earlier, interrupted process ran (`--resume`).
    resumed: String,
    cpu: String,
    cores: usize,
    date: String,
    commit: String,
    dirty: bool,
    rustc: String,
    h: String,
    wrong_pressure: String,
    solvers: Vec<SolverInfo>,
    profile_charts: Vec<ChartRef>,
    convergence_charts: Vec<ChartRef>,
    sweep_scene: String,
    sweep_h: String,
    work_precision_charts: Vec<ChartRef>,
    variation_charts: Vec<ChartRef>,
    stability_charts: Vec<ChartRef>,
    performance_charts: Vec<ChartRef>,
    files: Vec<String>,
    benchmark_charts: Vec<ChartRef>,
    errors_reference: String,
    errors_charts: Vec<ChartRef>,
    #[serde(flatten)]
    table1: &'a Table1Section,
    #[serde(flatten)]
    compare: &'a CompareSection,
    #[serde(flatten)]
    sweep: &'a SweepSection,
    #[serde(flatten)]
    stability: &'a StabilitySection,
    #[serde(flatten)]
    bench: &'a BenchSection,
    #[serde(flatten)]
    benchmark: &'a BenchmarkSection,
    #[serde(flatten)]
    errors: &'a ErrorsSection,
}

/// What the README says of the run as a whole.
pub struct RunFacts<'a> {
    pub files: &'a [String],
    pub charts: &'a [String],
    /// Wall seconds of the whole run (its earlier processes included).
    pub seconds: f64,
    /// The studies run by an earlier, interrupted process.
    pub resumed: &'a [String],
}

/// Renders the README from every study's section.
///
/// `files` are the paths the run wrote (its artifacts), `charts` the names
/// of its charts.
pub fn render(
    spec: &ReproduceSpec,
    m: &Manifest,
    sections: &Sections,
    run: &RunFacts,
) -> Result<String> {
    let missing = |study: &str| format!("the {study} study did not run");
    let chart_names = run.charts;
    let context = Context {
        quick: spec.quick,
        long: spec.long,
        seconds: format!("{:.0}", run.seconds),
        resumed: run
            .resumed
            .iter()
            .map(|s| format!("`{s}`"))
            .collect::<Vec<_>>()
            .join(", "),
        cpu: m.cpu.clone(),
        cores: m.cores,
        date: m.date.clone(),
        commit: m.git_commit.clone(),
        dirty: m.git_dirty == Some(true),
        rustc: m.rustc.to_string(),
        h: spec.h.to_string(),
        wrong_pressure: format!("{WRONG_PRESSURE:e}"),
        solvers: registry::solvers()
            .iter()
            .map(|e| SolverInfo {
                name: e.name,
                role: match e.role {
                    Role::PapersMethod => "the paper's method",
                    Role::Oracle => "the conic oracle",
                    Role::Other => "",
                },
                about: e.about,
                source: e.source,
            })
            .collect(),
        profile_charts: named(chart_names, "profile_"),
        convergence_charts: named(chart_names, "convergence_"),
        sweep_scene: spec
            .sweep
            .scenes
            .first()
            .map(|s| s.name.clone())
            .unwrap_or_default(),
        // The fine meshes' groups say their mesh in their own lines; the
        // heading names them too.
        sweep_h: if spec.sweep.fine_meshes.is_empty() {
            spec.sweep_h.to_string()
        } else {
            let fine: Vec<String> = spec
                .sweep
                .fine_meshes
                .iter()
                .map(|h| h.to_string())
                .collect();
            format!("{}; fine mesh h = {}", spec.sweep_h, fine.join(", "))
        },
        work_precision_charts: named(chart_names, "work_precision_"),
        variation_charts: named(chart_names, "sweep_"),
        stability_charts: named(chart_names, "stability_"),
        performance_charts: named(chart_names, "performance_"),
        files: run
            .files
            .iter()
            .filter(|f| !f.starts_with("charts/") && !f.starts_with("profiles/"))
            .cloned()
            .collect(),
        benchmark_charts: named(chart_names, "benchmark_"),
        errors_reference: spec.errors.reference.to_string(),
        errors_charts: named(chart_names, "discretization_error_"),
        table1: sections
            .table1
            .as_ref()
            .with_context(|| missing("table1"))?,
        compare: sections
            .compare
            .as_ref()
            .with_context(|| missing("compare"))?,
        sweep: sections.sweep.as_ref().with_context(|| missing("sweep"))?,
        stability: sections
            .stability
            .as_ref()
            .with_context(|| missing("stability"))?,
        bench: sections.bench.as_ref().with_context(|| missing("bench"))?,
        benchmark: sections
            .benchmark
            .as_ref()
            .with_context(|| missing("benchmark"))?,
        errors: sections
            .errors
            .as_ref()
            .with_context(|| missing("discretization_error"))?,
    };
    let mut env = minijinja::Environment::new();
    env.add_template("readme", TEMPLATE)?;
    Ok(env.get_template("readme")?.render(context)?)
}
