//! Changes to the settings as a user gives them, in the order given. The
//! command line's flags (`--stopping`, `--schedule`, `--epsilon`,
//! `--certify-tol`, `--max-friction-iterations`, `--SOLVER-KNOB`, `--set
//! PATH=VALUE`) and the Python package's `settings` mapping both become one
//! [`Changes`] list, applied here, so that both fronts resolve settings with
//! the same code and the same rules:
//!
//! - **the later change of a setting wins**, whichever way each was given
//!   (`--set stopping=paper --stopping relative` is relative; `--epsilon
//!   1e-6 --set relaxation.epsilon=1e-8` sets every ε to 1e-6 but the
//!   relaxation's);
//! - a setting of a registered solver that the run does not use is refused
//!   ([`Changes::check_used_by`]): it would be ignored without a word;
//! - a value is one line of at most [`MAX_VALUE_CHARS`] characters, so that
//!   every message that quotes it stays one short line.

use contactlab_solvers::registry::{self, Entry, Knob};

use super::Settings;

/// The longest value a setting takes, in characters (a number, a word, a
/// short list): anything longer is refused before it is parsed.
pub const MAX_VALUE_CHARS: usize = 200;

/// One change: a settings path (`coulomb.epsilon`, `relaxation.r`,
/// `stopping`, `schedule`, `certificate.tolerance`, or `epsilon`: the
/// paper's one ε for every loop that has one), its value as text, and how
/// the user gave it (`--epsilon`, `--set`, `settings["relaxation.r"]`), for
/// messages.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Change {
    pub path: String,
    pub value: String,
    pub given_as: String,
}

/// The changes of one run, in the order given.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Changes(pub Vec<Change>);

impl Changes {
    pub fn push(&mut self, path: &str, value: &str, given_as: &str) {
        self.0.push(Change {
            path: path.to_string(),
            value: value.to_string(),
            given_as: given_as.to_string(),
        });
    }

    /// Whether some change sets `path`.
    pub fn sets(&self, path: &str) -> bool {
        self.0.iter().any(|c| c.path == path)
    }

    /// `base` (the defaults, or a scene file's settings) with every change
    /// applied in order, the later winning, then validated. The error is
    /// one line that names how the setting was given.
    pub fn apply_to(&self, mut settings: Settings) -> Result<Settings, String> {
        for c in &self.0 {
            check_text(c)?;
            let result = if c.path == "epsilon" {
                c.value
                    .trim()
                    .parse::<f64>()
                    .map_err(|_| {
                        format!("epsilon = '{}' is invalid: give a positive number", c.value)
                    })
                    .and_then(|e| settings.set_epsilon(e))
            } else {
                settings.set_text(&c.path, &c.value)
            };
            result.map_err(|m| c.blame(&m))?;
        }
        settings.validate()?;
        Ok(settings)
    }

