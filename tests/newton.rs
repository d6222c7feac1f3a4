//! The fast solver: agreement with the oracle, no cycling, a status under
//! every stress condition.

use contactlab::certificate::certify;
use contactlab::mechanics::discretization::Discretization;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::{Scene, Traction};
use contactlab::settings::Settings;
use contactlab::solve::{solve_scene, solver_entry};
use contactlab::solvers::newton::tresca::{NewtonSettings, semismooth_newton};
use contactlab::solvers::{
    CondensedNewton, ContactNode, ContactProblem, Friction, Silent, Solver, Status,
};
use contactlab::study::agreement::agreement;
use faer::Mat;
use nalgebra_sparse::{CooMatrix, CsrMatrix};
use serde_json::Value;

fn scene(problem: u32, k: u32) -> Scene {
    let mut s = Scene::paper_problem(problem).unwrap();
    s.set_finest(MeshSize::from_level(k).unwrap());
    s
}

#[test]
fn agrees_with_the_oracle_on_the_same_subproblem_and_on_the_coulomb_problem() {
    for problem in [1, 2, 3] {
        let scene = scene(problem, 5);
        let oracle = solve_scene(
            &scene,
            Friction::Coulomb,
            solver_entry("clarabel").unwrap(),
            &Settings::default(),
            &mut Silent,
        )
        .unwrap();
        let g = oracle.outcome.bound.clone();
        let (d, reference, _) = solve_scene(
            &scene,
            Friction::Given(&g),
            solver_entry("clarabel").unwrap(),
            &Settings::default(),
            &mut Silent,
        )
        .map(|x| (x.finest, x.outcome.solution, x.outcome.levels))
        .unwrap();
        let (_, fast, _) = solve_scene(
            &scene,
            Friction::Given(&g),
            solver_entry("newton").unwrap(),
            &Settings::default(),
            &mut Silent,
        )
        .map(|x| (x.finest, x.outcome.solution, x.outcome.levels))
        .unwrap();
        assert_eq!(fast.status, Status::Converged, "{}", fast.detail);
        let a = agreement(&d, &g, &fast, &reference);
        assert!(
            a.displacement_max <= 1e-6 && a.pressure_max <= 1e-4,
            "problem {problem}: {a:?}"
        );
        // Judged by the certificate, it is far more accurate than the oracle
        // it agrees with.
        let cert = |s: &contactlab::solvers::Solution| {
            certify(
                &d.problem,
                Friction::Given(&g),
                &s.v,
                &s.pressure,
                &s.friction_traction,
                1e-10,
            )
        };
        let (r, ro) = (cert(&fast), cert(&reference));
        assert!(
            r.passed() && r.residual() <= ro.residual(),
            "problem {problem}: {r:?} vs oracle {ro:?}"
        );
        // The whole Coulomb problem.
        let tight = Settings::default();
        let fast = solve_scene(
            &scene,
            Friction::Coulomb,
            solver_entry("newton").unwrap(),
            &tight,
            &mut Silent,
        )
        .unwrap();
        let slow = solve_scene(
            &scene,
            Friction::Coulomb,
            solver_entry("clarabel").unwrap(),
            &tight,
            &mut Silent,
        )
        .unwrap();
        assert!(fast.outcome.claim.is_converged(), "{}", fast.outcome.detail);
        let a = agreement(
            &slow.finest,
            &slow.outcome.bound,
            &fast.outcome.solution,
            &slow.outcome.solution,
        );
        assert!(
            a.displacement_max <= 1e-6 && a.pressure_max <= 1e-4,
            "Coulomb problem {problem}: {a:?}"
        );
        assert_eq!(fast.outcome.status, Status::Converged);
        assert!(
            fast.outcome.certificate.residual() < 1e-7,
            "{:?}",
            fast.outcome.certificate
        );
    }
}

/// A frictionless 3-node contact problem (S symmetric positive definite)
/// found by random search, on which the plain primal-dual active set method
/// cycles with period 3.
fn cycling_problem() -> (Mat<f64>, Vec<f64>) {
    let s3 = [
        [0.6760494081275411, 0.6929330192509897, -0.7494857500573355],
        [0.6929330192509896, 0.7426696311285729, -0.6963863039632536],
        [-0.7494857500573355, -0.6963863039632537, 1.6087693599426487],
    ];
    let b3 = [0.44646449752232753, 0.0525486607111563, -1.3086721980346467];
    // As a condensed contact problem: unknowns (t_i, s_i), slips decoupled
    // with unit stiffness and no friction.
    let s = Mat::from_fn(6, 6, |r, c| match (r % 2, c % 2) {
        (0, 0) => s3[r / 2][c / 2],
        (1, 1) if r == c => 1.0,
        _ => 0.0,
    });
    let b = (0..6)
        .map(|k| if k % 2 == 0 { b3[k / 2] } else { 0.0 })
        .collect();
    (s, b)
}

