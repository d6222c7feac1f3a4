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

/// A positive number as a tree value (for tolerances and penalties).
pub fn parse_positive(text: &str) -> Result<Value, String> {
    match text.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(Value::from(x)),
        _ => Err(format!("'{text}' is not a positive number")),
    }
}

/// Checks that `value` is a positive finite number: `Err("name = value is
/// invalid: it must be a positive number (hint)")` otherwise.
pub fn positive(name: &str, value: f64, hint: &str) -> Result<(), String> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(format!(
            "{name} = {value} is invalid: it must be a positive number ({hint})"
        ))
    }
}

/// Checks a count cap: at least 1.
pub fn at_least_one(name: &str, value: usize, default: usize) -> Result<(), String> {
    if value >= 1 {
        Ok(())
    } else {
        Err(format!(
            "{name} = 0 is invalid: allow at least 1 (default {default})"
        ))
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
        assert!(parse_positive("-1").is_err() && parse_positive("0").is_err());
    }
}
