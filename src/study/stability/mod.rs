//! The stability map: each solver across stress conditions, every trial
//! classified ([`classify`]) with the reason. Every trial is stopped by a
//! work cap (a count, from the registry), never by the clock, so the map is
//! the same on every machine. Groups:
//!
//! - `default` and `stress`: each solver at its defaults and across the
//!   stress conditions its registry entry lists, on problem 1;
//! - `friction`: the friction coefficient 𝓕, with bisection for the largest
//!   𝓕 whose Coulomb solve is certified, on problems 1-3;
//! - `load`: total vertical loads approaching 0 (condition (13) barely holds);
//! - `scenes`: each solver at its defaults on the classical scenes of
//!   `scenes/` (Hertz, a flat punch, Cattaneo–Mindlin sheared and free to
//!   slide): a gap, a slip offset and a second rigid mode;
//! - `refused`: loads that violate condition (13): refused by our check,
//!   and (check bypassed) what each solver does with such a problem.

pub mod charts;
pub mod classify;
pub mod uniqueness;
pub mod views;

use anyhow::Result;
use contactlab_solvers::registry::{self, Entry};
use contactlab_solvers::{Law, Status};
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::io::csv::{fixed, fixed_opt};
use crate::mechanics::discretization::Discretization;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::{Scene, Traction};
use crate::settings::Settings;
use crate::study::catalog::{Catalogued, by_length};
use crate::study::cores::{Shared, on_both_cores, trial_need};
use crate::study::lab::{Artifact, Lab, Ran, RunLength, Section, Study};
use crate::study::runner::{Keep, Measured, measure};
use crate::study::sweep::work_cap;
use crate::study::trial::{Setting, Trial, TrialSpec};
use classify::{Class, Context, classify, trend};

/// The study's name in trial records.
pub const STUDY: &str = "stability";

/// What the map runs: its parameters (its flags, and Python's keywords).
#[derive(Clone, Debug, Serialize, Deserialize, clap::Args)]
pub struct StabilitySpec {
    /// Mesh of the default, stress, load and refused groups, such as 1/16.
    #[arg(long, value_name = "H", required = false)]
    pub h: MeshSize,
    /// Mesh of the friction scan, such as 1/16.
    #[arg(long, value_name = "H", required = false)]
    pub h_friction: MeshSize,
    /// Mesh of the classical scenes (their contact half-width is 1/32),
    /// such as 1/32.
    #[arg(long, value_name = "H", required = false)]
    pub h_scenes: MeshSize,
    /// The registry's short value lists (`--quick`).
    #[arg(skip)]
    pub quick: bool,
    /// Multiplies each solver's study work cap, a number > 0.
    #[arg(long, value_name = "FACTOR", required = false)]
    pub work_scale: f64,
    /// The friction coefficients of the scan, such as 0,0.5,16.
    #[arg(long, value_delimiter = ',', value_name = "F")]
    pub friction_values: Vec<f64>,
    /// Bisection steps for the largest certified friction coefficient.
    #[arg(long, value_name = "N", required = false, value_parser = clap::value_parser!(u64).range(0..=20))]
    pub bisection_steps: u64,
    /// |total vertical load| values approaching 0 (problem 1 is 20), such
    /// as 20,2e-4.
    #[arg(long, value_delimiter = ',', value_name = "P")]
    pub load_totals: Vec<f64>,
    /// Upward totals that violate condition (13) (0: no load at all).
    #[arg(long, value_delimiter = ',', value_name = "P")]
    pub violating_totals: Vec<f64>,
    /// Friction coefficients of the uniqueness study (solvers of the
    /// Coulomb problem itself, from several starts, on problem 1).
    #[arg(long, value_delimiter = ',', value_name = "F")]
    pub uniqueness_values: Vec<f64>,
}

