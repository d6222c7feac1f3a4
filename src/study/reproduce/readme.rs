//! The README of a results folder: a template (`readme.md`) filled with
//! findings computed from the trials, never typed in. Each finding is a
//! threshold crossed, a ratio or a best value; explanations appear only
//! beside the data that support them.

use std::fmt::Write as _;

use anyhow::Result;
use contactlab_solvers::Law;
use contactlab_solvers::registry::{self, Role};
use serde::Serialize;

use crate::io::manifest::Manifest;
use crate::study::compare;
use crate::study::reproduce::intents::{ChartRef, named};
use crate::study::reproduce::{FILES, Outputs, PAPER_SETTINGS, ReproduceSpec};
use crate::study::runner::Measured;
use crate::study::stability::classify::WRONG_PRESSURE;
use crate::study::stability::views;
use crate::study::sweep::{WORK_PRECISION, WORK_PRECISION_COULOMB};
use crate::study::table1::markdown as table1_markdown;
use crate::study::trial::Trial;

const TEMPLATE: &str = include_str!("readme.md");

/// The paper's reported separation (section 5, h = 1/64): problem 1 with
/// friction on [0.81, 1.00] (19%), without friction 34%; problem 3 closed.
pub const PAPER_SEPARATION: [(u32, &str, &str); 3] = [
    (1, "[0.81, 1.00] = 19%", "34%"),
    (2, "not reported", "not reported"),
    (3, "none (closed on all of Γ_K)", "not reported"),
];

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
    speed_table: String,
    performance_charts: Vec<ChartRef>,
    files: Vec<&'static str>,
    benchmark: String,
    benchmark_charts: Vec<ChartRef>,
    errors_reference: String,
    errors_table: String,
    errors_text: String,
    errors_charts: Vec<ChartRef>,
}

/// Renders the README.
pub fn render(spec: &ReproduceSpec, m: &Manifest, out: &Outputs, seconds: f64) -> Result<String> {
    let chart_names: Vec<String> = out.charts.iter().map(|(n, _)| n.clone()).collect();
    let compare_trials: Vec<&Measured> = out.compare.iter().flat_map(|(_, v)| v.iter()).collect();
    let tol = compare_trials
        .first()
        .map(|t| t.trial.certificate_tolerance)
        .unwrap_or(crate::certificate::DEFAULT_TOLERANCE);
    let context = Context {
        quick: spec.quick,
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
        references: references_text(out),
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
        separation_text: separation_text(spec, out),
        table1: table1_markdown(&out.table1),
        table1_text: table1_text(out),
        profile_charts: named(&chart_names, "profile_"),
        convergence_charts: named(&chart_names, "convergence_"),
        sweep_scene: spec
            .sweep
            .scenes
            .first()
            .map(|s| s.name.clone())
            .unwrap_or_default(),
        sweep_h: spec.sweep_h.to_string(),
        work_precision_charts: named(&chart_names, "work_precision_"),
        work_precision_text: work_precision_text(&out.sweep),
        variations_text: variations_text(&out.sweep),
        variation_charts: named(&chart_names, "sweep_"),
        stability_section: {
            let mut s = views::readme_section(&out.stability.trials);
            let lines =
                crate::study::stability::uniqueness::readme_lines(&out.stability.uniqueness);
            if !lines.is_empty() {
                s += "\n**Past the fixed point's limit** (problem 1; a solver of the Coulomb problem itself from its \
                      default start and from each starting point its registry entry lists; `stability_uniqueness.csv`):\n\n";
                s += &lines.join("\n");
                s += "\n";
            }
            s
        },
        stability_charts: named(&chart_names, "stability_"),
        stability_summary: views::summary_markdown(&out.stability.trials),
        goals: crate::study::bench::goals::goals_markdown(&out.bench.goals),
        speed_table: speed_table(out),
        performance_charts: named(&chart_names, "performance_"),
        files: FILES.to_vec(),
        benchmark: crate::study::benchmark::views::report(&out.benchmark),
        benchmark_charts: named(&chart_names, "benchmark_"),
        errors_reference: spec.errors.reference.to_string(),
        errors_table: crate::study::discretization_error::markdown(&out.errors),
        errors_text: crate::study::discretization_error::findings(&out.errors),
        errors_charts: named(&chart_names, "discretization_error_"),
    };
    let mut env = minijinja::Environment::new();
    env.add_template("readme", TEMPLATE)?;
    Ok(env.get_template("readme")?.render(context)?)
}

fn worst(trials: &[&Trial], f: fn(&Trial) -> Option<f64>) -> f64 {
    trials.iter().filter_map(|t| f(t)).fold(0.0, f64::max)
}

