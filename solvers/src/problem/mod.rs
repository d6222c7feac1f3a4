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

use std::borrow::Cow;
use std::sync::atomic::{AtomicU64, Ordering};

use nalgebra_sparse::CsrMatrix;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::numerics::linalg::{
    Csr, CsrError, IntoCsr, RowValues, max_abs, max_abs_if_finite, spmv, spmv_values_into,
};

mod scales;
mod symmetry;

pub use scales::{MIN_NET_LOAD_FRACTION, Scales};
use symmetry::check_stiffness_and_mass;

/// The unknowns of one contact node of Γ_K.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactNode {
    /// Index of the jump `t_i = v'_2 − v''_2` in the unknown vector.
    pub t: usize,
    /// Index of the slip `s_i = v'_1 − v''_1` in the unknown vector.
    pub s: usize,
    /// Trapezoid weight `w_i` (h inside Γ_K, h/2 at its ends).
    pub weight: f64,
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
    #[error("contact node {node}: friction coefficient {value} must be finite and ≥ 0")]
    BadCoefficient { node: usize, value: f64 },
    #[error("{what} holds a non-finite value (NaN or infinity)")]
    NonFinite { what: &'static str },
    #[error(
        "rigid mode {index} is not in the kernel of A: ‖A z‖∞/‖z‖∞ = {residual:.1e} > 1e-9·max A_ii"
    )]
    NotAKernel { index: usize, residual: f64 },
    #[error(
        "rigid mode {index} holds a non-finite value or is zero: give a nonzero kernel vector of A"
    )]
    BadRigidMode { index: usize },
    #[error(
        "the load along rigid mode {index} is {fraction:.1e} of the gross load Σ|f|, below {MIN_NET_LOAD_FRACTION:e}: \
         the contact forces must carry it (condition (13)), and a load so nearly balanced cannot be certified in double precision"
    )]
    NetLoad { index: usize, fraction: f64 },
    #[error("A: {0}")]
    Stiffness(#[from] CsrError),
    #[error(
        "the problem has no contact node: give at least one (t, s, weight, coefficient); without contact there is no contact problem"
    )]
    NoContact,
    #[error(
        "A's diagonal entry ({index}, {index}) is {value:e}: a positive semidefinite A whose kernel is the rigid modes has a positive diagonal (is A negated, or an unknown unused?)"
    )]
    Diagonal { index: usize, value: f64 },
    #[error(
        "rigid mode {index} is a combination of the modes before it: give each rigid motion once (a basis of A's kernel)"
    )]
    DependentRigidModes { index: usize },
    #[error(
        "the load along rigid mode {index} ({load:e}) cannot be carried by the contact: it pulls the body off Γ_K, where pressures p ≥ 0 can only push (paper condition (13)); reverse the load or give the rigid mode of a body that is held"
    )]
    LiftsOff { index: usize, load: f64 },
    #[error("the problem's {what} scale is {value:e}: {why}")]
    Scale {
        what: &'static str,
        value: f64,
        why: &'static str,
    },
}

/// Every diagonal entry of A positive: necessary for A ⪰ 0 with no kernel
/// beyond the rigid modes (A_ii = e_iᵀA e_i, and e_i is in no rigid mode's
/// span unless the mode is e_i itself, which a stiffness never has). It
/// catches a negated or indefinite A at the cost of one pass; the full
/// check, a Cholesky factorization with the modes pinned, is the
/// certificate's (`contactlab::certificate::problem_checks`).
fn check_diagonal(a: &Csr) -> Result<(), ProblemError> {
    for i in 0..a.nrows() {
        let (cols, vals) = a.row(i);
        let value = cols.find(i).map_or(0.0, |k| vals[k]);
        if value.is_nan() || value <= 0.0 {
            return Err(ProblemError::Diagonal { index: i, value });
        }
    }
    Ok(())
}

