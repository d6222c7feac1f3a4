//! The one solve: a problem, a friction law, the solver's entry and the
//! validated settings in; one [`Outcome`] out (the solution, its
//! certificate, the certified status beside the solver's claim, the work,
//! the times with the set-up apart, the fixed point's record, the work per
//! mesh level). `solve`'s summary, every study's trial and the reference
//! are views of it, so they cannot count or time a run differently.
//!
//! A solver of the Coulomb law solves the Coulomb problem directly; any
//! other runs inside the successive approximations of paper (9)
//! ([`crate::coulomb::fixed_point`]); a solver that warm-starts does each
//! given-friction step by mesh continuation over the scene's levels
//! (Algorithm 1, [`crate::coulomb::continuation`]).

mod outcome;
pub mod summary;

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use contactlab_solvers::entry::Entry;
use contactlab_solvers::{ContactProblem, Friction, Law, Observer, Solution, Status};

use crate::certificate::certify_solution;
use crate::coulomb::budget::Budget;
use crate::coulomb::continuation::{Continuation, LevelCount};
use crate::coulomb::fixed_point::{GivenFrictionStep, SingleLevel, friction_fixed_point_accepting};
use crate::mechanics::contact_zone::{ProfileRow, Separation, contact_profile, separation_of};
use crate::mechanics::discretization::Discretization;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;

pub use outcome::{FixedPoint, Outcome, Work};

/// A scene assembled for one solver: its finest level, and before it the
/// coarser levels its mesh continuation visits (only if it warm-starts).
/// Each is shared ([`Arc`]), so that a caller that keeps the finest level
/// (the Python package's problem) lends it to the solve instead of copying
/// it: the copy, mass matrix included, took the Python solve's peak from
/// 1.90 to 3.04 GiB at h = 1/2048.
pub struct Assembled {
    /// Coarse to fine; the last is the finest.
    levels: Vec<Arc<Discretization>>,
}

impl Assembled {
    /// Assembles `scene` (condition (13) checked) for `entry`: every level
    /// of the scene if the solver warm-starts, else the finest alone.
    /// A solver with a cap on its unknowns ([`Entry::max_unknowns`]) is
    /// refused a finer mesh once the finest level is assembled, before
    /// anything else is.
    /// The levels carry the mass matrix M only if the solver reads it
    /// ([`Entry::uses_mass`]).
    pub fn for_solver(scene: &Scene, entry: &'static Entry) -> Result<Self> {
        refuse_too_large(scene, entry)?;
        Self::around(
            scene,
            entry,
            Arc::new(level_for(scene, scene.finest(), entry)?),
        )
    }

    /// As [`Assembled::for_solver`], with the finest level already
    /// assembled and kept by the caller (the Python package's problem: no
    /// second assembly of the finest mesh per solve): the solve reads it
    /// where it is, and the memory check counts what the solve needs beside it
    /// ([`crate::memory::check_solve_beside`]), not the level a second time.
    pub fn lending(
        scene: &Scene,
        entry: &'static Entry,
        finest: Arc<Discretization>,
    ) -> Result<Self> {
        refuse_too_large_beside(scene, entry, true)?;
        Self::around(scene, entry, finest)
    }

    /// As [`Assembled::for_solver`] with the finest level already
    /// assembled, for a caller that refused a solve too
    /// large ([`refuse_too_large`]) before it assembled `finest`: a second
    /// check now would count the finest level twice, in what the process
    /// holds and in the need (`bench-one` at 1/8192 was refused for 19.6
    /// GB against 17.5 GB left beside its 6.7 GB problem, with 24 GB free
    /// before it).
    pub fn with_finest_checked(
        scene: &Scene,
        entry: &'static Entry,
        finest: Discretization,
    ) -> Result<Self> {
        Self::around(scene, entry, Arc::new(finest))
    }

