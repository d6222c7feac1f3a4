//! The field's solver families on the same problem: every registered solver
//! agrees with the earned reference (so with every other) in each contact
//! regime and on the paper's problems, and each answer passes the
//! certificate; the direct Coulomb solver agrees with the fixed point, whose
//! difference at the paper's ε is the size its stopping rule predicts; the
//! dual methods carry exactly the applied load.

use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::Scene;
use contactlab::settings::Settings;
use contactlab::solve::{solve_scene, solver_entry};
use contactlab::solvers::{Friction, Law, Silent, registry};
use contactlab::study::agreement::agreement;
use contactlab::study::compare::Compare;
use contactlab::study::lab::{Lab, Quiet};
use contactlab::study::reference::References;
use contactlab::study::runner::Measured;

/// Agreement with the reference: displacements and pressures to 1e-5 of
/// their largest value (ten times the certificate's default tolerance, which
/// every answer must pass).
const AGREE: f64 = 1e-5;

fn at(mut s: Scene, k: u32) -> Scene {
    s.set_finest(MeshSize::from_level(k).unwrap());
    s
}

/// Three small scenes, one per contact regime, at h = 1/8.
fn regimes() -> Vec<(&'static str, Scene)> {
    let p = |n| Scene::paper_problem(n).unwrap();
    // Everything closed and sticking: the whole top loaded, much friction.
    let mut stick = p(3);
    stick.friction = 2.0;
    stick.name = "stick".into();
    // Slipping: a sideways traction on the whole top, little friction.
    let mut slip = p(3);
    slip.friction = 0.1;
    slip.loads[0].p1 = 30.0;
    slip.name = "slip".into();
    // Separating: problem 1 without friction (a third of Γ_K opens).
    let mut open = p(1);
    open.friction = 0.0;
    open.name = "separation".into();
    vec![
        ("stick", at(stick, 3)),
        ("slip", at(slip, 3)),
        ("separation", at(open, 3)),
    ]
}

fn check_all_agree(scene: &Scene) -> (Vec<Measured>, References) {
    let mut lab = Lab::new(Settings::default(), &|_| {}, &Quiet);
    let study = Compare {
        scene: scene.clone(),
        solvers: registry::solvers(),
        repeats: 0,
        reference: None,
    };
    let measured = lab.run(&study).unwrap().findings;
    let references = std::mem::take(&mut lab.references);
    let reference = references.all().next().expect("a reference is earned");
    assert!(reference.coulomb.outcome.certificate.passed());
    for m in &measured {
        let t = &m.trial;
        let what = format!("{} on {} ({})", t.solver.name, t.scene, t.law.as_str());
        assert!(t.certified(), "{what}: {} {}", t.status, t.detail);
        let (du, dp) = (t.displacement_error().unwrap(), t.pressure_error().unwrap());
        assert!(
            du <= AGREE && dp <= AGREE,
            "{what}: Δu {du:.1e}, Δp {dp:.1e}"
        );
    }
    // Every solver of each law took part.
    for e in registry::solvers() {
        assert!(
            measured
                .iter()
                .any(|m| m.trial.solver.name == e.name && m.trial.law == Law::Coulomb)
        );
    }
    (measured, references)
}

#[test]
fn every_solver_agrees_in_each_contact_regime() {
    for (regime, scene) in regimes() {
        let (_, references) = check_all_agree(&scene);
        // The scene is in the regime it is named for: the reference's answer,
        // read with thresholds relative to its largest displacement (an
        // interior-point answer carries roundoff jumps ~1e-10 of it).
        let reference = references.all().next().unwrap();
        let (d, s) = (
            &reference.coulomb.finest,
            &reference.coulomb.outcome.solution,
        );
        let u = s.v.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let nodes: Vec<(f64, f64, f64, f64)> = d
            .problem
            .contacts()
            .iter()
            .enumerate()
            .map(|(i, c)| {
                (
                    s.v[c.t] / u,
                    s.v[c.s] / u,
                    s.pressure[i],
                    s.friction_traction[i],
                )
            })
            .collect();
        let p_max = nodes.iter().fold(0.0f64, |a, n| a.max(n.2));
        let bound = |p: f64| scene.friction * p;
        match regime {
            "stick" => assert!(
                nodes.iter().all(|&(t, s, p, mu)| t.abs() < 1e-8
                    && s.abs() < 1e-8
                    && mu.abs() < 0.99 * bound(p)),
                "stick: something opens or slips: {nodes:?}"
            ),
            "slip" => assert!(
                nodes.iter().any(|&(_, s, p, mu)| s.abs() > 1e-4
                    && p > 1e-3 * p_max
                    && (mu.abs() - bound(p)).abs() < 1e-6 * p_max),
                "slip: nothing slips: {nodes:?}"
            ),
            _ => assert!(
                nodes
                    .iter()
                    .any(|&(t, _, p, _)| t < -1e-4 && p.abs() < 1e-8 * p_max),
                "separation: nothing opens: {nodes:?}"
            ),
        }
    }
}