/// The rigid modes linearly independent: Gram–Schmidt on them, each
/// refused if less than 1e-8 of it is left after the earlier ones are taken
/// off (a mode given twice, or as a sum of two others).
fn check_independent(modes: &[Vec<f64>]) -> Result<(), ProblemError> {
    let mut basis: Vec<Vec<f64>> = Vec::new();
    for (index, z) in modes.iter().enumerate() {
        let size = max_abs(z);
        let mut w: Vec<f64> = z.iter().map(|x| x / size).collect();
        let norm = w.iter().map(|x| x * x).sum::<f64>().sqrt();
        for b in &basis {
            let along: f64 = w.iter().zip(b).map(|(x, y)| x * y).sum();
            w.iter_mut().zip(b).for_each(|(x, y)| *x -= along * y);
        }
        let left = w.iter().map(|x| x * x).sum::<f64>().sqrt();
        if left.is_nan() || left <= 1e-8 * norm {
            return Err(ProblemError::DependentRigidModes { index });
        }
        w.iter_mut().for_each(|x| *x /= left);
        basis.push(w);
    }
    Ok(())
}

/// Paper condition (13), the solvability of the semicoercive problem: the
/// load along each rigid mode z must be one the contact forces can carry,
/// zᵀf = Σ_i w_i (p_i z_{t_i} − q_i z_{s_i}) with p_i ≥ 0. A node can give
/// a positive share if z_{t_i} > 0 or z_{s_i} ≠ 0 (friction, of either
/// sign), a negative one if z_{t_i} < 0 or z_{s_i} ≠ 0; a load of a sign
/// no node can give lifts the body off, and no solution exists (the
/// energy is unbounded below along z).
fn check_carried(
    f: &[f64],
    contacts: &[ContactNode],
    modes: &[Vec<f64>],
) -> Result<(), ProblemError> {
    for (index, z) in modes.iter().enumerate() {
        let size = max_abs(z);
        let load: f64 = z.iter().zip(f).map(|(zk, fk)| (zk / size) * fk).sum();
        let (mut up, mut down) = (false, false);
        for c in contacts {
            let (zt, zs) = (z[c.t], z[c.s]);
            up |= zt > 0.0 || zs != 0.0;
            down |= zt < 0.0 || zs != 0.0;
        }
        if (load > 0.0 && !up) || (load < 0.0 && !down) {
            return Err(ProblemError::LiftsOff { index, load });
        }
    }
    Ok(())
}

static NEXT_OPERATOR_ID: AtomicU64 = AtomicU64::new(1);

/// Whether M has exactly A's pattern.
fn on_pattern_of(m: &CsrMatrix<f64>, a: &Csr) -> bool {
    m.nrows() == a.nrows()
        && m.ncols() == a.ncols()
        && m.row_offsets()
            .iter()
            .copied()
            .eq(a.row_offsets().iter().map(|&o| o as usize))
        && (0..a.nrows()).all(|i| {
            let (lo, hi) = a.row_range(i);
            m.col_indices()[lo..hi]
                .iter()
                .copied()
                .eq(a.row_columns(i).iter())
        })
}

/// The mass matrix M as a problem is given it.
///
/// An assembly that puts A and M on one pattern hands over M's values alone,
/// so that the problem keeps one pattern: a second copy is about 230 MB at
/// h = 1/1024, and writing it was a quarter of a 1/64 assembly's page faults.
/// A matrix given on exactly A's pattern is kept the same way.
#[derive(Clone, Debug)]
pub enum Mass {
    /// M's stored values in the order of A's stored entries.
    OnStiffnessPattern(Vec<f64>),
    /// M with a pattern of its own.
    Matrix(CsrMatrix<f64>),
    /// No M: the problem was built for a solver that does not read it
    /// ([`crate::entry::Entry::uses_mass`]). M's values are a third of an
    /// assembled problem (235 MB at h = 1/1024).
    Omitted,
}

impl From<CsrMatrix<f64>> for Mass {
    fn from(m: CsrMatrix<f64>) -> Self {
        Mass::Matrix(m)
    }
}

/// The discrete contact problem. It holds matrices and index sets, never a
/// mesh.
#[derive(Clone, Debug)]
pub struct ContactProblem {
    a: Csr,
    f: Vec<f64>,
    mass: Mass,
    contacts: Vec<ContactNode>,
    rigid_modes: Vec<Vec<f64>>,
    scales: Scales,
    operator_id: u64,
    /// Prolongations of a nested hierarchy, coarse to fine, the last onto
    /// these unknowns (empty: no hierarchy). Shared between clones.
    prolongations: std::sync::Arc<[Csr]>,
}

