//! The certificate's word on answers of the paper's problem 1: it refuses
//! every wrong answer above its tolerance and accepts the true one below it
//! (conditions one by one are in `certify.rs`).
//!
//! - A property test perturbs a true solution of problem 1 in every way
//!   (scale, shift, one node, all pressures, one unknown; the sign of a
//!   friction force, the contact zone moved by a node, another problem's
//!   answer, non-finite or huge entries elsewhere) and checks that what is
//!   above the tolerance is refused and what is far below it accepted.
//! - The crafted answers through `contactlab certify`: displacements
//!   of 1e308 away from Γ_K (A·v overflows to NaN), and, for a load nearly
//!   balanced by an upward one, the whole net force on a node where the
//!   bodies are apart, or no friction where the bodies slide.

mod common;

use std::path::Path;
use std::process::{Command, Output};
use std::sync::OnceLock;

use contactlab::certificate::{DEFAULT_TOLERANCE, certify};
use contactlab::formats::instance::export;
use contactlab::mechanics::discretization::Discretization;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::{Scene, Traction};

use contactlab::solvers::Friction;
use proptest::prelude::*;

/// A true answer of problem `k` at h = 1/8 (newton-coulomb, tight), its
/// discretization, and its x along Γ_K.
struct Truth {
    d: std::sync::Arc<Discretization>,
    v: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
}

fn truth(k: u32) -> Truth {
    let scene = Scene::paper_problem_to(k, MeshSize::from_level(3).unwrap()).unwrap();
    let run = common::true_answer(&scene);
    let s = run.outcome.solution;
    Truth {
        d: run.finest,
        v: s.v,
        p: s.pressure,
        q: s.friction_traction,
    }
}

fn problem_1() -> &'static Truth {
    static T: OnceLock<Truth> = OnceLock::new();
    T.get_or_init(|| truth(1))
}

fn problem_3() -> &'static Truth {
    static T: OnceLock<Truth> = OnceLock::new();
    T.get_or_init(|| truth(3))
}

/// A perturbation of a true answer of size δ (where it has one).
#[derive(Clone, Copy, Debug)]
enum Perturbation {
    ScaleDisplacements,
    ShiftDisplacements,
    OnePressure,
    OneTraction,
    AllPressures,
    OneUnknown,
}

const PERTURBATIONS: [Perturbation; 6] = [
    Perturbation::ScaleDisplacements,
    Perturbation::ShiftDisplacements,
    Perturbation::OnePressure,
    Perturbation::OneTraction,
    Perturbation::AllPressures,
    Perturbation::OneUnknown,
];

/// Wrong answers whatever their size.
#[derive(Clone, Copy, Debug)]
enum Wrong {
    FrictionSign,
    ZoneMovedByANode,
    AnotherProblemsAnswer,
    NonFiniteDisplacement(f64),
    NonFinitePressure(f64),
    HugeDisplacementAwayFromContact,
}

fn certify_p1(v: &[f64], p: &[f64], q: &[f64]) -> (bool, f64) {
    let t = problem_1();
    let c = certify(&t.d.problem, Friction::Coulomb, v, p, q, DEFAULT_TOLERANCE);
    (c.passed(), c.residual())
}

fn perturbed(kind: Perturbation, delta: f64, pick: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let t = problem_1();
    let s = t.d.problem.scales();
    let (mut v, mut p, mut q) = (t.v.clone(), t.p.clone(), t.q.clone());
    let m = p.len();
    match kind {
        Perturbation::ScaleDisplacements => v.iter_mut().for_each(|x| *x *= 1.0 + delta),
        Perturbation::ShiftDisplacements => v.iter_mut().for_each(|x| *x += delta * s.displacement),
        Perturbation::OnePressure => p[pick % m] += delta * s.pressure,
        Perturbation::OneTraction => q[pick % m] += delta * s.pressure,
        Perturbation::AllPressures => p.iter_mut().for_each(|x| *x *= 1.0 + delta),
        Perturbation::OneUnknown => {
            let k = pick % v.len();
            v[k] += delta * s.displacement;
        }
    }
    (v, p, q)
}