impl StabilitySpec {
    /// The map `reproduce` runs.
    pub fn standard() -> Self {
        let k = |k| MeshSize::from_level(k).expect("in range");
        Self {
            h: k(4),
            h_friction: k(4),
            h_scenes: k(5),
            quick: false,
            work_scale: 1.0,
            friction_values: vec![0.0, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 64.0],
            bisection_steps: 5,
            load_totals: vec![20.0, 2.0, 0.2, 2e-2, 2e-3, 2e-4, 2e-6],
            violating_totals: vec![0.0, 2.0],
            uniqueness_values: vec![4.0, 7.5, 8.0, 10.0, 16.0, 32.0, 64.0],
        }
    }

    /// A small map for tests (seconds).
    pub fn quick() -> Self {
        let k = |k| MeshSize::from_level(k).expect("in range");
        Self {
            h: k(3),
            h_friction: k(4),
            h_scenes: k(4),
            quick: true,
            work_scale: 0.2,
            friction_values: vec![0.0, 0.5, 16.0],
            bisection_steps: 2,
            load_totals: vec![20.0, 2e-4],
            violating_totals: vec![2.0],
            uniqueness_values: vec![8.0],
        }
    }
}

/// One step of a fixed point in the friction scan.
#[derive(Clone, Debug, Serialize)]
pub struct FrictionStep {
    pub scene: String,
    pub solver: String,
    #[serde(serialize_with = "fixed")]
    pub friction_coefficient: f64,
    pub iteration: usize,
    #[serde(serialize_with = "fixed")]
    pub change: f64,
    #[serde(serialize_with = "fixed_opt")]
    pub contraction: Option<f64>,
    pub certified: bool,
}

/// The groups of the map's trials.
pub const DEFAULT: &str = "default";
pub const STRESS: &str = "stress";
pub const LOAD: &str = "load";
pub const SCENES: &str = "scenes";
pub const REFUSED: &str = "refused";
pub const BYPASSED: &str = "refused_check_bypassed";
pub const FRICTION: &str = "friction";
pub const FRICTION_BISECTION: &str = "friction_bisection";

/// The map: classified trials, the friction scan's steps and the
/// uniqueness study's findings.
pub struct Map {
    pub trials: Vec<Trial>,
    pub steps: Vec<FrictionStep>,
    pub uniqueness: Vec<uniqueness::UniquenessRow>,
}

/// Problem 1 plus an upward traction on [2/3, 1] so that the total
/// vertical load is −`total` (a negative `total` lifts the body).
pub fn lifted_problem(total: f64, h: MeshSize) -> Result<Scene> {
    let mut s = Scene::paper_problem_to(1, h)?;
    let up = 3.0 * (20.0 - total);
    if up != 0.0 {
        s.loads.push(Traction {
            from: 2.0 / 3.0,
            to: 1.0,
            p2: up,
            p1: 0.0,
        });
    }
    s.name = format!("problem 1, total load {:e}", -total);
    Ok(s)
}

/// The map as a study: stability.csv, stability_friction.csv,
/// stability_uniqueness.csv, its references file (if named) and the charts.
pub struct Stability {
    pub spec: StabilitySpec,
    pub references_file: Option<&'static str>,
}

impl StabilitySpec {
    /// The spec's own consistency: a one-line error naming the field.
    pub fn check(&self) -> Result<()> {
        anyhow::ensure!(
            self.work_scale.is_finite() && self.work_scale > 0.0,
            "work-scale = {}: give a factor > 0",
            self.work_scale
        );
        for (name, values, least) in [
            ("friction-values", &self.friction_values, 0.0),
            ("uniqueness-values", &self.uniqueness_values, 0.0),
            ("violating-totals", &self.violating_totals, 0.0),
        ] {
            if let Some(v) = values.iter().find(|v| !(v.is_finite() && **v >= least)) {
                anyhow::bail!("{name}: {v} is not a number ≥ 0");
            }
        }
        if let Some(v) = self
            .load_totals
            .iter()
            .find(|v| !(v.is_finite() && **v > 0.0))
        {
            anyhow::bail!("load-totals: {v} is not a load > 0 (violating-totals holds 0)");
        }
        Ok(())
    }
}

