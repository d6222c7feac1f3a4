//! The conic oracle: certified by the solver-independent certificate,
//! equilibrium, the frictionless limit, the contact zones, and closed-form
//! answers.

use contactlab::certificate::{Condition, certify};
use contactlab::mechanics::discretization::Discretization;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::Scene;
use contactlab::settings::Settings;
use contactlab::solve::{Solved, solve_scene, solver_entry};
use contactlab::solvers::{
    ConicSettings, ConicSolver, ContactNode, ContactProblem, Friction, Law, Silent, Solver, Status,
};
use nalgebra_sparse::{CooMatrix, CsrMatrix};

/// The oracle's accuracy in the certificate's measure at its default
/// tolerance (1e-10), on the problem written in its own scales.
const ORACLE_CERTIFICATE: f64 = 1e-6;

fn solve(problem: u32, k: u32, friction: f64) -> Solved {
    let mut scene = Scene::paper_problem(problem).unwrap();
    scene.set_finest(MeshSize::from_level(k).unwrap());
    scene.friction = friction;
    solve_scene(
        &scene,
        Friction::Coulomb,
        solver_entry("clarabel").unwrap(),
        &Settings::default(),
        &mut Silent,
    )
    .unwrap()
}

#[test]
fn the_coulomb_law_holds_for_every_problem_with_and_without_friction() {
    for problem in [1, 2, 3] {
        for friction in [0.0, 0.5] {
            let run = solve(problem, 4, friction);
            assert_eq!(
                run.outcome.status,
                Status::Converged,
                "{}",
                run.outcome.detail
            );
            let c = run.outcome.certificate;
            assert_eq!(c.law, Law::Coulomb);
            assert!(
                c.residual() < ORACLE_CERTIFICATE,
                "problem {problem}, 𝓕 = {friction}: {c:?}"
            );
        }
    }
}

#[test]
fn contact_forces_carry_the_whole_applied_load() {
    // The upper body's vertical rigid mode leaves nothing else to carry it.
    for (problem, load) in [(1, 20.0), (2, 40.0), (3, 60.0)] {
        for friction in [0.0, 0.5] {
            let run = solve(problem, 4, friction);
            let s = &run.outcome.solution;
            let total = run.finest.problem.total_contact_force(&s.pressure);
            assert!(
                (total - load).abs() <= 1e-8 * load,
                "problem {problem}: {total} vs {load}"
            );
            assert_eq!(run.finest.total_load, -load);
        }
    }
}

#[test]
fn frictionless_limit_has_no_friction_and_stops_after_one_step() {
    let run = solve(1, 4, 0.0);
    assert_eq!(run.outcome.history().len(), 1);
    assert!(run.outcome.claim.is_converged());
    let scale = run
        .outcome
        .solution
        .pressure
        .iter()
        .fold(0.0f64, |m, p| m.max(*p));
    for q in &run.outcome.solution.friction_traction {
        assert!(q.abs() <= 1e-9 * scale, "friction traction {q} with 𝓕 = 0");
    }
}

#[test]
fn problem_3_stays_closed_and_problems_1_and_2_open_near_x_equal_1() {
    let closed = solve(3, 4, 0.5);
    assert!(
        closed.separation().intervals.is_empty(),
        "{:?}",
        closed.separation()
    );
    for problem in [1, 2] {
        let run = solve(problem, 4, 0.5);
        let zones = &run.separation().intervals;
        assert_eq!(zones.len(), 1, "{zones:?}");
        let [a, b] = zones[0];
        assert_eq!(b, 1.0);
        assert!(a > 0.5 && a < 1.0, "{zones:?}");
        // Inside the open zone the pressure vanishes; outside, the jump does.
        for row in &run.profile() {
            if row.x > a + 1e-9 {
                assert!(row.pressure <= 1e-6 * 60.0, "{row:?}");
            } else if row.x < a - 1e-9 {
                assert!(row.jump.abs() <= 1e-6 * 1e-3, "{row:?}");
            }
        }
    }
}

#[test]
fn friction_narrows_the_separation_zone() {
    // Paper, figures 3-4: with friction the bodies separate on less of Γ_K.
    let without = solve(1, 5, 0.0).separation().fraction;
    let with = solve(1, 5, 0.5).separation().fraction;
    assert!(with < without, "{with} vs {without}");
}

