use super::*;

fn step(solver: &str, f: f64, iteration: usize, q: Option<f64>, certified: bool) -> FrictionStep {
    FrictionStep {
        scene: "problem 1".into(),
        solver: solver.into(),
        friction_coefficient: f,
        iteration,
        change: 1.0,
        contraction: q,
        certified,
    }
}

/// A fixed point of five steps with these factors after the first.
fn run(solver: &str, f: f64, qs: [f64; 4], certified: bool) -> Vec<FrictionStep> {
    let mut out = vec![step(solver, f, 1, None, certified)];
    out.extend(
        qs.iter()
            .enumerate()
            .map(|(k, &q)| step(solver, f, k + 2, Some(q), certified)),
    );
    out
}

#[test]
fn a_stalled_fixed_point_is_a_cross_at_its_late_factor_not_a_point_of_the_line() {
    let mut steps = run("newton", 0.5, [0.3, 0.3, 0.3, 0.3], true);
    steps.extend(run("newton", 1.0, [0.4, 0.4, 0.4, 0.4], true));
    // Fast at first, then stalled at 1, and refused.
    steps.extend(run("newton", 64.0, [0.086, 0.129, 1.056, 1.0], false));
    let charts = charts(&[], &steps);
    let (_, chart) = charts
        .iter()
        .find(|(n, _)| n == "stability_friction_problem_1")
        .unwrap();
    let line = chart.series.iter().find(|s| s.name == "newton").unwrap();
    assert_eq!(line.points.len(), 2, "only the certified runs on the line");
    let crosses = chart
        .series
        .iter()
        .find(|s| s.name == "newton: not certified")
        .unwrap();
    assert_eq!(crosses.style, crate::io::charts::Style::Failed);
    let (f, q) = crosses.points[0];
    assert_eq!(f, 64.0);
    assert!(
        q > 1.0,
        "the stalled end's factor, not a mix with the start: {q}"
    );
}
