//! The comparison on the paper's problems, as `reproduce` runs it: every
//! solver on each problem against the earned reference, the paper's method
//! at the paper's own settings beside them, the contact-zone profiles with
//! and without friction (the paper's figures), the separation zones, the
//! convergence charts, and problem 1 in plane stress.

use anyhow::{Context, Result};
use contactlab_solvers::Law;
use contactlab_solvers::registry::{self, Role};
use serde::Serialize;

use crate::io::csv::fixed;
use crate::mechanics::contact_zone::{PROFILE_COLUMNS, contact_profile};
use crate::mechanics::material::PlaneModel;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::compare::charts::{
    ProfilePair, convergence_charts, inner_convergence_panels, profile_charts,
};
use crate::study::compare::{STUDY, plan};
use crate::study::cores::measure_alone_on_cores;
use crate::study::error_bound::views::{bound_against_error_chart, trial_points};
use crate::study::lab::{Artifact, Lab, Ran, RunLength, Section, Study};
use crate::study::runner::{Keep, Measured};
use crate::study::trial::{TrialSpec, intervals_text};

/// The group of the paper's method at the paper's settings in compare.csv.
pub const PAPER_SETTINGS: &str = "paper_settings";

/// One problem's separation with one solver.
#[derive(Clone, Debug, Serialize)]
pub struct SeparationRow {
    pub problem: u32,
    pub solver: String,
    #[serde(serialize_with = "fixed")]
    pub friction_coefficient: f64,
    pub status: String,
    pub separated: String,
    #[serde(serialize_with = "fixed")]
    pub separated_fraction: f64,
    /// Where the first separated interval starts (1 without separation).
    #[serde(skip)]
    pub zone_start: f64,
}

/// What the comparison found.
#[derive(Default)]
pub struct PaperFindings {
    /// Per problem: its comparison trials, then the paper's method at the
    /// paper's settings.
    pub measured: Vec<(u32, Vec<Measured>)>,
    pub separation: Vec<SeparationRow>,
    /// The keys of its references (see [`Lab::asked`]).
    pub references: Vec<String>,
    /// Separated fraction of problem 1 in plane stress (the reference's).
    pub plane_stress_fraction: Option<f64>,
}

/// The comparison of every registered solver on the paper's `problems` at
/// mesh `h`, each trial timed `1 + repeats` times.
pub struct PaperCompare {
    pub h: MeshSize,
    pub problems: Vec<u32>,
    pub repeats: usize,
}

impl Study for PaperCompare {
    type Findings = PaperFindings;

    fn name(&self) -> &'static str {
        STUDY
    }

    fn estimated_seconds(&self, length: RunLength) -> f64 {
        match length {
            RunLength::Quick => 1.2,
            // The main job's: 148 s measured on 7ffa5e6.
            RunLength::Standard => 150.0,
            RunLength::Long => 300.0,
        }
    }

    fn section(&self, out: &PaperFindings, lab: &Lab, charts: &[String]) -> Result<Section> {
        Ok(Section {
            markdown: crate::study::compare::section::section(
                self.h,
                &self.problems,
                out,
                &lab.references,
                lab.settings.certificate.tolerance,
                charts,
            )?,
        })
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<PaperFindings>> {
        let mut findings = PaperFindings::default();
        let findings = &mut findings;
        let solvers = registry::solvers();
        let paper_method =
            registry::with_role(Role::PapersMethod).context("no paper's method registered")?;
        let mut paper = Settings::paper();
        paper.certificate = lab.settings.certificate;
        let mut artifacts = Vec::new();
        for &problem in &self.problems {
            lab.log(&format!(
                "problem {problem}: every solver at h = {}",
                self.h
            ));
            let sc = Scene::paper_problem_to(problem, self.h)?;
            let keep = Keep {
                history: true,
                solution: true,
            };
            let mut measured =
                lab.measure(&plan(&sc, &lab.settings, &solvers, self.repeats), keep)?;
            let at_paper = TrialSpec::new(
                PAPER_SETTINGS,
                PAPER_SETTINGS,
                &sc,
                paper_method,
                Law::Coulomb,
                &paper,
            )
            .with_repeats(self.repeats);
            measured.extend(lab.measure(&[at_paper], Keep::default())?);
            artifacts.extend(self.profiles(lab, problem, &sc, &measured, findings)?);
            let ours: Vec<Measured> = measured
                .iter()
                .filter(|m| m.trial.study == STUDY)
                .map(Measured::without_finest)
                .collect();
            let h = self.h.to_string();
            artifacts.extend(Artifact::charts(convergence_charts(problem, &h, &ours)));
            if let Some(c) = bound_against_error_chart(
                &format!("Error bound against measured error, problem {problem}, h = {h}"),
                &trial_points(ours.iter().map(|m| &m.trial)),
            ) {
                artifacts.push(Artifact::chart(&format!("bound_vs_error_p{problem}"), c));
            }
            artifacts.push(Artifact::panels(
                &format!("convergence_inner_p{problem}"),
                inner_convergence_panels(problem, &h, &ours),
            ));
            findings.measured.push((problem, measured));
        }
        let all: Vec<Measured> = findings
            .measured
            .iter()
            .flat_map(|(_, m)| m.iter().map(Measured::without_finest))
            .collect();
        artifacts.extend(Artifact::trials(STUDY, &all)?);
        artifacts.push(Artifact::csv("references.csv", &lab.candidates(), &[])?);
        for (name, tex) in super::latex::tables(&all, "contactlab reproduce")? {
            artifacts.push(Artifact::text(&name, &tex));
        }
        artifacts.push(Artifact::csv("separation.csv", &findings.separation, &[])?);
        let mut stress = Scene::paper_problem_to(1, self.h)?;
        stress.material.plane = PlaneModel::Stress;
        stress.name = "problem 1, plane stress".into();
        let settings = lab.settings.clone();
        findings.plane_stress_fraction = lab
            .reference(&stress, &settings)?
            .map(|r| r.coulomb.separation().fraction);
        findings.references = lab.asked().to_vec();
        Ok(Ran {
            findings: std::mem::take(findings),
            artifacts,
        })
    }
}

