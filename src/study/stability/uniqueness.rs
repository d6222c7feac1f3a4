//! Past the friction coefficient where the successive approximations stop
//! contracting: does a solver of the Coulomb problem itself converge there,
//! and to one solution from every start? For each coefficient, every solver
//! whose registry entry solves the Coulomb law and lists other starting
//! points runs from its default start and from each of them (with its
//! diagnostics on, e.g. the condition number of its final Newton matrix);
//! the fixed point runs beside it, around the given-friction solver that
//! earned the scene's given-friction reference.
//! The answers are compared pairwise: one solution, or several.

use anyhow::Result;
use contactlab_solvers::Law;
use contactlab_solvers::registry::{self, Entry};
use serde::Serialize;

use crate::io::csv::{fixed, fixed_opt};
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::agreement::agreement;
use crate::study::lab::Lab;
use crate::study::plans::plan;
use crate::study::runner::{Keep, Measured, measure};
use crate::study::stability::STUDY;
use crate::study::sweep::work_cap;
use crate::study::trial::{Setting, TrialSpec};

/// One friction coefficient's finding for one direct solver.
#[derive(Clone, Debug, Serialize)]
pub struct UniquenessRow {
    pub scene: String,
    pub solver: String,
    #[serde(serialize_with = "fixed")]
    pub friction_coefficient: f64,
    /// Starts tried and answers certified.
    pub starts: usize,
    pub certified: usize,
    /// The largest pressure difference between two certified answers,
    /// relative to the largest pressure (0: one solution).
    #[serde(serialize_with = "fixed_opt")]
    pub spread: Option<f64>,
    /// The range of the condition numbers its diagnostics report.
    #[serde(serialize_with = "fixed_opt")]
    pub condition_min: Option<f64>,
    #[serde(serialize_with = "fixed_opt")]
    pub condition_max: Option<f64>,
    /// The fixed point beside it: its inner solver, certified status,
    /// outcome, last contraction factor and distance from the first
    /// certified direct answer.
    pub fixed_point_solver: String,
    pub fixed_point_status: String,
    pub fixed_point_outcome: String,
    #[serde(serialize_with = "fixed_opt")]
    pub fixed_point_contraction: Option<f64>,
    #[serde(serialize_with = "fixed_opt")]
    pub fixed_point_difference: Option<f64>,
}

fn diagnostic(m: &Measured, name: &str) -> Option<f64> {
    m.trial
        .diagnostics
        .iter()
        .find(|(k, _)| *k == name)
        .map(|(_, v)| *v)
}

