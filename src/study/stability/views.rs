//! Views of the stability map: counts per group and class, the trials that
//! did not simply converge, findings computed from the trials (where each
//! solver's settings stop working, the largest certified friction
//! coefficient), and charts.

use std::collections::BTreeMap;

use anyhow::Result;
use serde::Serialize;

use crate::certificate::Condition;
use crate::study::stability::classify::{Class, SLOW_FACTOR, WRONG_PRESSURE};
use crate::study::stability::uniqueness::{ONE_SOLUTION, UniquenessRow};
use crate::study::stability::{BYPASSED, DEFAULT, FRICTION, LOAD, SCENES, STRESS};
use crate::study::template;
use crate::study::trial::Trial;

pub(super) fn class_of(t: &Trial) -> Class {
    t.class.unwrap_or(Class::Converged)
}

/// The class as the tables write it.
fn class_text(t: &Trial) -> &'static str {
    class_of(t).as_str()
}

/// A group's count of trials in each class, in [`Class::ALL`]'s order.
#[derive(Serialize)]
struct GroupCounts<'a> {
    group: &'a str,
    counts: Vec<usize>,
}

/// A trial that did not simply converge, as the summary lists it.
#[derive(Serialize)]
struct Listed<'a> {
    group: &'a str,
    solver: &'static str,
    scene: &'a str,
    h: String,
    setting: String,
    class: &'static str,
    /// Its reason, cut to 220 characters, `|` as `/` (a table cell).
    reason: String,
}

/// Counts per group and class, then every trial that did not simply
/// converge with its reason (`templates/stability_summary.md`).
pub fn summary_markdown(trials: &[Trial]) -> Result<String> {
    let mut groups: Vec<&str> = Vec::new();
    for t in trials {
        if !groups.contains(&t.group.as_str()) {
            groups.push(&t.group);
        }
    }
    let counts: Vec<GroupCounts> = groups
        .into_iter()
        .map(|g| GroupCounts {
            group: g,
            counts: Class::ALL
                .iter()
                .map(|&c| {
                    trials
                        .iter()
                        .filter(|r| r.group == g && class_of(r) == c)
                        .count()
                })
                .collect(),
        })
        .collect();
    let listed: Vec<Listed> = trials
        .iter()
        .filter(|r| class_of(r) != Class::Converged)
        .map(|r| Listed {
            group: &r.group,
            solver: r.solver.name,
            scene: &r.scene,
            h: r.h.to_string(),
            setting: setting(r),
            class: class_text(r),
            reason: r
                .reason
                .chars()
                .take(220)
                .collect::<String>()
                .replace('|', "/"),
        })
        .collect();
    template::render(
        "stability_summary",
        include_str!("../templates/stability_summary.md"),
        template::facts! {
            classes => Class::ALL.map(|c| c.as_str()),
            counts,
            trials => listed,
        },
    )
}

fn setting(r: &Trial) -> String {
    match &r.setting {
        None => "defaults".into(),
        Some(s) => format!("{} = {}", s.path, s.value),
    }
}

/// The values of a stress knob that fell in one class, in the order run.
#[derive(Serialize)]
pub struct ClassValues {
    pub class: &'static str,
    pub values: Vec<String>,
}

/// A stress knob of a solver and its values by class.
#[derive(Serialize)]
pub struct StressKnob {
    pub knob: String,
    pub classes: Vec<ClassValues>,
}

/// Per solver and stress knob: the values in each class (in
/// [`Class::ALL`]'s order), each class's in the order run.
pub fn stress_findings(trials: &[Trial]) -> Vec<StressKnob> {
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
        out.push(StressKnob {
            knob,
            classes: by
                .into_values()
                .map(|(c, values)| ClassValues {
                    class: c.as_str(),
                    values,
                })
                .collect(),
        });
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

/// A solver at its defaults and under its stress knobs.
#[derive(Serialize)]
struct SolverFacts {
    name: &'static str,
    class: &'static str,
    work: usize,
    certificate: f64,
    stress: Vec<StressKnob>,
}

/// Where the friction scan of one problem and solver stops being
/// certified ([`FrictionLimit`], none for no coefficient certified).
#[derive(Serialize)]
struct FrictionFacts {
    scene: String,
    solver: String,
    up_to: Option<f64>,
    first_failure: Option<f64>,
    again: Vec<f64>,
}

/// A trial of the load group that did not converge.
#[derive(Serialize)]
struct LoadFacts<'a> {
    scene: &'a str,
    solver: &'static str,
    class: &'static str,
    failing: Vec<&'static str>,
}

