//! The README of a results folder: a template (`readme.md`) filled with
//! findings computed from the trials, never typed in. Each finding is a
//! threshold crossed, a ratio or a best value; explanations appear only
//! beside the data that support them.

use std::fmt::Write as _;

use anyhow::{Context as _, Result};
use contactlab_solvers::Law;
use contactlab_solvers::registry::{self, Role};
use serde::Serialize;

use crate::io::manifest::Manifest;
use crate::study::bench::goals::BenchOutput;
use crate::study::compare;
use crate::study::compare::paper::PAPER_SETTINGS;
use crate::study::lab::Findings;
use crate::study::reference::References;
use crate::study::reproduce::ReproduceSpec;
use crate::study::reproduce::intents::{ChartRef, named};
use crate::study::runner::Measured;
use crate::study::stability::classify::WRONG_PRESSURE;
use crate::study::stability::views;
use crate::study::table1::markdown as table1_markdown;
use crate::study::trial::Trial;

pub use crate::study::reproduce::separation_text::PAPER_SEPARATION;
use crate::study::reproduce::separation_text::{separation_table, separation_text};
use crate::study::reproduce::sweep_text::{variations_text, work_precision_text};

const TEMPLATE: &str = include_str!("readme.md");

#[derive(Serialize)]
struct SolverInfo {
    name: &'static str,
    role: &'static str,
    about: &'static str,
    source: &'static str,
}

#[derive(Serialize)]
struct Context {
    quick: bool,
    long: bool,
    benchmark_instances: usize,
    seconds: String,
    cpu: String,
    cores: usize,
    date: String,
    commit: String,
    dirty: bool,
    rustc: String,
    h: String,
    tol: String,
    wrong_pressure: String,
    solvers: Vec<SolverInfo>,
    references: String,
    agreement: String,
    compare_table: String,
    separation_table: String,
    separation_text: String,
    table1: String,
    table1_text: String,
    profile_charts: Vec<ChartRef>,
    convergence_charts: Vec<ChartRef>,
    sweep_scene: String,
    sweep_h: String,
    work_precision_charts: Vec<ChartRef>,
    work_precision_text: String,
    variations_text: String,
    variation_charts: Vec<ChartRef>,
    stability_section: String,
    stability_charts: Vec<ChartRef>,
    stability_summary: String,
    goals: String,
    memory: String,
    equal_accuracy: String,
    speed_table: String,
    performance_charts: Vec<ChartRef>,
    files: Vec<String>,
    benchmark: String,
    benchmark_charts: Vec<ChartRef>,
    errors_reference: String,
    errors_solver: String,
    errors_solver_note: &'static str,
    errors_table: String,
    errors_text: String,
    errors_charts: Vec<ChartRef>,
}

