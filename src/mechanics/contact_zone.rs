//! The contact zone Γ_K of a solution: per-node profile and the separated
//! part of Γ_K.

use contactlab_solvers::{Solution, Status};
use serde::Serialize;

use crate::io::csv::fixed;
use crate::mechanics::discretization::Discretization;

/// Separation means jump < −tol with tol = SEPARATION_TOL × (largest nodal
/// displacement of both bodies). The oracle's jumps at closed nodes are below
/// 1e-9 of that, the relaxation's (r = 1e12) far below.
pub const SEPARATION_TOL: f64 = 1e-6;

/// One row of `profile.csv`, one contact node. Lengths in the scene's
/// units, forces per unit length of Γ_K.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ProfileRow {
    /// Position along Γ_K.
    #[serde(serialize_with = "fixed")]
    pub x: f64,
    /// Displacements of the lower body's and the upper body's node there.
    #[serde(serialize_with = "fixed")]
    pub u1_lower: f64,
    #[serde(serialize_with = "fixed")]
    pub u2_lower: f64,
    #[serde(serialize_with = "fixed")]
    pub u1_upper: f64,
    #[serde(serialize_with = "fixed")]
    pub u2_upper: f64,
    /// t = u2_lower − u2_upper ≤ 0: the jump [u] (negative: separated).
    #[serde(serialize_with = "fixed")]
    pub jump: f64,
    /// s = u1_lower − u1_upper: the slip.
    #[serde(serialize_with = "fixed")]
    pub slip: f64,
    /// p ≥ 0: contact pressure (the multiplier l = −σ_n).
    #[serde(serialize_with = "fixed")]
    pub pressure: f64,
    /// x-traction on the lower body; |q| ≤ g, opposing the slip.
    #[serde(serialize_with = "fixed")]
    pub friction_traction: f64,
    /// The friction bound g of the last given-friction subproblem (for a
    /// Coulomb answer of the fixed point 𝓕p of the previous iterate; for a
    /// direct Coulomb solver 𝓕p of its own answer), force per length.
    #[serde(serialize_with = "fixed")]
    pub g: f64,
    /// The node's contact state, from the jump and slip at the separation
    /// tolerance ([`SEPARATION_TOL`] × the largest displacement).
    pub state: ContactState,
    /// The certified status of the run the profile comes from.
    pub status: Status,
}

/// A contact node's state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactState {
    /// Closed and not slipping: |jump| and |slip| within the tolerance.
    Stick,
    /// Closed and slipping: |slip| beyond the tolerance.
    Slip,
    /// Separated: jump below −tolerance.
    Open,
}

impl ContactState {
    /// The state from a node's jump t and slip s at tolerance `tol`.
    pub fn of(jump: f64, slip: f64, tol: f64) -> Self {
        if jump < -tol {
            Self::Open
        } else if slip.abs() > tol {
            Self::Slip
        } else {
            Self::Stick
        }
    }

    pub fn as_str(self) -> &'static str {
        match self {
            Self::Stick => "stick",
            Self::Slip => "slip",
            Self::Open => "open",
        }
    }
}

/// Column names of `profile.csv`, in order.
pub const PROFILE_COLUMNS: [&str; 12] = [
    "x",
    "u1_lower",
    "u2_lower",
    "u1_upper",
    "u2_upper",
    "jump",
    "slip",
    "pressure",
    "friction_traction",
    "g",
    "state",
    "status",
];

/// The profile along Γ_K in increasing x at the friction bound `g` (one
/// per contact node), marked with the run's status.
pub fn contact_profile(
    d: &Discretization,
    solution: &Solution,
    g: &[f64],
    status: Status,
) -> Vec<ProfileRow> {
    let u = d.displacements(&solution.v);
    let tol = SEPARATION_TOL * largest_displacement(d, solution);
    let p = &d.problem;
    d.dofs
        .contacts()
        .iter()
        .enumerate()
        .map(|(i, c)| ProfileRow {
            x: c.x,
            u1_lower: u[c.lower_node][0],
            u2_lower: u[c.lower_node][1],
            u1_upper: u[c.upper_node][0],
            u2_upper: u[c.upper_node][1],
            jump: solution.v[c.t],
            // The slip of the bodies, s − σ (σ: a side shift's rigid lift).
            slip: p.slip(&solution.v, i),
            pressure: solution.pressure[i],
            friction_traction: solution.friction_traction[i],
            g: g[i],
            // Open where the jump stays short of the initial gap.
            state: ContactState::of(p.jump(&solution.v, i), p.slip(&solution.v, i), tol),
            status,
        })
        .collect()
}

