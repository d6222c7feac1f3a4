//! Work against precision on one scene: each solver at each target
//! accuracy by the benchmark's rule ([`target_settings`]: its accuracy knob
//! and every ε at a safety factor below the target, the certificate at the
//! target), timed, certified, and measured against the earned reference.
//! The study behind Python's `cl.work_precision`; its chart is the
//! certificate's largest violation against seconds, certified points
//! joined and failed ones as crosses; beside it the same against the
//! error bound (an accuracy that needs no reference, issue 51) and the
//! bound against the measured error.

use anyhow::Result;
use contactlab_solvers::Law;
use contactlab_solvers::registry::Entry;

use crate::io::charts::{Chart, Series};
use crate::mechanics::scene::Scene;
use crate::study::benchmark::target_settings;
use crate::study::error_bound::views::{bound_against_error_chart, trial_points};
use crate::study::lab::{Artifact, Lab, Ran, RunLength, Section, Study};
use crate::study::runner::{Keep, Measured};
use crate::study::template;
use crate::study::trial::TrialSpec;

/// The study's name in trial records.
pub const STUDY: &str = "work_precision";

/// `solvers` on `scene` at each of `targets`.
pub struct WorkPrecision {
    pub scene: Scene,
    pub solvers: Vec<&'static Entry>,
    pub targets: Vec<f64>,
    /// Timed runs per trial after the first.
    pub repeats: usize,
}

impl WorkPrecision {
    /// The trials: per solver, per target, the whole Coulomb problem.
    pub fn plan(&self, lab: &Lab) -> Result<Vec<TrialSpec>> {
        let mut out = Vec::new();
        for &e in &self.solvers {
            for &target in &self.targets {
                let mut settings = target_settings(e, &lab.settings, target)?;
                settings.certificate.tolerance = target;
                let mut t = TrialSpec::new(STUDY, e.name, &self.scene, e, Law::Coulomb, &settings)
                    .with_repeats(self.repeats);
                t.setting = Some(crate::study::trial::Setting::new(
                    "target",
                    &format!("{target:e}"),
                ));
                out.push(t);
            }
        }
        Ok(out)
    }
}

/// What a work-precision chart puts on its x axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    /// The certificate's largest violation (every answer has one).
    Violation,
    /// The error bound on ‖v − v*‖_A over √K·U (issue 51): an accuracy
    /// that needs no reference.
    Bound,
}

impl Precision {
    fn of(self, t: &crate::study::trial::Trial) -> Option<f64> {
        match self {
            Precision::Violation => Some(t.residual()),
            Precision::Bound => t.error_bound().map(|b| b.displacement),
        }
    }

    fn label(self) -> &'static str {
        match self {
            Precision::Violation => "largest violation in the certificate (relative)",
            Precision::Bound => "error bound on ‖v − v*‖_A / (√K·U)",
        }
    }
}

/// The chart: per solver, the certificate's largest violation against the
/// fastest of its timed runs.
pub fn chart(title: &str, measured: &[Measured]) -> Chart {
    chart_of(title, measured, Precision::Violation)
}

/// The chart with `precision` on the x axis (answers without it left out).
pub fn chart_of(title: &str, measured: &[Measured], precision: Precision) -> Chart {
    let mut names: Vec<&str> = Vec::new();
    for m in measured {
        if !names.contains(&m.trial.solver.name) {
            names.push(m.trial.solver.name);
        }
    }
    let mut series = Vec::new();
    for name in names {
        // Each point labelled with its target.
        let points = |ok: bool| {
            let mut p: Vec<((f64, f64), String)> = measured
                .iter()
                .filter(|m| m.trial.solver.name == name && m.trial.certified() == ok)
                .filter_map(|m| {
                    Some((
                        (precision.of(&m.trial)?, m.timing.seconds_min),
                        m.trial.knob().1.to_string(),
                    ))
                })
                .filter(|((x, y), _)| *x > 0.0 && x.is_finite() && *y > 0.0)
                .collect();
            p.sort_by(|a, b| a.0.0.total_cmp(&b.0.0));
            p
        };
        series.extend(Series::certified_and_failed_labelled(
            name,
            points(true),
            points(false),
        ));
    }
    Chart::new(title, precision.label(), "seconds", true, true, series)
}

impl Study for WorkPrecision {
    /// Its trials, measured.
    type Findings = Vec<Measured>;

    fn name(&self) -> &'static str {
        STUDY
    }

    fn estimated_seconds(&self, length: RunLength) -> f64 {
        let s = 2.0 * (self.solvers.len() * self.targets.len() * (1 + self.repeats)) as f64;
        if length == RunLength::Quick {
            s / 100.0
        } else {
            s
        }
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<Vec<Measured>>> {
        let specs = self.plan(lab)?;
        let measured = lab.measure(&specs, Keep::default())?;
        let mut artifacts = Artifact::trials(STUDY, &measured)?;
        artifacts.push(Artifact::chart(
            STUDY,
            chart(
                &format!(
                    "Work against precision: {}, h = {}",
                    self.scene.name,
                    self.scene.finest()
                ),
                &measured,
            ),
        ));
        let title = format!("{}, h = {}", self.scene.name, self.scene.finest());
        let bounded = chart_of(
            &format!("Work against the error bound: {title}"),
            &measured,
            Precision::Bound,
        );
        if !bounded.series.is_empty() {
            artifacts.push(Artifact::chart(&format!("{STUDY}_bound"), bounded));
        }
        if let Some(c) = bound_against_error_chart(
            &format!("Error bound against measured error: {title}"),
            &trial_points(measured.iter().map(|m| &m.trial)),
        ) {
            artifacts.push(Artifact::chart(&format!("{STUDY}_bound_vs_error"), c));
        }
        artifacts.push(Artifact::csv("references.csv", &lab.candidates(), &[])?);
        Ok(Ran {
            findings: measured,
            artifacts,
        })
    }

    fn section(&self, measured: &Vec<Measured>, _: &Lab, charts: &[String]) -> Result<Section> {
        let markdown = template::render(
            "work_precision",
            include_str!("templates/work_precision.md"),
            template::facts! {
                scene => self.scene.name,
                h => self.scene.finest().to_string(),
                certified => measured.iter().filter(|m| m.trial.certified()).count(),
                runs => measured.len(),
                charts,
            },
        )?;
        Ok(Section { markdown })
    }
}