/// Runs the study on `scene` for each coefficient; returns the trials (to be
/// classified with the map's) and one row per coefficient and solver.
pub fn run(
    scene: &Scene,
    coefficients: &[f64],
    settings: &Settings,
    work_scale: f64,
    lab: &mut Lab,
) -> Result<(Vec<Measured>, Vec<UniquenessRow>)> {
    let tracker = lab.tracker();
    let direct: Vec<&'static Entry> = registry::solvers()
        .into_iter()
        .filter(|e| e.solves(Law::Coulomb) && !plan(e).restarts.is_empty())
        .collect();
    let keep = Keep {
        history: false,
        solution: true,
    };
    let mut measured = Vec::new();
    let mut rows = Vec::new();
    for &f in coefficients {
        let mut sc = scene.clone();
        sc.friction = f;
        // The fixed point around the given-friction solver that earned this
        // scene's given-friction reference (the most accurate one), else
        // the first exact one.
        let earned = lab
            .reference(&sc, settings)?
            .and_then(|r| r.given_friction.as_ref())
            .and_then(|g| registry::by_name(g.solver))
            .filter(|e| !e.solves(Law::Coulomb));
        let fixed_point = earned.or_else(|| {
            registry::solvers().into_iter().find(|e| {
                e.accuracy.exact && !e.solves(Law::Coulomb) && e.solves(Law::GivenFriction)
            })
        });
        let fp = match fixed_point {
            Some(e) => {
                let mut t = TrialSpec::new(STUDY, "uniqueness", &sc, e, Law::Coulomb, settings)
                    .with_work(work_cap(e, work_scale));
                t.setting = Some(Setting::new("friction", &format!("{f}")));
                let reference = lab.reference(&sc, settings)?;
                let m = measure(&t, reference, keep)?;
                crate::study::lab::ticked(tracker, &t)?;
                Some(m)
            }
            None => None,
        };
        for &e in &direct {
            let mut answers: Vec<Measured> = Vec::new();
            let mut starts: Vec<Vec<(&str, &str)>> = vec![Vec::new()];
            starts.extend(plan(e).restarts.iter().map(|r| r.to_vec()));
            for (k, start) in starts.iter().enumerate() {
                let mut t = TrialSpec::new(STUDY, "uniqueness", &sc, e, Law::Coulomb, settings)
                    .with_work(work_cap(e, work_scale));
                for (knob, value) in start.iter().chain(plan(e).diagnose) {
                    t.settings
                        .set_text(&format!("{}.{knob}", e.name), value)
                        .map_err(anyhow::Error::msg)?;
                }
                let label = if start.is_empty() {
                    "default".to_string()
                } else {
                    start
                        .iter()
                        .map(|(k, v)| format!("{k}={v}"))
                        .collect::<Vec<_>>()
                        .join(",")
                };
                t.setting = Some(Setting::new(
                    &format!("friction (start {k}: {label})"),
                    &format!("{f}"),
                ));
                let reference = lab.reference(&sc, settings)?;
                let m = measure(&t, reference, keep)?;
                crate::study::lab::ticked(tracker, &t)?;
                answers.push(m);
            }
            let good: Vec<&Measured> = answers.iter().filter(|m| m.trial.certified()).collect();
            let mut spread: Option<f64> = None;
            for (i, a) in good.iter().enumerate() {
                for b in &good[i + 1..] {
                    if let (Some((d, sa, _)), Some((_, sb, g))) = (a.solution(), b.solution()) {
                        let p = agreement(d, g, sa, sb).pressure_max;
                        spread = Some(spread.map_or(p, |s| s.max(p)));
                    }
                }
            }
            if good.len() == 1 {
                spread = Some(0.0);
            }
            let conds: Vec<f64> = answers
                .iter()
                .filter_map(|m| diagnostic(m, "condition"))
                .collect();
            let fp_difference = match (&fp, good.first()) {
                (Some(fp), Some(g)) if fp.trial.certified() => {
                    match (fp.solution(), g.solution()) {
                        (Some((d, a, _)), Some((_, b, g))) => {
                            Some(agreement(d, g, a, b).pressure_max)
                        }
                        _ => None,
                    }
                }
                _ => None,
            };
            rows.push(UniquenessRow {
                scene: sc.name.clone(),
                solver: e.name.into(),
                friction_coefficient: f,
                starts: answers.len(),
                certified: good.len(),
                spread,
                condition_min: conds.iter().copied().reduce(f64::min),
                condition_max: conds.iter().copied().reduce(f64::max),
                fixed_point_solver: fp
                    .as_ref()
                    .map(|m| m.trial.solver.name.to_string())
                    .unwrap_or_default(),
                fixed_point_status: fp
                    .as_ref()
                    .map(|m| m.trial.status.to_string())
                    .unwrap_or_default(),
                fixed_point_outcome: fp
                    .as_ref()
                    .map(|m| format!("{:?}", m.trial.outcome).to_lowercase())
                    .unwrap_or_default(),
                fixed_point_contraction: fp.as_ref().and_then(|m| m.trial.contraction),
                fixed_point_difference: fp_difference,
            });
            measured.extend(answers);
        }
        measured.extend(fp);
    }
    Ok((measured, rows))
}

/// Certified answers whose pressures differ by at most this, relative to
/// the largest pressure, are one solution.
pub const ONE_SOLUTION: f64 = 1e-6;
