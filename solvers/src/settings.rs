//! Solver settings as trees of values, so that the registry (not the
//! harness) knows every solver's settings by path (`relaxation.r`,
//! `clarabel.tol`), their defaults and their meaning.
//!
//! Each solver keeps a plain settings struct with serde; its registry entry
//! turns it into a tree for defaults and back (with `deny_unknown_fields` and
//! a range check) when the solver is built.

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use serde_json::Value;

/// How a solver's tolerances and scale-dependent parameters are read.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Stopping {
    /// Relative to the problem's own scales ([`crate::Scales`]): multiplying
    /// the loads by a factor, or the stiffness and the loads together,
    /// changes no iteration count and no status.
    #[default]
    Relative,
    /// The paper's absolute rules and values (section 5, Table 1): r = 1e12,
    /// ε = 1e-4 on max|Δl| and max|Δg|, sweeps until max|Δv| ≤ 1e-4·ε·(1/64).
    /// Meaningful only in the paper's units (E = 73e3, loads of order 60).
    Paper,
}

impl Stopping {
    pub fn as_str(self) -> &'static str {
        match self {
            Stopping::Relative => "relative",
            Stopping::Paper => "paper",
        }
    }
}

/// A settings struct that can check its own ranges.
pub trait Validate {
    /// Checks ranges; the message starts with the field name and says what is valid.
    fn validate(&self) -> Result<(), String>;
}

/// The tree of a settings struct (for defaults).
pub fn to_tree<S: Serialize>(settings: &S) -> Value {
    serde_json::to_value(settings).expect("settings serialize to a tree")
}

/// A settings struct from its tree, range-checked. Unknown fields and wrong
/// types are errors that name the field.
pub fn from_tree<S: DeserializeOwned + Validate>(tree: &Value) -> Result<S, String> {
    let s: S = serde_json::from_value(tree.clone()).map_err(|e| e.to_string())?;
    s.validate()?;
    Ok(s)
}

/// A command-line value as a tree value: a number, `true`/`false`, or a word.
pub fn parse_scalar(text: &str) -> Result<Value, String> {
    let t = text.trim();
    if let Ok(i) = t.parse::<u64>() {
        return Ok(Value::from(i));
    }
    if let Ok(x) = t.parse::<f64>() {
        return serde_json::Number::from_f64(x)
            .map(Value::Number)
            .ok_or_else(|| format!("'{t}' is not a finite number"));
    }
    match t {
        "true" => Ok(Value::Bool(true)),
        "false" => Ok(Value::Bool(false)),
        "" => Err("an empty value".into()),
        word => Ok(Value::String(word.to_string())),
    }
}

/// What values a setting takes: how its text is read, how a value is
/// checked, and how both are described in help and in messages. Every
/// solver's settings are checked by their knobs' kinds
/// ([`crate::entry::Entry::check`]), so that a setting's default is written
/// once, in its settings struct, and its help and its error message are
/// made from it.
#[derive(Clone, Copy, Debug)]
pub enum Kind {
    /// A finite number > 0 (tolerances, penalties).
    Positive,
    /// A finite number ≥ 0 (0 often turns a feature off).
    NonNegative,
    /// A whole number ≥ 1 (iteration caps).
    Count,
    /// A whole number ≥ 0 (seeds).
    Whole,
    /// A number in [0, 1).
    Fraction,
    /// A number strictly between the two.
    Between(f64, f64),
    /// `true` or `false`.
    Flag,
    /// One of the words.
    Word(&'static [&'static str]),
    /// A rule of the solver's own: a description, a parser, a check.
    Custom {
        describe: &'static str,
        parse: fn(&str) -> Result<Value, String>,
        check: fn(&Value) -> bool,
    },
}

impl Kind {
    /// Reads a value as the command line writes it.
    pub fn parse(&self, text: &str) -> Result<Value, String> {
        let value = match self {
            Kind::Custom { parse, .. } => parse(text)?,
            Kind::Word(_) => Value::String(text.trim().to_string()),
            Kind::Flag => match text.trim().to_ascii_lowercase().as_str() {
                "true" | "yes" | "on" | "1" => Value::Bool(true),
                "false" | "no" | "off" | "0" => Value::Bool(false),
                other => Value::String(other.to_string()),
            },
            _ => parse_scalar(text)?,
        };
        if self.check(&value) {
            Ok(value)
        } else {
            Err(format!("'{}' is not {}", text.trim(), self.describe()))
        }
    }

    /// Whether a settings tree's value is of this kind.
    pub fn check(&self, value: &Value) -> bool {
        let number = value.as_f64().filter(|x| x.is_finite());
        match self {
            Kind::Positive => number.is_some_and(|x| x > 0.0),
            Kind::NonNegative => number.is_some_and(|x| x >= 0.0),
            Kind::Count => value.as_u64().is_some_and(|n| n >= 1),
            Kind::Whole => value.as_u64().is_some(),
            Kind::Fraction => number.is_some_and(|x| (0.0..1.0).contains(&x)),
            Kind::Between(lo, hi) => number.is_some_and(|x| x > *lo && x < *hi),
            Kind::Flag => value.is_boolean(),
            Kind::Word(words) => value.as_str().is_some_and(|w| words.contains(&w)),
            Kind::Custom { check, .. } => check(value),
        }
    }

