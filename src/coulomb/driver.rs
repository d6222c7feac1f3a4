//! Solving a scene with a registered solver: the Coulomb fixed point around
//! the given-friction solver, then everything a report needs.

use anyhow::{Context, Result, bail};
use contactlab_solvers::registry;
use contactlab_solvers::{Observer, Residuals};
use serde::Serialize;

use crate::coulomb::continuation::{Continuation, LevelCount};
use crate::coulomb::fixed_point::{
    CoulombSolution, GivenFrictionStep, SingleLevel, friction_fixed_point,
};
use crate::mechanics::contact_zone::{ProfileRow, Separation, contact_profile, separation_of};
use crate::mechanics::discretization::Discretization;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;

/// A solved scene.
pub struct Run {
    pub scene: Scene,
    pub solver: &'static str,
    /// The finest level's discretization, with g set to the last bound used.
    pub discretization: Discretization,
    pub coulomb: CoulombSolution,
    pub residuals: Residuals,
    pub profile: Vec<ProfileRow>,
    pub separation: Separation,
    pub objective: f64,
    /// Work per mesh level (one entry when run on the finest level only).
    pub levels: Vec<LevelCount>,
}

/// Looks up a registered solver or says which exist.
pub fn solver_entry(name: &str) -> Result<&'static registry::Entry> {
    registry::by_name(name).with_context(|| {
        format!(
            "unknown solver '{name}': the registered solvers are {}",
            registry::names().join(", ")
        )
    })
}

/// Runs `work` on the given-friction step the named solver uses for `scene`:
/// mesh continuation over the scene's levels if it warm-starts, otherwise
/// the finest level alone. Returns what `work` returned, the finest level's
/// discretization, and the work per level (None on a single level: the
/// caller knows how to count it).
pub fn with_step<T>(
    scene: &Scene,
    settings: &Settings,
    solver: &str,
    work: impl FnOnce(&mut dyn GivenFrictionStep, &Settings) -> T,
) -> Result<(
    T,
    Discretization,
    Option<Vec<LevelCount>>,
    &'static registry::Entry,
)> {
    let entry = solver_entry(solver)?;
    let mut settings = settings.clone();
    settings.solver.relaxation.h_finest = scene.finest().h();
    if let Err(e) = settings.validate() {
        bail!(e);
    }
    let mut inner = (entry.build)(&settings.solver);
    if entry.continuation && scene.levels.len() > 1 {
        let levels = scene
            .levels
            .iter()
            .map(|&h| Discretization::new(scene, h))
            .collect::<Result<Vec<_>, _>>()?;
        let mut step = Continuation::new(levels, inner.as_mut(), settings.schedule);
        let out = work(&mut step, &settings);
        Ok((out, step.finest().clone(), Some(step.counts.clone()), entry))
    } else {
        let finest = Discretization::new(scene, scene.finest())?;
        let mut step = SingleLevel::new(finest.problem.clone(), inner.as_mut());
        let out = work(&mut step, &settings);
        Ok((out, finest, None, entry))
    }
}

/// Solves `scene` with the Coulomb fixed point around the named solver: by
/// mesh continuation over the scene's levels if the solver warm-starts,
/// otherwise on the finest level.
pub fn solve_scene(
    scene: &Scene,
    settings: &Settings,
    solver: &str,
    observer: &mut dyn Observer,
) -> Result<Run> {
    let (coulomb, finest, counts, entry) = with_step(scene, settings, solver, |step, s| {
        friction_fixed_point(step, scene.friction, &s.coulomb, observer)
    })?;
    let levels = counts.unwrap_or_else(|| {
        let total = coulomb.total_iterations();
        vec![LevelCount {
            h: finest.h(),
            visits: coulomb.history.len(),
            uzawa: total.outer,
            sweeps: total.inner,
            seconds: coulomb.history.iter().map(|h| h.seconds).sum(),
        }]
    });
    Ok(report(scene.clone(), entry.name, finest, coulomb, levels))
}

/// Residuals, profile and separation of a finished fixed point.
pub fn report(
    scene: Scene,
    solver: &'static str,
    mut discretization: Discretization,
    coulomb: CoulombSolution,
    levels: Vec<LevelCount>,
) -> Run {
    discretization
        .problem
        .set_friction_bound(&coulomb.g)
        .expect("the fixed point keeps g finite and ≥ 0");
    let s = &coulomb.solution;
    let residuals = Residuals::compute(
        &discretization.problem,
        &s.v,
        &s.pressure,
        &s.friction_traction,
    );
    let profile = contact_profile(&discretization, s);
    let separation = separation_of(&discretization, s);
    let objective = discretization.problem.objective(&s.v);
    Run {
        scene,
        solver,
        discretization,
        coulomb,
        residuals,
        profile,
        separation,
        objective,
        levels,
    }
}

/// `summary.json`.
#[derive(Debug, Serialize)]
pub struct Summary {
    pub problem: String,
    pub h: String,
    pub solver: String,
    pub plane: String,
    pub friction_coefficient: f64,
    pub friction_iterations: usize,
    pub status: String,
    pub detail: String,
    pub separated_intervals: Vec<[f64; 2]>,
    pub separated_fraction: f64,
    pub separation_tolerance: f64,
    pub max_pressure: f64,
    pub total_contact_force: f64,
    pub total_applied_load: f64,
    pub objective: f64,
    pub residuals: Residuals,
    pub iterations_outer: usize,
    pub iterations_inner: usize,
    pub seconds: f64,
    pub seconds_setup: f64,
    pub seconds_solve: f64,
    pub history: Vec<crate::coulomb::fixed_point::FrictionIteration>,
    pub levels: Vec<LevelCount>,
    pub settings: Settings,
}

impl Run {
    pub fn summary(&self, settings: &Settings) -> Summary {
        let s = &self.coulomb.solution;
        let contacts = self.discretization.problem.contacts();
        let total_contact_force = contacts
            .iter()
            .zip(&s.pressure)
            .map(|(c, p)| c.weight * p)
            .sum();
        let iterations = self.coulomb.total_iterations();
        let setup: f64 = self.coulomb.history.iter().map(|h| h.setup_seconds).sum();
        Summary {
            problem: self.scene.name.clone(),
            h: self.discretization.h().to_string(),
            solver: self.solver.to_string(),
            plane: self.scene.material.plane.to_string(),
            friction_coefficient: self.scene.friction,
            friction_iterations: self.coulomb.history.len(),
            status: self.coulomb.status.to_string(),
            detail: self.coulomb.detail.clone(),
            separated_intervals: self.separation.intervals.clone(),
            separated_fraction: self.separation.fraction,
            separation_tolerance: self.separation.tolerance,
            max_pressure: s.pressure.iter().fold(f64::NEG_INFINITY, |m, p| m.max(*p)),
            total_contact_force,
            total_applied_load: self.discretization.total_load,
            objective: self.objective,
            residuals: self.residuals,
            iterations_outer: iterations.outer,
            iterations_inner: iterations.inner,
            seconds: self.coulomb.seconds,
            seconds_setup: setup,
            seconds_solve: self.coulomb.seconds - setup,
            history: self.coulomb.history.clone(),
            levels: self.levels.clone(),
            settings: settings.clone(),
        }
    }
}
