//! The algebraic contact problem: the one boundary between the mechanics and
//! the solvers. It holds matrices and index sets, never a mesh.
//!
//! Discretized paper (10) after the change of variables of section 5, the
//! given-friction (Tresca) problem
//!
//! ```text
//! minimize  ½ vᵀA v − fᵀv + Σ_i w_i g_i |s_i|   subject to  t_i ≤ 0,
//! ```
//!
//! where at contact node i, `t_i = v'_2 − v''_2` is the jump [v] and
//! `s_i = v'_1 − v''_1` the slip, and `w_i` are the trapezoid weights of Γ_K.
//! The Coulomb problem (paper (8)) is the same with g_i = 𝓕_i p_i, p_i the
//! contact pressure of the solution itself. A is symmetric positive
//! semidefinite: the upper body keeps a rigid vertical translation (the
//! problem is semicoercive), given as [`ContactProblem::rigid_modes`]. The
//! mass matrix M gives the L2 norm of the displacement field in the same
//! variables, for the proximal term of paper (15).

use std::sync::atomic::{AtomicU64, Ordering};

use nalgebra_sparse::CsrMatrix;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::linalg::{max_abs, spmv};

/// The unknowns of one contact node of Γ_K.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactNode {
    /// Index of the jump `t_i = v'_2 − v''_2` in the unknown vector.
    pub t: usize,
    /// Index of the slip `s_i = v'_1 − v''_1` in the unknown vector.
    pub s: usize,
    /// Trapezoid weight `w_i` (h inside Γ_K, h/2 at its ends).
    pub weight: f64,
    /// Given friction bound `g_i ≥ 0` per unit length (𝓕 times a pressure)
    /// of the given-friction subproblem.
    pub g: f64,
    /// Coulomb friction coefficient 𝓕_i ≥ 0 of the Coulomb problem.
    pub coefficient: f64,
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
    #[error("contact node {node}: friction coefficient {value} must be finite and ≥ 0")]
    BadCoefficient { node: usize, value: f64 },
    #[error("{what} holds a non-finite value (NaN or infinity)")]
    NonFinite { what: &'static str },
    #[error(
        "rigid mode {index} is not in the kernel of A: ‖A z‖∞ = {residual:.1e} > 1e-9·max A_ii·‖z‖∞"
    )]
    NotAKernel { index: usize, residual: f64 },
    #[error("the problem's {what} scale is {value:e}: {why}")]
    Scale {
        what: &'static str,
        value: f64,
        why: &'static str,
    },
}

/// The problem's own scales, from its data alone. Every stopping test of a
/// solver in relative mode and every measure of the certificate is stated
/// in them, so that multiplying the loads by a factor, or the stiffness and
/// the loads together, changes no iteration count and no verdict.
///
/// - force F = Σ_i |f_i| (for a traction load: ∫|P| ds, whatever the mesh);
/// - length L = Σ_i w_i (the length of Γ_K);
/// - stiffness K = max_i A_ii;
/// - pressure P = F/L (force per unit length of Γ_K);
/// - displacement U = F/K.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scales {
    pub force: f64,
    pub length: f64,
    pub stiffness: f64,
    pub pressure: f64,
    pub displacement: f64,
}

impl Scales {
    fn of(a: &CsrMatrix<f64>, f: &[f64], contacts: &[ContactNode]) -> Result<Self, ProblemError> {
        let or_one = |x: f64| if x > 0.0 { x } else { 1.0 };
        let force = or_one(f.iter().map(|x| x.abs()).sum());
        let length = or_one(contacts.iter().map(|c| c.weight).sum());
        let stiffness = or_one(
            a.row_iter()
                .enumerate()
                .filter_map(|(i, row)| row.get_entry(i).map(|e| e.into_value().abs()))
                .fold(0.0, f64::max),
        );
        let scales = Self {
            force,
            length,
            stiffness,
            pressure: force / length,
            displacement: force / stiffness,
        };
        for (what, value) in [
            ("force", scales.force),
            ("stiffness", scales.stiffness),
            ("pressure", scales.pressure),
            ("displacement", scales.displacement),
        ] {
            if !(value.is_finite() && value.is_normal()) {
                return Err(ProblemError::Scale {
                    what,
                    value,
                    why: "it over- or underflows in double precision; \
                          the loads and the stiffness are too far apart in magnitude",
                });
            }
        }
        Ok(scales)
    }
}

static NEXT_OPERATOR_ID: AtomicU64 = AtomicU64::new(1);

