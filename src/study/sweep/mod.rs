//! Parameter sweeps, one factor at a time around the defaults:
//! - each solver's variations (its registry entry lists them; the paper's
//!   method has r, ε and the smoothing of |s|) and, for solvers that
//!   warm-start, the continuation schedule, on the whole Coulomb problem;
//! - every solver through its accuracy knob on the given-friction
//!   subproblem at the reference's g: the work-precision diagram, where no
//!   outer loop blurs the comparison;
//! - every solver on the whole Coulomb problem: a solver of the Coulomb law
//!   through its accuracy knob, a solver run inside the fixed point through
//!   ε (every loop's, as `--epsilon` sets it): the second diagram, which
//!   puts the direct solvers beside the fixed points.
//!
//! Every planned trial gives a row, certified or not: the status says which.

pub mod charts;
pub mod section;

use anyhow::Result;
use contactlab_solvers::Law;
use contactlab_solvers::registry::{self, Entry};
use serde::Serialize;

use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::lab::{Artifact, Lab, Ran, RunLength, Section, Study};
use crate::study::plans::{self, Fine};
use crate::study::runner::Keep;
use crate::study::sweep::charts::sweep_charts;
use crate::study::template;
use crate::study::trial::TrialSpec;

/// The study's name in trial records.
pub const STUDY: &str = "sweep";
/// The group of work-precision trials.
pub const WORK_PRECISION: &str = "work_precision";
/// The group of work-precision trials on the Coulomb problem.
pub const WORK_PRECISION_COULOMB: &str = "work_precision_coulomb";
/// The ε values (relative) of fixed points in the Coulomb diagram.
pub const FIXED_POINT_EPSILONS: &[f64] = &[1e-3, 1e-5, 1e-7, 1e-9];
/// The group (and path) of the continuation schedule.
pub const SCHEDULE: &str = "schedule";

/// What to sweep.
#[derive(Clone)]
pub struct SweepSpec {
    /// Scenes (their levels are replaced by 1/8 ... each mesh).
    pub scenes: Vec<Scene>,
    pub meshes: Vec<MeshSize>,
    /// Fine meshes on which each solver whose plan says how ([`Fine`]) is
    /// swept with the settings that make it fast there, its trials measured
    /// by their certificates alone (no reference: at 1/256 earning one took
    /// 7 of a sweep's 8 minutes, the oracle's fixed point at its time cap).
    pub fine_meshes: Vec<MeshSize>,
    /// Solvers whose variations and accuracy knobs are swept.
    pub solvers: Vec<&'static Entry>,
    /// One-factor variations of the Coulomb problem.
    pub variations: bool,
    /// The accuracy knob on the subproblem (work-precision).
    pub work_precision: bool,
    /// The registry's short value lists, and every other accuracy value.
    pub quick: bool,
    /// Extra timed runs of each work-precision trial.
    pub repeats: usize,
    /// Multiplies each solver's study work cap.
    pub work_scale: f64,
}

impl Default for SweepSpec {
    fn default() -> Self {
        Self {
            scenes: vec![Scene::paper_problem(1).expect("built in")],
            meshes: vec![MeshSize::from_level(5).expect("in range")],
            fine_meshes: Vec::new(),
            solvers: registry::solvers(),
            variations: true,
            work_precision: true,
            quick: false,
            repeats: 2,
            work_scale: 1.0,
        }
    }
}

/// The work cap of `entry` in a study scaled by `scale`.
pub fn work_cap(entry: &Entry, scale: f64) -> Option<usize> {
    Some(((plans::plan(entry).work as f64) * scale).ceil().max(1.0) as usize)
}