impl ContactProblem {
    /// Checks dimensions, symmetry, index sets, finiteness, that each rigid
    /// mode z is finite, nonzero and satisfies A z = 0, that the load along
    /// it is at least [`MIN_NET_LOAD_FRACTION`] of the gross load, and that
    /// the scales are representable.
    /// M is a matrix or its values on A's pattern ([`Mass`]); a matrix on
    /// exactly A's pattern is kept as its values. A is kept with 32-bit
    /// column indices ([`Csr`]); a nalgebra matrix is converted; its
    /// distinct rows are kept once when they are few ([`Csr::shared`]: the
    /// same numbers to the bit, without 8 bytes per entry).
    pub fn new(
        a: impl IntoCsr,
        f: Vec<f64>,
        mass: impl Into<Mass>,
        contacts: Vec<ContactNode>,
        rigid_modes: Vec<Vec<f64>>,
    ) -> Result<Self, ProblemError> {
        Self::build(a, f, mass, contacts, rigid_modes, true)
    }

    /// As [`ContactProblem::new`] without the checks that the problem has
    /// a solution (a positive diagonal, condition (13)): only to show what
    /// a solver does with a problem that has none (the stability map, the
    /// solvers' stress tests). Everything else goes through `new`.
    pub fn without_solvability_checks(
        a: impl IntoCsr,
        f: Vec<f64>,
        mass: impl Into<Mass>,
        contacts: Vec<ContactNode>,
        rigid_modes: Vec<Vec<f64>>,
    ) -> Result<Self, ProblemError> {
        Self::build(a, f, mass, contacts, rigid_modes, false)
    }

    fn build(
        a: impl IntoCsr,
        f: Vec<f64>,
        mass: impl Into<Mass>,
        contacts: Vec<ContactNode>,
        rigid_modes: Vec<Vec<f64>>,
        solvable: bool,
    ) -> Result<Self, ProblemError> {
        let a = a.into_csr()?;
        let n = a.nrows();
        let mass = match mass.into() {
            Mass::Matrix(m) if on_pattern_of(&m, &a) => Mass::OnStiffnessPattern(m.disassemble().2),
            other => other,
        };
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
        if contacts.is_empty() {
            return Err(ProblemError::NoContact);
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
            if !(c.coefficient.is_finite() && c.coefficient >= 0.0) {
                return Err(ProblemError::BadCoefficient {
                    node,
                    value: c.coefficient,
                });
            }
        }
        for (index, z) in rigid_modes.iter().enumerate() {
            if z.len() != n {
                return Err(ProblemError::Dimension {
                    what: "rigid mode",
                    expected: n,
                    got: z.len(),
                });
            }
            if !max_abs_if_finite(z).is_some_and(|m| m > 0.0) {
                return Err(ProblemError::BadRigidMode { index });
            }
        }
        if solvable {
            check_diagonal(&a)?;
        }
        check_independent(&rigid_modes)?;
        let scales = Scales::of(&a, &f, &contacts, &rigid_modes)?;
        if solvable {
            check_carried(&f, &contacts, &rigid_modes)?;
        }
        for (index, z) in rigid_modes.iter().enumerate() {
            // In units of z's largest entry, so that no product overflows.
            let size = max_abs(z);
            let unit: Vec<f64> = z.iter().map(|zk| zk / size).collect();
            let residual = max_abs_if_finite(&spmv(&a, &unit)).unwrap_or(f64::INFINITY);
            if residual > 1e-9 * scales.stiffness {
                return Err(ProblemError::NotAKernel { index, residual });
            }
        }
        Ok(Self {
            a: a.shared(),
            f,
            mass,
            contacts,
            rigid_modes,
            scales,
            operator_id: NEXT_OPERATOR_ID.fetch_add(1, Ordering::Relaxed),
            prolongations: std::sync::Arc::from(Vec::new()),
        })
    }