fn wrong(kind: Wrong, pick: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let t = problem_1();
    let (mut v, mut p, mut q) = (t.v.clone(), t.p.clone(), t.q.clone());
    let contacts = t.d.problem.contacts();
    let on_contact = |k: usize| contacts.iter().any(|c| c.t == k || c.s == k);
    let away = (0..v.len()).filter(|&k| !on_contact(k)).collect::<Vec<_>>();
    match kind {
        Wrong::FrictionSign => {
            // The node with the largest traction slides or sticks at a bound.
            let i = (0..q.len())
                .max_by(|&a, &b| q[a].abs().total_cmp(&q[b].abs()))
                .unwrap();
            q[i] = -q[i];
        }
        Wrong::ZoneMovedByANode => {
            // The first separated node closed, carrying its neighbour's pressure.
            let u = t.d.problem.scales().displacement;
            let i = (1..p.len())
                .find(|&i| v[contacts[i].t] < -1e-3 * u)
                .expect("problem 1 separates");
            v[contacts[i].t] = 0.0;
            p[i] = p[i - 1];
        }
        Wrong::AnotherProblemsAnswer => {
            let other = problem_3();
            (v, p, q) = (other.v.clone(), other.p.clone(), other.q.clone());
        }
        Wrong::NonFiniteDisplacement(x) => v[away[pick % away.len()]] = x,
        Wrong::NonFinitePressure(x) => {
            let i = pick % p.len();
            p[i] = x;
        }
        Wrong::HugeDisplacementAwayFromContact => {
            for &k in &away {
                v[k] = 1e308;
            }
            for c in contacts {
                v[c.t] = 0.0;
                v[c.s] = 0.0;
            }
        }
    }
    (v, p, q)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Amplification from δ to the largest violation lies between 1/20
    /// (a pressure at an end node, half a weight, seen by the balance) and
    /// 20 (a shift seen at the clamped side), so δ ≥ 20·tol is refused and
    /// δ ≤ tol/200 accepted whatever the kind.
    #[test]
    fn perturbations_above_the_tolerance_are_refused_and_far_below_accepted(
        kind in 0..PERTURBATIONS.len(),
        exponent in -14.0f64..-1.0,
        pick in 0usize..10_000,
    ) {
        let delta = 10f64.powf(exponent) * if pick % 2 == 0 { 1.0 } else { -1.0 };
        let (v, p, q) = perturbed(PERTURBATIONS[kind], delta, pick);
        let (passed, residual) = certify_p1(&v, &p, &q);
        let tol = DEFAULT_TOLERANCE;
        if delta.abs() >= 20.0 * tol {
            prop_assert!(!passed, "{:?} by {delta:e} passed ({residual:e})", PERTURBATIONS[kind]);
        }
        if delta.abs() <= tol / 200.0 {
            prop_assert!(passed, "{:?} by {delta:e} refused ({residual:e})", PERTURBATIONS[kind]);
        }
    }

    #[test]
    fn wrong_answers_of_every_kind_are_refused(kind in 0usize..8, pick in 0usize..10_000) {
        let kinds = [
            Wrong::FrictionSign,
            Wrong::ZoneMovedByANode,
            Wrong::AnotherProblemsAnswer,
            Wrong::NonFiniteDisplacement(f64::NAN),
            Wrong::NonFiniteDisplacement(f64::INFINITY),
            Wrong::NonFinitePressure(f64::NEG_INFINITY),
            Wrong::NonFinitePressure(f64::NAN),
            Wrong::HugeDisplacementAwayFromContact,
        ];
        let (v, p, q) = wrong(kinds[kind], pick);
        let (passed, residual) = certify_p1(&v, &p, &q);
        prop_assert!(!passed, "{:?} passed ({residual:e})", kinds[kind]);
    }
}

#[test]
fn the_true_answer_passes() {
    let t = problem_1();
    let (passed, residual) = certify_p1(&t.v, &t.p, &t.q);
    assert!(passed && residual < 1e-8, "{residual:e}");
}

fn contactlab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args(args)
        .output()
        .unwrap()
}

fn refuses(o: &Output, what: &str) {
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(!o.status.success(), "{what}: exit 0: {stdout}");
    assert!(stdout.contains("FAILS"), "{what}: {stdout}");
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("not certified"),
        "{what}"
    );
}

fn write_forces(path: &Path, p: &[f64], q: &[f64]) {
    let mut text = String::from("pressure,friction_traction\n");
    for (a, b) in p.iter().zip(q) {
        text += &format!("{a:e},{b:e}\n");
    }
    std::fs::write(path, text).unwrap();
}

fn write_lines(path: &Path, x: &[f64]) {
    std::fs::write(
        path,
        x.iter().map(|v| format!("{v:e}\n")).collect::<String>(),
    )
    .unwrap();
}