/// Expands a spec into trials.
pub fn plan(spec: &SweepSpec, base: &Settings) -> Result<Vec<TrialSpec>> {
    let mut out = Vec::new();
    for scene in &spec.scenes {
        for &h in &spec.meshes {
            let mut scene = scene.clone();
            scene.set_finest(h);
            for &entry in &spec.solvers {
                let cap = work_cap(entry, spec.work_scale);
                let trial = |group: String, law| {
                    TrialSpec::new(STUDY, group, &scene, entry, law, base).with_work(cap)
                };
                let study = plans::plan(entry);
                if spec.variations {
                    for v in study.sweeps {
                        let values = if spec.quick { v.quick } else { v.values };
                        let path = format!("{}.{}", entry.name, v.knob);
                        for value in values {
                            out.push(trial(path.clone(), Law::Coulomb).varying(&path, value)?);
                        }
                    }
                    if entry.warm_starts {
                        for value in ["revisit", "finest-only"] {
                            out.push(
                                trial(SCHEDULE.into(), Law::Coulomb).varying(SCHEDULE, value)?,
                            );
                        }
                    }
                }
                let stride = if spec.quick { 2 } else { 1 };
                let path = format!("{}.{}", entry.name, entry.accuracy.knob);
                if spec.work_precision && entry.solves(Law::GivenFriction) {
                    for value in study.accuracy_values(entry).iter().step_by(stride) {
                        out.push(
                            trial(WORK_PRECISION.into(), Law::GivenFriction)
                                .varying(&path, &format!("{value:e}"))?
                                .with_repeats(spec.repeats),
                        );
                    }
                }
                if spec.work_precision {
                    let coulomb = || trial(WORK_PRECISION_COULOMB.into(), Law::Coulomb);
                    if entry.solves(Law::Coulomb) {
                        for value in study.accuracy_values(entry).iter().step_by(stride) {
                            out.push(
                                coulomb()
                                    .varying(&path, &format!("{value:e}"))?
                                    .with_repeats(spec.repeats),
                            );
                        }
                    } else {
                        for &value in FIXED_POINT_EPSILONS.iter().step_by(stride) {
                            out.push(coulomb().varying_epsilon(value)?.with_repeats(spec.repeats));
                        }
                    }
                }
            }
        }
    }
    out.extend(plan_fine(spec, base)?);
    Ok(out)
}

/// The group of a variation on a fine mesh: the knob's path and the
/// settings that make the solver fast there, `relaxation.r (inner =
/// multigrid)`.
pub fn fine_group(path: &str, fine: &Fine) -> String {
    let settings: Vec<String> = fine
        .settings
        .iter()
        .map(|(k, v)| format!("{k} = {v}"))
        .collect();
    format!("{path} ({})", settings.join(", "))
}

/// The fine meshes' trials ([`SweepSpec::fine_meshes`]).
fn plan_fine(spec: &SweepSpec, base: &Settings) -> Result<Vec<TrialSpec>> {
    let mut out = Vec::new();
    for scene in &spec.scenes {
        for &h in &spec.fine_meshes {
            let mut scene = scene.clone();
            scene.set_finest(h);
            for &entry in &spec.solvers {
                let Some(fine) = plans::plan(entry).fine else {
                    continue;
                };
                let mut settings = base.clone();
                for (knob, value) in fine.settings {
                    settings
                        .set_text(&format!("{}.{knob}", entry.name), value)
                        .map_err(anyhow::Error::msg)?;
                }
                for v in fine.sweeps {
                    let path = format!("{}.{}", entry.name, v.knob);
                    let group = fine_group(&path, &fine);
                    for value in if spec.quick { v.quick } else { v.values } {
                        out.push(
                            TrialSpec::new(
                                STUDY,
                                group.clone(),
                                &scene,
                                entry,
                                Law::Coulomb,
                                &settings,
                            )
                            .with_work(work_cap(entry, spec.work_scale))
                            .varying(&path, value)?
                            .without_reference(),
                        );
                    }
                }
            }
        }
    }
    Ok(out)
}

/// The sweep as a study: sweep.csv, sweep_timing.csv, its references file
/// and the charts.
pub struct Sweep {
    pub spec: SweepSpec,
    /// Trials planned apart (`--vary`).
    pub extra: Vec<TrialSpec>,
    /// The file of its references' candidates (`references.csv` alone,
    /// `sweep_references.csv` in a results folder).
    pub references_file: &'static str,
}

impl Study for Sweep {
    /// Its trials, measured.
    type Findings = Vec<crate::study::runner::Measured>;