    /// The coarser levels `entry` needs assembled around `finest`, checked
    /// already: a second check after the finest is assembled would count
    /// it twice, in what the process holds and in the need.
    fn around(scene: &Scene, entry: &'static Entry, finest: Arc<Discretization>) -> Result<Self> {
        anyhow::ensure!(
            finest.h() == scene.finest(),
            "the finest level given is on h = {}, the scene's finest mesh is {}",
            finest.h(),
            scene.finest()
        );
        let mut levels = Vec::with_capacity(scene.levels.len());
        if entry.warm_starts && scene.levels.len() > 1 {
            for &h in &scene.levels[..scene.levels.len() - 1] {
                levels.push(Arc::new(level_for(scene, h, entry)?));
            }
        }
        levels.push(finest);
        Ok(Self { levels })
    }

    /// One level already assembled (e.g. to time the assembly apart, or a
    /// scene assembled without the check of condition (13)).
    pub fn one_level(finest: Discretization) -> Self {
        Self {
            levels: vec![Arc::new(finest)],
        }
    }

    pub fn finest(&self) -> &Discretization {
        self.levels.last().expect("an assembled scene has a level")
    }

    /// The finest level, the coarser ones dropped.
    pub fn into_finest(mut self) -> Arc<Discretization> {
        self.levels.pop().expect("an assembled scene has a level")
    }
}

/// A solve refused before anything large is allocated.
#[derive(Debug, thiserror::Error)]
pub enum TooLarge {
    /// The mesh is finer than the solver's cap on unknowns
    /// ([`Entry::max_unknowns`]: a factor that grows faster than the
    /// problem).
    #[error(
        "h = {h} gives {unknowns} unknowns, more than the {cap} that {solver} is allowed: it factors a matrix of that size, whose factor would not fit in memory; use h ≥ 1/1024, or a solver without a factorization (tnnmg, or relaxation with --set relaxation.inner=multigrid)"
    )]
    Cap {
        h: MeshSize,
        unknowns: usize,
        cap: usize,
        solver: &'static str,
    },
    /// Its estimated memory does not fit in what the process may use.
    #[error(transparent)]
    Memory(#[from] crate::memory::MemoryError),
}

impl TooLarge {
    /// The status a refused run reports.
    pub fn status(&self) -> Status {
        match self {
            TooLarge::Cap { .. } => Status::NotRun,
            TooLarge::Memory(_) => Status::OutOfMemory,
        }
    }
}

/// Refuses a solve of `scene` by `entry` before anything is assembled: a
/// mesh finer than the solver's cap on unknowns, or one whose estimated
/// memory does not fit ([`crate::memory`]; the estimate counts the finest
/// level, which is assembled for the solve). The unknowns are counted from
/// h alone.
pub fn refuse_too_large(scene: &Scene, entry: &'static Entry) -> Result<(), TooLarge> {
    refuse_too_large_beside(scene, entry, false)
}

/// As [`refuse_too_large`]; with `held`, for a finest level the process
/// already holds and lends to the solve: what the solve needs beside it.
fn refuse_too_large_beside(
    scene: &Scene,
    entry: &'static Entry,
    held: bool,
) -> Result<(), TooLarge> {
    let h = scene.finest();
    let n = crate::memory::unknowns(h);
    if let Some(cap) = entry.max_unknowns.filter(|&cap| n > cap) {
        return Err(TooLarge::Cap {
            h,
            unknowns: n,
            cap,
            solver: entry.name,
        });
    }
    crate::memory::check_solve_beside(
        &scene.name,
        h,
        entry,
        &contactlab_solvers::registry::solvers(),
        held,
    )?;
    Ok(())
}

/// One level of `scene` assembled for `entry`: with M only if it reads it.
pub fn level_for(scene: &Scene, h: MeshSize, entry: &Entry) -> Result<Discretization> {
    Ok(if entry.uses_mass {
        Discretization::new(scene, h)?
    } else {
        Discretization::new_without_mass(scene, h)?
    })
}

/// Caps on a solve's work (events of the solver's work stage, over the
/// whole solve) and wall-clock time, enforced through the observer hook.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Caps {
    pub work: Option<usize>,
    pub seconds: Option<f64>,
}