    /// The same problem with a hierarchy of nested spaces for multigrid
    /// solvers: `prolongations[l]` maps the unknowns of level l to those of
    /// level l + 1, the last onto this problem's unknowns. Plain matrices:
    /// the mechanics builds them, no solver sees a mesh. Checked: chained
    /// dimensions, finite entries. Their distinct rows kept once where they are few, like A's.
    pub fn with_hierarchy(
        mut self,
        prolongations: Vec<impl IntoCsr>,
    ) -> Result<Self, ProblemError> {
        let prolongations = prolongations
            .into_iter()
            .map(|p| p.into_csr().map(Csr::shared))
            .collect::<Result<Vec<Csr>, CsrError>>()?;
        let mut expected = self.n();
        for p in prolongations.iter().rev() {
            if p.nrows() != expected {
                return Err(ProblemError::Dimension {
                    what: "prolongation",
                    expected,
                    got: p.nrows(),
                });
            }
            if p.values().max_abs_if_finite().is_none() {
                return Err(ProblemError::NonFinite {
                    what: "prolongation",
                });
            }
            expected = p.ncols();
        }
        self.prolongations = prolongations.into();
        Ok(self)
    }

    /// The hierarchy's prolongations, coarse to fine (empty without one).
    pub fn prolongations(&self) -> &[Csr] {
        &self.prolongations
    }

    /// Number of unknowns.
    pub fn n(&self) -> usize {
        self.f.len()
    }

    /// The stiffness matrix A in the (v', t, s) variables (full symmetric
    /// storage, 32-bit column indices).
    pub fn a(&self) -> &Csr {
        &self.a
    }

    /// The load vector f.
    pub fn f(&self) -> &[f64] {
        &self.f
    }

