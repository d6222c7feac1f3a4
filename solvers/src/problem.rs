//! The algebraic given-friction (Tresca) subproblem: the one boundary between
//! the mechanics and the solvers.
//!
//! Discretized paper (10) after the change of variables of section 5:
//!
//! ```text
//! minimize  ½ vᵀA v − fᵀv + Σ_i w_i g_i |s_i|   subject to  t_i ≤ 0,
//! ```
//!
//! where at contact node i, `t_i = v'_2 − v''_2` is the jump [v] and
//! `s_i = v'_1 − v''_1` the slip, and `w_i` are the trapezoid weights of Γ_K.
//! A is symmetric positive semidefinite (the upper body keeps a rigid vertical
//! translation: the problem is semicoercive). The mass matrix M gives the L2
//! norm of the displacement field in the same variables, for the proximal term
//! of paper (15).

use std::sync::atomic::{AtomicU64, Ordering};

use nalgebra_sparse::CsrMatrix;
use thiserror::Error;

/// The unknowns of one contact node of Γ_K.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactNode {
    /// Index of the jump `t_i = v'_2 − v''_2` in the unknown vector.
    pub t: usize,
    /// Index of the slip `s_i = v'_1 − v''_1` in the unknown vector.
    pub s: usize,
    /// Trapezoid weight `w_i` (h inside Γ_K, h/2 at its ends).
    pub weight: f64,
    /// Given friction bound `g_i ≥ 0` per unit length (𝓕 times a pressure).
    pub g: f64,
}

/// A problem that cannot be built as given.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ProblemError {
    #[error("{what} has dimension {got}, expected {expected}")]
    Dimension {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("{what} is not symmetric: entry ({row}, {col}) differs from its transpose")]
    NotSymmetric {
        what: &'static str,
        row: usize,
        col: usize,
    },
    #[error("contact node {node}: index {index} is out of range 0..{n}")]
    IndexOutOfRange { node: usize, index: usize, n: usize },
    #[error("contact node {node}: index {index} is used twice")]
    DuplicateIndex { node: usize, index: usize },
    #[error("contact node {node}: weight {value} must be positive and finite")]
    BadWeight { node: usize, value: f64 },
    #[error("contact node {node}: friction bound g = {value} must be finite and ≥ 0")]
    BadFrictionBound { node: usize, value: f64 },
    #[error("{what} holds a non-finite value (NaN or infinity)")]
    NonFinite { what: &'static str },
}

static NEXT_OPERATOR_ID: AtomicU64 = AtomicU64::new(1);

/// The discrete given-friction subproblem. It holds matrices and index sets,
/// never a mesh.
#[derive(Clone, Debug)]
pub struct GivenFrictionProblem {
    a: CsrMatrix<f64>,
    f: Vec<f64>,
    mass: CsrMatrix<f64>,
    contacts: Vec<ContactNode>,
    operator_id: u64,
}

impl GivenFrictionProblem {
    /// Checks dimensions, symmetry, index sets and finiteness.
    pub fn new(
        a: CsrMatrix<f64>,
        f: Vec<f64>,
        mass: CsrMatrix<f64>,
        contacts: Vec<ContactNode>,
    ) -> Result<Self, ProblemError> {
        let n = a.nrows();
        check_square_symmetric("A", &a, n)?;
        check_square_symmetric("M", &mass, n)?;
        if f.len() != n {
            return Err(ProblemError::Dimension {
                what: "f",
                expected: n,
                got: f.len(),
            });
        }
        if f.iter().any(|x| !x.is_finite()) {
            return Err(ProblemError::NonFinite { what: "f" });
        }
        let mut used = vec![false; n];
        for (node, c) in contacts.iter().enumerate() {
            for index in [c.t, c.s] {
                if index >= n {
                    return Err(ProblemError::IndexOutOfRange { node, index, n });
                }
                if std::mem::replace(&mut used[index], true) {
                    return Err(ProblemError::DuplicateIndex { node, index });
                }
            }
            if !(c.weight.is_finite() && c.weight > 0.0) {
                return Err(ProblemError::BadWeight {
                    node,
                    value: c.weight,
                });
            }
            check_g(node, c.g)?;
        }
        Ok(Self {
            a,
            f,
            mass,
            contacts,
            operator_id: NEXT_OPERATOR_ID.fetch_add(1, Ordering::Relaxed),
        })
    }

    /// Number of unknowns.
    pub fn n(&self) -> usize {
        self.f.len()
    }

    /// The stiffness matrix A in the (v', t, s) variables (full symmetric storage).
    pub fn a(&self) -> &CsrMatrix<f64> {
        &self.a
    }

    /// The load vector f.
    pub fn f(&self) -> &[f64] {
        &self.f
    }

    /// The consistent mass matrix M (L2 inner product of displacement fields).
    pub fn mass(&self) -> &CsrMatrix<f64> {
        &self.mass
    }

    /// Contact nodes of Γ_K in increasing x.
    pub fn contacts(&self) -> &[ContactNode] {
        &self.contacts
    }

    /// Identifies A and M: it changes only when a problem is built, not when
    /// the friction bound changes, so solvers may keep factorizations keyed by it.
    pub fn operator_id(&self) -> u64 {
        self.operator_id
    }

    /// Sets the friction bounds g_i (one per contact node, each finite and ≥ 0):
    /// the step g^{m+1} = 𝓕 p(u^m) of the successive approximations, paper (9).
    pub fn set_friction_bound(&mut self, g: &[f64]) -> Result<(), ProblemError> {
        if g.len() != self.contacts.len() {
            return Err(ProblemError::Dimension {
                what: "friction bound g",
                expected: self.contacts.len(),
                got: g.len(),
            });
        }
        for (node, &value) in g.iter().enumerate() {
            check_g(node, value)?;
        }
        for (c, &value) in self.contacts.iter_mut().zip(g) {
            c.g = value;
        }
        Ok(())
    }

    /// The objective ½ vᵀAv − fᵀv + Σ w_i g_i |s_i| of paper (10).
    pub fn objective(&self, v: &[f64]) -> f64 {
        let av = crate::linalg::spmv(&self.a, v);
        let quad: f64 = v.iter().zip(&av).map(|(x, y)| x * y).sum::<f64>() * 0.5;
        let lin: f64 = v.iter().zip(&self.f).map(|(x, y)| x * y).sum();
        let fric: f64 = self
            .contacts
            .iter()
            .map(|c| c.weight * c.g * v[c.s].abs())
            .sum();
        quad - lin + fric
    }
}

fn check_g(node: usize, value: f64) -> Result<(), ProblemError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(ProblemError::BadFrictionBound { node, value })
    }
}

fn check_square_symmetric(
    what: &'static str,
    m: &CsrMatrix<f64>,
    n: usize,
) -> Result<(), ProblemError> {
    for (dim, got) in [(n, m.nrows()), (n, m.ncols())] {
        if dim != got {
            return Err(ProblemError::Dimension {
                what,
                expected: dim,
                got,
            });
        }
    }
    if m.values().iter().any(|x| !x.is_finite()) {
        return Err(ProblemError::NonFinite { what });
    }
    let scale = m.values().iter().fold(0.0f64, |s, x| s.max(x.abs()));
    let tol = 1e-12 * scale;
    for (row, col, &value) in m.triplet_iter() {
        let mirror = m.get_entry(col, row).map(|e| e.into_value()).unwrap_or(0.0);
        if (mirror - value).abs() > tol {
            return Err(ProblemError::NotSymmetric { what, row, col });
        }
    }
    Ok(())
}
