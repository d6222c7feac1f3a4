//! The one runner every study measures its trials with: solve (the whole
//! Coulomb problem, or the given-friction subproblem at the reference's g),
//! certify, compare with the reference, and time by repeating.

use anyhow::{Result, bail};
use contactlab_solvers::{Control, Friction, Law, Observer, Progress, Silent, Solution, Status};

use crate::certificate::BoundReport;
use crate::coulomb::continuation::LevelCount;
use crate::coulomb::fixed_point::{FrictionIteration, STAGE};
use crate::mechanics::contact_zone::separation_of;
use crate::mechanics::discretization::Discretization;
use crate::solve::summary::bound_within_limit;
use crate::solve::{Assembled, Caps, Outcome, solve};
use crate::study::agreement::{Agreement, agreement};
use crate::study::reference::{Reference, References};
pub use crate::study::trial::intervals_text;
use crate::study::trial::{Trial, TrialOutcome, TrialSpec, TrialTiming};

/// How the repeated runs' times are summarized and what is kept.
#[derive(Clone, Copy, Debug, Default)]
pub struct Keep {
    /// Keep the convergence history (the stages their solvers mark for it,
    /// and the fixed point's).
    pub history: bool,
    /// Keep the finest level's discretization and the solution (profiles).
    pub solution: bool,
}

/// A measured trial: its record (the CSV row), its times, and the
/// outcome of its first solve (the typed record the views read).
pub struct Measured {
    pub trial: Trial,
    pub timing: TrialTiming,
    pub outcome: Outcome,
    /// The convergence history (kept only when asked).
    pub history: Vec<Progress>,
    /// The finest level it was certified on (kept only when asked).
    pub finest: Option<std::sync::Arc<Discretization>>,
}

impl Measured {
    /// The fixed point's steps (empty without a fixed point).
    pub fn friction(&self) -> &[FrictionIteration] {
        self.outcome.history()
    }

    /// Work per mesh level.
    pub fn levels(&self) -> &[LevelCount] {
        &self.outcome.levels
    }

    /// A copy without the finest level (charts need trials and histories).
    pub fn without_finest(&self) -> Measured {
        Measured {
            trial: self.trial.clone(),
            timing: self.timing.clone(),
            outcome: self.outcome.clone(),
            history: self.history.clone(),
            finest: None,
        }
    }

    /// The finest level, the answer and its bound, if kept.
    pub fn solution(&self) -> Option<(&Discretization, &Solution, &[f64])> {
        self.finest
            .as_deref()
            .map(|d| (d, &self.outcome.solution, self.outcome.bound.as_slice()))
    }
}

/// Keeps the stages a convergence history wants: the fixed point's and
/// those the running solver's registry entry marks for it.
struct Recorder {
    keep: bool,
    entry: &'static contactlab_solvers::registry::Entry,
    events: Vec<Progress>,
}

impl Observer for Recorder {
    fn observe(&mut self, p: &Progress) -> Control {
        self.events.push(*p);
        Control::Continue
    }

    fn wants(&self, stage: &str) -> bool {
        self.keep && (stage == STAGE || self.entry.stage(stage).is_some_and(|s| s.history))
    }
}

/// One solve of the trial, with the finest level it was certified on.
fn solve_once(
    spec: &TrialSpec,
    reference: Option<&Reference>,
    observer: &mut dyn Observer,
) -> Result<(std::sync::Arc<Discretization>, Outcome)> {
    let caps = Caps {
        work: spec.work,
        seconds: spec.seconds,
    };
    let zero;
    let (problem, friction) = if !spec.check_solvable {
        // One solve of the law the trial names, on the finest level,
        // without the check of condition (13): no fixed point (a solver of
        // the subproblem at g = 0).
        let d = Discretization::new_unchecked(&spec.scene, spec.scene.finest())?;
        zero = vec![0.0; d.problem.contacts().len()];
        let friction = match spec.law {
            Law::GivenFriction => Friction::Given(&zero),
            Law::Coulomb => Friction::Coulomb,
        };
        (Assembled::one_level(d), friction)
    } else {
        let friction = match (spec.law, reference) {
            (Law::Coulomb, _) => Friction::Coulomb,
            (Law::GivenFriction, Some(r)) => Friction::Given(&r.g),
            (Law::GivenFriction, None) => bail!(
                "a given-friction trial needs the reference's bound g, and no reference could be earned for {} at h = {}",
                spec.scene.name,
                spec.scene.finest()
            ),
        };
        (Assembled::for_solver(&spec.scene, spec.solver)?, friction)
    };
    let solved = solve(
        problem,
        friction,
        spec.solver,
        &spec.settings,
        caps,
        observer,
    )?;
    Ok((solved.finest, solved.outcome))
}

