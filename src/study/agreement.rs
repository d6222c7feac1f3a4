//! Agreement between two solutions of the same problem: differences of the
//! displacement fields of both bodies, the pressures, the friction tractions
//! and the objective, each relative to the reference's size.

use contactlab_solvers::{ContactProblem, Solution};
use serde::Serialize;

use crate::mechanics::discretization::Discretization;

/// Differences of a solution from a reference, each relative to the
/// reference's largest value (max) or its Euclidean norm (l2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Agreement {
    /// Nodal displacements of both bodies.
    pub displacement_max: f64,
    pub displacement_l2: f64,
    /// Contact pressure.
    pub pressure_max: f64,
    pub pressure_l2: f64,
    /// Friction traction (relative to the largest pressure when the
    /// reference has no friction).
    pub traction_max: f64,
    pub traction_l2: f64,
    /// (J(v) − J(v_ref)) / |J(v_ref)| for the objective J of paper (10).
    pub objective_gap: f64,
    /// ‖v − v_ref‖_A over √K·U: the distance in the energy seminorm (blind
    /// to the rigid mode), what the certificate's error bound bounds.
    pub energy: f64,
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, |m, d| if d.is_nan() { f64::NAN } else { m.max(d) })
}

fn l2(a: &[f64]) -> f64 {
    a.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn max_abs(a: &[f64]) -> f64 {
    a.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// ‖x − y‖_A for the problem's stiffness A (a seminorm: the rigid mode
/// has no energy, up to rounding). Measured, not a bound: the plain sum.
pub fn energy_distance(problem: &ContactProblem, x: &[f64], y: &[f64]) -> f64 {
    if x.len() != problem.n() || y.len() != problem.n() {
        return f64::NAN;
    }
    let a = problem.a();
    let mut value = 0.0;
    for i in 0..problem.n() {
        let (cols, vals) = a.row(i);
        let e_i = x[i] - y[i];
        let row: f64 = cols
            .iter()
            .zip(vals)
            .map(|(c, a_ic)| a_ic * (x[c] - y[c]))
            .sum();
        value += e_i * row;
    }
    // Not `max`: a NaN (an answer that is not finite) must stay NaN.
    if value < 0.0 { 0.0 } else { value.sqrt() }
}

fn rel(num: f64, den: f64) -> f64 {
    if den > 0.0 { num / den } else { num }
}

/// How far `s` is from `reference`, both solutions of `d.problem` (the
/// objective taken at the reference's bound `g`).
pub fn agreement(d: &Discretization, g: &[f64], s: &Solution, reference: &Solution) -> Agreement {
    let flat =
        |sol: &Solution| -> Vec<f64> { d.displacements(&sol.v).into_iter().flatten().collect() };
    let (u, u_ref) = (flat(s), flat(reference));
    let du: Vec<f64> = u.iter().zip(&u_ref).map(|(a, b)| a - b).collect();
    let dp: Vec<f64> = s
        .pressure
        .iter()
        .zip(&reference.pressure)
        .map(|(a, b)| a - b)
        .collect();
    let dq: Vec<f64> = s
        .friction_traction
        .iter()
        .zip(&reference.friction_traction)
        .map(|(a, b)| a - b)
        .collect();
    let p_max = max_abs(&reference.pressure);
    let q_max = max_abs(&reference.friction_traction).max(
        if max_abs(&reference.friction_traction) == 0.0 {
            p_max
        } else {
            0.0
        },
    );
    let q_l2 = if l2(&reference.friction_traction) > 0.0 {
        l2(&reference.friction_traction)
    } else {
        l2(&reference.pressure)
    };
    let scales = d.problem.scales();
    let j = d.problem.objective(&s.v, g);
    let j_ref = d.problem.objective(&reference.v, g);
    Agreement {
        displacement_max: rel(max_abs(&du), max_abs(&u_ref)),
        displacement_l2: rel(l2(&du), l2(&u_ref)),
        pressure_max: rel(max_diff(&s.pressure, &reference.pressure), p_max),
        pressure_l2: rel(l2(&dp), l2(&reference.pressure)),
        traction_max: rel(max_abs(&dq), q_max),
        traction_l2: rel(l2(&dq), q_l2),
        objective_gap: rel(j - j_ref, j_ref.abs()),
        energy: energy_distance(&d.problem, &s.v, &reference.v)
            / (scales.stiffness.sqrt() * scales.displacement),
    }
}