    fn name(&self) -> &'static str {
        STUDY
    }

    fn estimated_seconds(&self, length: RunLength) -> f64 {
        match length {
            RunLength::Quick => 1.05,
            RunLength::Standard => 115.0,
            RunLength::Long => 205.0,
        }
    }

    fn section(
        &self,
        measured: &Vec<crate::study::runner::Measured>,
        _: &Lab,
        charts: &[String],
    ) -> Result<Section> {
        let list = |meshes: &[MeshSize]| meshes.iter().map(|h| h.to_string()).collect::<Vec<_>>();
        let named = |prefix: &str| -> Vec<&String> {
            charts.iter().filter(|c| c.starts_with(prefix)).collect()
        };
        let markdown = template::render(
            "sweep",
            include_str!("../templates/sweep.md"),
            template::facts! {
                scene => self.spec.scenes.first().map(|s| s.name.clone()).unwrap_or_default(),
                meshes => list(&self.spec.meshes),
                fine_meshes => list(&self.spec.fine_meshes),
                work_precision_charts => named("work_precision"),
                work_precision => section::work_precision(measured),
                variations => section::variations(measured),
                sweep_charts => named("sweep_"),
            },
        )?;
        Ok(Section { markdown })
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<Vec<crate::study::runner::Measured>>> {
        let list = |meshes: &[MeshSize]| {
            meshes
                .iter()
                .map(|h| h.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        };
        lab.log(&format!(
            "sweep at h = {}{}",
            list(&self.spec.meshes),
            if self.spec.fine_meshes.is_empty() {
                String::new()
            } else {
                format!("; tuned for speed at h = {}", list(&self.spec.fine_meshes))
            }
        ));
        let mut specs = plan(&self.spec, &lab.settings)?;
        specs.extend(self.extra.iter().cloned());
        let measured = lab.measure(&specs, Keep::default())?;
        let mut artifacts = Artifact::trials(STUDY, &measured)?;
        artifacts.push(Artifact::csv(self.references_file, &lab.candidates(), &[])?);
        artifacts.push(Artifact::text(
            "sweep_summary.md",
            &summary_markdown(&measured)?,
        ));
        let pairs: Vec<_> = measured.iter().map(|m| (&m.trial, &m.timing)).collect();
        artifacts.extend(Artifact::charts(sweep_charts(&pairs)));
        Ok(Ran {
            findings: measured,
            artifacts,
        })
    }
}

/// A row of the sweep's summary table.
#[derive(Serialize)]
struct SummaryRow<'a> {
    group: &'a str,
    solver: &'static str,
    scene: &'a str,
    h: String,
    law: &'static str,
    setting: String,
    status: String,
    certificate: f64,
    friction: usize,
    outer: usize,
    inner: usize,
    seconds: f64,
}

/// The sweep as a readable table (`templates/sweep_summary.md`): one row
/// per trial with the setting it varies, its certified status, the
/// certificate, its work and its time.
pub fn summary_markdown(measured: &[crate::study::runner::Measured]) -> Result<String> {
    let rows: Vec<SummaryRow> = measured
        .iter()
        .map(|m| {
            let r = &m.trial;
            SummaryRow {
                group: &r.group,
                solver: r.solver.name,
                scene: &r.scene,
                h: r.h.to_string(),
                law: r.law.as_str(),
                setting: r.setting.as_ref().map_or("defaults".to_string(), |s| {
                    format!("{} = {}", s.path, s.value)
                }),
                status: r.status.to_string(),
                certificate: r.residual(),
                friction: r.friction_iterations,
                outer: r.outer_iterations,
                inner: r.inner_iterations,
                seconds: m.timing.seconds_min,
            }
        })
        .collect();
    template::render(
        "sweep_summary",
        include_str!("../templates/sweep_summary.md"),
        template::facts! { rows },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a fine mesh the paper's method is swept in its fast form (inner
    /// minimization by multigrid) over r and ε, and its trials ask for no
    /// reference; nothing else is planned there.
    #[test]
    fn fine_meshes_sweep_the_fast_form_without_a_reference() {
        let fine = MeshSize::from_level(5).unwrap();
        let spec = SweepSpec {
            meshes: vec![MeshSize::from_level(3).unwrap()],
            fine_meshes: vec![fine],
            variations: false,
            work_precision: false,
            quick: true,
            ..SweepSpec::default()
        };
        let trials = plan(&spec, &Settings::default()).unwrap();
        let groups: Vec<&str> = trials.iter().map(|t| t.group.as_str()).collect();
        assert_eq!(
            groups,
            [
                "relaxation.r (inner = multigrid)",
                "relaxation.r (inner = multigrid)",
                "relaxation.epsilon (inner = multigrid)",
                "relaxation.epsilon (inner = multigrid)",
            ]
        );
        for t in &trials {
            assert_eq!(t.scene.finest(), fine);
            assert_eq!(t.solver.name, "relaxation");
            assert_eq!(
                t.settings.get("relaxation.inner"),
                Some(serde_json::Value::from("multigrid"))
            );
            assert!(!t.wants_reference(), "{}", t.group);
        }
        // Without fine meshes, none of them.
        let coarse = SweepSpec {
            fine_meshes: Vec::new(),
            ..spec
        };
        assert!(plan(&coarse, &Settings::default()).unwrap().is_empty());
    }
}
