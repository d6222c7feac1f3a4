//! The comparison: every registered solver on one scene, on the
//! given-friction subproblem at the reference's g and on the whole Coulomb
//! problem, each measured against the earned reference.

use anyhow::Result;
use contactlab_solvers::Law;
use contactlab_solvers::registry::Entry;
use serde::Serialize;

use crate::certificate::BoundKind;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::lab::{Artifact, Lab, Ran, RunLength, Section, Study};
use crate::study::runner::{Keep, Measured};
use crate::study::template;
use crate::study::trial::{Trial, TrialSpec, intervals_text};

/// The study's name in trial records.
pub const STUDY: &str = "compare";

pub mod charts;
pub mod latex;
pub mod paper;
pub mod section;

/// The comparison of `solvers` on one scene, as a study: compare.csv,
/// compare_timing.csv, compare_<law>.tex (one LaTeX table per law) and
/// references.csv.
pub struct Compare {
    pub scene: Scene,
    pub solvers: Vec<&'static Entry>,
    pub repeats: usize,
    /// The reference the user named (None: the earned one, among the exact
    /// solvers at their tightest settings).
    pub reference: Option<&'static Entry>,
}

impl Study for Compare {
    /// Its trials, measured.
    type Findings = Vec<Measured>;

    fn name(&self) -> &'static str {
        STUDY
    }

    fn estimated_seconds(&self, length: RunLength) -> f64 {
        let per_solver = 5.0 * (1 + self.repeats) as f64;
        let s = per_solver * self.solvers.len() as f64;
        if length == RunLength::Quick {
            s / 100.0
        } else {
            s
        }
    }

    fn section(&self, measured: &Vec<Measured>, _: &Lab, _: &[String]) -> Result<Section> {
        let table = markdown_of(measured)?;
        Ok(Section {
            markdown: template::render(
                "compare",
                include_str!("../templates/compare.md"),
                template::facts! { scene => self.scene.name, table },
            )?,
        })
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<Vec<Measured>>> {
        if let Some(e) = self.reference {
            lab.name_reference(e);
        }
        let specs = plan(&self.scene, &lab.settings, &self.solvers, self.repeats);
        let measured = lab.measure(&specs, Keep::default())?;
        let mut artifacts = Artifact::trials(STUDY, &measured)?;
        for (name, tex) in latex::tables(&measured, "contactlab compare")? {
            artifacts.push(Artifact::text(&name, &tex));
        }
        artifacts.push(Artifact::csv("references.csv", &lab.candidates(), &[])?);
        Ok(Ran {
            findings: measured,
            artifacts,
        })
    }
}

/// The Markdown table of measured comparison trials.
pub fn markdown_of(measured: &[Measured]) -> Result<String> {
    let trials: Vec<Trial> = measured.iter().map(|m| m.trial.clone()).collect();
    let seconds: Vec<f64> = measured.iter().map(|m| m.timing.seconds_min).collect();
    markdown(&trials, &seconds)
}

/// The trials: per solver, the subproblem (if it solves it) and the Coulomb
/// problem, each run `1 + repeats` times for its time.
pub fn plan(
    scene: &Scene,
    settings: &Settings,
    solvers: &[&'static Entry],
    repeats: usize,
) -> Vec<TrialSpec> {
    let mut out = Vec::new();
    for &entry in solvers {
        for law in [Law::GivenFriction, Law::Coulomb] {
            if law == Law::GivenFriction && !entry.solves(Law::GivenFriction) {
                continue;
            }
            out.push(
                TrialSpec::new(STUDY, law.as_str(), scene, entry, law, settings)
                    .with_repeats(repeats),
            );
        }
    }
    out
}

/// A trial's iterations: `[friction iterations:] outer [/ inner]`.
pub fn iterations(r: &Trial) -> String {
    match (r.friction_iterations, r.inner_iterations) {
        (0, 0) => format!("{}", r.outer_iterations),
        (0, i) => format!("{} / {i}", r.outer_iterations),
        (f, 0) => format!("{f}: {}", r.outer_iterations),
        (f, i) => format!("{f}: {} / {i}", r.outer_iterations),
    }
}

/// A row of the comparison table: a trial's numbers, none where not
/// measured.
#[derive(Serialize)]
struct TableRow<'a> {
    scene: &'a str,
    h: String,
    law: Law,
    solver: &'a str,
    study: &'a str,
    status: String,
    claim: String,
    du: Option<f64>,
    dp: Option<f64>,
    dq: Option<f64>,
    energy: Option<f64>,
    /// The error bound on ‖v − v*‖_A over √K·U, and whether it is at the
    /// answer's own g = 𝓕p (a Coulomb answer's, the fixed point's part
    /// not included).
    bound: Option<f64>,
    bound_at_own_g: bool,
    /// The separation intervals (empty: none), and Γ_K's fraction in %.
    separated: String,
    separated_percent: f64,
    certificate: f64,
    failing: Vec<&'static str>,
    iterations: String,
    seconds: f64,
}

/// A reference named in the table: its solver and the law it solved.
#[derive(PartialEq, Serialize)]
struct ReferenceUsed {
    solver: &'static str,
    law: Law,
}

/// A Markdown table of comparison trials, with its key
/// (`templates/compare_table.md`).
pub fn markdown(trials: &[Trial], seconds: &[f64]) -> Result<String> {
    let rows: Vec<TableRow> = trials
        .iter()
        .zip(seconds)
        .map(|(r, &seconds)| TableRow {
            scene: &r.scene,
            h: r.h.to_string(),
            law: r.law,
            solver: r.solver.name,
            study: r.study,
            status: r.status.to_string(),
            claim: r.solver_status.to_string(),
            du: r.displacement_error(),
            dp: r.pressure_error(),
            dq: r.agreement.map(|a| a.traction_max),
            energy: r.agreement.map(|a| a.energy),
            bound: r.error_bound().map(|b| b.displacement),
            bound_at_own_g: r
                .error_bound()
                .is_some_and(|b| b.kind == BoundKind::AtOwnBound),
            separated: intervals_text(&r.separated).replace(';', ", "),
            separated_percent: 100.0 * r.separated_fraction,
            certificate: r.residual(),
            failing: r.failing().iter().map(|c| c.as_str()).collect(),
            iterations: iterations(r),
            seconds,
        })
        .collect();
    let mut references: Vec<ReferenceUsed> = Vec::new();
    for r in trials {
        let Some(solver) = r.reference else { continue };
        let used = ReferenceUsed { solver, law: r.law };
        if !references.contains(&used) {
            references.push(used);
        }
    }
    let tolerance = trials
        .first()
        .map(|r| r.tolerance)
        .unwrap_or(crate::certificate::DEFAULT_TOLERANCE);
    template::render(
        "compare_table",
        include_str!("../templates/compare_table.md"),
        template::facts! { rows, study => STUDY, references, tolerance },
    )
}
