//! Mesh sizes h = 1/2^k, written as the paper writes them (`1/64`).

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use thiserror::Error;

/// Smallest and largest exponent k accepted for h = 1/2^k.
pub const MIN_LEVEL: u32 = 1;
pub const MAX_LEVEL: u32 = 13;

/// A mesh size h = 1/2^k with 1/2 ≥ h ≥ 1/8192 (finer than 1/1024 for the
/// solvers without a factorization only: [`Entry::max_unknowns`]; 1/4096
/// has 33.6 million unknowns and takes `tnnmg` 3.9 GiB, 1/8192 134 million
/// and 15.3 GiB; a run is refused up front where its memory estimate does
/// not fit, see [`crate::memory`]).
///
/// [`Entry::max_unknowns`]: contactlab_solvers::entry::Entry::max_unknowns
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct MeshSize {
    k: u32,
}

/// An h that is not a power-of-two fraction in range.
#[derive(Debug, Error, Clone, PartialEq)]
#[error(
    "h = '{input}' is not valid: {reason}; write it as 1/2^k between 1/{lo} and 1/{hi}, e.g. 1/64",
    lo = 1u32 << MIN_LEVEL,
    hi = 1u32 << MAX_LEVEL
)]
pub struct MeshSizeError {
    pub input: String,
    pub reason: &'static str,
}

impl MeshSize {
    /// h = 1/2^k.
    pub fn from_level(k: u32) -> Result<Self, MeshSizeError> {
        if (MIN_LEVEL..=MAX_LEVEL).contains(&k) {
            Ok(Self { k })
        } else {
            Err(MeshSizeError {
                input: format!("1/{}", 1u64 << k.min(63)),
                reason: "it is out of range",
            })
        }
    }

    /// The exponent k of h = 1/2^k.
    pub fn level(self) -> u32 {
        self.k
    }

    /// 1/h, the number of elements along a side of the unit square.
    pub fn divisions(self) -> usize {
        1usize << self.k
    }

    /// h as a number.
    pub fn h(self) -> f64 {
        1.0 / self.divisions() as f64
    }

    /// The paper's continuation schedule 1/8, 1/16, ... down to `finest`.
    pub fn schedule_to(finest: MeshSize) -> Vec<MeshSize> {
        let start = 3.min(finest.k);
        (start..=finest.k).map(|k| MeshSize { k }).collect()
    }
}

impl fmt::Display for MeshSize {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "1/{}", self.divisions())
    }
}

impl FromStr for MeshSize {
    type Err = MeshSizeError;

    /// Accepts `1/64`, `64` is refused (ambiguous), and a decimal such as
    /// `0.015625` that is exactly 1/2^k.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let err = |reason| MeshSizeError {
            input: s.to_string(),
            reason,
        };
        let t = s.trim();
        let value = if let Some((num, den)) = t.split_once('/') {
            let num: f64 = num
                .trim()
                .parse()
                .map_err(|_| err("the numerator is not a number"))?;
            let den: f64 = den
                .trim()
                .parse()
                .map_err(|_| err("the denominator is not a number"))?;
            if num != 1.0 {
                return Err(err("the numerator must be 1"));
            }
            if !(den.is_finite() && den > 0.0) {
                return Err(err("the denominator must be a positive number"));
            }
            1.0 / den
        } else {
            t.parse::<f64>()
                .map_err(|_| err("it is not a fraction 1/N or a number"))?
        };
        if !(value.is_finite() && value > 0.0 && value < 1.0) {
            return Err(err("h must lie strictly between 0 and 1"));
        }
        let inv = 1.0 / value;
        let k = inv.log2().round();
        if (2f64.powf(k) - inv).abs() > 1e-9 * inv {
            return Err(err("it is not a power-of-two fraction"));
        }
        Self::from_level(k as u32).map_err(|_| err("it is out of range"))
    }
}

impl Serialize for MeshSize {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

impl<'de> Deserialize<'de> for MeshSize {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Repr {
            Text(String),
            Number(f64),
        }
        let text = match Repr::deserialize(d)? {
            Repr::Text(t) => t,
            Repr::Number(x) => x.to_string(),
        };
        text.parse().map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_papers_notation() {
        for (s, k) in [
            ("1/8", 3),
            ("1/64", 6),
            (" 1/256 ", 8),
            ("0.015625", 6),
            ("1/2", 1),
        ] {
            assert_eq!(s.parse::<MeshSize>().unwrap().level(), k, "{s}");
        }
        assert_eq!("1/64".parse::<MeshSize>().unwrap().to_string(), "1/64");
    }

    #[test]
    fn refuses_what_is_not_one_over_a_power_of_two() {
        for s in [
            "1/60", "2/64", "1/0", "0", "1", "64", "abc", "1/16384", "1/-8", "-0.125",
        ] {
            assert!(s.parse::<MeshSize>().is_err(), "{s} was accepted");
        }
    }

    #[test]
    fn schedule_runs_from_one_eighth() {
        let s = MeshSize::schedule_to("1/64".parse().unwrap());
        let names: Vec<String> = s.iter().map(|m| m.to_string()).collect();
        assert_eq!(names, ["1/8", "1/16", "1/32", "1/64"]);
    }
}
