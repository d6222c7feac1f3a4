//! What each chart of a results folder is for, in one sentence, by its name.

use serde::Serialize;

/// A chart in the README: its file stem and its intent.
#[derive(Clone, Debug, Serialize)]
pub struct ChartRef {
    pub name: String,
    pub intent: String,
}

/// The intent of the chart named `name`.
pub fn intent(name: &str) -> String {
    let s: &str = if name.ends_with("_displacement") {
        "Whether the paper's method (dots) reproduces the oracle's vertical displacements of both bodies on Γ_K (the paper's figure 2)."
    } else if name.ends_with("_zoom") {
        "How friction changes the separation zone: both bodies near the opening, with friction (solid) and without (dashed)."
    } else if name.ends_with("_jump") {
        "Where the bodies separate (negative jump) with and without friction; values below 1e-9 of the largest displacement are drawn as zero."
    } else if name.ends_with("_pressure") {
        "The contact pressure (the multiplier l) along Γ_K with and without friction, and the paper's method on the oracle's curve."
    } else if name.starts_with("convergence_inner") {
        "How each inner solver converges inside the friction fixed point: its residual against its own iteration count over the whole run."
    } else if name.starts_with("convergence") {
        "How fast the friction fixed point (or a direct Coulomb solver's own iteration) converges for each solver."
    } else if name.starts_with("work_precision_coulomb") {
        "Time against accuracy on the whole Coulomb problem, certified points joined and failed claims as crosses: the cheapest solver at each accuracy."
    } else if name.starts_with("work_precision") {
        "Time against accuracy on one given-friction subproblem, where no outer loop blurs the comparison."
    } else if name.starts_with("sweep_") && name.contains("_error_") {
        "How one setting of a solver moves its error against the reference and its certificate."
    } else if name.starts_with("sweep_") {
        "How one setting of a solver moves its work (iterations) on the Coulomb problem."
    } else if name == "stability_friction" {
        "Where the friction fixed point stops contracting as 𝓕 grows, for each inner solver and problem (above the line at 1 it cannot converge)."
    } else if name == "stability_load" {
        "Whether each solver stays certified as the net load approaches zero (condition (13) barely holding)."
    } else if name.starts_with("stability_") {
        "How a solver's work and outcome class change under a stress condition of its registry entry."
    } else if name.starts_with("performance_") {
        "How each solver's time grows with the number of unknowns (slope in the legend, fitted through three or more certified runs; runs stopped or refused are crosses), beside the best sparse factorization (faer on both cores, symbolic analysis once)."
    } else if name.starts_with("benchmark_profile") {
        "Performance profile over the collection: the fraction of instances each solver solves (certified) within τ times the fastest solver's time."
    } else if name.starts_with("discretization_error") {
        "How fast each error falls as h → 0 against the finest mesh: on log–log axes the slope is the observed order."
    } else {
        "A chart of this run."
    };
    s.to_string()
}

/// The charts among `names` that start with `prefix`, with their intents.
pub fn named(names: &[String], prefix: &str) -> Vec<ChartRef> {
    names
        .iter()
        .filter(|n| n.starts_with(prefix))
        .map(|n| ChartRef {
            name: n.clone(),
            intent: intent(n),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_chart_family_has_its_own_intent() {
        for name in [
            "profile_p1_displacement",
            "profile_p1_zoom",
            "profile_p1_jump",
            "profile_p1_pressure",
            "convergence_p1",
            "convergence_inner_p1",
            "work_precision_problem_1_h32",
            "work_precision_coulomb_problem_1_h32",
            "sweep_relaxation_r_error_problem_1_h32",
            "sweep_relaxation_r_iterations_problem_1_h32",
            "stability_friction",
            "stability_load",
            "stability_relaxation_r",
            "performance_coulomb",
            "benchmark_profile_1e-4",
        ] {
            assert_ne!(intent(name), "A chart of this run.", "{name}");
        }
    }
}
