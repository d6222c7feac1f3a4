//! All settings of a computation: the stopping mode, the continuation
//! schedule, the certificate's tolerance, and changes to the defaults of the
//! Coulomb fixed point and of every registered solver, by path
//! (`coulomb.epsilon`, `relaxation.r`, `clarabel.tol`). The defaults depend on
//! the stopping mode (relative, or the paper's absolute values), so only the
//! changes are stored and every setting is resolved when it is used. Paths are
//! checked against the registry: the harness never names a solver.

pub mod changes;

use std::collections::BTreeMap;

use contactlab_solvers::Solver;
use contactlab_solvers::registry::{self, Entry};
use contactlab_solvers::settings::{Knob, Stopping, from_tree, to_tree};
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::certificate::error_bound::SOLVE_BOUND_MAX_UNKNOWNS;
use crate::certificate::{DEFAULT_TOLERANCE, check_tolerance};
use crate::coulomb::continuation::Schedule;
use crate::coulomb::fixed_point::{self, CoulombSettings};

pub use changes::{Change, Changes};

/// The certificate's settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CertificateSettings {
    /// Largest violation of any condition (dimensionless, in the problem's
    /// scales) that still certifies a solution.
    pub tolerance: f64,
    /// The largest problem (in unknowns) whose answers get an error bound
    /// beside their certificate in `solve` and in every trial: the bound
    /// takes sparse factorizations of its own, which at fine h cost more
    /// than the fast solvers (0: never).
    pub bound_max_unknowns: usize,
}

impl Default for CertificateSettings {
    fn default() -> Self {
        Self {
            tolerance: DEFAULT_TOLERANCE,
            bound_max_unknowns: SOLVE_BOUND_MAX_UNKNOWNS,
        }
    }
}

impl CertificateSettings {
    /// Whether an answer of a problem of `n` unknowns gets an error bound.
    pub fn bounds(&self, n: usize) -> bool {
        n <= self.bound_max_unknowns
    }
}

/// Settings of one computation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Settings {
    pub stopping: Stopping,
    /// Mesh continuation schedule for solvers that warm-start; None: each
    /// solver's own (its registry entry's fastest, [`Settings::schedule_of`]).
    pub schedule: Option<Schedule>,
    pub certificate: CertificateSettings,
    /// Changes to the defaults, by path (one settings field each).
    overrides: BTreeMap<String, Value>,
}

/// The prefix of the Coulomb fixed point's settings.
pub const COULOMB: &str = "coulomb";

impl Settings {
    /// The paper's absolute rules and values everywhere.
    pub fn paper() -> Self {
        Self {
            stopping: Stopping::Paper,
            ..Self::default()
        }
    }

    /// Sets `path` (`coulomb.FIELD`, or `SOLVER.KNOB` / `SOLVER.FIELD` of a
    /// registered solver) to `value`. A knob that stands for several fields
    /// sets them all. Unknown paths are errors that list what exists.
    pub fn set(&mut self, path: &str, value: Value) -> Result<(), String> {
        let (owner, key) = path.split_once('.').ok_or_else(|| {
            format!(
                "setting '{path}': write it as OWNER.NAME, e.g. coulomb.epsilon or {}",
                example_path()
            )
        })?;
        let defaults = self.defaults_of(owner).ok_or_else(|| {
            format!(
                "setting '{path}': '{owner}' is neither `coulomb` nor a registered solver ({})",
                registry::names().join(", ")
            )
        })?;
        let fields: Vec<&str> = match registry::by_name(owner).and_then(|e| e.knob(key)) {
            Some(knob) => knob.fields.to_vec(),
            None => vec![key],
        };
        let before = self.overrides.clone();
        for field in fields {
            if defaults.get(field).is_none() {
                let known: Vec<String> = defaults
                    .as_object()
                    .map(|o| o.keys().cloned().collect())
                    .unwrap_or_default();
                return Err(format!(
                    "setting '{path}': {owner} has no setting '{key}' (its settings: {})",
                    known.join(", ")
                ));
            }
            self.overrides
                .insert(format!("{owner}.{field}"), value.clone());
        }
        // Check now, so that a wrong type or range is blamed on this setting.
        let check = if owner == COULOMB {
            self.coulomb().map(|_| ())
        } else {
            let entry = registry::by_name(owner).expect("checked above");
            self.build(entry).map(|_| ())
        };
        if let Err(message) = check {
            self.overrides = before;
            return Err(if message.starts_with(path) {
                message
            } else {
                format!(
                    "{path} = {value} is invalid: {}",
                    strip_owner(owner, &message)
                )
            });
        }
        Ok(())
    }