/// Solves `problem` under `friction` (the Coulomb law, or the
/// given-friction subproblem at a bound on the finest level) with the
/// solver of `entry` at `settings` (validated where they were resolved),
/// within `caps`, and certifies the answer on the finest level. The solve
/// takes the assembled levels (the nested schedule drops the coarse ones
/// once done with them) and gives the finest back with the outcome.
pub fn solve(
    problem: Assembled,
    friction: Friction<'_>,
    entry: &'static Entry,
    settings: &Settings,
    caps: Caps,
    observer: &mut dyn Observer,
) -> Result<Solved> {
    let mut solver = settings.build(entry).map_err(anyhow::Error::msg)?;
    let mut budget = Budget::new(entry, caps.work, caps.seconds, observer);
    let start = Instant::now();
    let (done, finest) = if friction == Friction::Coulomb && entry.solves(Law::Coulomb) {
        let finest = problem.into_finest();
        let s = solver.solve(&finest.problem, Friction::Coulomb, None, &mut budget);
        let bound = finest
            .problem
            .contacts()
            .iter()
            .zip(&s.pressure)
            .map(|(c, p)| c.coefficient * p.max(0.0))
            .collect();
        let done = Done::direct(&finest, s, bound, start.elapsed().as_secs_f64());
        (done, finest)
    } else if problem.levels.len() > 1 {
        let mut step =
            Continuation::new(problem.levels, solver.as_mut(), settings.schedule_of(entry));
        let done = steps(&mut step, friction, settings, &mut budget, start)?;
        let done = Done {
            levels: step.counts.clone(),
            ..done
        };
        (done, step.into_finest())
    } else {
        let finest = problem.into_finest();
        let mut step = SingleLevel::new(&finest.problem, solver.as_mut());
        let mut done = steps(&mut step, friction, settings, &mut budget, start)?;
        done.levels = vec![done.one_level_count(&finest)];
        (done, finest)
    };
    // The solver's hierarchies and vectors go before the certificate's are
    // allocated: at h = 1/4096 they were the solve's peak together.
    drop(solver);
    let outcome = judge(
        entry,
        friction,
        &finest.problem,
        finest.total_load,
        done,
        settings,
        budget.work(),
    );
    Ok(Solved { finest, outcome })
}

/// Certifies what a solve gave on `problem` (the finest level) and puts
/// the outcome together: the certified status beside the solver's claim.
/// `total_load` is the scene's Σ p2·(to − from), negative when condition
/// (13) holds (NaN for a problem given by its matrices: not known).
fn judge(
    entry: &'static Entry,
    friction: Friction<'_>,
    problem: &ContactProblem,
    total_load: f64,
    done: Done,
    settings: &Settings,
    work_events: usize,
) -> Outcome {
    let certificate = certify_solution(
        problem,
        friction,
        &done.solution,
        settings.certificate.tolerance,
    );
    let status = certificate.verdict(done.claim);
    let mut detail = match &done.fixed_point {
        Some(fp) => fp.detail.clone(),
        None => done.solution.detail.clone(),
    };
    if matches!(status, Status::Unbounded | Status::Infeasible) && total_load < 0.0 {
        // The load satisfies condition (13): a solution exists. (A scene
        // assembled without the check may violate it: then the solver's
        // word stands.)
        detail = format!(
            "{detail} — but condition (13) holds (total vertical load {:e} < 0), so a solution exists: \
             this is a failure of the solver, not a property of the problem",
            total_load
        );
    }
    let (work, timing) = match &done.fixed_point {
        Some(fp) => (fp.work(), fp.timing(done.seconds)),
        None => (Work::of(&done.solution), done.solution.timing),
    };
    Outcome {
        solver: entry,
        law: friction.law(),
        bound: done.bound,
        certificate,
        status,
        claim: done.claim,
        detail,
        work: Work {
            events: work_events,
            ..work
        },
        timing,
        fixed_point: done.fixed_point,
        levels: done.levels,
        solution: done.solution,
    }
}

