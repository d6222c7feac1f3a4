//! The comparison: every registered solver on one scene, on the
//! given-friction subproblem at the reference's g and on the whole Coulomb
//! problem, each measured against the earned reference.

use anyhow::Result;
use contactlab_solvers::Law;
use contactlab_solvers::registry::Entry;

use crate::certificate::BoundKind;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::lab::{Artifact, Lab, Ran, RunLength, Section, Study};
use crate::study::runner::{Keep, Measured};
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
        Ok(Section {
            markdown: format!(
                "## Every solver against the reference ({})\n\n{}",
                self.scene.name,
                markdown_of(measured)
            ),
        })
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<Vec<Measured>>> {
        if let Some(e) = self.reference {
            lab.name_reference(e);
        }
        let specs = plan(&self.scene, &lab.settings, &self.solvers, self.repeats);
        let measured = lab.measure(&specs, Keep::default())?;
        let mut artifacts = Artifact::trials(STUDY, &measured)?;
        for (name, tex) in latex::tables(&measured, "contactlab compare") {
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
pub fn markdown_of(measured: &[Measured]) -> String {
    let trials: Vec<Trial> = measured.iter().map(|m| m.trial.clone()).collect();
    let seconds: Vec<f64> = measured.iter().map(|m| m.timing.seconds_min).collect();
    markdown(&trials, &seconds)
}

/// The error bound's cell: its value, † when at the answer's own g.
fn bound_cell(t: &Trial) -> String {
    match t.error_bound() {
        Some(b) if b.kind == BoundKind::AtOwnBound => format!("{:.1e}†", b.displacement),
        Some(b) => format!("{:.1e}", b.displacement),
        None => "–".into(),
    }
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

/// A Markdown table of comparison trials.
pub fn markdown(trials: &[Trial], seconds: &[f64]) -> String {
    let mut out = String::from(
        "| problem | h | law | solver | status | claim | Δu | Δp | Δq | ‖Δv‖_A | error bound | separated | certificate | iterations | time (s) |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let e = |x: Option<f64>| x.map(|v| format!("{v:.1e}")).unwrap_or_else(|| "–".into());
    for (r, t) in trials.iter().zip(seconds) {
        let sep = if r.separated.is_empty() {
            "none".to_string()
        } else {
            intervals_text(&r.separated).replace(';', ", ")
        };
        let failing = r.failing();
        let certificate = if failing.is_empty() {
            format!("{:.1e}", r.residual())
        } else {
            let names: Vec<&str> = failing.iter().map(|c| c.as_str()).collect();
            format!("**{:.1e}** ({})", r.residual(), names.join(", "))
        };
        out += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} ({:.1}%) | {} | {} | {:.3} |\n",
            r.scene,
            r.h,
            r.law.as_str(),
            if r.study == STUDY {
                r.solver.name.to_string()
            } else {
                format!("{} ({})", r.solver.name, r.study.replace('_', " "))
            },
            r.status,
            r.solver_status,
            e(r.displacement_error()),
            e(r.pressure_error()),
            e(r.agreement.map(|a| a.traction_max)),
            e(r.agreement.map(|a| a.energy)),
            bound_cell(r),
            sep,
            100.0 * r.separated_fraction,
            certificate,
            iterations(r),
            t
        );
    }
    let reference: Vec<String> = {
        let mut v: Vec<String> = Vec::new();
        for (name, r) in trials.iter().filter_map(|r| Some((r.reference?, r))) {
            let s = format!("`{name}` ({})", r.law.as_str());
            if !v.contains(&s) {
                v.push(s);
            }
        }
        v
    };
    let tol = trials
        .first()
        .map(|r| r.tolerance)
        .unwrap_or(crate::certificate::DEFAULT_TOLERANCE);
    out + &format!(
        "\nStatus: certified (a claim of convergence that fails the certificate is `inaccurate`); claim: the solver's own. \
         Δ: max difference from the reference, relative to its largest value; ‖Δv‖_A: the difference in the energy seminorm over √K·U; \
         error bound: the certificate's bound on ‖v − v*‖_A over √K·U (issue 51; † for a Coulomb answer: at its own g = 𝓕p, the fixed point's part not included; – where not computed); the reference: {} (unless named \
         with --reference, the most accurate certified answer among the exact solvers at their tightest settings). Certificate: the largest violation of any condition \
         of the law, in the problem's scales (tolerance {tol:e}; failing conditions named). Iterations: [friction \
         iterations:] outer [/ inner]. Time: minimum over the runs.\n",
        if reference.is_empty() {
            "none could be earned".to_string()
        } else {
            reference.join(", ")
        }
    )
}
