//! The README's sections, one per study, each computed from that study's
//! findings as soon as it has run: plain text, saved with the study's
//! checkpoint, so that a resumed run renders the README without the trials
//! of the studies an earlier process ran.

use std::fmt::Write as _;

use anyhow::{Context as _, Result};
use contactlab_solvers::Law;
use contactlab_solvers::registry::{self, Role};
use serde::{Deserialize, Serialize};

use crate::study::bench::goals::BenchOutput;
use crate::study::compare;
use crate::study::compare::paper::PAPER_SETTINGS;
use crate::study::lab::Findings;
use crate::study::reference::References;
use crate::study::reproduce::ReproduceSpec;
use crate::study::reproduce::separation_text::{separation_table, separation_text};
use crate::study::reproduce::sweep_text::{variations_text, work_precision_text};
use crate::study::runner::Measured;
use crate::study::stability::classify::WRONG_PRESSURE;
use crate::study::stability::views;
use crate::study::table1::markdown as table1_markdown;
use crate::study::trial::Trial;

/// Table 1 at the paper's settings.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Table1Section {
    table1: String,
    table1_text: String,
}

/// The comparison against the earned references, and the separation zones.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CompareSection {
    tol: String,
    references: String,
    agreement: String,
    compare_table: String,
    separation_table: String,
    separation_text: String,
}

/// The sweep's work-precision and variation findings.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SweepSection {
    work_precision_text: String,
    variations_text: String,
}

/// The stability map.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StabilitySection {
    stability_section: String,
    stability_summary: String,
}

/// The speed measurements and their goals.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BenchSection {
    goals: String,
    memory: String,
    equal_accuracy: String,
    speed_table: String,
}

/// The benchmark over the problem collection.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BenchmarkSection {
    benchmark_instances: usize,
    benchmark: String,
}

/// The discretization error.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ErrorsSection {
    errors_solver: String,
    errors_solver_note: String,
    errors_table: String,
    errors_text: String,
}

/// One study's part of the README, computed from its findings as soon as
/// it has run (so that a resumed run has it without the trials).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub enum Section {
    Table1(Table1Section),
    Compare(CompareSection),
    Sweep(SweepSection),
    Stability(StabilitySection),
    Bench(BenchSection),
    Benchmark(BenchmarkSection),
    Errors(ErrorsSection),
}

/// The sections of a run's studies, as they come.
#[derive(Default)]
pub struct Sections {
    pub(super) table1: Option<Table1Section>,
    pub(super) compare: Option<CompareSection>,
    pub(super) sweep: Option<SweepSection>,
    pub(super) stability: Option<StabilitySection>,
    pub(super) bench: Option<BenchSection>,
    pub(super) benchmark: Option<BenchmarkSection>,
    pub(super) errors: Option<ErrorsSection>,
}

impl Sections {
    pub fn add(&mut self, section: Section) {
        match section {
            Section::Table1(s) => self.table1 = Some(s),
            Section::Compare(s) => self.compare = Some(s),
            Section::Sweep(s) => self.sweep = Some(s),
            Section::Stability(s) => self.stability = Some(s),
            Section::Bench(s) => self.bench = Some(s),
            Section::Benchmark(s) => self.benchmark = Some(s),
            Section::Errors(s) => self.errors = Some(s),
        }
    }
}

/// The README's section of study `study` (by its name), from the findings
/// it recorded and, for the comparison, the references it earned.
pub fn section(
    study: &str,
    spec: &ReproduceSpec,
    out: &Findings,
    references: &References,
) -> Result<Section> {
    Ok(match study {
        "table1" => Section::Table1(Table1Section {
            table1: table1_markdown(&out.table1),
            table1_text: table1_text(out),
        }),
        "compare" => {
            let compare_trials: Vec<&Measured> =
                out.compare.iter().flat_map(|(_, v)| v.iter()).collect();
            let tol = compare_trials
                .first()
                .map(|t| t.trial.tolerance)
                .unwrap_or(crate::certificate::DEFAULT_TOLERANCE);
            Section::Compare(CompareSection {
                tol: format!("{tol:e}"),
                references: references_text(references, &out.compare_references),
                agreement: agreement(&compare_trials, tol),
                compare_table: {
                    let trials: Vec<Trial> =
                        compare_trials.iter().map(|m| m.trial.clone()).collect();
                    let secs: Vec<f64> = compare_trials
                        .iter()
                        .map(|m| m.timing.seconds_min)
                        .collect();
                    compare::markdown(&trials, &secs)
                },
                separation_table: separation_table(spec, out),
                separation_text: separation_text(spec, out, references),
            })
        }
        "sweep" => Section::Sweep(SweepSection {
            work_precision_text: work_precision_text(&out.sweep),
            variations_text: variations_text(&out.sweep),
        }),
        "stability" => {
            let stability = out
                .stability
                .as_ref()
                .context("the stability study recorded no map")?;
            let mut s = views::readme_section(&stability.trials);
            let lines = crate::study::stability::uniqueness::readme_lines(&stability.uniqueness);
            if !lines.is_empty() {
                s += "\n**Past the fixed point's limit** (problem 1; a solver of the Coulomb problem itself from its \
                      default start and from each starting point its registry entry lists; `stability_uniqueness.csv`):\n\n";
                s += &lines.join("\n");
                s += "\n";
            }
            Section::Stability(StabilitySection {
                stability_section: s,
                stability_summary: views::summary_markdown(&stability.trials),
            })
        }
        "bench" => {
            let bench = out
                .bench
                .as_ref()
                .context("the bench study recorded no output")?;
            Section::Bench(BenchSection {
                goals: crate::study::bench::goals::goals_markdown(&bench.goals),
                memory: crate::study::bench::memory::markdown(&bench.memory),
                equal_accuracy: crate::study::bench::goals::equal_accuracy_markdown(
                    &bench.rows,
                    bench.problem,
                ),
                speed_table: speed_table(bench),
            })
        }
        "benchmark" => Section::Benchmark(BenchmarkSection {
            benchmark_instances: {
                let mut ids: Vec<&str> =
                    out.benchmark.iter().map(|r| r.instance.as_str()).collect();
                ids.sort_unstable();
                ids.dedup();
                ids.len()
            },
            benchmark: crate::study::benchmark::views::report(&out.benchmark),
        }),
        "discretization_error" => Section::Errors(ErrorsSection {
            errors_solver: out
                .errors
                .first()
                .map_or(String::new(), |r| r.solver.clone()),
            errors_solver_note: out
                .errors
                .first()
                .map_or("", |r| {
                    crate::study::discretization_error::solver_note(&r.solver)
                })
                .to_string(),
            errors_table: crate::study::discretization_error::markdown(&out.errors),
            errors_text: crate::study::discretization_error::findings(&out.errors),
        }),
        other => anyhow::bail!("the README has no section for study `{other}`"),
    })
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