/// Solves a problem given by its matrices alone (an exported instance,
/// one's own matrices) under `friction` with the solver of `entry`: the
/// Coulomb law directly if the solver solves it, else by the fixed point of
/// paper (9) over single-level given-friction steps (there is no mesh to
/// continue on). A solver that needs a multigrid hierarchy the problem
/// does not carry says so in its status. Certified like every solve.
pub fn solve_algebraic(
    problem: &ContactProblem,
    friction: Friction<'_>,
    entry: &'static Entry,
    settings: &Settings,
    caps: Caps,
    observer: &mut dyn Observer,
) -> Result<Outcome> {
    let mut solver = settings.build(entry).map_err(anyhow::Error::msg)?;
    let mut budget = Budget::new(entry, caps.work, caps.seconds, observer);
    let start = Instant::now();
    let done = if friction == Friction::Coulomb && entry.solves(Law::Coulomb) {
        let s = solver.solve(problem, Friction::Coulomb, None, &mut budget);
        let bound = problem
            .contacts()
            .iter()
            .zip(&s.pressure)
            .map(|(c, p)| c.coefficient * p.max(0.0))
            .collect();
        Done {
            claim: s.status,
            solution: s,
            bound,
            fixed_point: None,
            levels: Vec::new(),
            seconds: start.elapsed().as_secs_f64(),
        }
    } else {
        let mut step = SingleLevel::new(problem, solver.as_mut());
        steps(&mut step, friction, settings, &mut budget, start)?
    };
    Ok(judge(
        entry,
        friction,
        problem,
        f64::NAN,
        done,
        settings,
        budget.work(),
    ))
}

/// What the solver, or the fixed point around it, gave before the
/// certificate.
struct Done {
    solution: Solution,
    /// The bound of the last given-friction step, or 𝓕p of a direct answer.
    bound: Vec<f64>,
    /// The solver's claim, or the fixed point's.
    claim: Status,
    fixed_point: Option<FixedPoint>,
    levels: Vec<LevelCount>,
    /// Wall-clock seconds.
    seconds: f64,
}

impl Done {
    /// A direct solve of the Coulomb problem on the finest level.
    fn direct(finest: &Discretization, solution: Solution, bound: Vec<f64>, seconds: f64) -> Self {
        let mut done = Self {
            claim: solution.status,
            solution,
            bound,
            fixed_point: None,
            levels: Vec::new(),
            seconds,
        };
        done.levels = vec![done.one_level_count(finest)];
        done
    }

    /// The work on the finest level when it is the only one.
    fn one_level_count(&self, finest: &Discretization) -> LevelCount {
        let h = finest.h();
        match &self.fixed_point {
            Some(fp) => {
                let work = fp.work();
                LevelCount {
                    h,
                    visits: fp.history.len(),
                    uzawa: work.outer,
                    sweeps: work.inner,
                    seconds: fp.history.iter().map(|s| s.seconds).sum(),
                }
            }
            None => LevelCount {
                h,
                visits: 1,
                uzawa: self.solution.iterations.outer,
                sweeps: self.solution.iterations.inner,
                seconds: self.solution.timing.total(),
            },
        }
    }
}

/// The given-friction steps of a solve: the fixed point of paper (9) for
/// the Coulomb law, one step at the given bound otherwise.
fn steps(
    step: &mut dyn GivenFrictionStep,
    friction: Friction<'_>,
    settings: &Settings,
    observer: &mut dyn Observer,
    start: Instant,
) -> Result<Done> {
    Ok(match friction {
        Friction::Coulomb => {
            let coulomb = settings.coulomb().map_err(anyhow::Error::msg)?;
            let tolerance = settings.certificate.tolerance;
            let accept = |problem: &ContactProblem, s: &Solution| {
                certify_solution(problem, Friction::Coulomb, s, tolerance).passed()
            };
            let c = friction_fixed_point_accepting(step, &coulomb, observer, &accept);
            let fp = FixedPoint {
                history: c.history,
                ending: c.ending,
                status: c.status,
                detail: c.detail,
            };
            Done {
                claim: fp.status,
                solution: c.solution,
                bound: c.g,
                levels: Vec::new(),
                fixed_point: Some(fp),
                seconds: start.elapsed().as_secs_f64(),
            }
        }
        Friction::Given(g) => {
            let s = given_step(step, g, settings.certificate.tolerance, observer);
            Done {
                claim: s.status,
                solution: s,
                bound: g.to_vec(),
                levels: Vec::new(),
                fixed_point: None,
                seconds: start.elapsed().as_secs_f64(),
            }
        }
    })
}

