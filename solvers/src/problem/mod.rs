//! The algebraic contact problem: the one boundary between the mechanics and
//! the solvers. It holds matrices and index sets, never a mesh.
//!
//! Discretized paper (10) after the change of variables of section 5, the
//! given-friction (Tresca) problem
//!
//! ```text
//! minimize  ½ vᵀA v − fᵀv + Σ_i w_i g_i |s_i − σ_i|   subject to  t_i ≤ d_i,
//! ```
//!
//! where at contact node i, `t_i = v'_2 − v''_2` is the jump [v] (the
//! lower body Ω' is primed, the upper Ω'' double-primed, the normal of
//! Γ_K is vertical, so t_i > 0 would move the lower body into the upper),
//! `d_i ≥ 0` the initial gap between them (zero in the paper's scene:
//! [`ContactProblem::gap`]), and
//! `s_i = v'_1 − v''_1` the slip, `σ_i` a prescribed slip offset (zero in
//! the paper's scene: [`ContactProblem::slip_offset`]; a body moved
//! sideways by a rigid lift slips by s_i − σ_i), and `w_i` are the
//! trapezoid weights of Γ_K.
//! The Coulomb problem (paper (8)) is the same with g_i = 𝓕_i p_i, p_i the
//! contact pressure of the solution itself. A is symmetric positive
//! semidefinite: the upper body keeps a rigid vertical translation (the
//! problem is semicoercive), given as [`ContactProblem::rigid_modes`]. The
//! mass matrix M gives the L2 norm of the displacement field in the same
//! variables, for the proximal term of paper (15).

use std::borrow::Cow;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use nalgebra_sparse::CsrMatrix;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::numerics::linalg::{
    Csr, CsrError, IntoCsr, RowValues, max_abs, max_abs_if_finite, spmv, spmv_values_into,
};

mod scales;
mod symmetry;

pub use scales::{MIN_NET_LOAD_FRACTION, Scales, moves_a_jump};
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
    #[error(
        "contact node {node}: gap {value} must be finite and ≥ 0 (an initial distance between the bodies; an initial overlap is not supported)"
    )]
    BadGap { node: usize, value: f64 },
    #[error(
        "the largest gap, {size:e}, is beyond {MAX_GAP_IN_DISPLACEMENTS:e} times the problem's displacement scale U = F/K = {displacement:e}: the loads could not close it, and the problem in the closed unknowns could not be represented; give the gap in the units of the displacements"
    )]
    GapSize { size: f64, displacement: f64 },
    #[error(
        "contact node {node}: slip offset {value} must be finite (the slip s_i − σ_i is what friction acts on)"
    )]
    BadSlipOffset { node: usize, value: f64 },
    #[error(
        "the largest slip offset, {size:e}, is beyond {MAX_GAP_IN_DISPLACEMENTS:e} times the problem's displacement scale U = F/K = {displacement:e}: the problem in the shifted unknowns could not be represented; give the offset in the units of the displacements"
    )]
    SlipOffsetSize { size: f64, displacement: f64 },
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

