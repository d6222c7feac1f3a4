//! The paper's solver against the conic oracle, and what its parts do.
//!
//! The paper's default ε = 1e-4 stops the relaxation at about 1e-4 relative
//! accuracy (its threshold bounds the change per sweep, not the error), so
//! the agreement tests run the same method at ε = 1e-8: they check that it
//! converges to the oracle's solution, not that the default is that accurate.

use contactlab::coulomb::continuation::Schedule;
use contactlab::coulomb::driver::{Run, solve_scene};
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::Scene;
use contactlab::settings::Settings;
use contactlab::solvers::{Residuals, Silent, Status};
use contactlab::study::compare::{agreement, solve_given_friction};

/// Displacements to 1e-6 of the largest one, pressures to 1e-4 of the
/// largest one (the tolerances).
const DISPLACEMENT_TOL: f64 = 1e-6;
const PRESSURE_TOL: f64 = 1e-4;

fn scene(problem: u32, k: u32) -> Scene {
    let mut s = Scene::paper_problem(problem).unwrap();
    s.set_finest(MeshSize::from_level(k).unwrap());
    s
}

fn tight() -> Settings {
    let mut s = Settings::default();
    s.solver.relaxation.epsilon = 1e-8;
    s
}

#[test]
fn same_given_friction_problem_agrees_with_the_oracle() {
    for k in [4, 5] {
        for problem in [1, 2, 3] {
            let scene = scene(problem, k);
            // The real operating point: g of the oracle's Coulomb solution.
            let oracle =
                solve_scene(&scene, &Settings::default(), "clarabel", &mut Silent).unwrap();
            let g = oracle.coulomb.g.clone();
            assert!(g.iter().any(|&x| x > 0.0));
            let (d, reference, _) =
                solve_given_friction(&scene, &Settings::default(), "clarabel", &g, &mut Silent)
                    .unwrap();
            let (_, relaxed, _) =
                solve_given_friction(&scene, &tight(), "relaxation", &g, &mut Silent).unwrap();
            assert_eq!(relaxed.status, Status::Converged, "{}", relaxed.detail);
            let a = agreement(&d, &relaxed, &reference);
            let what = format!("problem {problem}, h = 1/{}: {a:?}", 1 << k);
            assert!(a.displacement_max <= DISPLACEMENT_TOL, "{what}");
            assert!(a.pressure_max <= PRESSURE_TOL, "{what}");
            // Both are judged by the same solver-independent residuals.
            for s in [&relaxed, &reference] {
                let r = Residuals::compute(&d.problem, &s.v, &s.pressure, &s.friction_traction);
                assert!(r.kkt() < 1e-6, "{what}: {r:?}");
            }
        }
    }
}

fn coulomb(scene: &Scene, settings: &Settings, solver: &str) -> Run {
    let run = solve_scene(scene, settings, solver, &mut Silent).unwrap();
    assert!(
        run.coulomb.status.is_converged(),
        "{solver}: {}",
        run.coulomb.detail
    );
    run
}

#[test]
fn whole_coulomb_problem_agrees_with_the_oracles_coulomb_solution() {
    for problem in [1, 2, 3] {
        let scene = scene(problem, 5);
        // Both fixed points stop at max|Δg| ≤ 1e-6.
        let mut oracle_settings = Settings::default();
        oracle_settings.coulomb.epsilon = 1e-6;
        let mut relax_settings = tight();
        relax_settings.coulomb.epsilon = 1e-6;
        let oracle = coulomb(&scene, &oracle_settings, "clarabel");
        let relaxed = coulomb(&scene, &relax_settings, "relaxation");
        let a = agreement(
            &oracle.discretization,
            &relaxed.coulomb.solution,
            &oracle.coulomb.solution,
        );
        let what = format!("problem {problem}: {a:?}");
        assert!(a.displacement_max <= DISPLACEMENT_TOL, "{what}");
        assert!(a.pressure_max <= PRESSURE_TOL, "{what}");
        assert!(
            relaxed.residuals.kkt() < 1e-6,
            "{what}: {:?}",
            relaxed.residuals
        );
        assert_eq!(
            relaxed.separation.intervals.len(),
            oracle.separation.intervals.len()
        );
    }
}

