//! The stability map detects each documented failure and reports it with a
//! non-converged status (these tests check detection, not success), and its
//! accuracy file is the same on a second run (work caps, not the clock).

use contactlab::certificate::Condition;
use contactlab::io::csv::to_csv;
use contactlab::settings::Settings;
use contactlab::solvers::{
    ContactNode, ContactProblem, Friction, ProxUzawa, RelaxationSettings, Silent, Solver, Status,
    registry,
};
use contactlab::study::lab::{Lab, Quiet};
use contactlab::study::stability::classify::Class;
use contactlab::study::stability::{Map, StabilitySpec, run};
use contactlab::study::trial::Trial;
use nalgebra_sparse::{CooMatrix, CsrMatrix};

fn quick_map() -> Map {
    let mut lab = Lab::new(Settings::default(), &|_| {}, &Quiet);
    run(&StabilitySpec::quick(), &mut lab).unwrap()
}

fn find<'a>(trials: &'a [Trial], group: &str, solver: &str, knob: &str, value: &str) -> &'a Trial {
    trials
        .iter()
        .find(|t| t.group == group && t.solver.name == solver && t.knob() == (knob, value))
        .unwrap_or_else(|| panic!("no trial {group} / {solver} / {knob} = {value}"))
}

fn class(t: &Trial) -> Class {
    t.class.unwrap_or_else(|| panic!("no class: {t:?}"))
}

#[test]
fn each_documented_failure_is_detected_and_reported() {
    let map = quick_map();
    let t = &map.trials;
    // Every solver at its defaults is certified on problem 1.
    for d in t.iter().filter(|t| t.group == "default") {
        assert_eq!(class(d), Class::Converged, "{d:?}");
        assert!(d.certified());
    }
    // A far too small penalty: stopped by the work cap. An ε below what
    // the arithmetic resolves: stopped at resolution, long before the cap.
    for (knob, value, status) in [
        ("relaxation.r", "1e-8", Status::MaxIterations),
        ("relaxation.epsilon", "1e-15", Status::InsufficientProgress),
    ] {
        let r = find(t, "stress", "relaxation", knob, value);
        assert_eq!(class(r), Class::Stalled, "{r:?}");
        assert_eq!(r.status, status, "{}: {}", r.status, r.detail);
    }
    // A coarse smoothing converges by its own test but fails the certificate.
    let r = find(t, "stress", "relaxation", "relaxation.smoothing", "1e-2");
    assert_eq!(class(r), Class::Wrong, "{r:?}");
    assert_eq!(
        (r.solver_status, r.status),
        (Status::Converged, Status::Inaccurate)
    );
    assert!(r.failing().contains(&Condition::Stick), "{r:?}");
    // So does Clarabel at a loose tolerance.
    let r = find(t, "stress", "clarabel", "clarabel.tol", "1e-4");
    assert_eq!(class(r), Class::Wrong, "{r:?}");
    // A large friction coefficient: the fixed point stops contracting on problem 1.
    let r = t
        .iter()
        .find(|r| {
            r.group == "friction"
                && r.scene == "problem 1"
                && r.knob().1 == "16"
                && r.solver.name == "newton"
        })
        .unwrap();
    assert!(
        matches!(class(r), Class::Diverged | Class::Stalled),
        "{r:?}"
    );
    assert!(!r.certified());
    assert!(
        map.steps
            .iter()
            .filter(|s| s.scene == "problem 1"
                && s.friction_coefficient == 16.0
                && s.solver == "newton")
            .any(|s| s.contraction.is_some_and(|q| q >= 1.0)),
        "the fixed point at 𝓕 = 16 should show a contraction factor ≥ 1"
    );
    // Condition (13) violated: refused by our check for every solver; with
    // the check bypassed, Clarabel in each form and the dual methods (whose
    // equilibrium along the rigid mode has no root) say unbounded, a correct
    // refusal; the others stop at their caps, uncertified.
    for r in t.iter().filter(|r| r.group == "refused") {
        assert_eq!(class(r), Class::Refused, "{r:?}");
        assert_eq!(r.status, Status::NotRun);
    }
    let mut says_unbounded: Vec<&str> = registry::oracle_family().iter().map(|e| e.name).collect();
    says_unbounded.extend(["nsgs", "apgd"]);
    assert!(says_unbounded.len() > 2, "the oracle is registered");
    for r in t.iter().filter(|r| r.group == "refused_check_bypassed") {
        if says_unbounded.contains(&r.solver.name) {
            assert_eq!(
                (r.status, class(r)),
                (Status::Unbounded, Class::Refused),
                "{r:?}"
            );
        } else {
            assert!(!r.certified() && class(r) == Class::Stalled, "{r:?}");
        }
    }
}

#[test]
fn the_map_is_the_same_on_a_second_run() {
    let a = quick_map();
    let b = quick_map();
    let rows = |m: &contactlab::study::stability::Map| -> Vec<_> {
        m.trials.iter().map(|t| t.row()).collect()
    };
    assert_eq!(
        to_csv(&rows(&a), &[]).unwrap(),
        to_csv(&rows(&b), &[]).unwrap(),
        "stability.csv must not depend on the machine's speed"
    );
}

#[test]
fn a_non_finite_iterate_stops_the_relaxation_with_that_status() {
    // Unknown 1 has no stiffness and no mass: its coordinate minimization
    // divides by zero, which must be caught, not propagated. (A zero on
    // A's diagonal is refused as posed; built past that check here.)
    let mut a = CooMatrix::new(3, 3);
    a.push(0, 0, 2.0);
    a.push(2, 2, 1.0);
    let p = ContactProblem::without_solvability_checks(
        CsrMatrix::from(&a),
        vec![1.0, 1.0, 0.0],
        CsrMatrix::from(&CooMatrix::new(3, 3)),
        vec![ContactNode {
            t: 0,
            s: 2,
            weight: 1.0,
            coefficient: 0.0,
        }],
        vec![],
    )
    .unwrap();
    let s = ProxUzawa::new(RelaxationSettings::default()).solve(
        &p,
        Friction::Given(&[0.0]),
        None,
        &mut Silent,
    );
    assert_eq!(s.status, Status::NonFinite, "{}", s.detail);
}