/// Renders the README.
///
/// `files` are the paths the run wrote (its artifacts), `charts` the names
/// of its charts.
pub fn render(
    spec: &ReproduceSpec,
    m: &Manifest,
    out: &Findings,
    references: &References,
    files: &[String],
    chart_names: &[String],
    seconds: f64,
) -> Result<String> {
    let stability = out
        .stability
        .as_ref()
        .context("the stability study did not run")?;
    let bench = out.bench.as_ref().context("the bench study did not run")?;
    let compare_trials: Vec<&Measured> = out.compare.iter().flat_map(|(_, v)| v.iter()).collect();
    let tol = compare_trials
        .first()
        .map(|t| t.trial.tolerance)
        .unwrap_or(crate::certificate::DEFAULT_TOLERANCE);
    let context = Context {
        quick: spec.quick,
        long: spec.long,
        benchmark_instances: {
            let mut ids: Vec<&str> = out.benchmark.iter().map(|r| r.instance.as_str()).collect();
            ids.sort_unstable();
            ids.dedup();
            ids.len()
        },
        seconds: format!("{seconds:.0}"),
        cpu: m.cpu.clone(),
        cores: m.cores,
        date: m.date.clone(),
        commit: m.git_commit.clone(),
        dirty: m.git_dirty == Some(true),
        rustc: m.rustc.to_string(),
        h: spec.h.to_string(),
        tol: format!("{tol:e}"),
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
        references: references_text(references, &out.compare_references),
        agreement: agreement(&compare_trials, tol),
        compare_table: {
            let trials: Vec<Trial> = compare_trials.iter().map(|m| m.trial.clone()).collect();
            let secs: Vec<f64> = compare_trials
                .iter()
                .map(|m| m.timing.seconds_min)
                .collect();
            compare::markdown(&trials, &secs)
        },
        separation_table: separation_table(spec, out),
        separation_text: separation_text(spec, out, references),
        table1: table1_markdown(&out.table1),
        table1_text: table1_text(out),
        profile_charts: named(chart_names, "profile_"),
        convergence_charts: named(chart_names, "convergence_"),
        sweep_scene: spec
            .sweep
            .scenes
            .first()
            .map(|s| s.name.clone())
            .unwrap_or_default(),
        sweep_h: spec.sweep_h.to_string(),
        work_precision_charts: named(chart_names, "work_precision_"),
        work_precision_text: work_precision_text(&out.sweep),
        variations_text: variations_text(&out.sweep),
        variation_charts: named(chart_names, "sweep_"),
        stability_section: {
            let mut s = views::readme_section(&stability.trials);
            let lines = crate::study::stability::uniqueness::readme_lines(&stability.uniqueness);
            if !lines.is_empty() {
                s += "\n**Past the fixed point's limit** (problem 1; a solver of the Coulomb problem itself from its \
                      default start and from each starting point its registry entry lists; `stability_uniqueness.csv`):\n\n";
                s += &lines.join("\n");
                s += "\n";
            }
            s
        },
        stability_charts: named(chart_names, "stability_"),
        stability_summary: views::summary_markdown(&stability.trials),
        goals: crate::study::bench::goals::goals_markdown(&bench.goals),
        memory: crate::study::bench::memory::markdown(&bench.memory),
        equal_accuracy: crate::study::bench::goals::equal_accuracy_markdown(
            &bench.rows,
            bench.problem,
        ),
        speed_table: speed_table(bench),
        performance_charts: named(chart_names, "performance_"),
        files: files
            .iter()
            .filter(|f| !f.starts_with("charts/") && !f.starts_with("profiles/"))
            .cloned()
            .collect(),
        benchmark: crate::study::benchmark::views::report(&out.benchmark),
        benchmark_charts: named(chart_names, "benchmark_"),
        errors_reference: spec.errors.reference.to_string(),
        errors_solver: out
            .errors
            .first()
            .map_or(String::new(), |r| r.solver.clone()),
        errors_solver_note: out.errors.first().map_or("", |r| {
            crate::study::discretization_error::solver_note(&r.solver)
        }),
        errors_table: crate::study::discretization_error::markdown(&out.errors),
        errors_text: crate::study::discretization_error::findings(&out.errors),
        errors_charts: named(chart_names, "discretization_error_"),
    };
    let mut env = minijinja::Environment::new();
    env.add_template("readme", TEMPLATE)?;
    Ok(env.get_template("readme")?.render(context)?)
}

fn worst(trials: &[&Trial], f: fn(&Trial) -> Option<f64>) -> f64 {
    trials.iter().filter_map(|t| f(t)).fold(0.0, f64::max)
}

fn references_text(references: &References, keys: &[String]) -> String {
    let mut parts: Vec<String> = references
        .of(keys)
        .map(|r| {
            format!(
                "{} at h = {}: `{}`{}",
                r.scene.name,
                r.scene.finest(),
                r.solver,
                r.given_friction
                    .as_ref()
                    .filter(|g| g.solver != r.solver)
                    .map(|g| format!(" (subproblem: `{}`)", g.solver))
                    .unwrap_or_default()
            )
        })
        .collect();
    parts.dedup();
    if parts.is_empty() {
        "none could be earned".into()
    } else {
        parts.join("; ")
    }
}