/// A 2-unknown given-friction problem: v = (t, s), A = [[a, b], [b, c]].
/// The problem and its given friction bound.
fn two_unknowns(a: f64, b: f64, c: f64, f: [f64; 2], w: f64, g: f64) -> (ContactProblem, Vec<f64>) {
    let mut coo = CooMatrix::new(2, 2);
    for (i, j, v) in [(0, 0, a), (0, 1, b), (1, 0, b), (1, 1, c)] {
        coo.push(i, j, v);
    }
    let id = CsrMatrix::identity(2);
    ContactProblem::new(
        CsrMatrix::from(&coo),
        f.to_vec(),
        id,
        vec![ContactNode {
            t: 0,
            s: 1,
            weight: w,
            coefficient: 0.0,
        }],
        vec![],
    )
    .map(|p| (p, vec![g]))
    .unwrap()
}

fn oracle((p, g): &(ContactProblem, Vec<f64>)) -> (Vec<f64>, f64, f64) {
    let s =
        ConicSolver::new(ConicSettings::default()).solve(p, Friction::Given(g), None, &mut Silent);
    assert!(s.status.is_converged(), "{}", s.detail);
    let r = certify(
        p,
        Friction::Given(g),
        &s.v,
        &s.pressure,
        &s.friction_traction,
        1e-7,
    );
    assert!(r.passed(), "{r:?} v = {:?}", s.v);
    (s.v, s.pressure[0], s.friction_traction[0])
}

fn close(x: f64, y: f64) -> bool {
    (x - y).abs() <= 1e-7 * (1.0 + y.abs())
}

#[test]
fn closed_form_two_unknown_problems_in_each_regime() {
    let (a, b, c, w, g) = (4.0, 1.0, 3.0, 0.5, 2.0);
    // Open and sticking: f_t < 0 pulls t negative; friction holds s = 0.
    // t = f_t / a, λ = 0; μ = b t − f_s with |μ| ≤ w g.
    let (ft, fs) = (-2.0, 0.3);
    let (v, p, q) = oracle(&two_unknowns(a, b, c, [ft, fs], w, g));
    let t = ft / a;
    assert!(close(v[0], t) && v[0] < 0.0 && close(v[1], 0.0), "{v:?}");
    assert!(close(p, 0.0), "p = {p}");
    assert!(close(q, (b * t - fs) / w), "q = {q}");
    // Closed and sticking: f_t > 0 pushes into contact, |f_s| ≤ w g.
    // t = 0, s = 0, λ = f_t, μ = −f_s.
    let (ft, fs) = (2.0, 0.7);
    let (v, p, q) = oracle(&two_unknowns(a, b, c, [ft, fs], w, g));
    assert!(close(v[0], 0.0) && close(v[1], 0.0), "{v:?}");
    assert!(close(p, ft / w) && p > 0.0, "p = {p}");
    assert!(close(q, -fs / w) && q.abs() < g, "q = {q}");
    // Closed and slipping: |f_s| > w g: s = (f_s − w g sign f_s) / c,
    // λ = f_t − b s, and the traction on the lower body is at its bound,
    // opposite to the slip: q = −g sign(s).
    let (ft, fs) = (2.0, 2.5);
    let (v, p, q) = oracle(&two_unknowns(a, b, c, [ft, fs], w, g));
    let s = (fs - w * g) / c;
    assert!(close(v[0], 0.0) && close(v[1], s) && s > 0.0, "{v:?}");
    assert!(close(p, (ft - b * s) / w), "p = {p}");
    assert!(close(q, -g), "q = {q}");
    let (v, _, q) = oracle(&two_unknowns(a, b, c, [ft, -fs], w, g));
    assert!(v[1] < 0.0 && close(q, g), "slip {} traction {q}", v[1]);
}

