//! Agreement between two solutions of the same problem, and solving one
//! given-friction subproblem (a fixed g) with any registered solver.

use anyhow::{Result, bail};
use contactlab_solvers::{Observer, Solution};
use serde::Serialize;

use crate::continuation::{Continuation, LevelCount};
use crate::discretization::Discretization;
use crate::friction::{GivenFrictionStep, SingleLevel};
use crate::run::solver_entry;
use crate::scene::Scene;
use crate::settings::Settings;

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

fn rel(num: f64, den: f64) -> f64 {
    if den > 0.0 { num / den } else { num }
}

/// How far `s` is from `reference`, both solutions of `d.problem`.
pub fn agreement(d: &Discretization, s: &Solution, reference: &Solution) -> Agreement {
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
    let j = d.problem.objective(&s.v);
    let j_ref = d.problem.objective(&reference.v);
    Agreement {
        displacement_max: rel(max_abs(&du), max_abs(&u_ref)),
        displacement_l2: rel(l2(&du), l2(&u_ref)),
        pressure_max: rel(max_diff(&s.pressure, &reference.pressure), p_max),
        pressure_l2: rel(l2(&dp), l2(&reference.pressure)),
        traction_max: rel(max_abs(&dq), q_max),
        traction_l2: rel(l2(&dq), q_l2),
        objective_gap: rel(j - j_ref, j_ref.abs()),
    }
}

/// One given-friction subproblem (bound `g` on the finest level's contact
/// nodes) solved by a registered solver, the way it solves inside the
/// Coulomb fixed point: by continuation over the scene's levels if it
/// warm-starts, otherwise on the finest level.
pub fn solve_given_friction(
    scene: &Scene,
    settings: &Settings,
    solver: &str,
    g: &[f64],
    observer: &mut dyn Observer,
) -> Result<(Discretization, Solution, Vec<LevelCount>)> {
    let entry = solver_entry(solver)?;
    let mut settings = settings.clone();
    settings.solver.relaxation.h_finest = scene.finest().h();
    if let Err(e) = settings.validate() {
        bail!(e);
    }
    let mut inner = (entry.build)(&settings.solver);
    let (mut finest, solution, counts) = if entry.continuation && scene.levels.len() > 1 {
        let levels = scene
            .levels
            .iter()
            .map(|&h| Discretization::new(scene, h))
            .collect::<Result<Vec<_>, _>>()?;
        let mut step = Continuation::new(levels, inner.as_mut(), settings.schedule);
        let solution = step.solve_step(g, observer);
        (step.finest().clone(), solution, step.counts.clone())
    } else {
        let finest = Discretization::new(scene, scene.finest())?;
        let mut step = SingleLevel::new(finest.problem.clone(), inner.as_mut());
        let solution = step.solve_step(g, observer);
        let count = LevelCount {
            h: finest.h(),
            visits: 1,
            uzawa: solution.iterations.outer,
            sweeps: solution.iterations.inner,
            seconds: solution.timing.total(),
        };
        (finest, solution, vec![count])
    };
    finest.problem.set_friction_bound(g)?;
    Ok((finest, solution, counts))
}