impl Catalogued for Stability {
    const COMMAND: &'static str = "stability";
    const ABOUT: &'static str = "The stability map: each solver across stress conditions (its registry entry's, \
        the friction coefficient, loads near and past condition (13), the classical scenes), every trial classified \
        converged, slow, stalled, diverged, wrong or refused, with the reason. Writes stability.csv, \
        stability_friction.csv, stability_summary.md, stability_references.csv and charts into --out.";
    type Spec = StabilitySpec;

    fn spec(length: RunLength) -> StabilitySpec {
        // One map for the main job and the long run.
        by_length(
            length,
            StabilitySpec::quick,
            StabilitySpec::standard,
            StabilitySpec::standard,
        )
    }

    fn of(spec: StabilitySpec) -> Result<Self> {
        spec.check()?;
        Ok(Self {
            spec,
            references_file: Some("stability_references.csv"),
        })
    }
}

impl Study for Stability {
    /// The map.
    type Findings = Map;

    fn name(&self) -> &'static str {
        STUDY
    }

    fn estimated_seconds(&self, length: RunLength) -> f64 {
        match length {
            // On both cores: 88 s measured in the main job on 7ffa5e6 (168 s
            // on one core).
            RunLength::Quick => 1.0,
            _ => 90.0,
        }
    }

    fn section(&self, map: &Map, _: &Lab, charts: &[String]) -> Result<Section> {
        Ok(Section {
            markdown: views::section(&map.trials, &map.uniqueness, charts)?,
        })
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<Map>> {
        lab.log("stability map");
        let map = run(&self.spec, lab)?;
        let rows: Vec<_> = map.trials.iter().map(|t| t.row()).collect();
        let mut artifacts = vec![
            Artifact::csv("stability.csv", &rows, &[])?,
            Artifact::csv("stability_friction.csv", &map.steps, &[])?,
            Artifact::csv("stability_uniqueness.csv", &map.uniqueness, &[])?,
            Artifact::text(
                "stability_summary.md",
                &views::summary_markdown(&map.trials)?,
            ),
        ];
        if let Some(file) = self.references_file {
            artifacts.push(Artifact::csv(file, &lab.candidates(), &[])?);
        }
        artifacts.extend(Artifact::charts(charts::charts(&map.trials, &map.steps)));
        Ok(Ran {
            findings: map,
            artifacts,
        })
    }
}

/// Where a trial goes in the map's order: its group (defaults and stress,
/// the friction scan, loads, classical scenes, refused loads), its place
/// in the group (which load, which scene), then its solver; within that,
/// the order it ran in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Place {
    group: u8,
    within: usize,
    solver: usize,
}

/// One solver's part of the map: its classified trials, each with its
/// place and the scene whose reference it asked for, and its friction
/// scan's steps.
#[derive(Default)]
struct Part {
    trials: Vec<(Place, Trial, Option<Scene>)>,
    steps: Vec<FrictionStep>,
}

