//! Views of the stability map: counts per group and class, the trials that
//! did not simply converge, findings computed from the trials (where each
//! solver's settings stop working, the largest certified friction
//! coefficient), and charts.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::certificate::Condition;
use crate::study::stability::classify::{Class, SLOW_FACTOR, WRONG_PRESSURE};
use crate::study::stability::{BYPASSED, DEFAULT, FRICTION, LOAD, SCENES, STRESS};
use crate::study::trial::Trial;

pub(super) fn class_of(t: &Trial) -> Class {
    t.class.unwrap_or(Class::Converged)
}

/// The class as the tables write it.
fn class_text(t: &Trial) -> &'static str {
    class_of(t).as_str()
}

/// The failing conditions, `, `-separated.
fn failing_text(t: &Trial) -> String {
    t.failing()
        .iter()
        .map(|c| c.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Counts per group and class, then every trial that did not simply
/// converge with its reason.
pub fn summary_markdown(trials: &[Trial]) -> String {
    let mut s = counts_markdown(trials);
    s += "\n| group | solver | problem | h | setting | class | reason |\n|---|---|---|---|---|---|---|\n";
    for r in trials.iter().filter(|r| class_of(r) != Class::Converged) {
        let reason: String = r.reason.chars().take(220).collect();
        s += &format!(
            "| {} | {} | {} | {} | {} | **{}** | {} |\n",
            r.group,
            r.solver.name,
            r.scene,
            r.h,
            setting(r),
            class_text(r),
            reason.replace('|', "/")
        );
    }
    s
}

/// The trials counted per group and class, as a Markdown table.
pub fn counts_markdown(trials: &[Trial]) -> String {
    let mut groups: Vec<&str> = trials.iter().map(|r| r.group.as_str()).collect();
    groups.dedup();
    let mut s = String::from("| group | ");
    s += &Class::ALL.map(|c| c.as_str()).join(" | ");
    s += " |\n|---|";
    s += &"---|".repeat(Class::ALL.len());
    s += "\n";
    let mut seen = Vec::new();
    for g in groups {
        if seen.contains(&g) {
            continue;
        }
        seen.push(g);
        s += &format!("| {g} |");
        for c in Class::ALL {
            let n = trials
                .iter()
                .filter(|r| r.group == g && class_of(r) == c)
                .count();
            s += &format!(" {n} |");
        }
        s += "\n";
    }
    s
}

fn setting(r: &Trial) -> String {
    match &r.setting {
        None => "defaults".into(),
        Some(s) => format!("{} = {}", s.path, s.value),
    }
}

/// Per solver and stress knob: the values in each class, in the order run.
pub fn stress_findings(trials: &[Trial]) -> Vec<String> {
    let mut out = Vec::new();
    for (solver, knob) in stress_keys(trials) {
        let mut by: BTreeMap<usize, (Class, Vec<String>)> = BTreeMap::new();
        for t in trials
            .iter()
            .filter(|t| t.group == STRESS && t.solver.name == solver && t.knob().0 == knob)
        {
            let c = class_of(t);
            let i = Class::ALL.iter().position(|x| *x == c).unwrap_or(0);
            by.entry(i)
                .or_insert((c, Vec::new()))
                .1
                .push(t.knob().1.to_string());
        }
        let parts: Vec<String> = by
            .values()
            .map(|(c, v)| format!("{} at {}", c.as_str(), v.join(", ")))
            .collect();
        out.push(format!("`{knob}`: {}", parts.join("; ")));
    }
    out
}

/// Each (solver, knob) of the stress groups, in the order run.
pub(super) fn stress_keys(trials: &[Trial]) -> Vec<(String, String)> {
    let mut keys: Vec<(String, String)> = Vec::new();
    for t in trials.iter().filter(|t| t.group == STRESS) {
        let k = (t.solver.name.to_string(), t.knob().0.to_string());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys
}

/// Where the friction scan stops being certified, for one problem and solver.
#[derive(Clone, Debug, PartialEq)]
pub struct FrictionLimit {
    pub scene: String,
    pub solver: String,
    /// Every coefficient tried up to this one is certified.
    pub certified_up_to: f64,
    pub first_failure: Option<f64>,
    /// Larger coefficients certified after a failure.
    pub certified_again: Vec<f64>,
}

/// Per problem and solver: the largest friction coefficient up to which
/// every coefficient tried is certified, the first one that is not (if
/// any), and the larger coefficients certified again (the scan is not
/// monotone when an inner solver's noise, not the method, ends a run).
pub fn friction_limits(trials: &[Trial]) -> Vec<FrictionLimit> {
    let friction: Vec<&Trial> = trials
        .iter()
        .filter(|t| t.group.starts_with(FRICTION))
        .collect();
    let mut keys: Vec<(String, String)> = friction
        .iter()
        .map(|t| (t.scene.clone(), t.solver.name.to_string()))
        .collect();
    keys.sort();
    keys.dedup();
    keys.into_iter()
        .map(|(p, s)| {
            let mut runs: Vec<(f64, bool)> = friction
                .iter()
                .filter(|t| t.scene == p && t.solver.name == s)
                .map(|t| {
                    let f = t.setting.as_ref().and_then(|s| s.number);
                    (f.unwrap_or(f64::NAN), t.certified())
                })
                .collect();
            runs.sort_by(|a, b| a.0.total_cmp(&b.0));
            let first_bad = runs.iter().find(|r| !r.1).map(|r| r.0);
            let ok = runs
                .iter()
                .filter(|r| r.1 && first_bad.is_none_or(|b| r.0 < b))
                .map(|r| r.0)
                .fold(f64::NEG_INFINITY, f64::max);
            let again: Vec<f64> = runs
                .iter()
                .filter(|r| r.1 && first_bad.is_some_and(|b| r.0 > b))
                .map(|r| r.0)
                .collect();
            FrictionLimit {
                scene: p,
                solver: s,
                certified_up_to: ok,
                first_failure: first_bad,
                certified_again: again,
            }
        })
        .collect()
}

/// The README's section on the map: the thresholds, then what the trials
/// show, each line computed from them.
pub fn readme_section(trials: &[Trial]) -> String {
    let mut s = String::new();
    let tol = trials
        .first()
        .map(|t| t.tolerance)
        .unwrap_or(crate::certificate::DEFAULT_TOLERANCE);
    let _ = writeln!(
        s,
        "Classes (`src/study/stability/classify.rs`): **refused**, the problem has no solution and this is said (our \
         check of condition (13), or a solver reporting it unbounded or infeasible); **diverged**, a NaN, a numerical \
         breakdown, a fixed point whose max|Δg| grows, or a solver that reports a solvable problem unbounded; \
         **stalled**, stopped by a work cap, at reduced accuracy, at floating-point resolution short of its tolerance, or a fixed point that stopped contracting; **wrong**, \
         converged by its own test but failing the certificate (tolerance {tol:e}) or with a pressure off the reference's \
         by more than {WRONG_PRESSURE:e}; **slow**, right but more than {SLOW_FACTOR}× the work of the same solver at its \
         defaults; **converged**. Every trial stops at a work cap (a count), so the map is the same on every machine.\n"
    );
    let mut solvers: Vec<&str> = trials.iter().map(|t| t.solver.name).collect();
    solvers.dedup();
    let mut seen = Vec::new();
    for solver in solvers {
        if seen.contains(&solver) {
            continue;
        }
        seen.push(solver);
        let own: Vec<Trial> = trials
            .iter()
            .filter(|t| t.solver.name == solver)
            .cloned()
            .collect();
        let lines = stress_findings(&own);
        if let Some(d) = own.iter().find(|t| t.group == DEFAULT) {
            let _ = writeln!(
                s,
                "- **{solver}** at its defaults: {} ({} work, certificate {:.1e}). {}",
                class_text(d),
                d.work,
                d.residual(),
                lines.join("; ")
            );
        }
    }
    for FrictionLimit {
        scene: p,
        solver,
        certified_up_to: ok,
        first_failure: bad,
        certified_again: again,
    } in friction_limits(trials)
    {
        let _ = writeln!(
            s,
            "- **Friction coefficient**, {p}, {solver}: certified for every 𝓕 tried up to {}{}{}.",
            if ok.is_finite() {
                format!("{ok}")
            } else {
                "none".into()
            },
            match bad {
                Some(b) => format!("; not at 𝓕 = {b}"),
                None => " (no failure among the coefficients tried)".into(),
            },
            if again.is_empty() {
                String::new()
            } else {
                format!(
                    "; certified again at {} (not monotone: see the reasons below)",
                    again
                        .iter()
                        .map(|f| f.to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            }
        );
    }
    let load: Vec<&Trial> = trials
        .iter()
        .filter(|t| t.group == LOAD && class_of(t) != Class::Converged)
        .collect();
    let listed: Vec<String> = load
        .iter()
        .map(|t| {
            let failing = if t.failing().is_empty() {
                String::new()
            } else {
                format!(": {}", failing_text(t))
            };
            format!(
                "{} with {} ({}{failing})",
                t.scene,
                t.solver.name,
                class_text(t)
            )
        })
        .collect();
    let _ = writeln!(
        s,
        "- **Total load approaching zero** (an upward traction cancelling most of problem 1's load): {}.{}",
        if listed.is_empty() {
            "every solver is certified at every load tried".to_string()
        } else {
            listed.join("; ")
        },
        if load
            .iter()
            .any(|t| t.failing().first() == Some(&Condition::ForceBalance))
        {
            " The force balance is held to the net load the contact carries, while relative stopping rules are scaled \
             by the gross load Σ|f|: as the net load falls, a solver stopped at the same relative change resolves it \
             less and less."
        } else {
            ""
        }
    );
    let mut scenes: Vec<&str> = Vec::new();
    for t in trials.iter().filter(|t| t.group == SCENES) {
        if !scenes.contains(&t.scene.as_str()) {
            scenes.push(&t.scene);
        }
    }
    for scene in scenes {
        let own: Vec<&Trial> = trials
            .iter()
            .filter(|t| t.group == SCENES && t.scene == scene)
            .collect();
        let converged = own
            .iter()
            .filter(|t| class_of(t) == Class::Converged)
            .count();
        let others: Vec<String> = own
            .iter()
            .filter(|t| class_of(t) != Class::Converged)
            .map(|t| format!("{} {} ({})", t.solver.name, class_text(t), t.reason))
            .collect();
        let _ = writeln!(
            s,
            "- **Scene {scene}**: {converged} of {} solvers converged at their defaults{}.",
            own.len(),
            if others.is_empty() {
                String::new()
            } else {
                format!("; {}", others.join("; "))
            }
        );
    }
    let bypassed: Vec<String> = trials
        .iter()
        .filter(|t| t.group == BYPASSED)
        .map(|t| {
            format!(
                "{} on {}: {} ({})",
                t.solver.name,
                t.scene,
                t.status,
                class_text(t)
            )
        })
        .collect();
    if !bypassed.is_empty() {
        let _ = writeln!(
            s,
            "- **Condition (13) violated**: refused with a one-line error before any solve. With the check bypassed (one \
             given-friction solve): {}.",
            bypassed.join("; ")
        );
    }
    s
}
