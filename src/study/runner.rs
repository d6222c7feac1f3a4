//! The one runner every study measures its trials with: solve (the whole
//! Coulomb problem, or the given-friction subproblem at the reference's g),
//! certify, compare with the reference, and time by repeating.

use std::time::Instant;

use anyhow::{Result, bail};
use contactlab_solvers::{Control, Friction, Law, Observer, Progress, Silent, Solution};

use crate::certificate::certify_solution;
use crate::coulomb::budget::Budget;
use crate::coulomb::continuation::LevelCount;
use crate::coulomb::driver::{solve_given_friction, solve_scene};
use crate::coulomb::fixed_point::{FrictionIteration, STAGE};
use crate::io::csv::to_csv;
use crate::io::output::write_atomic;
use crate::mechanics::contact_zone::separation_of;
use crate::mechanics::discretization::Discretization;
use crate::study::agreement::{Agreement, agreement};
use crate::study::reference::{Reference, References};
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

/// A measured trial.
pub struct Measured {
    pub trial: Trial,
    pub timing: TrialTiming,
    /// The fixed point's steps (empty for given-friction trials).
    pub friction: Vec<FrictionIteration>,
    /// Work per mesh level.
    pub levels: Vec<LevelCount>,
    pub history: Vec<Progress>,
    /// The finest level's discretization, the solution and the friction
    /// bound it was certified at (kept only when asked).
    pub solution: Option<(Discretization, Solution, Vec<f64>)>,
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

/// One solve of the trial: the answer, the finest discretization, and what
/// the fixed point did.
struct Solved {
    discretization: Discretization,
    solution: Solution,
    /// The friction bound of the answer: the given g, or 𝓕p (Coulomb).
    bound: Vec<f64>,
    certificate: crate::certificate::Certificate,
    /// The certified status, and the solver's (or the fixed point's) claim.
    status: contactlab_solvers::Status,
    claim: contactlab_solvers::Status,
    outcome: TrialOutcome,
    friction: Vec<FrictionIteration>,
    levels: Vec<LevelCount>,
    seconds: f64,
    setup: f64,
    /// Events of the solver's work stage.
    work: usize,
    detail: String,
}

fn solve_once(
    spec: &TrialSpec,
    reference: Option<&Reference>,
    observer: &mut dyn Observer,
) -> Result<Solved> {
    let mut budget = Budget::new(spec.solver, spec.work, spec.seconds, observer);
    if !spec.check_solvable {
        return solve_unchecked(spec, &mut budget);
    }
    match spec.law {
        Law::Coulomb => {
            let run = solve_scene(&spec.scene, &spec.settings, spec.solver.name, &mut budget)?;
            let setup = run.coulomb.history.iter().map(|h| h.setup_seconds).sum();
            Ok(Solved {
                work: budget.work(),
                status: run.status,
                claim: run.coulomb.status,
                certificate: run.certificate,
                outcome: run.coulomb.outcome.into(),
                friction: run.coulomb.history,
                levels: run.levels,
                seconds: run.coulomb.seconds,
                setup,
                detail: run.coulomb.detail,
                discretization: run.discretization,
                bound: run.coulomb.g,
                solution: run.coulomb.solution,
            })
        }
        Law::GivenFriction => {
            let Some(reference) = reference else {
                bail!(
                    "a given-friction trial needs the reference's bound g, and no reference could be earned for {} at h = {}",
                    spec.scene.name,
                    spec.scene.finest()
                );
            };
            let t = Instant::now();
            let (d, solution, levels) = solve_given_friction(
                &spec.scene,
                &spec.settings,
                spec.solver.name,
                &reference.g,
                &mut budget,
            )?;
            let seconds = t.elapsed().as_secs_f64();
            let work = budget.work();
            let certificate = certify_solution(
                &d.problem,
                Friction::Given(&reference.g),
                &solution,
                spec.settings.certificate.tolerance,
            );
            Ok(Solved {
                work,
                status: certificate.verdict(solution.status),
                claim: solution.status,
                certificate,
                outcome: TrialOutcome::NotApplicable,
                friction: Vec::new(),
                levels,
                seconds: solution.timing.total().min(seconds),
                setup: solution.timing.setup,
                detail: solution.detail.clone(),
                discretization: d,
                bound: reference.g.clone(),
                solution,
            })
        }
    }
}

/// One given-friction solve (g = 0) of a scene that may violate condition
/// (13), without the check.
fn solve_unchecked(spec: &TrialSpec, budget: &mut Budget<'_>) -> Result<Solved> {
    let d = Discretization::new_unchecked(&spec.scene, spec.scene.finest())?;
    let mut solver = spec
        .settings
        .build(spec.solver)
        .map_err(anyhow::Error::msg)?;
    let t = Instant::now();
    // One solve of the law the trial names, on the finest level: no fixed
    // point (a solver of the subproblem at g = 0).
    let zero = vec![0.0; d.problem.contacts().len()];
    let friction = match spec.law {
        Law::GivenFriction => Friction::Given(&zero),
        Law::Coulomb => Friction::Coulomb,
    };
    let solution = solver.solve(&d.problem, friction, None, budget);
    let seconds = t.elapsed().as_secs_f64();
    let certificate = certify_solution(
        &d.problem,
        friction,
        &solution,
        spec.settings.certificate.tolerance,
    );
    Ok(Solved {
        work: budget.work(),
        status: certificate.verdict(solution.status),
        claim: solution.status,
        certificate,
        outcome: TrialOutcome::NotApplicable,
        friction: Vec::new(),
        levels: Vec::new(),
        seconds,
        setup: solution.timing.setup,
        detail: solution.detail.clone(),
        discretization: d,
        bound: zero,
        solution,
    })
}

/// Measures one trial against `reference` (its Coulomb or given-friction
/// answer, by the trial's law).
pub fn measure(spec: &TrialSpec, reference: Option<&Reference>, keep: Keep) -> Result<Measured> {
    let mut recorder = Recorder {
        keep: keep.history,
        entry: spec.solver,
        events: Vec::new(),
    };
    let solved = solve_once(spec, reference, &mut recorder)?;
    let mut times = vec![solved.seconds];
    for _ in 0..spec.repeats {
        times.push(solve_once(spec, reference, &mut Silent)?.seconds);
    }
    let s = &solved.solution;
    let total = s.iterations;
    let (outer, inner) = if solved.friction.is_empty() {
        (total.outer, total.inner)
    } else {
        solved.friction.iter().fold((0, 0), |(o, i), f| {
            (o + f.iterations.outer, i + f.iterations.inner)
        })
    };
    let work = solved.work;
    let against: Option<(&str, Agreement)> = reference.and_then(|r| match spec.law {
        Law::Coulomb => Some((
            r.solver,
            agreement(
                &r.coulomb.discretization,
                &r.g,
                s,
                &r.coulomb.coulomb.solution,
            ),
        )),
        Law::GivenFriction => r.given_friction.as_ref().map(|gf| {
            (
                gf.solver,
                agreement(&gf.discretization, &r.g, s, &gf.solution),
            )
        }),
    });
    let separation = separation_of(&solved.discretization, s);
    let mut trial = Trial::not_run(spec, solved.status, solved.detail.clone());
    trial.solver_status = solved.claim;
    trial.outcome = solved.outcome;
    trial.friction_iterations = solved.friction.len();
    trial.outer_iterations = outer;
    trial.inner_iterations = inner;
    trial.work = work;
    trial.contraction = solved.friction.last().and_then(|f| f.contraction);
    if let Some((name, a)) = against {
        trial.reference = name.to_string();
        trial.displacement_error = Some(a.displacement_max);
        trial.pressure_error = Some(a.pressure_max);
        trial.traction_error = Some(a.traction_max);
        trial.objective_gap = Some(a.objective_gap);
    }
    trial.separated = intervals_text(&separation.intervals);
    trial.diagnostics = s
        .diagnostics
        .iter()
        .map(|(k, v)| format!("{k}={v:e}"))
        .collect::<Vec<_>>()
        .join(";");
    trial.separated_fraction = separation.fraction;
    if solved.status == contactlab_solvers::Status::Inaccurate {
        trial.detail = format!("{} ({})", trial.detail, solved.certificate.summary());
    }
    trial.set_certificate(&solved.certificate);
    let timing = TrialTiming {
        trial: 0,
        scene: trial.scene.clone(),
        h: trial.h.clone(),
        solver: trial.solver.clone(),
        law: trial.law,
        knob: trial.knob.clone(),
        value: trial.value.clone(),
        runs: times.len(),
        seconds_min: times.iter().copied().fold(f64::INFINITY, f64::min),
        seconds_median: median(&times),
        seconds_setup: solved.setup,
    };
    Ok(Measured {
        trial,
        timing,
        friction: solved.friction,
        levels: solved.levels,
        history: recorder.events,
        solution: keep
            .solution
            .then_some((solved.discretization, solved.solution, solved.bound)),
    })
}

/// Writes `STEM.csv` (the trials) and `STEM_timing.csv` (their times).
pub fn write_trials(dir: &std::path::Path, stem: &str, measured: &[Measured]) -> Result<()> {
    let trials: Vec<&Trial> = measured.iter().map(|m| &m.trial).collect();
    let timing: Vec<&TrialTiming> = measured.iter().map(|m| &m.timing).collect();
    write_atomic(&dir.join(format!("{stem}.csv")), &to_csv(&trials, &[])?)?;
    write_atomic(
        &dir.join(format!("{stem}_timing.csv")),
        &to_csv(&timing, &[])?,
    )
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

/// Separated intervals as `[a;b] [c;d]` (no commas, for CSV).
pub fn intervals_text(intervals: &[[f64; 2]]) -> String {
    intervals
        .iter()
        .map(|[a, b]| format!("[{a:.4};{b:.4}]"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Measures trials in order, each against the reference of its scene and
/// mesh (earned on first use); `tick` hears of each one done. The timing
/// rows are numbered by trial.
pub fn measure_all(
    specs: &[TrialSpec],
    references: &mut References,
    keep: Keep,
    tick: &dyn Fn(&TrialSpec),
) -> Result<Vec<Measured>> {
    let mut out = Vec::with_capacity(specs.len());
    for (i, spec) in specs.iter().enumerate() {
        let reference = if spec.check_solvable {
            references.get(&spec.scene, &spec.settings)?
        } else {
            None
        };
        let mut m = measure(spec, reference, keep)?;
        m.timing.trial = i;
        out.push(m);
        tick(spec);
    }
    Ok(out)
}