/// Runs the whole map in `lab` (at its settings): each solver's part on
/// one of the machine's cores ([`on_both_cores`]: every trial is stopped
/// by a work cap, never the clock, and nothing here is timed), the parts
/// put back in the map's order; then the uniqueness study. The lab's log
/// hears of each stage, its progress of each trial.
pub fn run(spec: &StabilitySpec, lab: &mut Lab) -> Result<Map> {
    let base = &lab.settings.clone();
    let log = lab.logger();
    let log = |line: &str| log(&format!("stability: {line}"));
    let mut map = Map {
        trials: Vec::new(),
        steps: Vec::new(),
        uniqueness: Vec::new(),
    };
    let solvers: Vec<(usize, &'static Entry)> =
        registry::solvers().into_iter().enumerate().collect();
    log(&format!(
        "{} solvers, each on one core: at its defaults and under its stress conditions, the friction coefficient, \
         loads approaching and violating condition (13), the classical scenes",
        solvers.len()
    ));
    let finest = spec.h.max(spec.h_friction).max(spec.h_scenes);
    let need = solvers
        .iter()
        .map(|(_, e)| trial_need(finest, e))
        .fold(0.0, f64::max);
    let parts = on_both_cores(lab, &solvers, need, |&(i, entry), shared| {
        solver_part(spec, base, i, entry, shared)
    })?;
    let mut placed = Vec::new();
    for part in parts {
        placed.extend(part.trials);
        map.steps.extend(part.steps);
    }
    // Stable: within a place, the order each part ran its trials in.
    placed.sort_by_key(|(place, ..)| *place);
    for (_, trial, asked) in placed {
        if let Some(scene) = asked {
            lab.ask(&scene)?;
        }
        map.trials.push(trial);
    }
    log("past the fixed point's limit: solvers of the Coulomb problem from several starts");
    if !spec.uniqueness_values.is_empty() {
        let (measured, rows) = uniqueness::run(
            &Scene::paper_problem_to(1, spec.h_friction)?,
            &spec.uniqueness_values,
            base,
            spec.work_scale,
            lab,
        )?;
        for m in measured {
            let contractions: Vec<Option<f64>> =
                m.friction().iter().map(|f| f.contraction).collect();
            let cx = Context {
                solvable: true,
                trend: trend(&contractions),
                ..Context::default()
            };
            let mut t = m.trial;
            let (class, reason) = classify(&t, &cx);
            t.class = Some(class);
            t.reason = reason;
            map.trials.push(t);
        }
        map.uniqueness = rows;
    }
    Ok(map)
}

/// Measures `trial` against its reference, classifies it in context and
/// files it in `part` at `place`.
fn one(
    shared: &Shared,
    part: &mut Part,
    place: Place,
    trial: TrialSpec,
    cx: Context,
) -> Result<Measured> {
    let reference = shared.reference(&trial)?;
    let m = measure(&trial, reference.as_deref(), Keep::default())?;
    let contractions: Vec<Option<f64>> = m.friction().iter().map(|f| f.contraction).collect();
    let cx = Context {
        trend: trend(&contractions),
        ..cx
    };
    let mut t = m.trial.clone();
    let (class, reason) = classify(&t, &cx);
    t.class = Some(class);
    t.reason = reason;
    let asked = trial.wants_reference().then(|| trial.scene.clone());
    part.trials.push((place, t, asked));
    shared.tick(&trial)?;
    Ok(m)
}

/// One solver's whole part of the map, in the order of the groups.
fn solver_part(
    spec: &StabilitySpec,
    base: &Settings,
    solver: usize,
    entry: &'static Entry,
    shared: &Shared,
) -> Result<Part> {
    let mut part = Part::default();
    let place = |group: u8, within: usize| Place {
        group,
        within,
        solver,
    };
    let cap = work_cap(entry, spec.work_scale);
    let solvable = Context {
        solvable: true,
        ..Context::default()
    };
    let p1 = Scene::paper_problem_to(1, spec.h)?;
    let trial =
        |group: &str| TrialSpec::new(STUDY, group, &p1, entry, Law::Coulomb, base).with_work(cap);
    let default = one(shared, &mut part, place(0, 0), trial(DEFAULT), solvable)?;
    let default_work = Some(default.trial.work).filter(|_| default.trial.certified());
    for v in crate::study::plans::plan(entry).stress {
        let path = format!("{}.{}", entry.name, v.knob);
        for value in if spec.quick { v.quick } else { v.values } {
            let cx = Context {
                default_work,
                ..solvable
            };
            one(
                shared,
                &mut part,
                place(0, 0),
                trial(STRESS).varying(&path, value)?,
                cx,
            )?;
        }
    }
    friction_scan(spec, base, entry, shared, &mut part, place(1, 0))?;
    for (k, &total) in spec.load_totals.iter().enumerate() {
        let scene = lifted_problem(total, spec.h)?;
        let t = TrialSpec::new(STUDY, LOAD, &scene, entry, Law::Coulomb, base).with_work(cap);
        one(shared, &mut part, place(2, k), t, solvable)?;
    }
    for (k, (name, _)) in crate::formats::classical::SCENES.iter().enumerate() {
        let mut scene = crate::formats::classical::scene(name)?;
        scene.set_finest(spec.h_scenes);
        let t = TrialSpec::new(STUDY, SCENES, &scene, entry, Law::Coulomb, base).with_work(cap);
        one(shared, &mut part, place(3, k), t, solvable)?;
    }
    for (k, &total) in spec.violating_totals.iter().enumerate() {
        let scene = lifted_problem(-total, spec.h)?;
        let refusal = scene
            .validate()
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        let t =
            TrialSpec::new(STUDY, REFUSED, &scene, entry, Law::GivenFriction, base).with_work(cap);
        let mut refused = Trial::not_run(&t, Status::NotRun, refusal.clone());
        refused.class = Some(Class::Refused);
        refused.reason = format!("our check of condition (13): {refusal}");
        part.trials.push((place(4, k), refused, None));
        let mut bypass = t.unchecked();
        bypass.group = BYPASSED.into();
        // A load that balances to rounding is refused by the algebraic
        // problem's own check too (its net load is no scale to measure
        // the contact in): recorded as refused, not solved.
        if let Err(e) = Discretization::new_unchecked(&scene, spec.h) {
            let mut refused = Trial::not_run(&bypass, Status::NotRun, e.to_string());
            refused.class = Some(Class::Refused);
            refused.reason = format!("the algebraic problem's check: {e}");
            part.trials.push((place(4, k), refused, None));
            continue;
        }
        one(shared, &mut part, place(4, k), bypass, Context::default())?;
    }
    Ok(part)
}

/// The friction scan of one solver: problems 1-3 for each coefficient,
/// then bisection between the largest certified one and the next.
fn friction_scan(
    spec: &StabilitySpec,
    base: &Settings,
    entry: &'static Entry,
    shared: &Shared,
    part: &mut Part,
    place: Place,
) -> Result<()> {
    let mut settings = base.clone();
    settings
        .set("coulomb.max_iterations", Value::from(200u64))
        .map_err(anyhow::Error::msg)?;
    for n in [1, 2, 3] {
        let mut default_iterations = None;
        let mut attempt = |part: &mut Part, f: f64, group: &str| -> Result<bool> {
            let mut scene = Scene::paper_problem_to(n, spec.h_friction)?;
            scene.friction = f;
            let mut t = TrialSpec::new(STUDY, group, &scene, entry, Law::Coulomb, &settings)
                .with_work(work_cap(entry, spec.work_scale));
            t.setting = Some(Setting::new(FRICTION, &format!("{f}")));
            let cx = Context {
                solvable: true,
                default_friction_iterations: default_iterations,
                ..Context::default()
            };
            let m = one(shared, part, place, t, cx)?;
            if (f - 0.5).abs() < 1e-12 {
                default_iterations = Some(m.trial.friction_iterations.max(1));
            }
            let certified = m.trial.certified();
            part.steps.extend(m.friction().iter().map(|s| FrictionStep {
                scene: scene.name.clone(),
                solver: entry.name.into(),
                friction_coefficient: f,
                iteration: s.iteration,
                change: s.change,
                contraction: s.contraction,
                certified,
            }));
            Ok(certified)
        };
        let (mut last_ok, mut first_bad) = (None, None);
        for &f in &spec.friction_values {
            let ok = attempt(part, f, FRICTION)?;
            if first_bad.is_none() {
                if ok {
                    last_ok = Some(f);
                } else {
                    first_bad = Some(f);
                }
            }
        }
        if let (Some(mut lo), Some(mut hi)) = (last_ok, first_bad) {
            for _ in 0..spec.bisection_steps {
                let mid = 0.5 * (lo + hi);
                if attempt(part, mid, FRICTION_BISECTION)? {
                    lo = mid
                } else {
                    hi = mid
                }
            }
        }
    }
    Ok(())
}