/// The headline: the paper's method at its relative defaults and at the
/// paper's settings, against the thresholds; the oracle beside it.
fn agreement(trials: &[&Measured], tol: f64) -> String {
    let mut s = String::new();
    let Some(paper) = registry::with_role(Role::PapersMethod) else {
        return "No solver has the role of the paper's method.".into();
    };
    let of = |study: &str, solver: &str| -> Vec<&Trial> {
        trials
            .iter()
            .map(|m| &m.trial)
            .filter(|t| t.study == study && t.solver.name == solver && t.law == Law::Coulomb)
            .collect()
    };
    let describe = |ts: &[&Trial]| -> (String, f64, f64, f64, usize) {
        let statuses: Vec<String> = ts
            .iter()
            .map(|t| format!("{}: {}", t.scene, t.status))
            .collect();
        let ok = ts.iter().filter(|t| t.certified()).count();
        (
            statuses.join(", "),
            worst(ts, |t| t.displacement_error()),
            worst(ts, |t| t.pressure_error()),
            ts.iter().map(|t| t.residual()).fold(0.0, f64::max),
            ok,
        )
    };
    let rel = of(compare::STUDY, paper.name);
    let (statuses, du, dp, cert, ok) = describe(&rel);
    let _ = write!(
        s,
        "At its relative defaults, `{}` on the whole Coulomb problem is certified on {ok} of {} problems ({statuses}); \
         its largest certificate violation is {cert:.1e}, and it differs from the reference by at most {du:.1e} in \
         displacement and {dp:.1e} in pressure. ",
        paper.name,
        rel.len()
    );
    let at = of(PAPER_SETTINGS, paper.name);
    let (statuses, _, dp, cert, ok) = describe(&at);
    let agrees = ok == at.len() && dp <= WRONG_PRESSURE;
    let _ = write!(
        s,
        "**At the paper's settings** (`--stopping paper`) it is certified on {ok} of {} problems ({statuses}): the \
         largest violation is {cert:.1e} against a tolerance of {tol:e}, and the pressure differs from the reference by \
         up to {dp:.1e}. {}",
        at.len(),
        if agrees {
            "That is within both thresholds: it agrees with the reference.".to_string()
        } else {
            format!(
                "By the thresholds above (the stability map's too) that is **not** agreement: the paper's stopping rules \
                 bound the change per iteration, not the error, and {}.",
                if dp > WRONG_PRESSURE {
                    format!("its pressure is off by more than {WRONG_PRESSURE:e}")
                } else {
                    "its answers fail the certificate".to_string()
                }
            )
        }
    );
    if let Some(oracle) = registry::with_role(Role::Oracle) {
        let o = of(compare::STUDY, oracle.name);
        let (statuses, _, dp, cert, _) = describe(&o);
        let _ = write!(
            s,
            " The oracle `{}` ({statuses}) differs from the reference by up to {dp:.1e} in pressure, with a largest \
             violation of {cert:.1e}.",
            oracle.name
        );
    }
    s
}

fn table1_text(out: &Findings) -> String {
    let score = |schedule: &str| -> f64 {
        out.table1
            .iter()
            .filter(|r| r.schedule.to_string() == schedule)
            .map(|r| {
                (r.mpp as f64 / r.paper_mpp.max(1) as f64).ln().abs()
                    + (r.mu as f64 / r.paper_mu.max(1) as f64).ln().abs()
            })
            .sum()
    };
    let better = if score("revisit") <= score("finest-only") {
        "revisit"
    } else {
        "finest-only"
    };
    let fewer = out.table1.iter().filter(|r| r.mpr < r.paper_mpr).count();
    format!(
        "\nThe `{better}` schedule is the closer match to the paper's friction (MPP) and Uzawa (MU) counts. Our sweep \
         count (MPR) is below the paper's in {fewer} of {} rows; the paper does not give its smoothing of |s|, its sweep \
         order or its treatment of the penalty along a coordinate, all of which change it. The certificates show what \
         the paper's stopping rules buy.\n",
        out.table1.len()
    )
}

fn speed_table(bench: &BenchOutput) -> String {
    let rows = &bench.rows;
    // Each mesh once, in the order of its first row (later studies revisit
    // meshes).
    let mut meshes: Vec<&str> = Vec::new();
    for r in rows {
        if !meshes.contains(&r.h.as_str()) {
            meshes.push(&r.h);
        }
    }
    let mut s = String::from(
        "\nWhole Coulomb problem, median seconds (× the best factorization: 2 threads, symbolic once), certified status:\n\n| solver |",
    );
    for h in &meshes {
        s += &format!(" {h} |");
    }
    s += "\n|---|";
    s += &"---|".repeat(meshes.len());
    s += "\n";
    let mut names = vec!["faer LLᵀ"];
    names.extend(registry::names());
    for name in names {
        s += &format!(
            "| {} |",
            if name == "faer LLᵀ" {
                "best factorization + solve (2 threads)"
            } else {
                name
            }
        );
        for h in &meshes {
            let cell = rows
                .iter()
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
                        format!(
                            "{:.4} ({:.1}×{st})",
                            r.median_seconds, r.ratio_to_factorization
                        )
                    } else {
                        r.status.clone()
                    }
                })
                .unwrap_or_default();
            s += &format!(" {cell} |");
        }
        s += "\n";
    }
    s
}