/// Measures one trial against `reference` (its Coulomb or given-friction
/// answer, by the trial's law).
pub fn measure(spec: &TrialSpec, reference: Option<&Reference>, keep: Keep) -> Result<Measured> {
    let mut recorder = Recorder {
        keep: keep.history,
        entry: spec.solver,
        events: Vec::new(),
    };
    let (finest, outcome) = solve_once(spec, reference, &mut recorder)?;
    // The first run is the warm-up: with repeats, the runs after it are
    // what is timed (the median of a cold and a warm run was reported as
    // "the median after a warm-up"); without, the one run there is.
    let mut times = Vec::with_capacity(spec.repeats.max(1));
    for _ in 0..spec.repeats {
        times.push(solve_once(spec, reference, &mut Silent)?.1.timing.total());
    }
    if times.is_empty() {
        times.push(outcome.timing.total());
    }
    let trial = trial_row(spec, reference, &finest, &outcome);
    let (knob, value) = trial.knob();
    let timing = TrialTiming {
        trial: 0,
        scene: trial.scene.clone(),
        h: trial.h.to_string(),
        solver: trial.solver.name.to_string(),
        law: trial.law,
        knob: knob.to_string(),
        value: value.to_string(),
        runs: times.len(),
        seconds_min: times.iter().copied().fold(f64::INFINITY, f64::min),
        seconds_median: median(&times),
        seconds_setup: outcome.timing.setup,
    };
    Ok(Measured {
        trial,
        timing,
        outcome,
        history: recorder.events,
        finest: keep.solution.then_some(finest),
    })
}

/// The trial: a view of its outcome, with its differences from the
/// reference.
pub fn trial_row(
    spec: &TrialSpec,
    reference: Option<&Reference>,
    finest: &Discretization,
    o: &Outcome,
) -> Trial {
    let s = &o.solution;
    let against: Option<(&'static str, Agreement)> = reference.and_then(|r| match spec.law {
        Law::Coulomb => Some((
            r.solver,
            agreement(&r.coulomb.finest, &r.g, s, &r.coulomb.outcome.solution),
        )),
        Law::GivenFriction => r.given_friction.as_ref().map(|gf| {
            (
                gf.solver,
                agreement(&r.coulomb.finest, &r.g, s, &gf.outcome.solution),
            )
        }),
    });
    let separation = separation_of(finest, s);
    let mut trial = Trial::not_run(spec, o.status, o.detail.clone());
    trial.solver_status = o.claim;
    trial.outcome = match o.law {
        Law::GivenFriction => TrialOutcome::NotApplicable,
        Law::Coulomb => o.ending().into(),
    };
    trial.friction_iterations = o.friction_iterations();
    trial.outer_iterations = o.work.outer;
    trial.inner_iterations = o.work.inner;
    trial.work = o.work.events;
    trial.contraction = o.contraction();
    if let Some((name, a)) = against {
        trial.reference = Some(name);
        trial.agreement = Some(a);
    }
    trial.separated = separation.intervals;
    trial.separated_fraction = separation.fraction;
    trial.diagnostics = s.diagnostics.clone();
    if o.status == Status::Inaccurate {
        trial.detail = format!("{} ({})", trial.detail, o.certificate.summary());
    }
    trial.certificate = Some(o.certificate);
    trial.bound = trial_bound(spec, reference, finest, s)
        .map(|b| b.with_contraction(o.contraction_for_estimate()));
    trial
}

/// The trial's error bound (issue 51), under the law it solved: none for
/// a trial that skips the check of condition (13) (its problem may have
/// no solution to be near), one whose study reads no bound
/// ([`TrialSpec::bounded`]), or a given-friction trial without the
/// reference's g; `none:` and why for a problem larger than
/// `certificate.bound_max_unknowns`.
fn trial_bound(
    spec: &TrialSpec,
    reference: Option<&Reference>,
    finest: &Discretization,
    s: &Solution,
) -> Option<BoundReport> {
    if !spec.check_solvable || !spec.bounded {
        return None;
    }
    let friction = match (spec.law, reference) {
        (Law::Coulomb, _) => Friction::Coulomb,
        (Law::GivenFriction, Some(r)) => Friction::Given(&r.g),
        (Law::GivenFriction, None) => return None,
    };
    Some(bound_within_limit(
        &finest.problem,
        friction,
        s,
        &spec.settings.certificate,
    ))
}

/// The median of a non-empty list (NaN for an empty one).
pub fn median(x: &[f64]) -> f64 {
    let mut v: Vec<f64> = x.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// Refuses a plan before any of its trials runs if one of them cannot run
/// on its mesh (too many unknowns for its solver, or more memory than the
/// process may use), naming it and the way out: a study never stops for
/// it halfway, nor aborts for memory.
fn refuse_what_cannot_run(specs: &[TrialSpec]) -> Result<()> {
    let mut seen: Vec<(crate::mechanics::mesh_size::MeshSize, &str)> = Vec::new();
    for spec in specs.iter().filter(|s| s.check_solvable) {
        let key = (spec.scene.finest(), spec.solver.name);
        if seen.contains(&key) {
            continue;
        }
        seen.push(key);
        if let Err(e) = crate::solve::refuse_too_large(&spec.scene, spec.solver) {
            bail!(
                "{}: {} cannot run at h = {} ({e}); leave it out (--solvers) or use a coarser mesh",
                spec.study,
                spec.solver.name,
                spec.scene.finest()
            );
        }
    }
    Ok(())
}

/// Measures trials in order, each against the reference of its scene and
/// mesh (earned on first use); `tick` hears of each one done. The timing
/// rows are numbered by trial.
pub fn measure_all(
    specs: &[TrialSpec],
    references: &mut References,
    keep: Keep,
    tick: &dyn Fn(&TrialSpec) -> Result<()>,
) -> Result<Vec<Measured>> {
    refuse_what_cannot_run(specs)?;
    let mut out = Vec::with_capacity(specs.len());
    for (i, spec) in specs.iter().enumerate() {
        let reference = if spec.wants_reference() {
            references.get(&spec.scene, &spec.settings)?
        } else {
            None
        };
        let mut m = measure(spec, reference, keep)?;
        m.timing.trial = i;
        out.push(m);
        tick(spec)?;
    }
    Ok(out)
}