    /// Sets `path` from text as the command line writes it: a solver's knob
    /// parses its own values (`exact`, `1e-10`), anything else is a number,
    /// `true`/`false` or a word.
    pub fn set_text(&mut self, path: &str, text: &str) -> Result<(), String> {
        match path {
            "schedule" => {
                self.schedule = Some(Schedule::from_name(text).ok_or_else(|| {
                    format!("schedule = '{text}' is invalid: give revisit, finest-only or nested")
                })?);
                return Ok(());
            }
            "stopping" => {
                self.stopping = match text.trim() {
                    "relative" => Stopping::Relative,
                    "paper" => Stopping::Paper,
                    _ => {
                        return Err(format!(
                            "stopping = '{text}' is invalid: give relative or paper"
                        ));
                    }
                };
                return Ok(());
            }
            "certificate.tolerance" => {
                let t = text.trim().parse::<f64>().map_err(|_| {
                    format!("certificate.tolerance = '{text}' is invalid: give a number")
                })?;
                self.certificate.tolerance =
                    check_tolerance(t).map_err(|m| format!("certificate.tolerance = {m}"))?;
                return Ok(());
            }
            "certificate.bound_max_unknowns" => {
                self.certificate.bound_max_unknowns = text.trim().parse::<usize>().map_err(|_| {
                    format!(
                        "certificate.bound_max_unknowns = '{text}' is invalid: give a whole number of unknowns (0: no error bounds; default {SOLVE_BOUND_MAX_UNKNOWNS})"
                    )
                })?;
                return Ok(());
            }
            _ => {}
        }
        let value = match knob_of(path) {
            Some((k, defaults)) => k.parse(text).map_err(|m| {
                format!(
                    "{path} = '{text}' is invalid: {m} (default {})",
                    k.default_text(defaults)
                )
            }),
            None => contactlab_solvers::settings::parse_scalar(text)
                .map_err(|m| format!("{path} = '{text}' is invalid: {m}")),
        }?;
        self.set(path, value)
    }

    /// Sets the paper's one ε "for every loop that uses it": the fixed
    /// point's, and every registered solver's knob named `epsilon`.
    pub fn set_epsilon(&mut self, epsilon: f64) -> Result<(), String> {
        self.set("coulomb.epsilon", Value::from(epsilon))?;
        for e in registry::solvers() {
            if e.knob("epsilon").is_some() {
                self.set(&format!("{}.epsilon", e.name), Value::from(epsilon))?;
            }
        }
        Ok(())
    }

    /// The value at `path` after the changes (None: no such setting).
    pub fn get(&self, path: &str) -> Option<Value> {
        let (owner, field) = path.split_once('.')?;
        self.tree(owner)?.get(field).cloned()
    }

    /// The changes, by path.
    pub fn overrides(&self) -> &BTreeMap<String, Value> {
        &self.overrides
    }

    fn defaults_of(&self, owner: &str) -> Option<Value> {
        if owner == COULOMB {
            Some(to_tree(&CoulombSettings::defaults(self.stopping)))
        } else {
            registry::by_name(owner).map(|e| (e.defaults)(self.stopping))
        }
    }

    /// The settings tree of `owner` with the changes applied.
    fn tree(&self, owner: &str) -> Option<Value> {
        let mut tree = self.defaults_of(owner)?;
        let prefix = format!("{owner}.");
        for (path, value) in &self.overrides {
            if let Some(field) = path.strip_prefix(&prefix) {
                tree[field] = value.clone();
            }
        }
        Some(tree)
    }

    /// The fixed point's settings.
    pub fn coulomb(&self) -> Result<CoulombSettings, String> {
        from_tree(&self.tree(COULOMB).expect("coulomb has defaults")).map_err(|e| named(COULOMB, e))
    }

    /// A solver's settings tree: its entry's defaults with the changes
    /// applied (an entry registered after these settings were made, too).
    pub fn solver_tree(&self, entry: &Entry) -> Value {
        self.tree(entry.name)
            .unwrap_or_else(|| (entry.defaults)(self.stopping))
    }

    /// Builds a registered solver with these settings.
    pub fn build(&self, entry: &Entry) -> Result<Box<dyn Solver>, String> {
        entry
            .build
            .call(&self.solver_tree(entry))
            .map_err(|e| named(entry.name, e))
    }