/// The plain primal-dual active set method (Newton on the min function) on
/// t ≤ 0, λ ≥ 0, S_tt t − b + λ = 0: returns the sequence of active sets.
fn plain_active_set(s: &Mat<f64>, b: &[f64], steps: usize) -> Vec<Vec<bool>> {
    let n = b.len() / 2;
    let (mut t, mut lam) = (vec![0.0; n], vec![0.0; n]);
    let mut sets = Vec::new();
    for _ in 0..steps {
        let active: Vec<bool> = (0..n).map(|i| lam[i] + t[i] > 0.0).collect();
        sets.push(active.clone());
        let free: Vec<usize> = (0..n).filter(|&i| !active[i]).collect();
        let a = Mat::from_fn(free.len(), free.len(), |r, c| s[(2 * free[r], 2 * free[c])]);
        let rhs = Mat::from_fn(free.len(), 1, |r, _| b[2 * free[r]]);
        use faer::linalg::solvers::Solve;
        let x = a.partial_piv_lu().solve(rhs);
        t = vec![0.0; n];
        for (k, &i) in free.iter().enumerate() {
            t[i] = x[(k, 0)];
        }
        for i in 0..n {
            lam[i] = if active[i] {
                b[2 * i] - (0..n).map(|j| s[(2 * i, 2 * j)] * t[j]).sum::<f64>()
            } else {
                0.0
            };
        }
    }
    sets
}

#[test]
fn the_plain_active_set_method_cycles_and_the_globalized_newton_does_not() {
    let (s, b) = cycling_problem();
    let sets = plain_active_set(&s, &b, 12);
    let period = (1..=4).find(|&p| sets[6..].iter().zip(&sets[6 + p..]).all(|(x, y)| x == y));
    assert_eq!(
        period,
        Some(3),
        "the plain method should cycle with period 3: {sets:?}"
    );
    assert!(sets[6] != sets[7], "a cycle, not convergence");
    // The same problem with the globalized semismooth Newton: the merit falls
    // strictly at every step, so no active set can repeat, and it converges.
    let g = vec![0.0; 3];
    let start = (vec![0.0; 6], vec![0.0; 3], vec![0.0; 3]);
    let out = semismooth_newton(&s, &b, &g, start, &NewtonSettings::default(), &mut Silent);
    assert_eq!(out.status, Status::Converged, "{}", out.detail);
    assert!(
        out.merit.windows(2).all(|w| w[1] < w[0]),
        "merit {:?}",
        out.merit
    );
    // And it is the solution: t ≤ 0, λ ≥ 0, complementary, stationary.
    for i in 0..3 {
        let t = out.y[2 * i];
        assert!(t <= 1e-12 && out.lambda[i] >= -1e-12 && (t * out.lambda[i]).abs() < 1e-12);
        let f: f64 = (0..3)
            .map(|j| s[(2 * i, 2 * j)] * out.y[2 * j])
            .sum::<f64>()
            - b[2 * i]
            + out.lambda[i];
        assert!(f.abs() < 1e-10);
    }
}

#[test]
fn terminates_with_a_status_under_the_stress_conditions() {
    // High friction: every inner solve converges; the fixed point stops as
    // not contracting.
    let mut high = scene(1, 4);
    high.friction = 16.0;
    let mut s = Settings::default();
    s.set("coulomb.max_iterations", Value::from(200u64))
        .unwrap();
    let run = solve_scene(
        &high,
        Friction::Coulomb,
        solver_entry("newton").unwrap(),
        &s,
        &mut Silent,
    )
    .unwrap();
    assert_eq!(
        run.outcome.claim,
        Status::InsufficientProgress,
        "{}",
        run.outcome.detail
    );
    assert!(
        run.outcome
            .history()
            .iter()
            .all(|h| h.status == Status::Converged)
    );
    // A total load barely downward: converges (the problem has a solution).
    let mut near = scene(1, 4);
    near.loads.push(Traction {
        from: 2.0 / 3.0,
        to: 1.0,
        p2: 3.0 * (20.0 - 2e-6),
        p1: 0.0,
    });
    let run = solve_scene(
        &near,
        Friction::Coulomb,
        solver_entry("newton").unwrap(),
        &Settings::default(),
        &mut Silent,
    )
    .unwrap();
    assert!(run.outcome.claim.is_converged(), "{}", run.outcome.detail);
    let total: f64 = run
        .finest
        .problem
        .contacts()
        .iter()
        .zip(&run.outcome.solution.pressure)
        .map(|(c, p)| c.weight * p)
        .sum();
    assert!((total - 2e-6).abs() < 1e-9, "contact force {total}");
    // An upward total (no solution; the check bypassed): a status, not a hang.
    let mut up = scene(1, 4);
    up.loads.push(Traction {
        from: 2.0 / 3.0,
        to: 1.0,
        p2: 3.0 * 22.0,
        p1: 0.0,
    });
    let d = Discretization::new_unchecked(&up, MeshSize::from_level(4).unwrap()).unwrap();
    let zero = vec![0.0; d.problem.contacts().len()];
    let sol =
        CondensedNewton::default().solve(&d.problem, Friction::Given(&zero), None, &mut Silent);
    assert!(
        !sol.status.is_converged(),
        "{:?}: {}",
        sol.status,
        sol.detail
    );
}

#[test]
fn a_problem_it_cannot_condense_gets_a_numerical_error_status() {
    // Unknown 0 is away from the contact unknowns and has no stiffness: A_II is singular.
    let mut a = CooMatrix::new(3, 3);
    a.push(1, 1, 1.0);
    a.push(2, 2, 1.0);
    let p = ContactProblem::without_solvability_checks(
        CsrMatrix::from(&a),
        vec![1.0, 0.0, 0.0],
        CsrMatrix::identity(3),
        vec![ContactNode {
            t: 1,
            s: 2,
            weight: 1.0,
            coefficient: 0.0,
        }],
        vec![],
    )
    .unwrap();
    let sol = CondensedNewton::default().solve(&p, Friction::Given(&[0.0]), None, &mut Silent);
    assert_eq!(sol.status, Status::NumericalError, "{}", sol.detail);
}