#[test]
fn schedules_visit_the_levels_as_documented() {
    // Revisit: every friction iteration runs every level (at least one Uzawa
    // iteration each). Finest-only: coarse levels in the first one only.
    let run = coulomb(&scene(1, 5), &Settings::default(), "relaxation");
    assert_eq!(run.levels.len(), 3);
    let mpp = run.coulomb.history.len();
    for level in &run.levels {
        assert_eq!(level.visits, mpp);
        assert!(level.uzawa >= mpp, "{level:?}");
    }
    let finest_only = Settings {
        schedule: Schedule::FinestOnly,
        ..Default::default()
    };
    let run = coulomb(&scene(1, 5), &finest_only, "relaxation");
    assert_eq!(
        run.levels[0].visits, 1,
        "coarse levels only in the first friction iteration"
    );
    assert_eq!(run.levels[2].visits, run.coulomb.history.len());
}

#[test]
fn proximal_term_changes_nothing_measurable_at_the_papers_penalty() {
    // The paper adds (1/2)‖v − v^k‖²_L2 because A is singular. With r = 1e12
    // the penalty w r t² on the active jumps already makes each Uzawa
    // subproblem coercive in the rigid mode, and the L2 term (entries ~h²)
    // is tiny beside the stiffness (~E): with and without it the method
    // converges to the same solution with the same work (within 1%).
    let scene = scene(1, 4);
    let with = coulomb(&scene, &Settings::default(), "relaxation");
    let mut off = Settings::default();
    off.solver.relaxation.proximal = 0.0;
    let without = coulomb(&scene, &off, "relaxation");
    let (a, b) = (
        with.coulomb.total_iterations().inner as f64,
        without.coulomb.total_iterations().inner as f64,
    );
    assert!((a - b).abs() <= 0.01 * a, "sweeps with {a}, without {b}");
    let agree = agreement(
        &with.discretization,
        &without.coulomb.solution,
        &with.coulomb.solution,
    );
    assert!(
        agree.displacement_max < 1e-6 && agree.pressure_max < 1e-6,
        "{agree:?}"
    );
}

#[test]
fn a_cap_reached_is_a_status_reported_on_the_finest_level() {
    let scene = scene(1, 4);
    let mut s = Settings::default();
    s.solver.relaxation.max_sweeps = 50; // far too few at h = 1/8 already
    let run = solve_scene(&scene, &s, "relaxation", &mut Silent).unwrap();
    assert_eq!(run.coulomb.status, Status::MaxIterations);
    assert!(
        run.coulomb.detail.contains("sweep cap"),
        "{}",
        run.coulomb.detail
    );
    assert_eq!(run.coulomb.solution.v.len(), run.discretization.problem.n());
    let mut s = Settings::default();
    s.solver.relaxation.max_uzawa = 1;
    let run = solve_scene(&scene, &s, "relaxation", &mut Silent).unwrap();
    assert_eq!(run.coulomb.status, Status::MaxIterations);
    assert!(
        run.coulomb.detail.contains("Uzawa iteration cap"),
        "{}",
        run.coulomb.detail
    );
}

#[test]
fn exact_and_smoothed_slip_minimizers_reach_the_same_solution() {
    let scene = scene(2, 4);
    let mut exact = tight();
    exact.solver.relaxation.smoothing = contactlab::solvers::Smoothing::Exact;
    let a = coulomb(&scene, &exact, "relaxation");
    let b = coulomb(&scene, &tight(), "relaxation");
    let agree = agreement(&a.discretization, &b.coulomb.solution, &a.coulomb.solution);
    assert!(
        agree.displacement_max < 1e-6 && agree.pressure_max < 1e-5,
        "{agree:?}"
    );
}