#[test]
fn every_solver_agrees_on_the_papers_problems() {
    for k in [4, 5] {
        for n in [1, 3] {
            check_all_agree(&at(Scene::paper_problem(n).unwrap(), k));
        }
    }
}

#[test]
fn the_direct_coulomb_solver_and_the_fixed_point_agree() {
    let scene = at(Scene::paper_problem(1).unwrap(), 5);
    let direct = solve_scene(
        &scene,
        Friction::Coulomb,
        solver_entry("newton-coulomb").unwrap(),
        &Settings::default(),
        &mut Silent,
    )
    .unwrap();
    assert!(
        direct.outcome.status.is_converged(),
        "{}",
        direct.outcome.detail
    );
    // The fixed point with a tight ε: the same solution.
    let mut tight = Settings::default();
    tight.set_text("coulomb.epsilon", "1e-12").unwrap();
    let fixed = solve_scene(
        &scene,
        Friction::Coulomb,
        solver_entry("newton").unwrap(),
        &tight,
        &mut Silent,
    )
    .unwrap();
    let a = agreement(
        &direct.finest,
        &direct.outcome.bound,
        &fixed.outcome.solution,
        &direct.outcome.solution,
    );
    assert!(a.pressure_max < 1e-9 && a.displacement_max < 1e-9, "{a:?}");
    // At the paper's ε the fixed point stops with max|Δg| ≤ 1e-4: its error
    // in g is about the last change times q/(1 − q) (q the contraction), so
    // its pressure error about that over 𝓕.
    let paper = solve_scene(
        &scene,
        Friction::Coulomb,
        solver_entry("newton").unwrap(),
        &Settings::paper(),
        &mut Silent,
    )
    .unwrap();
    let last = paper.outcome.history().last().unwrap();
    let q = last.contraction.unwrap();
    let p_max = direct
        .outcome
        .solution
        .pressure
        .iter()
        .fold(0.0f64, |m, p| m.max(*p));
    let predicted = last.change * q / (1.0 - q) / scene.friction / p_max;
    let measured = agreement(
        &direct.finest,
        &direct.outcome.bound,
        &paper.outcome.solution,
        &direct.outcome.solution,
    )
    .pressure_max;
    assert!(
        measured > 0.1 * predicted && measured < 10.0 * predicted,
        "measured {measured:.2e}, predicted {predicted:.2e} (q = {q:.2})"
    );
}

#[test]
fn the_dual_methods_carry_exactly_the_applied_load() {
    // At h = 1/64, the operating point of a certified Coulomb answer.
    let scene = at(Scene::paper_problem(1).unwrap(), 6);
    let settings = Settings::default();
    let g = solve_scene(
        &scene,
        Friction::Coulomb,
        solver_entry("newton").unwrap(),
        &settings,
        &mut Silent,
    )
    .unwrap()
    .outcome
    .bound;
    for solver in ["nsgs", "apgd"] {
        let (d, s, _) = solve_scene(
            &scene,
            Friction::Given(&g),
            solver_entry(solver).unwrap(),
            &settings,
            &mut Silent,
        )
        .map(|x| (x.finest, x.outcome.solution, x.outcome.levels))
        .unwrap();
        assert!(s.status.is_converged(), "{solver}: {}", s.detail);
        let carried: f64 = d
            .problem
            .contacts()
            .iter()
            .zip(&s.pressure)
            .map(|(c, p)| c.weight * p)
            .sum();
        let load = -d.total_load;
        assert!(
            (carried - load).abs() <= 1e-10 * load,
            "{solver} carries {carried} of {load}: {:.1e} lost",
            (carried - load) / load
        );
    }
}