#[test]
fn the_certificate_detects_each_kind_of_violation() {
    let (problem, g) = two_unknowns(4.0, 1.0, 3.0, [2.0, 2.5], 0.5, 2.0);
    let given = Friction::Given(&g);
    let s = (2.5 - 1.0) / 3.0;
    let exact = (vec![0.0, s], vec![(2.0 - s) / 0.5], vec![-2.0]);
    let c = certify(&problem, given, &exact.0, &exact.1, &exact.2, 1e-12);
    assert!(c.residual() < 1e-14, "{c:?}");
    let bad = |v: Vec<f64>, p: f64, q: f64, condition: Condition| {
        let c = certify(&problem, given, &v, &[p], &[q], 1e-6);
        assert!(!c.passed(), "{condition:?} not detected: {c:?}");
        assert!(c.get(condition) > 1e-3, "{condition:?}: {c:?}");
        assert!(c.failing().contains(&condition));
    };
    let p = exact.1[0];
    bad(vec![0.1, s], p, -2.0, Condition::Nonpenetration);
    bad(vec![0.0, s], -1.0, -2.0, Condition::PressureSign);
    bad(vec![-0.1, s], p, -2.0, Condition::Complementarity);
    bad(vec![0.0, s], p, -2.5, Condition::FrictionBound);
    bad(vec![0.0, s], p, 2.0, Condition::SlipDirection); // traction with the slip
    bad(vec![0.0, s], p, -1.0, Condition::Stick); // slipping below the bound
    bad(vec![0.0, s], p * 1.1, -2.0, Condition::Stationarity);
    let c = certify(&problem, given, &[f64::NAN, s], &[p], &[-2.0], 1e-6);
    assert!(c.residual().is_infinite() && !c.passed());
    // A claim of convergence that fails becomes `inaccurate`; other claims stand.
    let c = certify(&problem, given, &[0.0, s], &[p], &[-1.0], 1e-6);
    assert_eq!(c.verdict(Status::Converged), Status::Inaccurate);
    assert_eq!(c.verdict(Status::MaxIterations), Status::MaxIterations);
}

#[test]
fn the_coulomb_certificate_is_taken_at_the_bound_of_the_solutions_own_pressure() {
    // The closed, slipping solution of the Tresca problem with g = 2 at the
    // pressure p it produces: it satisfies the Coulomb law for 𝓕 = g/p and
    // fails it for 𝓕 = 1.25 g/p (there it slips below the bound 𝓕p).
    let (a, b, c, w, g, ft, fs) = (4.0, 1.0, 3.0, 0.5, 2.0, 2.0, 2.5);
    let (problem, _) = two_unknowns(a, b, c, [ft, fs], w, g);
    let s = (fs - w * g) / c;
    let p = (ft - b * s) / w;
    let (v, q) = (vec![0.0, s], -g);
    let coulomb =
        |problem: &ContactProblem| certify(problem, Friction::Coulomb, &v, &[p], &[q], 1e-9);
    let with_coefficient = |f: f64| {
        let mut contacts = problem.contacts().to_vec();
        contacts[0].coefficient = f;
        ContactProblem::new(
            problem.a().clone(),
            problem.f().to_vec(),
            problem.mass().unwrap().into_owned(),
            contacts,
            vec![],
        )
        .unwrap()
    };
    assert!(coulomb(&with_coefficient(g / p)).passed());
    let wrong = coulomb(&with_coefficient(1.25 * g / p));
    assert!(
        !wrong.passed() && wrong.failing().contains(&Condition::Stick),
        "{wrong:?}"
    );
    // The given-friction certificate at the problem's own g does not see it.
    assert!(
        certify(
            &with_coefficient(1.25 * g / p),
            Friction::Given(&[g]),
            &v,
            &[p],
            &[q],
            1e-9
        )
        .passed()
    );
}

#[test]
fn an_unbounded_problem_is_not_reported_solved() {
    // Condition (13) violated at the algebraic level: lift the upper body.
    let d = Discretization::new(
        &Scene::paper_problem(1).unwrap(),
        MeshSize::from_level(3).unwrap(),
    )
    .unwrap();
    let f: Vec<f64> = d.problem.f().iter().map(|x| -x).collect();
    let build = |f: Vec<f64>, checked: bool| {
        let parts = (
            d.problem.a().clone(),
            f,
            d.problem.mass().unwrap().into_owned(),
            d.problem.contacts().to_vec(),
            d.problem.rigid_modes().to_vec(),
        );
        if checked {
            ContactProblem::new(parts.0, parts.1, parts.2, parts.3, parts.4)
        } else {
            ContactProblem::without_solvability_checks(parts.0, parts.1, parts.2, parts.3, parts.4)
        }
    };
    // Refused as posed (condition (13)); built past the check to see what
    // the oracle does with it.
    assert!(matches!(
        build(f.clone(), true),
        Err(contactlab::solvers::ProblemError::LiftsOff { index: 0, .. })
    ));
    let p = build(f, false).unwrap();
    let zero = vec![0.0; p.contacts().len()];
    let s = ConicSolver::default().solve(&p, Friction::Given(&zero), None, &mut Silent);
    assert!(
        !s.status.is_converged(),
        "status {:?}: {}",
        s.status,
        s.detail
    );
}