/// The discrete contact problem. It holds matrices and index sets, never a
/// mesh.
#[derive(Clone, Debug)]
pub struct ContactProblem {
    a: CsrMatrix<f64>,
    f: Vec<f64>,
    mass: CsrMatrix<f64>,
    contacts: Vec<ContactNode>,
    rigid_modes: Vec<Vec<f64>>,
    scales: Scales,
    operator_id: u64,
}

impl ContactProblem {
    /// Checks dimensions, symmetry, index sets, finiteness, that each rigid
    /// mode z satisfies A z = 0, and that the scales are representable.
    pub fn new(
        a: CsrMatrix<f64>,
        f: Vec<f64>,
        mass: CsrMatrix<f64>,
        contacts: Vec<ContactNode>,
        rigid_modes: Vec<Vec<f64>>,
    ) -> Result<Self, ProblemError> {
        let n = a.nrows();
        check_stiffness_and_mass(&a, &mass, n)?;
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
            if !(c.coefficient.is_finite() && c.coefficient >= 0.0) {
                return Err(ProblemError::BadCoefficient {
                    node,
                    value: c.coefficient,
                });
            }
        }
        let scales = Scales::of(&a, &f, &contacts)?;
        for (index, z) in rigid_modes.iter().enumerate() {
            if z.len() != n {
                return Err(ProblemError::Dimension {
                    what: "rigid mode",
                    expected: n,
                    got: z.len(),
                });
            }
            let residual = max_abs(&spmv(&a, z));
            let bound = 1e-9 * scales.stiffness * max_abs(z);
            if residual.is_nan() || residual > bound {
                return Err(ProblemError::NotAKernel { index, residual });
            }
        }
        Ok(Self {
            a,
            f,
            mass,
            contacts,
            rigid_modes,
            scales,
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

    /// A basis of the kernel of A (the rigid motions the constraints must
    /// hold): here the upper body's vertical translation, +1 on its vertical
    /// displacements away from Γ_K and −1 on every jump t_i (paper (11)).
    pub fn rigid_modes(&self) -> &[Vec<f64>] {
        &self.rigid_modes
    }

    /// The problem's own scales.
    pub fn scales(&self) -> &Scales {
        &self.scales
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

    /// The friction bounds g_i.
    pub fn friction_bound(&self) -> Vec<f64> {
        self.contacts.iter().map(|c| c.g).collect()
    }

    /// The objective ½ vᵀAv − fᵀv + Σ w_i g_i |s_i| of paper (10).
    pub fn objective(&self, v: &[f64]) -> f64 {
        let av = spmv(&self.a, v);
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

/// Checks that A and M are n × n, finite and symmetric. When they share a
/// pattern (an assembly puts both on one), one pass over it checks both.
fn check_stiffness_and_mass(
    a: &CsrMatrix<f64>,
    mass: &CsrMatrix<f64>,
    n: usize,
) -> Result<(), ProblemError> {
    if a.pattern() == mass.pattern() {
        check_square_symmetric([("A", a), ("M", mass)], n)
    } else {
        check_square_symmetric([("A", a)], n)?;
        check_square_symmetric([("M", mass)], n)
    }
}

/// Checks that each matrix, all on one pattern, is n × n, finite and
/// symmetric to 1e-12 of its largest entry.
///
/// One pass over the pattern measures each matrix's largest entry, its
/// largest asymmetry and whether it is finite; only when a matrix fails is
/// the pattern walked again to name the first offending entry.
fn check_square_symmetric<const K: usize>(
    named: [(&'static str, &CsrMatrix<f64>); K],
    n: usize,
) -> Result<(), ProblemError> {
    for (what, m) in &named {
        for (dim, got) in [(n, m.nrows()), (n, m.ncols())] {
            if dim != got {
                return Err(ProblemError::Dimension {
                    what,
                    expected: dim,
                    got,
                });
            }
        }
    }
    let Some((_, first)) = named.first() else {
        return Ok(());
    };
    let (offsets, indices) = (first.row_offsets(), first.col_indices());
    let values = named.map(|(_, m)| m.values());
    let (mut scale, mut asymmetry, mut finite) = ([0.0f64; K], [0.0f64; K], [true; K]);
    walk_mirrors(offsets, indices, |_, _, k, mirror| {
        for m in 0..K {
            let x = values[m][k];
            finite[m] &= x.is_finite();
            scale[m] = scale[m].max(x.abs());
            let across = mirror.map_or(0.0, |c| values[m][c]);
            asymmetry[m] = asymmetry[m].max((across - x).abs());
        }
        true
    });
    if let Some(m) = (0..K).find(|&m| !finite[m]) {
        return Err(ProblemError::NonFinite { what: named[m].0 });
    }
    let tol = scale.map(|s| 1e-12 * s);
    if (0..K).all(|m| asymmetry[m] <= tol[m]) {
        return Ok(());
    }
    let mut offending = None;
    walk_mirrors(offsets, indices, |row, col, k, mirror| {
        for m in 0..K {
            let across = mirror.map_or(0.0, |c| values[m][c]);
            if (across - values[m][k]).abs() > tol[m] {
                offending = Some(ProblemError::NotSymmetric {
                    what: named[m].0,
                    row,
                    col,
                });
                return false;
            }
        }
        true
    });
    Err(offending.expect("an asymmetry was measured, so an entry exceeds it"))
}

/// Visits each stored (row, col, position) in row order with the position of
/// its mirror (col, row), if stored, until `visit` returns false. The mirror
/// is found by a cursor per row that only moves forward: the rows visiting
/// column `col` come in increasing order, and so do the columns of row
/// `col`. One pass over the pattern, no search (a binary search per entry
/// was a third of the set-up at h = 1/256).
fn walk_mirrors(
    offsets: &[usize],
    indices: &[usize],
    mut visit: impl FnMut(usize, usize, usize, Option<usize>) -> bool,
) {
    let n = offsets.len() - 1;
    let mut cursor = offsets[..n].to_vec();
    for row in 0..n {
        for k in offsets[row]..offsets[row + 1] {
            let col = indices[k];
            let end = offsets[col + 1];
            let mut c = cursor[col];
            while c < end && indices[c] < row {
                c += 1;
            }
            cursor[col] = c;
            let mirror = (c < end && indices[c] == row).then_some(c);
            if !visit(row, col, k, mirror) {
                return;
            }
        }
    }
}

#[cfg(test)]
mod symmetry_tests {
    use super::*;
    use nalgebra_sparse::CooMatrix;

    fn csr(n: usize, entries: &[(usize, usize, f64)]) -> CsrMatrix<f64> {
        let mut coo = CooMatrix::new(n, n);
        for &(i, j, v) in entries {
            coo.push(i, j, v);
        }
        CsrMatrix::from(&coo)
    }

    /// The check must fail naming matrix `what` and entry (row, col).
    fn assert_names(result: Result<(), ProblemError>, what: &str, row: usize, col: usize) {
        match result {
            Err(ProblemError::NotSymmetric {
                what: w,
                row: r,
                col: c,
            }) if (w, r, c) == (what, row, col) => {}
            other => panic!("expected {what}'s ({row}, {col}) to be named, got {other:?}"),
        }
    }

    #[test]
    fn a_symmetric_matrix_passes() {
        let m = csr(
            4,
            &[
                (0, 0, 2.0),
                (0, 3, -1.0),
                (3, 0, -1.0),
                (1, 2, 5.0),
                (2, 1, 5.0),
                (3, 3, 1.0),
            ],
        );
        assert!(check_square_symmetric([("A", &m)], 4).is_ok());
    }

    #[test]
    fn a_differing_mirror_is_named() {
        let m = csr(3, &[(0, 0, 1.0), (0, 2, 1.0), (2, 0, 1.5), (1, 1, 1.0)]);
        assert_names(check_square_symmetric([("A", &m)], 3), "A", 0, 2);
    }

    #[test]
    fn an_entry_without_a_stored_mirror_is_caught() {
        // (2, 1) is stored, (1, 2) is not: only the visit of row 2 sees it.
        let m = csr(3, &[(0, 0, 1.0), (1, 1, 1.0), (2, 1, 0.5), (2, 2, 1.0)]);
        assert_names(check_square_symmetric([("M", &m)], 3), "M", 2, 1);
        // A stored explicit zero mirrors a missing entry.
        let m = csr(3, &[(0, 0, 1.0), (1, 2, 0.0), (2, 2, 1.0)]);
        assert!(check_square_symmetric([("M", &m)], 3).is_ok());
    }

    #[test]
    fn a_pair_on_one_pattern_names_the_matrix_that_fails() {
        let entries = [(0, 0, 1.0), (0, 1, 2.0), (1, 0, 2.0), (1, 1, 1.0)];
        let a = csr(2, &entries);
        let mut m = a.clone();
        m.values_mut()[2] = 2.5; // (1, 0) of M only
        assert!(check_stiffness_and_mass(&a, &a, 2).is_ok());
        assert_names(check_stiffness_and_mass(&a, &m, 2), "M", 0, 1);
        m.values_mut()[2] = f64::NAN;
        assert!(matches!(
            check_stiffness_and_mass(&a, &m, 2),
            Err(ProblemError::NonFinite { what: "M" })
        ));
    }
}