/// The largest gap, in units of the displacement scale U = F/K: a gap of
/// 1e12 U is never closed by the loads (their displacements are of size U
/// and smaller), and f̃ = f − A D would carry the load in its last digits.
pub const MAX_GAP_IN_DISPLACEMENTS: f64 = 1e12;

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
    /// Shared between clones and with [`ContactProblem::closed`]'s
    /// problem, which differs only in f.
    a: Arc<Csr>,
    f: Vec<f64>,
    mass: Arc<Mass>,
    contacts: Vec<ContactNode>,
    rigid_modes: Arc<Vec<Vec<f64>>>,
    /// The initial gap d_i ≥ 0 per contact node (all zero: a closed start).
    gap: Vec<f64>,
    /// The slip offset σ_i per contact node (all zero: the paper's).
    slip_offset: Vec<f64>,
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
        let gap = vec![0.0; contacts.len()];
        let slip_offset = gap.clone();
        Ok(Self {
            a: Arc::new(a.shared()),
            f,
            mass: Arc::new(mass),
            contacts,
            rigid_modes: Arc::new(rigid_modes),
            gap,
            slip_offset,
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
        match self.mass.as_ref() {
            Mass::Matrix(m) => Some(Cow::Borrowed(m)),
            Mass::OnStiffnessPattern(values) => {
                Some(Cow::Owned(self.a.nalgebra_with_values(values.clone())))
            }
            Mass::Omitted => None,
        }
    }

    /// Whether the problem carries M.
    pub fn has_mass(&self) -> bool {
        !matches!(self.mass.as_ref(), Mass::Omitted)
    }

    /// M's stored values when M lives on A's pattern (in the order of A's
    /// stored entries), so that A + ρM is a sum of values.
    pub fn mass_on_stiffness_pattern(&self) -> Option<&[f64]> {
        match self.mass.as_ref() {
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
        match self.mass.as_ref() {
            Mass::OnStiffnessPattern(values) => {
                spmv_values_into(self.a.as_ref(), values.as_slice(), x, y)
            }
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
        self.rigid_modes.as_slice()
    }

    /// The same problem with the initial gap d_i ≥ 0 at each contact node
    /// (in contact order): the nonpenetration becomes t_i ≤ d_i, the
    /// complementarity p_i (d_i − t_i) = 0 (Johnson, *Contact Mechanics*,
    /// 1985, §4.2 for a curved profile; Kikuchi & Oden, 1988, §2 for the
    /// discrete form). The scales are those of the loads and the stiffness
    /// alone ([`Scales`]), whatever the gap: a problem posed with a gap and
    /// the same problem closed have the same scales, so the certificate's
    /// tolerances do not follow the gap's size.
    pub fn with_gap(mut self, gap: Vec<f64>) -> Result<Self, ProblemError> {
        self.check_per_contact(
            "gap",
            &gap,
            |d| d.is_finite() && d >= 0.0,
            |node, value| ProblemError::BadGap { node, value },
            |size, displacement| ProblemError::GapSize { size, displacement },
        )?;
        self.gap = gap;
        self.operator_id = NEXT_OPERATOR_ID.fetch_add(1, Ordering::Relaxed);
        Ok(self)
    }

    /// The checks of a per-contact offset (a gap, a slip offset): one value
    /// per contact node, each `valid` (else `bad`), and none so large that
    /// the closed problem's load f̃ = f − A D could not be represented
    /// ([`ContactProblem::closed`]; else `too_large`, with U).
    fn check_per_contact(
        &self,
        what: &'static str,
        values: &[f64],
        valid: fn(f64) -> bool,
        bad: fn(usize, f64) -> ProblemError,
        too_large: fn(f64, f64) -> ProblemError,
    ) -> Result<(), ProblemError> {
        if values.len() != self.contacts.len() {
            return Err(ProblemError::Dimension {
                what,
                expected: self.contacts.len(),
                got: values.len(),
            });
        }
        if let Some(node) = values.iter().position(|&x| !valid(x)) {
            return Err(bad(node, values[node]));
        }
        let size = max_abs(values);
        if !(size * self.scales.stiffness).is_finite()
            || size > MAX_GAP_IN_DISPLACEMENTS * self.scales.displacement
        {
            return Err(too_large(size, self.scales.displacement));
        }
        Ok(())
    }

    /// The initial gap d_i ≥ 0 per contact node (all zero unless
    /// [`ContactProblem::with_gap`] set one).
    pub fn gap(&self) -> &[f64] {
        &self.gap
    }

    /// Whether some contact node has a nonzero initial gap.
    pub fn has_gap(&self) -> bool {
        self.gap.iter().any(|&d| d != 0.0)
    }

    /// The same problem with a slip offset σ_i at each contact node (in
    /// contact order): friction acts on s_i − σ_i, the slip past it, in the
    /// bound (paper (7)) and in the objective Σ w_i g_i |s_i − σ_i|. This is
    /// how a body moved sideways by δ is posed without a load: in unknowns
    /// from which its rigid translation δ is taken (a rigid lift, which A
    /// does not see), the load stays the applied one and only the slip
    /// moves, s_i − δ. The scales are those of the loads and the stiffness,
    /// as for a gap ([`ContactProblem::with_gap`]).
    pub fn with_slip_offset(mut self, offset: Vec<f64>) -> Result<Self, ProblemError> {
        self.check_per_contact(
            "slip offset",
            &offset,
            f64::is_finite,
            |node, value| ProblemError::BadSlipOffset { node, value },
            |size, displacement| ProblemError::SlipOffsetSize { size, displacement },
        )?;
        self.slip_offset = offset;
        self.operator_id = NEXT_OPERATOR_ID.fetch_add(1, Ordering::Relaxed);
        Ok(self)
    }

    /// The slip offset σ_i per contact node (all zero unless
    /// [`ContactProblem::with_slip_offset`] set one).
    pub fn slip_offset(&self) -> &[f64] {
        &self.slip_offset
    }

    /// Whether some contact node has a nonzero slip offset.
    pub fn has_slip_offset(&self) -> bool {
        self.slip_offset.iter().any(|&x| x != 0.0)
    }

    /// The jump past the gap, t_i − d_i (≤ 0 when the bodies do not
    /// overlap), of contact node i in `v`.
    #[inline]
    pub fn jump(&self, v: &[f64], i: usize) -> f64 {
        v[self.contacts[i].t] - self.gap[i]
    }

    /// The slip friction acts on, s_i − σ_i, of contact node i in `v`.
    #[inline]
    pub fn slip(&self, v: &[f64], i: usize) -> f64 {
        v[self.contacts[i].s] - self.slip_offset[i]
    }

    /// The gap D as a vector of unknowns: d_i at each jump t_i, 0 elsewhere.
    pub fn gap_vector(&self) -> Vec<f64> {
        let mut d = vec![0.0; self.n()];
        for (c, &gi) in self.contacts.iter().zip(&self.gap) {
            d[c.t] = gi;
        }
        d
    }

    /// The offsets D as a vector of unknowns: d_i at each jump t_i if
    /// `gap`, σ_i at each slip s_i if `slip`, 0 elsewhere.
    pub fn offset_vector(&self, gap: bool, slip: bool) -> Vec<f64> {
        let mut d = if gap {
            self.gap_vector()
        } else {
            vec![0.0; self.n()]
        };
        if slip {
            for (c, &x) in self.contacts.iter().zip(&self.slip_offset) {
                d[c.s] = x;
            }
        }
        d
    }

    /// The same problem in the unknowns ṽ = v − D, whose gap (if `gap`)
    /// and slip offset (if `slip`) are closed: t̃_i = t_i − d_i ≤ 0, s̃_i = s_i − σ_i,
    /// and ½ vᵀAv − fᵀv = ½ ṽᵀAṽ − (f − A D)ᵀṽ + const, so the load is
    /// f̃ = f − A D; the pressures and the frictional tractions are
    /// unchanged. Exact: this is how every solver meets a gap or a slip
    /// offset ([`crate::reduction::gap`]), each solving the problem it was
    /// written for. A, M and the rigid modes are shared, and the scales
    /// are this problem's (a relative stopping test is not loosened by
    /// the large f̃ a gap far from contact gives); the operator id is
    /// kept, so factorizations of A are reused.
    pub fn closed(&self, gap: bool, slip: bool) -> ContactProblem {
        let d = self.offset_vector(gap, slip);
        let ad = spmv(self.a.as_ref(), &d);
        let f = self.f.iter().zip(&ad).map(|(f, ad)| f - ad).collect();
        let zero = vec![0.0; self.contacts.len()];
        ContactProblem {
            a: Arc::clone(&self.a),
            f,
            mass: Arc::clone(&self.mass),
            contacts: self.contacts.clone(),
            rigid_modes: Arc::clone(&self.rigid_modes),
            gap: if gap { zero.clone() } else { self.gap.clone() },
            slip_offset: if slip { zero } else { self.slip_offset.clone() },
            scales: self.scales,
            operator_id: self.operator_id,
            prolongations: Arc::clone(&self.prolongations),
        }
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

    /// The objective ½ vᵀAv − fᵀv + Σ w_i g_i |s_i − σ_i| of paper (10) at
    /// the bound g (one per contact node).
    pub fn objective(&self, v: &[f64], g: &[f64]) -> f64 {
        let av = spmv(self.a.as_ref(), v);
        let quad: f64 = v.iter().zip(&av).map(|(x, y)| x * y).sum::<f64>() * 0.5;
        let lin: f64 = v.iter().zip(&self.f).map(|(x, y)| x * y).sum();
        let fric: f64 = self
            .contacts
            .iter()
            .zip(g)
            .enumerate()
            .map(|(i, (c, g))| c.weight * g * self.slip(v, i).abs())
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

    /// A rigid mode that moves slips alone (a body free to slide) is held
    /// by friction: the load along it may be zero, and it sets no contact
    /// load; a mode that moves a jump with no load along it is refused.
    /// Unknowns (a, t, b, s): A couples a with t and b with s.
    #[test]
    fn a_mode_of_slips_alone_is_held_by_friction_and_sets_no_scale() {
        let pair = |i: usize| {
            [
                (i, i, 1.0),
                (i, i + 1, -1.0),
                (i + 1, i, -1.0),
                (i + 1, i + 1, 1.0),
            ]
        };
        let entries: Vec<_> = pair(0).into_iter().chain(pair(2)).collect();
        let a = csr(4, &entries);
        let contact = ContactNode {
            t: 1,
            s: 3,
            weight: 1.0,
            coefficient: 0.5,
        };
        let normal = vec![1.0, 1.0, 0.0, 0.0];
        let sliding = vec![0.0, 0.0, 1.0, 1.0];
        let problem = |f: Vec<f64>| {
            ContactProblem::new(
                a.clone(),
                f,
                Mass::Omitted,
                vec![contact],
                vec![normal.clone(), sliding.clone()],
            )
        };
        let p = problem(vec![1.0, 2.0, 0.0, 0.0]).unwrap();
        assert!(moves_a_jump(&normal, p.contacts()) && !moves_a_jump(&sliding, p.contacts()));
        assert_eq!(p.scales().contact_load, 3.0);
        // A tangential load along it: still the normal mode's contact load.
        let p = problem(vec![1.0, 2.0, 0.5, 0.0]).unwrap();
        assert_eq!(p.scales().contact_load, 3.0);
        assert!(matches!(
            problem(vec![0.0, 0.0, 0.5, 0.0]),
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