/// One given-friction solve at the bound `g`. An answer the solver claims
/// converged and the certificate (at `tolerance`) rejects is solved again
/// with the solver's tolerance tightened ([`Solver::tighten`]), while it
/// can tighten: the oracle's default tolerance loses accuracy as h falls
/// (1e-10 gave violations of 3.7e-5 at h = 1/128). The work of every
/// attempt is counted, and the detail says what was tightened.
///
/// [`Solver::tighten`]: contactlab_solvers::Solver::tighten
fn given_step(
    step: &mut dyn GivenFrictionStep,
    g: &[f64],
    tolerance: f64,
    observer: &mut dyn Observer,
) -> Solution {
    let mut s = step.solve_step(g, None, observer);
    let mut tightened = Vec::new();
    let (mut iterations, mut timing) = (s.iterations, s.timing);
    while s.status.is_converged()
        && !certify_solution(step.problem(), Friction::Given(g), &s, tolerance).passed()
    {
        let Some(what) = step.tighten() else { break };
        tightened.push(what);
        s = step.solve_step(g, None, observer);
        iterations.outer += s.iterations.outer;
        iterations.inner += s.iterations.inner;
        timing.setup += s.timing.setup;
        timing.solve += s.timing.solve;
    }
    if !tightened.is_empty() {
        s.detail = format!(
            "{} (solved {} times: the certificate rejected the answer, and the solver tightened: {})",
            s.detail,
            tightened.len() + 1,
            tightened.join(", then ")
        );
        (s.iterations, s.timing) = (iterations, timing);
    }
    s
}

/// Assembles `scene` for `entry` and solves it: the convenience of scripts,
/// tests and the `solve` command. Gives the finest level with the outcome.
pub fn solve_scene(
    scene: &Scene,
    friction: Friction<'_>,
    entry: &'static Entry,
    settings: &Settings,
    observer: &mut dyn Observer,
) -> Result<Solved> {
    let problem = Assembled::for_solver(scene, entry)?;
    solve(
        problem,
        friction,
        entry,
        settings,
        Caps::default(),
        observer,
    )
}

/// A solve with the finest level it was certified on: what reports need.
pub struct Solved {
    /// The finest level: the solve's own, or the one lent to it.
    pub finest: Arc<Discretization>,
    pub outcome: Outcome,
}

impl Solved {
    /// The separated part of Γ_K.
    pub fn separation(&self) -> Separation {
        separation_of(&self.finest, &self.outcome.solution)
    }

    /// The profile along Γ_K, marked with the certified status.
    pub fn profile(&self) -> Vec<ProfileRow> {
        contact_profile(
            &self.finest,
            &self.outcome.solution,
            &self.outcome.bound,
            self.outcome.status,
        )
    }

    /// The objective of paper (10) at the bound of the last step.
    pub fn objective(&self) -> f64 {
        self.finest
            .problem
            .objective(&self.outcome.solution.v, &self.outcome.bound)
    }
}

/// The registered solver named `name`, or an error that lists them.
pub fn solver_entry(name: &str) -> Result<&'static Entry> {
    contactlab_solvers::registry::by_name(name).with_context(|| {
        format!(
            "unknown solver '{name}': the registered solvers are {}",
            contactlab_solvers::registry::names().join(", ")
        )
    })
}