/// `export --problem 1 --h 1/8`, then displacements 0 at every t_i and s_i
/// of contact.csv and 1e308 elsewhere: A·v overflowed to inf − inf = NaN and
/// the stationarity maximum dropped it ("certified, largest violation 0").
#[test]
fn displacements_that_overflow_the_residual_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let inst = dir.path().join("base");
    let d = problem_1();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let o = contactlab(&["export", "--problem", "1", "--h", "1/8", "--out", &s(&inst)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (v, ..) = wrong(Wrong::HugeDisplacementAwayFromContact, 0);
    let m = d.p.len();
    let v_file = dir.path().join("v.txt");
    write_lines(&v_file, &v);
    let f_file = dir.path().join("f.csv");
    write_forces(&f_file, &vec![20.0; m], &vec![0.0; m]);
    let args = |extra: &[&str]| {
        let mut a = vec!["certify".to_string(), "--instance".into(), s(&inst)];
        a.extend(extra.iter().map(|x| x.to_string()));
        a
    };
    let run = |a: Vec<String>| contactlab(&a.iter().map(String::as_str).collect::<Vec<_>>());
    refuses(
        &run(args(&[
            "--displacements",
            &s(&v_file),
            "--forces",
            &s(&f_file),
        ])),
        "1e308 with made-up forces",
    );
    write_forces(&f_file, &d.p, &d.q);
    refuses(
        &run(args(&[
            "--displacements",
            &s(&v_file),
            "--forces",
            &s(&f_file),
        ])),
        "1e308 with the true forces",
    );
    refuses(&run(args(&["--displacements", &s(&v_file)])), "1e308 alone");
}

/// Problem 1 plus p2 = 59.999994 on [2/3, 1] at h = 1/16: net load −2e-6
/// against a gross 40. Measured in the gross load's scale, the whole net
/// force on the node at x = 1 (where the bodies are 44 U apart) and zero
/// friction at x = 1/2 both passed; in the net load's they are refused, and
/// the true answer (newton-coulomb) still passes.
#[test]
fn a_nearly_balanced_load_holds_the_contact_to_the_net_load() {
    let dir = tempfile::tempdir().unwrap();
    let inst = dir.path().join("nearly");
    std::fs::create_dir(&inst).unwrap();
    let mut scene = Scene::paper_problem_to(1, MeshSize::from_level(4).unwrap()).unwrap();
    scene.loads.push(Traction {
        from: 2.0 / 3.0,
        to: 1.0,
        p2: 59.999994,
        p1: 0.0,
    });
    scene.name = "nearly balanced".into();
    let d = Discretization::new(&scene, scene.finest()).unwrap();
    export(&inst, &scene, &d, None, "test").unwrap();
    let run = common::true_answer(&scene);
    let s = &run.outcome.solution;
    let x = d.contact_x();
    let m = x.len();
    let f_file = dir.path().join("forces.csv");
    let certify_forces = |p: &[f64], q: &[f64]| {
        write_forces(&f_file, p, q);
        contactlab(&[
            "certify",
            "--instance",
            inst.to_str().unwrap(),
            "--forces",
            f_file.to_str().unwrap(),
        ])
    };
    let o = certify_forces(&s.pressure, &s.friction_traction);
    assert!(
        o.status.success(),
        "the true answer: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    // The whole net force on the node at x = 1, where the bodies are apart.
    let last = m - 1;
    let net = d.problem.total_contact_force(&s.pressure);
    assert!(s.v[d.problem.contacts()[last].t] < -10.0 * d.problem.scales().displacement);
    let mut p = vec![0.0; m];
    p[last] = net / d.problem.contacts()[last].weight;
    refuses(&certify_forces(&p, &vec![0.0; m]), "the net force at x = 1");
    // No friction where the bodies slide, the true answer elsewhere. Here
    // that is x = 0, the one node in contact; at x = 1/2 the bodies are
    // apart (jump −9 U) and the true friction is 6e-14, rounding: zero
    // friction there is the right answer, and is rightly certified.
    let middle = x.iter().position(|&xi| (xi - 0.5).abs() < 1e-12).unwrap();
    assert!(s.v[d.problem.contacts()[middle].t] < -5.0 * d.problem.scales().displacement);
    let sliding = (0..m)
        .max_by(|&a, &b| {
            s.friction_traction[a]
                .abs()
                .total_cmp(&s.friction_traction[b].abs())
        })
        .unwrap();
    assert!(s.friction_traction[sliding].abs() > 0.1 * d.problem.scales().pressure);
    let mut q = s.friction_traction.clone();
    q[middle] = 0.0;
    let o = certify_forces(&s.pressure, &q);
    assert!(o.status.success(), "no friction where the bodies are apart");
    let mut q = s.friction_traction.clone();
    q[sliding] = 0.0;
    refuses(
        &certify_forces(&s.pressure, &q),
        "no friction where it slides",
    );
}