    /// The consistent mass matrix M (L2 inner product of displacement
    /// fields); None if the problem was built without it ([`Mass::Omitted`]).
    /// When M lives on A's pattern this builds the matrix, a copy of A's
    /// pattern: for products use [`ContactProblem::mass_times_into`].
    pub fn mass(&self) -> Option<Cow<'_, CsrMatrix<f64>>> {
        match &self.mass {
            Mass::Matrix(m) => Some(Cow::Borrowed(m)),
            Mass::OnStiffnessPattern(values) => {
                Some(Cow::Owned(self.a.nalgebra_with_values(values.clone())))
            }
            Mass::Omitted => None,
        }
    }

    /// Whether the problem carries M.
    pub fn has_mass(&self) -> bool {
        !matches!(self.mass, Mass::Omitted)
    }

    /// M's stored values when M lives on A's pattern (in the order of A's
    /// stored entries), so that A + ρM is a sum of values.
    pub fn mass_on_stiffness_pattern(&self) -> Option<&[f64]> {
        match &self.mass {
            Mass::OnStiffnessPattern(values) => Some(values),
            Mass::Matrix(_) | Mass::Omitted => None,
        }
    }

    /// y = M x into a caller's buffer, without building M. A solver that
    /// reads M checks [`ContactProblem::has_mass`] first.
    ///
    /// # Panics
    /// If the problem was built without M.
    pub(crate) fn mass_times_into(&self, x: &[f64], y: &mut [f64]) {
        match &self.mass {
            Mass::OnStiffnessPattern(values) => spmv_values_into(&self.a, values.as_slice(), x, y),
            Mass::Matrix(m) => crate::numerics::linalg::spmv_into(m, x, y),
            Mass::Omitted => panic!("M x on a problem built without M"),
        }
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
    pub(crate) fn operator_id(&self) -> u64 {
        self.operator_id
    }

    /// The total contact force Σ w_i p_i of the nodal pressures `pressure`
    /// (one per contact node): the load it balances, in force balance.
    pub fn total_contact_force(&self, pressure: &[f64]) -> f64 {
        self.contacts
            .iter()
            .zip(pressure)
            .map(|(c, p)| c.weight * p)
            .sum()
    }

    /// The objective ½ vᵀAv − fᵀv + Σ w_i g_i |s_i| of paper (10) at the
    /// bound g (one per contact node).
    pub fn objective(&self, v: &[f64], g: &[f64]) -> f64 {
        let av = spmv(&self.a, v);
        let quad: f64 = v.iter().zip(&av).map(|(x, y)| x * y).sum::<f64>() * 0.5;
        let lin: f64 = v.iter().zip(&self.f).map(|(x, y)| x * y).sum();
        let fric: f64 = self
            .contacts
            .iter()
            .zip(g)
            .map(|(c, g)| c.weight * g * v[c.s].abs())
            .sum();
        quad - lin + fric
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::CooMatrix;

    fn csr(n: usize, entries: &[(usize, usize, f64)]) -> CsrMatrix<f64> {
        let mut coo = CooMatrix::new(n, n);
        for &(i, j, v) in entries {
            coo.push(i, j, v);
        }
        CsrMatrix::from(&coo)
    }

    /// A's pattern with M's values.
    fn on_a(m: &CsrMatrix<f64>) -> Mass {
        Mass::OnStiffnessPattern(m.values().to_vec())
    }

    /// A rigid mode must be finite and nonzero (an inf entry or all zeros
    /// once passed the kernel check, and the balance along it was never
    /// measured), and the load along it must be a fraction of the gross
    /// load that rounding cannot produce.
    #[test]
    fn rigid_modes_must_be_real_kernel_vectors_that_carry_a_load() {
        // A = [[1, -1], [-1, 1]]: kernel (1, 1).
        let a = csr(2, &[(0, 0, 1.0), (0, 1, -1.0), (1, 0, -1.0), (1, 1, 1.0)]);
        let m = csr(2, &[(0, 0, 1.0), (1, 1, 1.0)]);
        let contact = ContactNode {
            t: 0,
            s: 1,
            weight: 1.0,
            coefficient: 0.0,
        };
        let problem = |f: Vec<f64>, z: Vec<f64>| {
            ContactProblem::new(
                a.clone(),
                f,
                Mass::Matrix(m.clone()),
                vec![contact],
                vec![z],
            )
        };
        let p = problem(vec![1.0, 2.0], vec![1.0, 1.0]).unwrap();
        assert_eq!(p.scales().contact_load, 3.0);
        assert_eq!(p.scales().pressure, 3.0);
        assert_eq!(p.scales().force, 3.0);
        // The net load, not the gross: (1 − 0.5)/1 along z.
        let p = problem(vec![1.0, -0.5], vec![2.0, 2.0]).unwrap();
        assert_eq!(p.scales().contact_load, 0.5);
        assert_eq!(p.scales().force, 1.5);
        for z in [
            vec![f64::INFINITY, 1.0],
            vec![0.0, 0.0],
            vec![f64::NAN, 1.0],
        ] {
            assert!(
                matches!(
                    problem(vec![1.0, 2.0], z.clone()),
                    Err(ProblemError::BadRigidMode { index: 0 })
                ),
                "{z:?}"
            );
        }
        // Huge but finite: checked in units of its largest entry.
        assert!(problem(vec![1.0, 2.0], vec![1e308, 1e308]).is_ok());
        assert!(matches!(
            problem(vec![1.0, 2.0], vec![1e308, -1e308]),
            Err(ProblemError::NotAKernel { .. })
        ));
        assert!(matches!(
            problem(vec![1.0, -1.0 + 1e-12], vec![1.0, 1.0]),
            Err(ProblemError::NetLoad { index: 0, .. })
        ));
    }

    /// M given on A's pattern, or as a matrix on exactly that pattern (kept
    /// as its values), or on a pattern of its own: `mass()` gives back the
    /// same matrix and `mass_times_into` the same product either way.
    #[test]
    fn the_mass_acts_alike_however_it_is_given() {
        let a = csr(2, &[(0, 0, 2.0), (0, 1, -1.0), (1, 0, -1.0), (1, 1, 2.0)]);
        let on_pattern = csr(2, &[(0, 0, 0.5), (0, 1, 0.25), (1, 0, 0.25), (1, 1, 0.5)]);
        let own = csr(2, &[(0, 0, 0.5), (1, 1, 0.5)]);
        let contact = ContactNode {
            t: 0,
            s: 1,
            weight: 1.0,
            coefficient: 0.0,
        };
        let problem = |m: Mass| {
            ContactProblem::new(a.clone(), vec![1.0, 0.0], m, vec![contact], vec![]).unwrap()
        };
        let x = [3.0, -1.0];
        for (m, shares) in [
            (on_a(&on_pattern), true),
            (Mass::Matrix(on_pattern.clone()), true),
            (Mass::Matrix(own.clone()), false),
        ] {
            let expected = if shares { &on_pattern } else { &own };
            let p = problem(m);
            assert_eq!(p.mass_on_stiffness_pattern().is_some(), shares);
            assert_eq!(p.mass().unwrap().csr_data(), expected.csr_data());
            let mut y = [0.0; 2];
            p.mass_times_into(&x, &mut y);
            assert_eq!(y.to_vec(), spmv(expected, &x));
        }
    }
}
