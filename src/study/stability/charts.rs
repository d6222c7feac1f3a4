//! The stability map's charts: work against each stressed setting, the
//! Coulomb fixed point's contraction against 𝓕, and the certificate
//! against a vanishing total load (condition (13)).

use crate::io::charts::{Chart, Series, suits_log_axis};
use crate::study::stability::classify::Class;
use crate::study::stability::views::{class_of, stress_keys};
use crate::study::stability::{FrictionStep, LOAD, STRESS};
use crate::study::trial::Trial;

/// Charts: work against each stress knob's value by class, the fixed
/// point's contraction against 𝓕, and the certificate against the load.
pub fn charts(trials: &[Trial], steps: &[FrictionStep]) -> Vec<(String, Chart)> {
    let mut out = Vec::new();
    for (solver, knob) in stress_keys(trials) {
        let runs: Vec<&Trial> = trials
            .iter()
            .filter(|t| t.group == STRESS && t.solver.name == solver && t.knob().0 == knob)
            .collect();
        let numeric: Vec<(f64, &Trial)> = runs
            .iter()
            .filter_map(|t| {
                t.setting
                    .as_ref()
                    .and_then(|s| s.number)
                    .filter(|v| *v > 0.0)
                    .map(|v| (v, *t))
            })
            .collect();
        if numeric.len() < 2 {
            continue;
        }
        let series = Class::ALL
            .iter()
            .filter_map(|&c| {
                let pts: Vec<(f64, f64)> = numeric
                    .iter()
                    .filter(|(_, t)| class_of(t) == c)
                    .map(|(v, t)| (*v, t.work.max(1) as f64))
                    .collect();
                (!pts.is_empty()).then(|| {
                    let s = Series::line(c.as_str(), pts).colored(c as usize);
                    if matches!(c, Class::Converged | Class::Slow) {
                        s.scatter()
                    } else {
                        s.failed()
                    }
                })
            })
            .collect();
        out.push((
            format!("stability_{}", knob.replace('.', "_")),
            Chart {
                title: format!("Stability: {solver} against {knob}, problem 1"),
                x_label: knob.clone(),
                y_label: "work (events of its work stage)".into(),
                log_x: suits_log_axis(numeric.iter().map(|p| p.0)),
                log_y: true,
                series,
                y_resolution: None,
                x_ticks: None,
            },
        ));
    }
    // Contraction of each fixed point against 𝓕: one chart per problem,
    // one series per inner solver (a legend a reader can match).
    let mut scenes: Vec<String> = steps.iter().map(|s| s.scene.clone()).collect();
    scenes.sort();
    scenes.dedup();
    for scene in scenes {
        out.extend(friction_chart(&scene, steps));
    }
    let load: Vec<&Trial> = trials.iter().filter(|t| t.group == LOAD).collect();
    if !load.is_empty() {
        let mut solvers: Vec<&str> = load.iter().map(|t| t.solver.name).collect();
        solvers.sort();
        solvers.dedup();
        let mut series = Vec::new();
        for &s in &solvers {
            let points = |certified: bool| -> Vec<(f64, f64)> {
                load.iter()
                    .filter(|t| t.solver.name == s && t.certified() == certified)
                    .map(|t| (t.total_load.abs(), t.residual().max(1e-16)))
                    .collect()
            };
            series.extend(Series::certified_and_failed(s, points(true), points(false)));
        }
        // The certificate's threshold: a point above it is refused.
        let (lo, hi) = load
            .iter()
            .map(|t| t.total_load.abs())
            .filter(|x| *x > 0.0)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
        let tolerance = load.iter().map(|t| t.tolerance).fold(0.0, f64::max);
        if lo.is_finite() && tolerance > 0.0 {
            // Named in the title, not the legend (a legend of every solver).
            let mut line = Series::line(
                format!("certificate's threshold ({tolerance:e})"),
                vec![(lo, tolerance), (hi, tolerance)],
            )
            .dashed()
            .black();
            line.legend = false;
            series.push(line);
        }
        out.push((
            "stability_load".into(),
            Chart {
                title: format!(
                    "Stability: total vertical load approaching 0 (condition (13)); dashed: the certificate's threshold {tolerance:e}"
                ),
                x_label: "|total vertical load| [force]".into(),
                y_label: "certificate (largest violation)".into(),
                log_x: true,
                log_y: true,
                series,
                y_resolution: None,
                x_ticks: None,
            },
        ));
    }
    out
}

#[cfg(test)]
mod tests;

/// The contraction factor of each inner solver's fixed point against 𝓕 on
/// `scene`: certified runs joined, the others as crosses.
fn friction_chart(scene: &str, steps: &[FrictionStep]) -> Option<(String, Chart)> {
    let mut solvers: Vec<String> = steps
        .iter()
        .filter(|s| s.scene == scene)
        .map(|s| s.solver.clone())
        .collect();
    solvers.sort();
    solvers.dedup();
    let mut series: Vec<Series> = Vec::new();
    for solver in solvers {
        let mut fs: Vec<f64> = steps
            .iter()
            .filter(|s| s.scene == scene && s.solver == solver && s.friction_coefficient > 0.0)
            .map(|s| s.friction_coefficient)
            .collect();
        fs.sort_by(f64::total_cmp);
        fs.dedup();
        // (𝓕, trend, whether its answer was certified)
        let pts: Vec<(f64, f64, bool)> = fs
            .iter()
            .filter_map(|&f| {
                let run: Vec<&FrictionStep> = steps
                    .iter()
                    .filter(|s| {
                        s.scene == scene && s.solver == solver && s.friction_coefficient == f
                    })
                    .collect();
                let q: Vec<Option<f64>> = run.iter().map(|s| s.contraction).collect();
                let certified = run.iter().all(|s| s.certified);
                (q.len() >= 5)
                    .then(|| crate::study::stability::classify::trend(&q))
                    .flatten()
                    .map(|t| (f, t, certified))
            })
            .collect();
        let of = |certified: bool| -> Vec<(f64, f64)> {
            pts.iter()
                .filter(|p| p.2 == certified)
                .map(|p| (p.0, p.1))
                .collect()
        };
        let (good, bad) = (of(true), of(false));
        if !good.is_empty() {
            series.push(
                Series::line(solver.clone(), good)
                    .with_markers()
                    .of_solver(&solver),
            );
        }
        if !bad.is_empty() {
            // A fixed point that stalled or whose answer was refused: its
            // factor is no rate of convergence, drawn apart as crosses.
            series.push(
                Series::line(format!("{solver}: not certified"), bad)
                    .failed()
                    .of_solver(&solver),
            );
        }
    }
    if !series.is_empty() {
        let xs: Vec<f64> = series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0))
            .collect();
        let (lo, hi) = xs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        series.push(
            Series::line("contraction factor 1", vec![(lo, 1.0), (hi, 1.0)])
                .dashed()
                .black(),
        );
        return Some((
            format!("stability_friction_{}", scene.replace(' ', "_")),
            Chart {
                title: format!("Coulomb fixed point: contraction factor against 𝓕, {scene}"),
                x_label: "friction coefficient 𝓕".into(),
                y_label: "contraction of max|Δg| (geometric mean over the later half of the steps)"
                    .into(),
                log_x: true,
                log_y: true,
                series,
                y_resolution: None,
                x_ticks: None,
            },
        ));
    }
    None
}
