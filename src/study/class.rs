//! The classes of an outcome that the stability map draws and every trial
//! carries (decided by the stability study's `classify`), and the
//! thresholds that decide "wrong" and "slow": part of the engine, so that
//! a trial's record does not depend on the stability study.

use serde::{Deserialize, Serialize};

/// Pressure difference from the reference above which a certified answer is
/// still wrong: about what moves the separation zone by a node at h = 1/64.
pub const WRONG_PRESSURE: f64 = 1e-3;
/// Work beyond this many times the default run's is slow.
pub const SLOW_FACTOR: f64 = 10.0;

/// The classes of the map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Class {
    Converged,
    Slow,
    Stalled,
    Diverged,
    Wrong,
    Refused,
}

impl Class {
    pub const ALL: [Class; 6] = [
        Class::Converged,
        Class::Slow,
        Class::Stalled,
        Class::Diverged,
        Class::Wrong,
        Class::Refused,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            Class::Converged => "converged",
            Class::Slow => "slow",
            Class::Stalled => "stalled",
            Class::Diverged => "diverged",
            Class::Wrong => "wrong",
            Class::Refused => "refused",
        }
    }

    pub fn parse(text: &str) -> Option<Class> {
        Class::ALL.into_iter().find(|c| c.as_str() == text)
    }
}
