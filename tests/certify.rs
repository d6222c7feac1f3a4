//! The certificate's word: it refuses every wrong answer above its
//! tolerance and accepts the true one below it.
//!
//! - Each condition of the law is shown to be checked by an answer that
//!   violates it alone, on a small problem built around the answer (the load
//!   is chosen so that stationarity holds exactly), so that a condition
//!   dropped from the certificate fails its own case.
//! - A property test perturbs a true solution of problem 1 in every way
//!   (scale, shift, one node, all pressures, one unknown; the sign of a
//!   friction force, the contact zone moved by a node, another problem's
//!   answer, non-finite or huge entries elsewhere) and checks that what is
//!   above the tolerance is refused and what is far below it accepted.
//! - The crafted answers through `contactlab certify`: displacements
//!   of 1e308 away from Γ_K (A·v overflows to NaN), and, for a load nearly
//!   balanced by an upward one, the whole net force on a node where the
//!   bodies are apart, or no friction where the bodies slide.

use std::path::Path;
use std::process::{Command, Output};
use std::sync::OnceLock;

use contactlab::certificate::{Condition, DEFAULT_TOLERANCE, certify};
use contactlab::formats::instance::export;
use contactlab::mechanics::discretization::Discretization;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::{Scene, Traction};
use contactlab::settings::Settings;
use contactlab::solve::{solve_scene, solver_entry};
use contactlab::solvers::{ContactNode, ContactProblem, Friction, Law, Mass, Silent};
use nalgebra_sparse::{CooMatrix, CsrMatrix};
use proptest::prelude::*;

/// One contact node of a small problem built around its answer: jump t,
/// slip s, pressure p, traction q, bound g (or Coulomb coefficient), weight.
#[derive(Clone, Copy)]
struct Node {
    t: f64,
    s: f64,
    p: f64,
    q: f64,
    g: f64,
    weight: f64,
}

const CLOSED: Node = Node {
    t: 0.0,
    s: 0.0,
    p: 1.0,
    q: 0.1,
    g: 0.5,
    weight: 0.5,
};

/// A problem whose answer is `nodes` (and u = 0.7 for the upper body's one
/// unknown), with the load f = A v + contact forces, so that stationarity
/// holds to rounding and every other condition is as the nodes make it.
/// Unknowns: t_i = 2i, s_i = 2i + 1, u = 2m; A = Σ_i (e_u + e_{t_i})(e_u +
/// e_{t_i})ᵀ + Σ_i e_{s_i} e_{s_i}ᵀ, whose kernel is the rigid mode z
/// (−1 on every t_i, +1 on u). `extra` is added to f afterwards (a residual).
fn built(nodes: &[Node], extra: &[(usize, f64)]) -> (ContactProblem, Vec<f64>, Vec<f64>, Vec<f64>) {
    let m = nodes.len();
    let n = 2 * m + 1;
    let u = 2 * m;
    let mut coo = CooMatrix::new(n, n);
    for i in 0..m {
        for (a, b) in [
            (u, u),
            (u, 2 * i),
            (2 * i, u),
            (2 * i, 2 * i),
            (2 * i + 1, 2 * i + 1),
        ] {
            coo.push(a, b, 1.0);
        }
    }
    let a = CsrMatrix::from(&coo);
    let mut v = vec![0.0; n];
    v[u] = 0.7;
    for (i, c) in nodes.iter().enumerate() {
        v[2 * i] = c.t;
        v[2 * i + 1] = c.s;
    }
    let mut f = vec![0.0; n];
    let (offsets, cols, vals) = a.csr_data();
    for (row, fr) in f.iter_mut().enumerate() {
        *fr = (offsets[row]..offsets[row + 1])
            .map(|k| vals[k] * v[cols[k]])
            .sum();
    }
    for (i, c) in nodes.iter().enumerate() {
        f[2 * i] += c.weight * c.p;
        f[2 * i + 1] -= c.weight * c.q;
    }
    for &(k, x) in extra {
        f[k] += x;
    }
    let mut mass = CooMatrix::new(n, n);
    for k in 0..n {
        mass.push(k, k, 1.0);
    }
    let contacts = nodes
        .iter()
        .enumerate()
        .map(|(i, c)| ContactNode {
            t: 2 * i,
            s: 2 * i + 1,
            weight: c.weight,
            coefficient: c.g,
        })
        .collect();
    let mut z = vec![0.0; n];
    z[u] = 1.0;
    for i in 0..m {
        z[2 * i] = -1.0;
    }
    let problem = ContactProblem::new(
        a,
        f,
        Mass::Matrix(CsrMatrix::from(&mass)),
        contacts,
        vec![z],
    )
    .unwrap();
    let p = nodes.iter().map(|c| c.p).collect();
    let q = nodes.iter().map(|c| c.q).collect();
    (problem, v, p, q)
}

