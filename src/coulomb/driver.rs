//! Solving a scene with a registered solver: the successive approximations
//! around a given-friction solver (or a Coulomb solver on its own), then the
//! certificate at g = 𝓕p and everything a report needs.

use anyhow::{Context, Result, bail};
use contactlab_solvers::registry::{self, Entry};
use contactlab_solvers::{Friction, Law, Observer, Solution, Status};
use serde::Serialize;

use crate::certificate::{Certificate, certify_solution};
use crate::coulomb::continuation::{Continuation, LevelCount};
use crate::coulomb::fixed_point::{
    CoulombSolution, GivenFrictionStep, Outcome, SingleLevel, friction_fixed_point,
};
use crate::mechanics::contact_zone::{ProfileRow, Separation, contact_profile, separation_of};
use crate::mechanics::discretization::Discretization;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;

/// A solved scene.
pub struct Run {
    pub scene: Scene,
    pub solver: &'static str,
    /// The finest level's discretization.
    pub discretization: Discretization,
    /// The solver's answer and its own claim (`coulomb.status`).
    pub coulomb: CoulombSolution,
    /// The certificate of the Coulomb law at g = 𝓕p.
    pub certificate: Certificate,
    /// The certified status: the claim, or `inaccurate` if a claim of
    /// convergence fails the certificate.
    pub status: Status,
    pub profile: Vec<ProfileRow>,
    pub separation: Separation,
    pub objective: f64,
    /// Work per mesh level (one entry when run on the finest level only).
    pub levels: Vec<LevelCount>,
}

/// Looks up a registered solver or says which exist.
pub fn solver_entry(name: &str) -> Result<&'static Entry> {
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
) -> Result<(T, Discretization, Option<Vec<LevelCount>>, &'static Entry)> {
    let entry = solver_entry(solver)?;
    if let Err(e) = settings.validate() {
        bail!(e);
    }
    let mut inner = settings.build(entry).map_err(anyhow::Error::msg)?;
    if entry.warm_starts && scene.levels.len() > 1 {
        let mut levels = scene
            .levels
            .iter()
            .map(|&h| Discretization::new(scene, h))
            .collect::<Result<Vec<_>, _>>()?;
        let (out, counts) = {
            let mut step = Continuation::new(&levels, inner.as_mut(), settings.schedule);
            let out = work(&mut step, settings);
            (out, step.counts.clone())
        };
        let finest = levels.pop().context("a scene has at least one level")?;
        Ok((out, finest, Some(counts), entry))
    } else {
        let finest = Discretization::new(scene, scene.finest())?;
        let out = {
            let mut step = SingleLevel::new(&finest.problem, inner.as_mut());
            work(&mut step, settings)
        };
        Ok((out, finest, None, entry))
    }
}