    /// The settings of a run, resolved once for every front (the command
    /// line and the Python package call this, so that both refuse the same
    /// things): `base` (the defaults, or a scene file's settings), then
    /// every change in order, validated ([`Changes::apply_to`]), then the
    /// check that each change is read by a solver that runs
    /// ([`Changes::check_used_by`]).
    pub fn resolve(
        &self,
        base: Settings,
        running: &[&'static Entry],
        spelling: &Spelling,
    ) -> Result<Settings, Refusal> {
        let settings = self.apply_to(base).map_err(Refusal::Value)?;
        self.check_used_by(running, spelling)
            .map_err(Refusal::Unused)?;
        Ok(settings)
    }

    /// Refuses a change of a registered solver's setting when the run uses
    /// only `running`: it would be ignored. The message names the setting
    /// of a solver that is run that has the same name, if any, as
    /// `spelling` writes it (a path here and in Python, a flag on the
    /// command line).
    pub fn check_used_by(
        &self,
        running: &[&'static Entry],
        spelling: &Spelling,
    ) -> Result<(), String> {
        let names: Vec<&str> = running.iter().map(|r| r.name).collect();
        for c in &self.0 {
            let Some(owner) = other_solver(&c.path, &names) else {
                continue;
            };
            let knob = c.path.split_once('.').map_or("", |(_, k)| k);
            let instead: Vec<String> = running
                .iter()
                .filter_map(|r| r.knob(knob).map(|k| (spelling.name)(r, k)))
                .collect();
            let hint = if instead.is_empty() {
                String::new()
            } else {
                format!(": {} {} instead", spelling.verb, instead.join(" or "))
            };
            return Err(format!(
                "{} sets a setting of {}, but this run uses {}; it would be ignored{hint}",
                c.shown(),
                owner.name,
                names.join(", ")
            ));
        }
        Ok(())
    }
}

/// How a front names a setting it suggests: the verb and the name
/// (`set tnnmg.tolerance`, `use --set tnnmg.tolerance=`).
pub struct Spelling {
    pub verb: &'static str,
    pub name: fn(&'static Entry, &'static Knob) -> String,
}

/// Settings named by their paths (`set tnnmg.tolerance instead`).
pub const AS_PATHS: Spelling = Spelling {
    verb: "set",
    name: |e, k| format!("{}.{}", e.name, k.name),
};

impl Change {
    /// How the change was given, for messages: `--set PATH`, or the flag.
    pub fn shown(&self) -> String {
        if self.given_as == "--set" {
            format!("--set {}", self.path)
        } else {
            self.given_as.clone()
        }
    }

    /// A message about this change that names how it was given, once: a
    /// flag of its own after the path the message starts with
    /// (`coulomb.max_iterations (--max-friction-iterations) = '0' is
    /// invalid: …`), anything else
    /// before it (`--set: …`, `settings["relaxation.r"]: …`).
    fn blame(&self, message: &str) -> String {
        if message.contains(self.given_as.as_str()) {
            return message.to_string();
        }
        let own_flag = self.given_as.starts_with("--") && self.given_as != "--set";
        match message.strip_prefix(self.path.as_str()) {
            Some(rest) if own_flag && rest.starts_with(' ') => {
                format!("{} ({}){rest}", self.path, self.given_as)
            }
            _ => format!("{}: {message}", self.given_as),
        }
    }
}

/// A value too long for a setting, or one that is not one line, is refused
/// before anything quotes it (a 100 kB `--set` value gave a 200 kB error
/// that quoted it twice).
fn check_text(c: &Change) -> Result<(), String> {
    let chars = c.value.chars().count();
    if chars > MAX_VALUE_CHARS {
        return Err(format!(
            "{}: the value has {chars} characters; a setting's value has at most {MAX_VALUE_CHARS} (a number or a word)",
            c.shown_path()
        ));
    }
    if c.path.chars().count() > MAX_VALUE_CHARS {
        return Err(format!(
            "{}: the setting's path has {} characters; write it as OWNER.NAME, e.g. coulomb.epsilon",
            c.given_as,
            c.path.chars().count()
        ));
    }
    if c.value.chars().chain(c.path.chars()).any(char::is_control) {
        return Err(format!(
            "{}: the setting contains a control character (a line break, a tab); give it on one line",
            c.given_as
        ));
    }
    Ok(())
}

impl Change {
    fn shown_path(&self) -> String {
        if self.path.chars().count() > MAX_VALUE_CHARS {
            self.given_as.clone()
        } else {
            self.shown()
        }
    }
}

/// The registered solver that owns setting `path`, if it is not one of
/// `names` (its settings would be ignored by a run of those).
pub fn other_solver(path: &str, names: &[&str]) -> Option<&'static Entry> {
    let owner = path.split('.').next().unwrap_or("");
    registry::by_name(owner).filter(|e| !names.contains(&e.name))
}

/// Why settings were refused, in one line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Refusal {
    /// A value the setting cannot take (the line starts with its path).
    Value(String),
    /// A setting of a solver the run does not use.
    Unused(String),
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Refusal::Value(m) | Refusal::Unused(m) => f.write_str(m),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use contactlab_solvers::Stopping;

    fn changes(list: &[(&str, &str, &str)]) -> Changes {
        let mut c = Changes::default();
        for (path, value, given_as) in list {
            c.push(path, value, given_as);
        }
        c
    }