/// The certificate of the built answer: the conditions it fails.
fn failing(nodes: &[Node], extra: &[(usize, f64)], law: Law) -> Vec<Condition> {
    let (problem, v, p, q) = built(nodes, extra);
    let g: Vec<f64> = nodes.iter().map(|c| c.g).collect();
    let friction = match law {
        Law::GivenFriction => Friction::Given(&g),
        Law::Coulomb => Friction::Coulomb,
    };
    let c = certify(&problem, friction, &v, &p, &q, DEFAULT_TOLERANCE);
    let mut bad = c.failing();
    bad.sort_by_key(|c| c.as_str());
    bad
}

/// Three nodes: closed and sticking, the one under test, open and sliding
/// (with the given bound as traction; none under the Coulomb law, whose
/// bound at zero pressure is zero).
fn three(middle: Node, law: Law) -> Vec<Node> {
    let open = Node {
        t: -1.0,
        s: 0.3,
        p: 0.0,
        q: if law == Law::Coulomb { 0.0 } else { -0.5 },
        g: 0.5,
        weight: 0.5,
    };
    vec![
        CLOSED,
        Node {
            weight: 1.0,
            ..middle
        },
        open,
    ]
}

#[test]
fn each_condition_is_checked_by_an_answer_that_violates_it_alone() {
    let law = Law::GivenFriction;
    let base = Node {
        p: 2.0,
        q: 0.0,
        ..CLOSED
    };
    assert_eq!(failing(&three(base, law), &[], law), [], "the true answer");
    let cases = [
        (
            Node {
                t: 0.2,
                p: 0.0,
                ..base
            },
            vec![Condition::Nonpenetration],
        ),
        (
            Node {
                t: -0.2,
                p: -0.3,
                ..base
            },
            vec![Condition::PressureSign],
        ),
        (Node { t: -0.2, ..base }, vec![Condition::Complementarity]),
        (Node { q: 0.8, ..base }, vec![Condition::FrictionBound]),
        // Slip at the bound, but in the direction of the traction.
        (
            Node {
                s: 0.2,
                q: 0.5,
                ..base
            },
            vec![Condition::SlipDirection],
        ),
        // Slip below the bound is also slip not opposed at the bound: a
        // stick violation is a slip-direction violation as well.
        (
            Node {
                s: 0.2,
                q: 0.0,
                ..base
            },
            vec![Condition::SlipDirection, Condition::Stick],
        ),
    ];
    for (node, expected) in cases {
        let mut expected = expected.clone();
        expected.sort_by_key(|c| c.as_str());
        assert_eq!(failing(&three(node, law), &[], law), expected);
    }
    // A residual at a slip row only: stationarity alone (the rigid mode
    // has no slip component, so the balance is untouched).
    assert_eq!(
        failing(&three(base, law), &[(3, 0.3)], law),
        [Condition::Stationarity]
    );
    // The Coulomb law takes the bound from the answer's own pressure:
    // g = 0.5 · 2 = 1, so q = 0.8 is within it, q = 1.3 is not.
    let coulomb = Node {
        g: 0.5,
        q: 0.8,
        ..base
    };
    assert_eq!(
        failing(&three(coulomb, Law::Coulomb), &[], Law::Coulomb),
        []
    );
    assert_eq!(
        failing(
            &three(Node { q: 1.3, ..coulomb }, Law::Coulomb),
            &[],
            Law::Coulomb
        ),
        [Condition::FrictionBound]
    );
    // The balance alone: a residual at every jump row, each below the
    // stationarity tolerance per node (half of it, in P·w_max with P = 1,
    // w_max = 1), adds up along the rigid mode to far more than the load's
    // tolerance when many nodes of small weight share it.
    let mut many = vec![Node {
        weight: 1.0,
        ..CLOSED
    }];
    many.extend(std::iter::repeat_n(
        Node {
            weight: 1e-3,
            ..CLOSED
        },
        49,
    ));
    let (problem, ..) = built(&many, &[]);
    let pw = problem.scales().pressure * 1.0;
    let extra: Vec<(usize, f64)> = (0..50)
        .map(|i| (2 * i, 0.5 * DEFAULT_TOLERANCE * pw))
        .collect();
    assert_eq!(failing(&many, &extra, law), [Condition::ForceBalance]);
}

/// A true answer of problem `k` at h = 1/8 (newton-coulomb, tight), its
/// discretization, and its x along Γ_K.
struct Truth {
    d: Discretization,
    v: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
}

fn truth(k: u32) -> Truth {
    let scene = Scene::paper_problem_to(k, MeshSize::from_level(3).unwrap()).unwrap();
    let run = solve_scene(
        &scene,
        Friction::Coulomb,
        solver_entry("newton-coulomb").unwrap(),
        &Settings::default(),
        &mut Silent,
    )
    .unwrap();
    assert!(run.outcome.status.is_converged(), "{}", run.outcome.detail);
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
    let run = solve_scene(
        &scene,
        Friction::Coulomb,
        solver_entry("newton-coulomb").unwrap(),
        &Settings::default(),
        &mut Silent,
    )
    .unwrap();
    assert!(run.outcome.status.is_converged(), "{}", run.outcome.detail);
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
    let net: f64 = d
        .problem
        .contacts()
        .iter()
        .zip(&s.pressure)
        .map(|(c, p)| c.weight * p)
        .sum();
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
