//! The initial gap between the bodies along Γ_K: the distance d(x) ≥ 0
//! from the lower body's top to the upper body's bottom before loading.
//! The paper's scene has none (flat bodies touching everywhere); a curved
//! upper body has the parabola of its profile (Johnson, *Contact
//! Mechanics*, 1985, §4.2: a cylinder of radius R touching at x₀ leaves
//! the gap (x − x₀)²/2R to second order, the profile Hertz's theory
//! assumes), and any other profile can be given as a table.

use serde::{Deserialize, Serialize};

use crate::mechanics::scene::{MAGNITUDES, SceneError};

/// The most points a gap table may have (a table finer than the finest
/// mesh, 8193 nodes, says nothing more).
pub const MAX_TABLE_POINTS: usize = 100_000;

/// The initial gap d(x) along Γ_K (0 ≤ x ≤ 1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case", deny_unknown_fields)]
pub enum Gap {
    /// d(x) = (x − center)² / (2 radius): a cylinder of radius R touching
    /// the flat lower body at x = center (Johnson 1985, §4.2, eq. (4.1)).
    Parabola { center: f64, radius: f64 },
    /// d(x) interpolated linearly between the points (x_k, d_k), x
    /// increasing from 0 to 1.
    Table { x: Vec<f64>, d: Vec<f64> },
}

impl Gap {
    /// The gap at x.
    pub fn at(&self, x: f64) -> f64 {
        match self {
            Gap::Parabola { center, radius } => (x - center) * (x - center) / (2.0 * radius),
            Gap::Table { x: xs, d } => {
                let k = xs.partition_point(|&a| a <= x).clamp(1, xs.len() - 1);
                let (x0, x1, d0, d1) = (xs[k - 1], xs[k], d[k - 1], d[k]);
                let w = ((x - x0) / (x1 - x0)).clamp(0.0, 1.0);
                d0 + w * (d1 - d0)
            }
        }
    }

    /// Checks the fields: a parabola's center on Γ_K and a radius of a size
    /// the solvers are shown to handle; a table's points increasing over
    /// [0, 1] with finite gaps ≥ 0.
    pub fn validate(&self) -> Result<(), SceneError> {
        let invalid = |field: &str, value: String, expected: &str| SceneError::Invalid {
            field: format!("gap.{field}"),
            value,
            expected: expected.to_string(),
        };
        match self {
            Gap::Parabola { center, radius } => {
                if !(center.is_finite() && (0.0..=1.0).contains(center)) {
                    return Err(invalid(
                        "center",
                        center.to_string(),
                        "the point where the bodies first touch must lie on Γ_K, in [0, 1]",
                    ));
                }
                if !(*radius >= MAGNITUDES.0 && *radius <= MAGNITUDES.1) {
                    return Err(invalid(
                        "radius",
                        radius.to_string(),
                        &format!(
                            "the radius of curvature R must lie in [{:e}, {:e}] (a flat body: leave the gap out)",
                            MAGNITUDES.0, MAGNITUDES.1
                        ),
                    ));
                }
            }
            Gap::Table { x, d } => {
                if x.len() != d.len() || x.len() < 2 || x.len() > MAX_TABLE_POINTS {
                    return Err(invalid(
                        "x",
                        format!("{} points (d: {})", x.len(), d.len()),
                        &format!("give x and d of one length, 2 to {MAX_TABLE_POINTS} points"),
                    ));
                }
                if x[0] != 0.0
                    || x[x.len() - 1] != 1.0
                    || x.windows(2).any(|w| w[0] >= w[1] || w[1].is_nan())
                {
                    return Err(invalid(
                        "x",
                        format!("from {} to {}", x[0], x[x.len() - 1]),
                        "the table's x must increase strictly from 0 to 1 (the whole of Γ_K)",
                    ));
                }
                if let Some(k) = d
                    .iter()
                    .position(|v| !(v.is_finite() && *v >= 0.0 && *v <= MAGNITUDES.1))
                {
                    return Err(invalid(
                        &format!("d[{k}]"),
                        d[k].to_string(),
                        "a gap is a finite distance ≥ 0 (an initial overlap is not supported)",
                    ));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_parabola_and_the_table_give_the_gap_they_describe() {
        let p = Gap::Parabola {
            center: 0.5,
            radius: 2.0,
        };
        assert_eq!(p.at(0.5), 0.0);
        assert_eq!(p.at(0.0), 0.0625);
        let t = Gap::Table {
            x: vec![0.0, 0.5, 1.0],
            d: vec![1.0, 0.0, 3.0],
        };
        t.validate().unwrap();
        for (x, d) in [(0.0, 1.0), (0.25, 0.5), (0.5, 0.0), (0.75, 1.5), (1.0, 3.0)] {
            assert_eq!(t.at(x), d, "x = {x}");
        }
    }

    #[test]
    fn bad_gaps_are_refused_naming_the_field() {
        let bad = |g: Gap, field: &str| {
            let msg = g.validate().unwrap_err().to_string();
            assert!(msg.contains(field), "{msg}");
        };
        bad(
            Gap::Parabola {
                center: 1.5,
                radius: 1.0,
            },
            "gap.center",
        );
        bad(
            Gap::Parabola {
                center: 0.5,
                radius: 0.0,
            },
            "gap.radius",
        );
        bad(
            Gap::Parabola {
                center: 0.5,
                radius: f64::NAN,
            },
            "gap.radius",
        );
        bad(
            Gap::Table {
                x: vec![0.0, 1.0],
                d: vec![1.0],
            },
            "gap.x",
        );
        bad(
            Gap::Table {
                x: vec![0.0, 0.9],
                d: vec![1.0, 1.0],
            },
            "gap.x",
        );
        bad(
            Gap::Table {
                x: vec![0.0, 0.5, 0.5, 1.0],
                d: vec![0.0; 4],
            },
            "gap.x",
        );
        bad(
            Gap::Table {
                x: vec![0.0, 1.0],
                d: vec![0.0, -1.0],
            },
            "gap.d[1]",
        );
    }
}