/// Solves the Coulomb problem of `scene` with the named solver: directly if
/// it solves the Coulomb law, otherwise by the successive approximations
/// around it (by mesh continuation over the scene's levels if the solver
/// warm-starts, otherwise on the finest level); then certifies the answer.
pub fn solve_scene(
    scene: &Scene,
    settings: &Settings,
    solver: &str,
    observer: &mut dyn Observer,
) -> Result<Run> {
    let entry = solver_entry(solver)?;
    if entry.solves(Law::Coulomb) {
        return solve_directly(scene, settings, entry, observer);
    }
    let coulomb_settings = settings.coulomb().map_err(anyhow::Error::msg)?;
    let (coulomb, finest, counts, entry) = with_step(scene, settings, solver, |step, _| {
        friction_fixed_point(step, &coulomb_settings, observer)
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
    Ok(report(
        scene.clone(),
        entry.name,
        finest,
        coulomb,
        levels,
        settings,
    ))
}

/// A solver of the Coulomb problem itself, on the finest level.
fn solve_directly(
    scene: &Scene,
    settings: &Settings,
    entry: &'static Entry,
    observer: &mut dyn Observer,
) -> Result<Run> {
    settings.validate().map_err(anyhow::Error::msg)?;
    let finest = Discretization::new(scene, scene.finest())?;
    solve_assembled(scene, finest, settings, entry, observer)
}

/// A solver of the Coulomb problem itself on `finest`, the scene's finest
/// level already assembled (e.g. to measure the assembly apart).
pub fn solve_assembled(
    scene: &Scene,
    finest: Discretization,
    settings: &Settings,
    entry: &'static Entry,
    observer: &mut dyn Observer,
) -> Result<Run> {
    settings.validate().map_err(anyhow::Error::msg)?;
    let mut solver = settings.build(entry).map_err(anyhow::Error::msg)?;
    let t = std::time::Instant::now();
    let solution = solver.solve(&finest.problem, Friction::Coulomb, None, observer);
    let seconds = t.elapsed().as_secs_f64();
    let g: Vec<f64> = finest
        .problem
        .contacts()
        .iter()
        .zip(&solution.pressure)
        .map(|(c, p)| c.coefficient * p.max(0.0))
        .collect();
    let levels = vec![LevelCount {
        h: finest.h(),
        visits: 1,
        uzawa: solution.iterations.outer,
        sweeps: solution.iterations.inner,
        seconds,
    }];
    let coulomb = CoulombSolution {
        g,
        history: Vec::new(),
        status: solution.status,
        outcome: Outcome::Direct,
        detail: solution.detail.clone(),
        seconds,
        solution,
    };
    Ok(report(
        scene.clone(),
        entry.name,
        finest,
        coulomb,
        levels,
        settings,
    ))
}

/// Certificate, profile and separation of a finished solve.
pub fn report(
    scene: Scene,
    solver: &'static str,
    discretization: Discretization,
    coulomb: CoulombSolution,
    levels: Vec<LevelCount>,
    settings: &Settings,
) -> Run {
    let s = &coulomb.solution;
    let certificate = certify_solution(
        &discretization.problem,
        Friction::Coulomb,
        s,
        settings.certificate.tolerance,
    );
    let status = certificate.verdict(coulomb.status);
    let mut coulomb = coulomb;
    if matches!(status, Status::Unbounded | Status::Infeasible) {
        // The scene passed our check of condition (13): a solution exists.
        coulomb.detail = format!(
            "{} — but condition (13) holds (total vertical load {:e} < 0), so a solution exists: \
             this is a failure of the solver, not a property of the problem",
            coulomb.detail, discretization.total_load
        );
    }
    let s = &coulomb.solution;
    let profile = contact_profile(&discretization, s, &coulomb.g, status);
    let separation = separation_of(&discretization, s);
    let objective = discretization.problem.objective(&s.v, &coulomb.g);
    Run {
        scene,
        solver,
        discretization,
        coulomb,
        certificate,
        status,
        profile,
        separation,
        objective,
        levels,
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
    let (solution, finest, counts, _) = with_step(scene, settings, solver, |step, _| {
        step.solve_step(g, observer)
    })?;
    let counts = counts.unwrap_or_else(|| {
        vec![LevelCount {
            h: finest.h(),
            visits: 1,
            uzawa: solution.iterations.outer,
            sweeps: solution.iterations.inner,
            seconds: solution.timing.total(),
        }]
    });
    Ok((finest, solution, counts))
}

/// `summary.json`.
#[derive(Debug, Serialize)]
pub struct Summary {
    /// The whole scene: material, loads (normal and tangential), friction,
    /// mesh levels.
    pub scene: Scene,
    /// The commit of contactlab that produced it.
    pub git_commit: String,
    pub problem: String,
    pub h: String,
    pub solver: String,
    pub plane: String,
    pub friction_coefficient: f64,
    pub friction_iterations: usize,
    /// The certified status: `converged` only if the solver claimed it and
    /// the certificate passed.
    pub status: Status,
    /// The solver's own claim, beside it.
    pub solver_status: Status,
    /// How the fixed point ended (`direct` for a Coulomb solver).
    pub outcome: Outcome,
    pub detail: String,
    /// Every condition of the Coulomb law at g = 𝓕p, in the problem's scales.
    pub certificate: Certificate,
    /// Which condition fails or is worst, in words.
    pub certificate_summary: String,
    pub separated_intervals: Vec<[f64; 2]>,
    pub separated_fraction: f64,
    pub separation_tolerance: f64,
    pub max_pressure: f64,
    pub total_contact_force: f64,
    pub total_applied_load: f64,
    pub objective: f64,
    pub iterations_outer: usize,
    pub iterations_inner: usize,
    pub seconds: f64,
    pub seconds_setup: f64,
    pub seconds_solve: f64,
    pub history: Vec<crate::coulomb::fixed_point::FrictionIteration>,
    pub levels: Vec<LevelCount>,
    /// Every setting, resolved.
    pub settings: serde_json::Value,
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
            scene: self.scene.clone(),
            git_commit: crate::io::manifest::git_commit(),
            problem: self.scene.name.clone(),
            h: self.discretization.h().to_string(),
            solver: self.solver.to_string(),
            plane: self.scene.material.plane.to_string(),
            friction_coefficient: self.scene.friction,
            friction_iterations: self.coulomb.history.len(),
            status: self.status,
            solver_status: self.coulomb.status,
            outcome: self.coulomb.outcome,
            detail: self.coulomb.detail.clone(),
            certificate: self.certificate,
            certificate_summary: self.certificate.summary(),
            separated_intervals: self.separation.intervals.clone(),
            separated_fraction: self.separation.fraction,
            separation_tolerance: self.separation.tolerance,
            max_pressure: s.pressure.iter().fold(f64::NEG_INFINITY, |m, p| m.max(*p)),
            total_contact_force,
            total_applied_load: self.discretization.total_load,
            objective: self.objective,
            iterations_outer: iterations.outer,
            iterations_inner: iterations.inner,
            seconds: self.coulomb.seconds,
            seconds_setup: setup,
            seconds_solve: self.coulomb.seconds - setup,
            history: self.coulomb.history.clone(),
            levels: self.levels.clone(),
            settings: settings.resolved(),
        }
    }
}