impl PaperCompare {
    /// The profiles of `problem` with friction (the comparison's trials)
    /// and without (a frictionless solve per solver), their separation
    /// rows, and the profile charts of the oracle and the paper's method.
    fn profiles(
        &self,
        lab: &mut Lab,
        problem: u32,
        sc: &Scene,
        measured: &[Measured],
        findings: &mut PaperFindings,
    ) -> Result<Vec<Artifact>> {
        let solvers = registry::solvers();
        let mut frictionless = sc.clone();
        frictionless.friction = 0.0;
        frictionless.name = format!("{}, frictionless", sc.name);
        let specs: Vec<TrialSpec> = solvers
            .iter()
            .map(|&e| {
                TrialSpec::new(
                    "profiles",
                    "frictionless",
                    &frictionless,
                    e,
                    Law::Coulomb,
                    &lab.settings,
                )
            })
            .collect();
        let keep = Keep {
            history: false,
            solution: true,
        };
        // Profiles, not times: on both cores.
        let without = measure_alone_on_cores(lab, &specs, keep)?;
        let mut artifacts = Vec::new();
        let mut profiles = Vec::new();
        for (&e, w) in solvers.iter().zip(&without) {
            let with = measured
                .iter()
                .find(|m| {
                    m.trial.solver.name == e.name
                        && m.trial.law == Law::Coulomb
                        && m.trial.study == STUDY
                })
                .context("a Coulomb trial per solver")?;
            let profile = |m: &Measured| {
                m.solution()
                    .map(|(d, s, g)| contact_profile(d, s, g, m.trial.status))
                    .unwrap_or_default()
            };
            let (pw, pwo) = (profile(with), profile(w));
            for (kind, rows) in [("friction", &pw), ("frictionless", &pwo)] {
                let path = format!("profiles/p{problem}_{}_{kind}.csv", e.name);
                artifacts.push(Artifact::csv(&path, rows, &PROFILE_COLUMNS)?);
            }
            for (m, f) in [(with, sc.friction), (w, 0.0)] {
                findings.separation.push(SeparationRow {
                    problem,
                    solver: e.name.into(),
                    friction_coefficient: f,
                    status: m.trial.status.to_string(),
                    separated: intervals_text(&m.trial.separated),
                    separated_fraction: m.trial.separated_fraction,
                    zone_start: m.trial.separated.first().map_or(1.0, |iv| iv[0]),
                });
            }
            profiles.push((e.name, pw, pwo));
        }
        let zoom_from = findings
            .separation
            .iter()
            .filter(|r| r.problem == problem)
            .map(|r| r.zone_start)
            .fold(1.0f64, f64::min)
            - 0.1;
        let pair = |role: Role| {
            let name = registry::with_role(role)?.name;
            profiles
                .iter()
                .find(|(s, ..)| *s == name)
                .map(|(s, w, wo)| ProfilePair {
                    solver: s,
                    friction: w,
                    frictionless: wo,
                })
        };
        if let Some(oracle) = pair(Role::Oracle) {
            artifacts.extend(Artifact::charts(profile_charts(
                problem,
                &self.h.to_string(),
                &oracle,
                pair(Role::PapersMethod).as_ref(),
                zoom_from.clamp(0.0, 0.9),
            )));
        }
        Ok(artifacts)
    }
}