    /// Checks every setting: the fixed point's, each solver's (against its
    /// knobs' kinds, without building it), the certificate's.
    pub fn validate(&self) -> Result<(), String> {
        self.coulomb()?;
        for e in registry::solvers() {
            e.check(&self.solver_tree(e))
                .map_err(|m| named(e.name, m))?;
        }
        check_tolerance(self.certificate.tolerance)
            .map_err(|m| format!("certificate.tolerance = {m}"))?;
        Ok(())
    }

    /// The mesh continuation `entry` runs: the one chosen, else its own.
    pub fn schedule_of(&self, entry: &Entry) -> Schedule {
        self.schedule
            .unwrap_or_else(|| entry.default_schedule(&self.solver_tree(entry)))
    }

    /// Every setting, resolved, as one tree (for summaries and manifests).
    pub fn resolved(&self) -> Value {
        let mut solvers = serde_json::Map::new();
        for e in registry::solvers() {
            let mut tree = self.solver_tree(e);
            if let Some(o) = tree.as_object_mut() {
                o.insert(
                    "laws".into(),
                    Value::from(e.laws.iter().map(|l| l.as_str()).collect::<Vec<_>>()),
                );
                if e.warm_starts {
                    o.insert("schedule".into(), Value::from(self.schedule_of(e).name()));
                }
            }
            solvers.insert(e.name.into(), tree);
        }
        serde_json::json!({
            "stopping": self.stopping,
            "schedule": self.schedule.map_or("each solver's own", Schedule::name),
            "certificate": self.certificate,
            "coulomb": self.tree(COULOMB),
            "solvers": solvers,
            "changed": self.overrides,
        })
    }
}

/// The knob at `path` (`coulomb.NAME` or `SOLVER.KNOB`) and its owner's
/// defaults, if there is one.
type Defaults = fn(Stopping) -> Value;
fn knob_of(path: &str) -> Option<(&'static Knob, Defaults)> {
    let (owner, key) = path.split_once('.')?;
    if owner == COULOMB {
        let knob = fixed_point::KNOBS.iter().find(|k| k.name == key)?;
        return Some((knob, fixed_point::default_tree));
    }
    let entry = registry::by_name(owner)?;
    Some((entry.knob(key)?, entry.defaults))
}

/// A solver setting's path for examples in messages: the first knob of the
/// first registered solver.
pub fn example_path() -> String {
    registry::solvers()
        .iter()
        .find_map(|e| e.knobs.first().map(|k| format!("{}.{}", e.name, k.name)))
        .unwrap_or_else(|| "coulomb.epsilon".into())
}

fn strip_owner<'a>(owner: &str, message: &'a str) -> &'a str {
    message
        .strip_prefix(owner)
        .and_then(|m| m.strip_prefix(": "))
        .unwrap_or(message)
}

/// Prefixes a settings error with its owner unless it already names a field.
fn named(owner: &str, message: String) -> String {
    if message.starts_with(&format!("{owner}.")) {
        message
    } else {
        format!("{owner}: {message}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_are_checked_against_the_registry() {
        let mut s = Settings::default();
        assert!(s.set("coulomb.epsilon", Value::from(1e-8)).is_ok());
        assert_eq!(s.coulomb().unwrap().epsilon, 1e-8);
        let e = s.set("nosuch.r", Value::from(1.0)).unwrap_err();
        assert!(e.contains("registered solver"), "{e}");
        let e = s.set("coulomb.nosuch", Value::from(1.0)).unwrap_err();
        assert!(e.contains("its settings"), "{e}");
        assert!(s.set("epsilon", Value::from(1.0)).is_err());
    }

    #[test]
    fn a_shorthand_knob_sets_every_field_it_names() {
        let mut s = Settings::default();
        for e in registry::solvers() {
            for k in e.knobs.iter().filter(|k| k.fields.len() > 1) {
                s.set(&format!("{}.{}", e.name, k.name), Value::from(1e-7))
                    .unwrap();
                for f in k.fields {
                    assert_eq!(s.get(&format!("{}.{f}", e.name)), Some(Value::from(1e-7)));
                }
            }
        }
    }

    #[test]
    fn defaults_follow_the_stopping_mode_and_changes_survive_it() {
        let mut s = Settings::default();
        s.set("coulomb.max_iterations", Value::from(7u64)).unwrap();
        let relative = s.coulomb().unwrap();
        s.stopping = Stopping::Paper;
        let paper = s.coulomb().unwrap();
        assert_eq!(paper.epsilon, 1e-4, "the paper's ε");
        assert_ne!(relative.epsilon, paper.epsilon);
        assert_eq!(paper.max_iterations, 7);
        s.validate().unwrap();
    }
}
