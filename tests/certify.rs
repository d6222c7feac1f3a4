//! The certificate's word, condition by condition: each condition of the
//! law is shown to be checked by an answer that violates it alone, on a
//! small problem built around the answer (the load is chosen so that
//! stationarity holds exactly), so that a condition dropped from the
//! certificate fails its own case. Answers of the paper's problems, true,
//! perturbed and crafted, are in `certify_answers.rs`.

use contactlab::certificate::{Condition, DEFAULT_TOLERANCE, certify};
use contactlab::solvers::{ContactNode, ContactProblem, Friction, Law, Mass};
use nalgebra_sparse::{CooMatrix, CsrMatrix};

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
