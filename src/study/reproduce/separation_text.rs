//! The README's separation table and the sentences about the zones, computed
//! from the runs.

use std::fmt::Write as _;

use contactlab_solvers::registry;

use crate::study::lab::Findings;
use crate::study::reference::References;
use crate::study::reproduce::ReproduceSpec;

/// The paper's reported separation (section 5, h = 1/64): problem 1 with
/// friction on [0.81, 1.00] (19%), without friction 34%; problem 3 closed.
pub const PAPER_SEPARATION: [(u32, &str, &str); 3] = [
    (1, "[0.81, 1.00] = 19%", "34%"),
    (2, "not reported", "not reported"),
    (3, "none (closed on all of Γ_K)", "not reported"),
];

pub(super) fn zone(
    out: &Findings,
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

pub(super) fn separation_table(spec: &ReproduceSpec, out: &Findings) -> String {
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

pub(super) fn separation_text(
    spec: &ReproduceSpec,
    out: &Findings,
    references: &References,
) -> String {
    let mut s = String::new();
    let reference = references
        .of(&out.compare_references)
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
            .of(&out.compare_references)
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