/// Largest nodal displacement component of both bodies.
pub fn largest_displacement(d: &Discretization, solution: &Solution) -> f64 {
    d.displacements(&solution.v)
        .iter()
        .flat_map(|u| u.iter())
        .fold(0.0f64, |m, x| m.max(x.abs()))
}

/// The separated part of Γ_K of a solution, at the stated tolerance
/// SEPARATION_TOL × its largest displacement.
pub fn separation_of(d: &Discretization, solution: &Solution) -> Separation {
    let x = d.contact_x();
    let jump: Vec<f64> = d
        .problem
        .contacts()
        .iter()
        .zip(d.problem.gap())
        .map(|(c, gap)| solution.v[c.t] - gap)
        .collect();
    separation(
        &x,
        &jump,
        SEPARATION_TOL * largest_displacement(d, solution),
    )
}

/// The separated part of Γ_K.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Separation {
    /// Maximal intervals where the P1 jump is below −tolerance.
    pub intervals: Vec<[f64; 2]>,
    /// Their total length over the length of Γ_K (= 1).
    pub fraction: f64,
    /// The absolute tolerance used.
    pub tolerance: f64,
}

/// Where the piecewise linear jump past the gap, t − d (nodal values at
/// increasing `x`), lies below −`tol`; crossings inside an edge are found by linear interpolation.
pub fn separation(x: &[f64], jump: &[f64], tol: f64) -> Separation {
    let mut intervals: Vec<[f64; 2]> = Vec::new();
    let below = |j: f64| j < -tol;
    for e in 0..x.len().saturating_sub(1) {
        let (xa, xb, ja, jb) = (x[e], x[e + 1], jump[e] + tol, jump[e + 1] + tol);
        let piece = match (below(jump[e]), below(jump[e + 1])) {
            (true, true) => Some([xa, xb]),
            (true, false) => Some([xa, xa + (xb - xa) * ja / (ja - jb)]),
            (false, true) => Some([xa + (xb - xa) * ja / (ja - jb), xb]),
            (false, false) => None,
        };
        if let Some([a, b]) = piece {
            match intervals.last_mut() {
                Some(last) if (last[1] - a).abs() <= 1e-12 => last[1] = b,
                _ => intervals.push([a, b]),
            }
        }
    }
    let length = x.last().copied().unwrap_or(0.0) - x.first().copied().unwrap_or(0.0);
    let fraction = if length > 0.0 {
        intervals.iter().fold(0.0, |s, [a, b]| s + (b - a)) / length
    } else {
        0.0
    };
    Separation {
        intervals,
        fraction,
        tolerance: tol,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separation_interpolates_crossings_and_merges_edges() {
        let x = [0.0, 0.25, 0.5, 0.75, 1.0];
        let s = separation(&x, &[0.0, 0.0, -1.0, -2.0, -1.0], 0.0);
        assert_eq!(s.intervals, vec![[0.25, 1.0]]);
        assert!((s.fraction - 0.75).abs() < 1e-15);
        // Tolerance moves the crossing inside the edge.
        let s = separation(&x, &[0.0, 0.0, -1.0, -2.0, -1.0], 0.5);
        assert!((s.intervals[0][0] - 0.375).abs() < 1e-15);
        // Two separate zones.
        let s = separation(&x, &[-1.0, 0.0, 0.0, 0.0, -1.0], 0.0);
        assert_eq!(s.intervals, vec![[0.0, 0.25], [0.75, 1.0]]);
        assert_eq!(separation(&x, &[0.0; 5], 0.0).fraction, 0.0);
    }
}