/// A trial named with its class and reason or status.
#[derive(Serialize)]
struct Other<'a> {
    solver: &'static str,
    scene: &'a str,
    class: &'static str,
    reason: &'a str,
    status: String,
}

/// A classical scene: how many solvers converged at their defaults, and
/// the others.
#[derive(Serialize)]
struct SceneFacts<'a> {
    scene: &'a str,
    converged: usize,
    total: usize,
    others: Vec<Other<'a>>,
}

fn other(t: &Trial) -> Other<'_> {
    Other {
        solver: t.solver.name,
        scene: &t.scene,
        class: class_text(t),
        reason: &t.reason,
        status: t.status.to_string(),
    }
}

/// The README's section on the map (`templates/stability.md`): the
/// thresholds, then what the trials show, each line computed from them,
/// the uniqueness rows, the charts and the summary.
pub fn section(
    trials: &[Trial],
    uniqueness: &[UniquenessRow],
    charts: &[String],
) -> Result<String> {
    let tolerance = trials
        .first()
        .map(|t| t.tolerance)
        .unwrap_or(crate::certificate::DEFAULT_TOLERANCE);
    let mut names: Vec<&str> = Vec::new();
    for t in trials {
        if !names.contains(&t.solver.name) {
            names.push(t.solver.name);
        }
    }
    let solvers: Vec<SolverFacts> = names
        .into_iter()
        .filter_map(|solver| {
            let own: Vec<Trial> = trials
                .iter()
                .filter(|t| t.solver.name == solver)
                .cloned()
                .collect();
            let d = own.iter().find(|t| t.group == DEFAULT)?;
            Some(SolverFacts {
                name: d.solver.name,
                class: class_text(d),
                work: d.work,
                certificate: d.residual(),
                stress: stress_findings(&own),
            })
        })
        .collect();
    let friction: Vec<FrictionFacts> = friction_limits(trials)
        .into_iter()
        .map(|f| FrictionFacts {
            scene: f.scene,
            solver: f.solver,
            up_to: f.certified_up_to.is_finite().then_some(f.certified_up_to),
            first_failure: f.first_failure,
            again: f.certified_again,
        })
        .collect();
    let load: Vec<&Trial> = trials
        .iter()
        .filter(|t| t.group == LOAD && class_of(t) != Class::Converged)
        .collect();
    let load_force_balance = load
        .iter()
        .any(|t| t.failing().first() == Some(&Condition::ForceBalance));
    let load: Vec<LoadFacts> = load
        .into_iter()
        .map(|t| LoadFacts {
            scene: &t.scene,
            solver: t.solver.name,
            class: class_text(t),
            failing: t.failing().iter().map(|c| c.as_str()).collect(),
        })
        .collect();
    let mut scene_names: Vec<&str> = Vec::new();
    for t in trials.iter().filter(|t| t.group == SCENES) {
        if !scene_names.contains(&t.scene.as_str()) {
            scene_names.push(&t.scene);
        }
    }
    let scenes: Vec<SceneFacts> = scene_names
        .into_iter()
        .map(|scene| {
            let own: Vec<&Trial> = trials
                .iter()
                .filter(|t| t.group == SCENES && t.scene == scene)
                .collect();
            SceneFacts {
                scene,
                converged: own
                    .iter()
                    .filter(|t| class_of(t) == Class::Converged)
                    .count(),
                total: own.len(),
                others: own
                    .iter()
                    .filter(|t| class_of(t) != Class::Converged)
                    .map(|t| other(t))
                    .collect(),
            }
        })
        .collect();
    let bypassed: Vec<Other> = trials
        .iter()
        .filter(|t| t.group == BYPASSED)
        .map(other)
        .collect();
    let uniqueness: Vec<UniquenessFacts> = uniqueness
        .iter()
        .map(|row| UniquenessFacts {
            row,
            one_solution: row.spread.is_some_and(|s| s <= ONE_SOLUTION),
        })
        .collect();
    let summary = summary_markdown(trials)?;
    template::render(
        "stability",
        include_str!("../templates/stability.md"),
        template::facts! {
            tolerance,
            wrong_pressure => WRONG_PRESSURE,
            slow_factor => SLOW_FACTOR,
            solvers,
            friction,
            load,
            load_force_balance,
            scenes,
            bypassed,
            uniqueness,
            charts,
            summary,
        },
    )
}

/// A uniqueness row and whether its certified answers are one solution
/// (their spread within [`ONE_SOLUTION`]).
#[derive(Serialize)]
struct UniquenessFacts<'a> {
    #[serde(flatten)]
    row: &'a UniquenessRow,
    one_solution: bool,
}
