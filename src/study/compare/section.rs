//! The comparison's section of a run's README: the headline (does the
//! paper's method agree with the reference?), the table, the separation
//! zones against the paper, the contact-zone and convergence charts; all
//! computed from the comparison's findings.

use std::fmt::Write as _;

use contactlab_solvers::Law;
use contactlab_solvers::registry::{self, Role};

use crate::mechanics::mesh_size::MeshSize;
use crate::study::compare::paper::{PAPER_SETTINGS, PaperFindings};
use crate::study::compare::{STUDY, markdown_of};
use crate::study::lab::chart_markdown;
use crate::study::reference::References;
use crate::study::runner::Measured;
use crate::study::trial::{Trial, WRONG_PRESSURE};

/// The paper's reported separation (section 5, h = 1/64): problem 1 with
/// friction on [0.81, 1.00] (19%), without friction 34%; problem 3 closed.
pub const PAPER_SEPARATION: [(u32, &str, &str); 3] = [
    (1, "[0.81, 1.00] = 19%", "34%"),
    (2, "not reported", "not reported"),
    (3, "none (closed on all of Γ_K)", "not reported"),
];

fn zone(
    out: &PaperFindings,
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

fn separation_table(problems: &[u32], out: &PaperFindings) -> String {
    let mut s = String::from(
        "| problem | solver | with friction | without friction | paper, with | paper, without |\n|---|---|---|---|---|---|\n",
    );
    for &(problem, paper_with, paper_without) in
        PAPER_SEPARATION.iter().filter(|p| problems.contains(&p.0))
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

fn separation_text(h: MeshSize, out: &PaperFindings, references: &References) -> String {
    let mut s = String::new();
    let reference = references
        .of(&out.references)
        .find(|r| r.scene.name == "problem 1");
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
        let f1 = r.coulomb.separation().fraction;
        let p2 = references
            .of(&out.references)
            .find(|x| x.scene.name == "problem 2")
            .map(|x| x.coulomb.separation().fraction);
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
        if let Some(a) = r.coulomb.separation().intervals.first().map(|i| i[0]) {
            let step = h.h();
            let _ = writeln!(
                s,
                "The paper's problem-1 zone [0.81, 1.00] starts {:.3} ({:.1} nodes at h = {}) before the reference's \
                 [{a:.3}, 1.000].",
                a - 0.81,
                (a - 0.81) / step,
                h
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

/// The whole section.
pub fn section(
    h: MeshSize,
    problems: &[u32],
    out: &PaperFindings,
    references: &References,
    tolerance: f64,
    charts: &[String],
) -> String {
    let trials: Vec<&Measured> = out.measured.iter().flat_map(|(_, v)| v.iter()).collect();
    let all: Vec<Measured> = trials.iter().map(|m| Measured::without_finest(m)).collect();
    let mut s = format!(
        "## Does the paper's solver agree with the reference?\n\nThe reference of each problem: {}; \
         `references.csv` lists every candidate.\n\n{}\n\n{}\n",
        references_text(references, &out.references),
        agreement(&trials, tolerance),
        markdown_of(&all)
    );
    let _ = write!(
        s,
        "\n## Separation zones against the paper (h = {h})\n\n{}{}",
        separation_table(problems, out),
        separation_text(h, out, references)
    );
    s += "\n## Contact zone (the paper's figures 2-5)\n\n";
    for c in charts.iter().filter(|c| c.starts_with("profile_")) {
        s += &chart_markdown(c, profile_intent(c));
    }
    if charts.iter().any(|c| c.starts_with("bound_vs_error")) {
        s += "## The error bound against the measured error\n\n";
    }
    for c in charts.iter().filter(|c| c.starts_with("bound_vs_error")) {
        s += &chart_markdown(
            c,
            "Each answer's error bound (issue 51) against its measured distance from the reference, both in the energy seminorm over √K·U: no given-friction point may lie below the line bound = error; a Coulomb answer's bound is at its own g = 𝓕p.",
        );
    }
    s += "## Convergence histories\n\n";
    for c in charts.iter().filter(|c| c.starts_with("convergence")) {
        s += &chart_markdown(
            c,
            if c.starts_with("convergence_inner") {
                "How each inner solver converges inside the friction fixed point: its residual against its own iteration count over the whole run."
            } else {
                "How fast the friction fixed point (or a direct Coulomb solver's own iteration) converges for each solver."
            },
        );
    }
    s
}

/// What each contact-zone chart is for.
fn profile_intent(name: &str) -> &'static str {
    if name.ends_with("_displacement") {
        "Whether the paper's method (dots) reproduces the oracle's vertical displacements of both bodies on Γ_K (the paper's figure 2)."
    } else if name.ends_with("_zoom") {
        "How friction changes the separation zone: both bodies near the opening, with friction (solid) and without (dashed)."
    } else if name.ends_with("_jump") {
        "Where the bodies separate (negative jump) with and without friction; values below 1e-9 of the largest displacement are drawn as zero."
    } else {
        "The contact pressure (the multiplier l) along Γ_K with and without friction, and the paper's method on the oracle's curve."
    }
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
    let rel = of(STUDY, paper.name);
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
        let o = of(STUDY, oracle.name);
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
