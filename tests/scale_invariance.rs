//! A result must not change with the units the user chose. Problem 1 with
//! its loads × 1e-6 and × 1e6, with E and the loads × 1e6 together, and at
//! both ends of the sizes a scene may have (`MAGNITUDES`: loads near 1e50
//! with E near 1e-50, the largest displacements, and the reverse), must
//! give every registered solver (inside the Coulomb loop, and alone on the
//! given-friction subproblem) the same status, the same iteration counts,
//! the same zone, and the solution scaled exactly, within the certificate's
//! tolerance: loads × c scale displacements and pressures by c; E and loads
//! × c leave displacements alone and scale pressures by c.

use contactlab::certificate::certify;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::Scene;
use contactlab::settings::Settings;
use contactlab::solve::{Solved, solve_scene, solver_entry};
use contactlab::solvers::{Friction, Law, Silent, Solution, registry};

/// (name, load factor, E factor): displacements scale by load/E, pressures by load.
const UNITS: [(&str, f64, f64); 5] = [
    ("loads × 1e-6", 1e-6, 1.0),
    ("loads × 1e6", 1e6, 1.0),
    ("E and loads × 1e6", 1e6, 1e6),
    ("loads × 1e48, E × 1e-54", 1e48, 1e-54),
    ("loads × 1e-48, E × 1e45", 1e-48, 1e45),
];

fn scene(load: f64, young: f64) -> Scene {
    let mut s = Scene::paper_problem(1).unwrap();
    s.set_finest(MeshSize::from_level(4).unwrap());
    for l in &mut s.loads {
        l.p2 *= load;
    }
    s.material.young *= young;
    s
}

/// Largest difference of two vectors relative to the first's largest entry.
fn rel(a: &[f64], b: &[f64]) -> f64 {
    let scale = a
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()))
        .max(f64::MIN_POSITIVE);
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

fn scaled(s: &Solution, u: f64, p: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    (
        s.v.iter().map(|x| x * u).collect(),
        s.pressure.iter().map(|x| x * p).collect(),
        s.friction_traction.iter().map(|x| x * p).collect(),
    )
}

fn same_answer(what: &str, base: &Solution, other: &Solution, u: f64, p: f64, tol: f64) {
    let (v, pr, q) = scaled(base, u, p);
    assert!(
        rel(&v, &other.v) <= tol,
        "{what}: displacements {:.1e}",
        rel(&v, &other.v)
    );
    assert!(
        rel(&pr, &other.pressure) <= tol,
        "{what}: pressures {:.1e}",
        rel(&pr, &other.pressure)
    );
    let q_scale = pr.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let dq = q
        .iter()
        .zip(&other.friction_traction)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(
        dq <= tol * q_scale,
        "{what}: tractions {:.1e}",
        dq / q_scale
    );
}

#[test]
fn every_solver_inside_the_coulomb_loop_gives_the_same_answer_in_any_units() {
    let settings = Settings::default();
    let tol = settings.certificate.tolerance;
    for entry in registry::solvers() {
        let run = |load, young| {
            solve_scene(
                &scene(load, young),
                Friction::Coulomb,
                solver_entry(entry.name).unwrap(),
                &settings,
                &mut Silent,
            )
            .unwrap()
        };
        let base: Solved = run(1.0, 1.0);
        assert!(
            base.outcome.status.is_converged(),
            "{}: {}",
            entry.name,
            base.outcome.detail
        );
        for (units, load, young) in UNITS {
            let other = run(load, young);
            let what = format!("{} with {units}", entry.name);
            assert_eq!(other.outcome.status, base.outcome.status, "{what}");
            assert_eq!(
                other.outcome.history().len(),
                base.outcome.history().len(),
                "{what}: friction iterations"
            );
            assert_eq!(other.outcome.work, base.outcome.work, "{what}: iterations");
            // The same separated nodes: the same intervals, their interpolated
            // ends within 1e-6 of Γ_K (a node is 1/16 away).
            let (a, b) = (&base.separation().intervals, &other.separation().intervals);
            assert_eq!(a.len(), b.len(), "{what}: zone {a:?} vs {b:?}");
            for (x, y) in a.iter().zip(b) {
                assert!(
                    (x[0] - y[0]).abs() < 1e-6 && (x[1] - y[1]).abs() < 1e-6,
                    "{what}: zone {a:?} vs {b:?}"
                );
            }
            same_answer(
                &what,
                &base.outcome.solution,
                &other.outcome.solution,
                load / young,
                load,
                tol,
            );
            assert!(
                other.outcome.certificate.passed(),
                "{what}: {:?}",
                other.outcome.certificate
            );
        }
    }
}

#[test]
fn every_solver_alone_gives_the_same_answer_in_any_units() {
    let settings = Settings::default();
    let tol = settings.certificate.tolerance;
    // The operating point: g = 𝓕p of a certified Coulomb answer, scaled with the units.
    let g = solve_scene(
        &scene(1.0, 1.0),
        Friction::Coulomb,
        solver_entry(registry::solvers()[0].name).unwrap(),
        &settings,
        &mut Silent,
    )
    .unwrap()
    .outcome
    .bound;
    for entry in registry::solvers()
        .iter()
        .filter(|e| e.solves(Law::GivenFriction))
    {
        let solve = |load: f64, young| {
            let gs: Vec<f64> = g.iter().map(|x| x * load).collect();
            let (d, s, _) = solve_scene(
                &scene(load, young),
                Friction::Given(&gs),
                solver_entry(entry.name).unwrap(),
                &settings,
                &mut Silent,
            )
            .map(|x| (x.finest, x.outcome.solution, x.outcome.levels))
            .unwrap();
            let c = certify(
                &d.problem,
                Friction::Given(&gs),
                &s.v,
                &s.pressure,
                &s.friction_traction,
                tol,
            );
            (s, c)
        };
        let (base, c) = solve(1.0, 1.0);
        assert!(c.passed(), "{}: {c:?}", entry.name);
        for (units, load, young) in UNITS {
            let (other, c) = solve(load, young);
            let what = format!("{} alone with {units}", entry.name);
            assert_eq!(other.status, base.status, "{what}");
            assert_eq!(other.iterations, base.iterations, "{what}: iterations");
            same_answer(&what, &base, &other, load / young, load, tol);
            assert!(c.passed(), "{what}: {c:?}");
        }
    }
}