fn references_text(out: &Outputs) -> String {
    let mut parts: Vec<String> = out
        .references
        .all()
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
            .filter(|t| t.study == study && t.solver == solver && t.law == Law::Coulomb)
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
            worst(ts, |t| t.displacement_error),
            worst(ts, |t| t.pressure_error),
            ts.iter().map(|t| t.certificate).fold(0.0, f64::max),
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

fn zone(
    out: &Outputs,
    problem: u32,
    solver: &str,
    friction: bool,
) -> Option<(String, f64, String)> {
    out.separation
        .iter()
        .find(|r| {
            r.problem == problem && r.solver == solver && (r.friction_coefficient > 0.0) == friction
        })
        .map(|r| {
            (
                r.separated.replace(';', ", "),
                r.separated_fraction,
                r.status.clone(),
            )
        })
}

fn separation_table(spec: &ReproduceSpec, out: &Outputs) -> String {
    let mut s = String::from(
        "| problem | solver | with friction | without friction | paper, with | paper, without |\n|---|---|---|---|---|---|\n",
    );
    for &(problem, paper_with, paper_without) in PAPER_SEPARATION
        .iter()
        .filter(|p| spec.problems.contains(&p.0))
    {
        for e in registry::solvers() {
            let cell = |friction| {
                zone(out, problem, e.name, friction)
                    .map(|(z, f, status)| {
                        let z = if z.is_empty() { "none".to_string() } else { z };
                        format!("{z} = {:.1}% ({status})", 100.0 * f)
                    })
                    .unwrap_or_default()
            };
            let _ = writeln!(
                s,
                "| {problem} | {} | {} | {} | {paper_with} | {paper_without} |",
                e.name,
                cell(true),
                cell(false)
            );
        }
    }
    s
}

fn separation_text(spec: &ReproduceSpec, out: &Outputs) -> String {
    let mut s = String::new();
    let reference = out.references.all().find(|r| r.scene.name == "problem 1");
    let mut differ = Vec::new();
    for a in &out.separation {
        for b in &out.separation {
            if a.problem == b.problem
                && a.status == "converged"
                && b.status == "converged"
                && a.friction_coefficient == b.friction_coefficient
                && a.solver < b.solver
                && (a.separated_fraction - b.separated_fraction).abs() > 1e-3
            {
                differ.push(format!(
                    "problem {} {}: {} {:.1}% vs {} {:.1}%",
                    a.problem,
                    if a.friction_coefficient > 0.0 {
                        "with friction"
                    } else {
                        "without"
                    },
                    a.solver,
                    100.0 * a.separated_fraction,
                    b.solver,
                    100.0 * b.separated_fraction
                ));
            }
        }
    }
    let uncertified: Vec<String> = out
        .separation
        .iter()
        .filter(|r| r.status != "converged")
        .map(|r| {
            format!(
                "{} on problem {} {} ({})",
                r.solver,
                r.problem,
                if r.friction_coefficient > 0.0 {
                    "with friction"
                } else {
                    "without"
                },
                r.status
            )
        })
        .collect();
    let _ = writeln!(
        s,
        "\nSeparation: the jump is below −1e-6 × the largest displacement; interval ends are where the P1 jump crosses \
         that level. The certified solvers' zones {}.{}",
        if differ.is_empty() {
            "agree to 0.1% of Γ_K everywhere".to_string()
        } else {
            format!("differ in: {}", differ.join("; "))
        },
        if uncertified.is_empty() {
            String::new()
        } else {
            format!(
                " Not certified, so not compared: {}.",
                uncertified.join("; ")
            )
        }
    );
    if let Some(r) = reference {
        let f1 = r.coulomb.separation.fraction;
        let p2 = out
            .references
            .all()
            .find(|x| x.scene.name == "problem 2")
            .map(|x| x.coulomb.separation.fraction);
        if let Some(f2) = p2 {
            let _ = writeln!(
                s,
                "Problems 1 and 2 have the same load shape and problem 2 twice the load; the Coulomb problem is \
                 positively homogeneous in the load, so their zones must be the same. The reference's zones: {:.2}% and \
                 {:.2}% — {}.",
                100.0 * f1,
                100.0 * f2,
                if (f1 - f2).abs() <= 1e-9 {
                    "the same"
                } else {
                    "**not** the same"
                }
            );
        }
        if let Some(a) = r.coulomb.separation.intervals.first().map(|i| i[0]) {
            let h = spec.h.h();
            let _ = writeln!(
                s,
                "The paper's problem-1 zone [0.81, 1.00] starts {:.3} ({:.1} nodes at h = {}) before the reference's \
                 [{a:.3}, 1.000].",
                a - 0.81,
                (a - 0.81) / h,
                spec.h
            );
        }
        if let Some(fs) = out.plane_stress_fraction {
            let _ = writeln!(
                s,
                "In plane stress (`--plane stress`), problem 1 with friction separates on {:.1}% of Γ_K (reference \
                 solution) against {:.1}% in plane strain and the paper's 19%: plane strain is {} reading of the paper.",
                100.0 * fs,
                100.0 * f1,
                if (f1 - 0.19).abs() < (fs - 0.19).abs() {
                    "the closer"
                } else {
                    "not the closer"
                }
            );
        }
    }
    s
}

fn table1_text(out: &Outputs) -> String {
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

/// Ratios of time at equal accuracy, interpolated log-log along each
/// solver's work-precision curve, in both diagrams.
fn work_precision_text(sweep: &[Measured]) -> String {
    let (Some(paper), Some(oracle)) = (
        registry::with_role(Role::PapersMethod),
        registry::with_role(Role::Oracle),
    ) else {
        return String::new();
    };
    format!(
        "Each point is one value of a solver's accuracy knob, certified; errors are measured against the reference. \
         On the given-friction subproblem at the reference's g, time at equal pressure error as a ratio (below 1: \
         faster) of each solver over the oracle; `{}` is the paper's method:\n\n{}\n\n\
         On the whole Coulomb problem (a solver run inside the fixed point through ε, every loop's; a solver of the \
         Coulomb law through its own accuracy knob), the same ratios:\n\n{}\n",
        paper.name,
        time_ratios(sweep, WORK_PRECISION, oracle.name),
        time_ratios(sweep, WORK_PRECISION_COULOMB, oracle.name),
    )
}

/// One line per solver: its time over `baseline`'s at equal pressure error
/// along the curves of `group`.
fn time_ratios(sweep: &[Measured], group: &str, baseline: &str) -> String {
    let curve = |solver: &str| -> Vec<(f64, f64)> {
        let mut pts: Vec<(f64, f64)> = sweep
            .iter()
            .filter(|m| m.trial.group == group && m.trial.solver == solver && m.trial.certified())
            .filter_map(|m| {
                m.trial
                    .pressure_error
                    .map(|e| (e.max(crate::study::report::WP_FLOOR), m.timing.seconds_min))
            })
            .filter(|(_, t)| *t > 0.0)
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        pts
    };
    let base = curve(baseline);
    registry::names()
        .into_iter()
        .filter(|n| {
            *n != baseline
                && sweep
                    .iter()
                    .any(|m| m.trial.group == group && m.trial.solver == *n)
        })
        .map(|other| {
            let points = curve(other);
            let ratios: Vec<String> = (2..=11)
                .map(|k| 10f64.powi(-k))
                .filter_map(|target| {
                    let (a, b) = (time_at(&points, target)?, time_at(&base, target)?);
                    Some(format!("{:.2} at {target:.0e}", a / b))
                })
                .collect();
            format!(
                "- `{other}` over `{baseline}`: {}",
                if ratios.is_empty() {
                    "no common range of pressure errors".into()
                } else {
                    ratios.join(", ")
                }
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The time a solver needs for `target` error, interpolated log-log between
/// its points (errors increasing); None outside its range.
fn time_at(points: &[(f64, f64)], target: f64) -> Option<f64> {
    points.windows(2).find_map(|w| {
        let ((e0, t0), (e1, t1)) = (w[0], w[1]);
        (e0 <= target && target <= e1 && e1 > e0).then(|| {
            let a = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
            (t0.ln() + a * (t1.ln() - t0.ln())).exp()
        })
    })
}

/// For each variation: the values certified, and the cheapest certified one.
fn variations_text(sweep: &[Measured]) -> String {
    let mut groups: Vec<&str> = sweep
        .iter()
        .map(|m| m.trial.group.as_str())
        .filter(|g| *g != WORK_PRECISION && *g != WORK_PRECISION_COULOMB)
        .collect();
    groups.dedup();
    let mut seen = Vec::new();
    let mut lines = Vec::new();
    for g in groups {
        if seen.contains(&g) {
            continue;
        }
        seen.push(g);
        let runs: Vec<&Trial> = sweep
            .iter()
            .map(|m| &m.trial)
            .filter(|t| t.group == g)
            .collect();
        let certified: Vec<&&Trial> = runs.iter().filter(|t| t.certified()).collect();
        let failed: Vec<String> = runs
            .iter()
            .filter(|t| !t.certified())
            .map(|t| format!("{} ({})", t.value, t.status))
            .collect();
        let cheapest = certified.iter().min_by_key(|t| t.work);
        lines.push(format!(
            "- `{g}` ({}): certified at {}; {}{}",
            runs.first().map(|t| t.solver.as_str()).unwrap_or(""),
            if certified.is_empty() {
                "no value".to_string()
            } else {
                certified
                    .iter()
                    .map(|t| t.value.clone())
                    .collect::<Vec<_>>()
                    .join(", ")
            },
            match cheapest {
                Some(t) => format!(
                    "the least work at {} ({} work, pressure error {})",
                    t.value,
                    t.work,
                    t.pressure_error
                        .map(|e| format!("{e:.1e}"))
                        .unwrap_or_else(|| "–".into())
                ),
                None => String::new(),
            },
            if failed.is_empty() {
                String::new()
            } else {
                format!("; not certified at {}", failed.join(", "))
            }
        ));
    }
    if lines.is_empty() {
        String::new()
    } else {
        format!(
            "One factor at a time around the defaults, on the whole Coulomb problem (every trial stops at a work cap):\n\n{}\n",
            lines.join("\n")
        )
    }
}

fn speed_table(out: &Outputs) -> String {
    let rows = &out.bench.rows;
    let mut meshes: Vec<&str> = rows.iter().map(|r| r.h.as_str()).collect();
    meshes.dedup();
    let mut s = String::from(
        "\nWhole Coulomb problem, median seconds (× one factorization), certified status:\n\n| solver |",
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
                "one factorization + solve"
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