    /// The kind in words: "a number > 0", "one of soc, qp".
    pub fn describe(&self) -> String {
        match self {
            Kind::Positive => "a number > 0".into(),
            Kind::NonNegative => "a number ≥ 0".into(),
            Kind::Count => "a whole number ≥ 1".into(),
            Kind::Whole => "a whole number ≥ 0".into(),
            Kind::Fraction => "a number in [0, 1)".into(),
            Kind::Between(lo, hi) => format!("a number strictly between {lo} and {hi}"),
            Kind::Flag => "true or false (also yes/no, on/off, 1/0)".into(),
            Kind::Word(words) => format!("one of {}", words.join(", ")),
            Kind::Custom { describe, .. } => describe.to_string(),
        }
    }
}

/// A setting reachable by path (`name.knob`) from scene files, `--set` and
/// a command-line flag `--name-knob`. Its default is not written here: it is
/// the solver's settings struct's, read through [`Entry::defaults`], and the
/// help and the messages quote it from there (a settings tree of its
/// owner's defaults).
#[derive(Clone, Copy, Debug)]
pub struct Knob {
    /// The knob's name within the solver's settings.
    pub name: &'static str,
    /// The settings fields it sets: itself, or several for a shorthand
    /// (Clarabel's `tol` sets its three tolerances).
    pub fields: &'static [&'static str],
    /// What it does (the default is added from the settings).
    pub help: &'static str,
    /// The values it takes: how they are read and checked.
    pub kind: Kind,
}

impl Knob {
    /// Reads a command-line value.
    pub fn parse(&self, text: &str) -> Result<Value, String> {
        self.kind.parse(text)
    }

    /// Its default as help shows it: `1e-10`, or `1e7; paper: 1e12` where
    /// the paper's stopping mode has another; `defaults` gives its owner's
    /// settings tree in a stopping mode.
    pub fn default_text(&self, defaults: fn(Stopping) -> Value) -> String {
        let field = self.fields.first().copied().unwrap_or(self.name);
        let at = |stopping| defaults(stopping).get(field).map(shown);
        match (at(Stopping::Relative), at(Stopping::Paper)) {
            (Some(r), Some(p)) if r != p => format!("{r}; paper: {p}"),
            (Some(r), _) => r,
            (None, _) => "none".into(),
        }
    }

    /// Its help with its default: `what it does [default 1e-10]`.
    pub fn help_with_default(&self, defaults: fn(Stopping) -> Value) -> String {
        format!("{} [default {}]", self.help, self.default_text(defaults))
    }
}

/// Checks a settings tree of `owner` (a solver, `coulomb`) against its
/// knobs' kinds: the first field whose value its knob refuses is an error
/// that names it, says what is valid and gives the default.
pub fn check_tree(
    owner: &str,
    knobs: &[Knob],
    defaults: fn(Stopping) -> Value,
    tree: &Value,
) -> Result<(), String> {
    for knob in knobs {
        for field in knob.fields {
            let Some(value) = tree.get(field) else {
                continue;
            };
            if !knob.kind.check(value) {
                return Err(format!(
                    "{owner}.{field} = {} is invalid: {} must be {} (default {})",
                    shown(value),
                    knob.help.split(';').next().unwrap_or(knob.help),
                    knob.kind.describe(),
                    knob.default_text(defaults)
                ));
            }
        }
    }
    Ok(())
}

/// A value of a settings tree as help and messages show it: `1e-10`, `200`,
/// `true`, `soc`, `{"huber":{"delta":1e-7}}`.
pub fn shown(value: &Value) -> String {
    match value {
        Value::Number(n) if n.is_u64() || n.is_i64() => n.to_string(),
        Value::Number(n) => {
            let x = n.as_f64().unwrap_or(f64::NAN);
            if x != 0.0 && !(1e-3..1e4).contains(&x.abs()) {
                format!("{x:e}")
            } else {
                format!("{x}")
            }
        }
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scalars_parse_to_the_right_kind() {
        assert_eq!(parse_scalar("12").unwrap(), Value::from(12u64));
        assert_eq!(parse_scalar("1e-10").unwrap(), Value::from(1e-10));
        assert_eq!(parse_scalar("-1e-10").unwrap(), Value::from(-1e-10));
        assert_eq!(parse_scalar("true").unwrap(), Value::Bool(true));
        assert_eq!(parse_scalar("exact").unwrap(), Value::from("exact"));
        assert!(parse_scalar("inf").is_err());
    }

    /// Each kind takes what it says and refuses the rest, in its parser
    /// and its check alike.
    #[test]
    fn kinds_take_what_they_describe() {
        let cases: [(Kind, &[&str], &[&str]); 7] = [
            (Kind::Positive, &["1e-10", "3"], &["0", "-1", "nan", "x"]),
            (Kind::NonNegative, &["0", "1e-5"], &["-1e-9", "inf"]),
            (Kind::Count, &["1", "200"], &["0", "1.5", "-3"]),
            (Kind::Fraction, &["0", "0.5"], &["1", "-0.1"]),
            (Kind::Between(0.0, 2.0), &["1", "1.9"], &["0", "2", "3"]),
            (
                Kind::Flag,
                &["true", "false", "yes", "No", "on", "OFF", "1", "0"],
                &["maybe", "2", "", "truth"],
            ),
            (Kind::Word(&["soc", "qp"]), &["soc", "qp"], &["socp", ""]),
        ];
        for (kind, good, bad) in cases {
            for t in good {
                let v = kind
                    .parse(t)
                    .unwrap_or_else(|e| panic!("{kind:?} {t}: {e}"));
                assert!(kind.check(&v), "{kind:?} {t}");
            }
            for t in bad {
                assert!(kind.parse(t).is_err(), "{kind:?} took '{t}'");
            }
        }
    }
}