    /// The later change wins, in either order, for every setting that has
    /// a flag of its own beside its `--set` path.
    #[test]
    fn the_later_change_of_a_setting_wins_whichever_way_each_was_given() {
        let pairs = [
            ("stopping", "paper", "relative", "--stopping"),
            ("schedule", "nested", "revisit", "--schedule"),
            ("certificate.tolerance", "1e-4", "1e-6", "--certify-tol"),
            (
                "coulomb.max_iterations",
                "7",
                "9",
                "--max-friction-iterations",
            ),
        ];
        for (path, a, b, flag) in pairs {
            for (first, second) in [("--set", flag), (flag, "--set")] {
                let s = changes(&[(path, a, first), (path, b, second)])
                    .apply_to(Settings::default())
                    .unwrap();
                let expected = changes(&[(path, b, "--set")])
                    .apply_to(Settings::default())
                    .unwrap();
                assert_eq!(s, expected, "{path}: {first} then {second}");
            }
        }
        // --epsilon sets every ε; a later --set of one ε wins for that one.
        let s = changes(&[
            ("epsilon", "1e-6", "--epsilon"),
            ("relaxation.epsilon", "1e-8", "--set"),
        ])
        .apply_to(Settings::default())
        .unwrap();
        assert_eq!(s.coulomb().unwrap().epsilon, 1e-6);
        assert_eq!(s.get("relaxation.epsilon"), Some(serde_json::json!(1e-8)));
        let s = changes(&[
            ("relaxation.epsilon", "1e-8", "--set"),
            ("epsilon", "1e-6", "--epsilon"),
        ])
        .apply_to(Settings::default())
        .unwrap();
        assert_eq!(s.get("relaxation.epsilon"), Some(serde_json::json!(1e-6)));
        let s = changes(&[
            ("stopping", "paper", "--set"),
            ("stopping", "relative", "--stopping"),
        ])
        .apply_to(Settings::default())
        .unwrap();
        assert_eq!(s.stopping, Stopping::Relative);
    }

    #[test]
    fn a_long_or_multiline_value_is_refused_in_one_short_line() {
        let long = "1".repeat(100_000);
        let e = changes(&[("coulomb.epsilon", &long, "--set")])
            .apply_to(Settings::default())
            .unwrap_err();
        assert!(e.len() < 300 && !e.contains('\n'), "{} characters", e.len());
        assert!(
            e.contains("--set coulomb.epsilon") && e.contains("100000"),
            "{e}"
        );
        let e = changes(&[("coulomb.epsilon", "1e-6\n--solver x", "--set")])
            .apply_to(Settings::default())
            .unwrap_err();
        assert!(!e.contains('\n') && e.contains("one line"), "{e}");
    }

    #[test]
    fn a_setting_of_a_solver_not_run_is_refused_naming_the_one_to_set() {
        let c = changes(&[("newton-coulomb.tolerance", "1e-2", "--set")]);
        let tnnmg = registry::by_name("tnnmg").unwrap();
        let e = c.check_used_by(&[tnnmg], &AS_PATHS).unwrap_err();
        assert!(
            e.contains("tnnmg.tolerance") && e.contains("ignored"),
            "{e}"
        );
        let newton = registry::by_name("newton-coulomb").unwrap();
        c.check_used_by(&[newton], &AS_PATHS).unwrap();
        // The fixed point's settings belong to no solver.
        changes(&[("coulomb.epsilon", "1e-6", "--set")])
            .check_used_by(&[tnnmg], &AS_PATHS)
            .unwrap();
    }

    #[test]
    fn the_forcing_of_the_inexact_fixed_point_is_below_one() {
        for bad in ["1", "1e9", "-0.1"] {
            let e = changes(&[("coulomb.forcing", bad, "--set")])
                .apply_to(Settings::default())
                .unwrap_err();
            assert!(e.contains("coulomb.forcing"), "{e}");
        }
        changes(&[("coulomb.forcing", "0.9", "--set")])
            .apply_to(Settings::default())
            .unwrap();
    }
}
