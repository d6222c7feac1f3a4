//! The stability map detects each documented failure and reports it with a
//! non-converged status (these tests check detection, not success).

use contactlab::settings::Settings;
use contactlab::solvers::{
    ContactNode, ContactProblem, Law, ProxUzawa, RelaxationSettings, Silent, Solver, Status,
};
use contactlab::study::stability::{Class, StabilityRow, StabilitySpec, stability};
use nalgebra_sparse::{CooMatrix, CsrMatrix};

fn find<'a>(
    rows: &'a [StabilityRow],
    group: &str,
    method: &str,
    condition: &str,
) -> &'a StabilityRow {
    rows.iter()
        .find(|r| r.group == group && r.method == method && r.condition.starts_with(condition))
        .unwrap_or_else(|| panic!("no run {group} / {method} / {condition}"))
}

#[test]
fn each_documented_failure_is_detected_and_reported() {
    let (rows, traces) = stability(&StabilitySpec::quick(), &Settings::default(), &|_| {}).unwrap();
    let not_converged = |r: &StabilityRow| r.status != "converged";
    // r far too small: the relaxation stops at its budget.
    let r = find(&rows, "r", "relaxation", "r = 1e-8");
    assert_eq!(r.class, Class::Stalled, "{r:?}");
    assert!(not_converged(r));
    // An unreachable ε: stopped by the budget.
    let r = find(&rows, "epsilon", "relaxation", "ε = 1e-15");
    assert_eq!(r.class, Class::Stalled, "{r:?}");
    assert!(not_converged(r));
    // A coarse smoothing converges by its own test but is wrong by the residuals.
    let r = find(&rows, "smoothing", "relaxation", "huber(1e-2)");
    assert_eq!(r.class, Class::Wrong, "{r:?}");
    assert!(r.kkt > contactlab::study::stability::WRONG_KKT);
    // A large friction coefficient: the fixed point stops contracting on problem 1.
    let r = rows
        .iter()
        .find(|r| r.group == "friction" && r.problem == "problem 1" && r.value == 16.0)
        .unwrap();
    assert!(matches!(r.class, Class::Diverged | Class::Stalled), "{r:?}");
    assert!(not_converged(r));
    let trace = traces
        .iter()
        .find(|t| t.problem.starts_with("problem 1") && t.friction == 16.0)
        .unwrap();
    assert!(
        !trace.converged && trace.contractions.iter().flatten().any(|&q| q >= 1.0),
        "{trace:?}"
    );
    // Condition (13) violated: refused; without the check Clarabel reports an
    // unbounded problem and the relaxation runs into its budget.
    for solver in ["clarabel", "relaxation"] {
        assert_eq!(
            find(&rows, "load", solver, "total vertical load +2e0").class,
            Class::Refused
        );
    }
    let r = find(
        &rows,
        "load",
        "clarabel (check (13) bypassed)",
        "total vertical load +2e0",
    );
    assert_eq!(r.status, "unbounded", "{r:?}");
    let r = find(
        &rows,
        "load",
        "relaxation (check (13) bypassed)",
        "total vertical load +2e0",
    );
    assert!(not_converged(r) && r.class == Class::Stalled, "{r:?}");
    // Clarabel: a loose tolerance is wrong, an extreme one ends at reduced accuracy.
    let r = rows
        .iter()
        .find(|r| {
            r.group == "clarabel" && r.method == "clarabel" && r.condition == "tolerance 1e-4"
        })
        .unwrap();
    assert_eq!(r.class, Class::Wrong, "{r:?}");
    let tight: Vec<&StabilityRow> = rows
        .iter()
        .filter(|r| {
            r.group == "clarabel" && r.condition == "tolerance 1e-14" && r.class == Class::Stalled
        })
        .collect();
    assert!(!tight.is_empty() && tight.iter().all(|r| r.status == "reduced_accuracy"));
}

#[test]
fn a_non_finite_iterate_stops_the_relaxation_with_that_status() {
    // Unknown 1 has no stiffness and no mass: its coordinate minimization
    // divides by zero, which must be caught, not propagated.
    let mut a = CooMatrix::new(3, 3);
    a.push(0, 0, 2.0);
    a.push(2, 2, 1.0);
    let p = ContactProblem::new(
        CsrMatrix::from(&a),
        vec![1.0, 1.0, 0.0],
        CsrMatrix::from(&CooMatrix::new(3, 3)),
        vec![ContactNode {
            t: 0,
            s: 2,
            weight: 1.0,
            g: 0.0,
            coefficient: 0.0,
        }],
        vec![],
    )
    .unwrap();
    let s = ProxUzawa::new(RelaxationSettings::default()).solve(
        &p,
        Law::GivenFriction,
        None,
        &mut Silent,
    );
    assert_eq!(s.status, Status::NonFinite, "{}", s.detail);
}
