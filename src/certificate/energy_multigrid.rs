//! The certificate's own solve with the stiffness A in O(n) memory and
//! O(n) work per step, for the error bound on fine meshes (issue 75):
//! conjugate gradients preconditioned by one symmetric V-cycle on the
//! Galerkin hierarchy of the problem's nested meshes (Hackbusch,
//! *Multi-Grid Methods and Applications*, 1985, ch. 2-3; as a
//! preconditioner, Braess, *Finite Elements*, ch. V.3; Saad, *Iterative
//! Methods for Sparse Linear Systems*, 2003, Alg. 9.1 for PCG).
//!
//! It takes only the problem's matrices (A and its prolongations, built by
//! the mechanics) and shares no code with the solvers crate: the coarse
//! operators P_lᵀ A_{l+1} P_l are formed here by nalgebra-sparse, the
//! smoother is forward Gauss-Seidel before the coarse correction and
//! backward after it, and the coarsest level is solved by its dense
//! pseudo-inverse (faer's symmetric eigendecomposition; the rigid mode
//! survives on every level). That V-cycle is a symmetric positive
//! definite operator whenever A ⪰ 0 with a positive diagonal (the
//! symmetrized Gauss-Seidel part M⁻ᵀ(M + Mᵀ − A)M⁻¹ = M⁻ᵀ D M⁻¹ is
//! definite, the coarse part semidefinite), Galerkin or not, so it is a
//! valid preconditioner for the pinned systems too.
//!
//! Two systems are solved, as by the factorization ([`super::energy_solve`]):
//! - A y = b for b ⟂ z (the semicoercive A is singular but the system
//!   consistent): b is made orthogonal to the rigid mode, and so is each
//!   preconditioned residual (the projected preconditioner Q B Q is
//!   definite on z^⊥), so that y gathers no drift along z;
//! - A_FF y_F = b_F with the unknowns of a mask held at zero (the contact
//!   unknowns, for the least-energy extension): the finest level's sweeps
//!   skip them and its restriction and prolongation are masked.
//!
//! A solve is accurate to the relative residual asked of it; what matters
//! is not its own stopping test: the error bound refines the answer once
//! with a residual summed in twice the working precision and counts the
//! refinement's change ([`super::error_bound`]), as it does for the
//! factorization. The preconditioner can only slow the solve, never change
//! the value it converges to: the products that define it are A's own.

use std::sync::Arc;

use faer::{Mat, Side};
use nalgebra_sparse::CsrMatrix;

use contactlab_solvers::ContactProblem;

use super::energy_solve::EnergySolveError;

/// The largest coarsest level solved by a dense pseudo-inverse.
pub const MAX_COARSEST: usize = 3000;

/// Conjugate-gradient steps before a solve is given up.
pub const MAX_STEPS: usize = 400;

/// Eigenvalues of the coarsest level below this times its largest are
/// taken as its kernel (the rigid mode, zero up to rounding).
const KERNEL: f64 = 1e-10;

/// One level: its operator and the inverse of its diagonal.
struct Level {
    a: CsrMatrix<f64>,
    inverse_diagonal: Vec<f64>,
}

/// The Galerkin hierarchy, coarse (0) to fine, with the coarsest level's
/// pseudo-inverse.
struct Hierarchy {
    levels: Vec<Level>,
    /// `prolongations[l]`: level l → level l + 1, and its transpose.
    prolongations: Vec<CsrMatrix<f64>>,
    restrictions: Vec<CsrMatrix<f64>>,
    /// Dense, row-major.
    coarsest: Vec<f64>,
}

/// Each level's right-hand side, iterate and residual, allocated once.
struct Scratch {
    rhs: Vec<f64>,
    x: Vec<f64>,
    residual: Vec<f64>,
}

/// A x = b by preconditioned conjugate gradients (module doc).
pub struct MultigridSolve {
    hierarchy: Arc<Hierarchy>,
    /// The finest unknowns held at zero (the pinned system), if any.
    mask: Option<Vec<bool>>,
    /// The rigid mode, normalized, that b and every preconditioned
    /// residual are made orthogonal to (the singular system only).
    mode: Option<Vec<f64>>,
}

impl MultigridSolve {
    /// The solve with A for b ⟂ z, if the problem has a hierarchy whose
    /// coarsest level is at most [`MAX_COARSEST`] unknowns (None
    /// otherwise), refusing before it allocates the hierarchy if that would
    /// take more than `room` bytes.
    pub fn new(problem: &ContactProblem, room: f64) -> Option<Result<Self, EnergySolveError>> {
        let coarsest = problem.prolongations().first()?.ncols();
        if coarsest > MAX_COARSEST {
            return None;
        }
        let need = Self::bytes(problem);
        if need > room {
            return Some(Err(EnergySolveError::TooLarge {
                need: need / 1e9,
                room: room / 1e9,
            }));
        }
        let hierarchy = match Hierarchy::new(problem) {
            Ok(h) => h,
            Err(e) => return Some(Err(e)),
        };
        let mode = problem.rigid_modes().first().map(|z| {
            let norm = z.iter().map(|x| x * x).sum::<f64>().sqrt();
            z.iter().map(|x| x / norm).collect()
        });
        Some(Ok(Self {
            hierarchy: Arc::new(hierarchy),
            mask: None,
            mode,
        }))
    }

    /// The same hierarchy for the system with the unknowns `pinned` held
    /// at zero.
    pub fn pinned(&self, pinned: &[usize]) -> Self {
        let n = self.hierarchy.levels.last().map_or(0, |l| l.a.nrows());
        let mut mask = vec![false; n];
        for &k in pinned {
            mask[k] = true;
        }
        Self {
            hierarchy: Arc::clone(&self.hierarchy),
            mask: Some(mask),
            mode: None,
        }
    }

    /// An estimate of the bytes the hierarchy takes: A's copy, the coarse
    /// levels (at most about half of it on nested 2D meshes, their
    /// stencils a little wider), the prolongations twice, and the vectors
    /// of the bound and of a solve on each core (about 32 per unknown).
    pub fn bytes(problem: &ContactProblem) -> f64 {
        let entry = 16.0;
        let a = entry * problem.a().nnz() as f64;
        let p: f64 = problem
            .prolongations()
            .iter()
            .map(|p| entry * p.nnz() as f64)
            .sum();
        1.6 * a + 2.0 * p + 8.0 * 32.0 * problem.n() as f64
    }

    /// y with A y = b (y_F for the pinned system, zero on the mask) to a
    /// residual ‖b − A y‖ ≤ `relative`·‖b‖. Its vectors are its own (one
    /// set per call, none per step), so that several solves may run at
    /// once.
    pub fn solve(&self, b: &[f64], relative: f64) -> Result<Vec<f64>, EnergySolveError> {
        let n = b.len();
        let mut scratch: Vec<Scratch> = self
            .hierarchy
            .levels
            .iter()
            .map(|l| Scratch {
                rhs: vec![0.0; l.a.nrows()],
                x: vec![0.0; l.a.nrows()],
                residual: vec![0.0; l.a.nrows()],
            })
            .collect();
        let mut r = b.to_vec();
        self.restrict_to_space(&mut r);
        let target = relative * norm(&r);
        let mut y = vec![0.0; n];
        if target == 0.0 || !target.is_finite() {
            return Ok(y);
        }
        let mut z = vec![0.0; n];
        self.precondition(&r, &mut z, &mut scratch);
        let mut p = z.clone();
        let mut ap = vec![0.0; n];
        let mut rz = dot(&r, &z);
        for _ in 0..MAX_STEPS {
            self.apply(&p, &mut ap);
            let curvature = dot(&p, &ap);
            if curvature.is_nan() || curvature <= 0.0 || rz.is_nan() || rz <= 0.0 {
                break;
            }
            let alpha = rz / curvature;
            axpy(alpha, &p, &mut y);
            axpy(-alpha, &ap, &mut r);
            if norm(&r) <= target {
                return Ok(y);
            }
            self.precondition(&r, &mut z, &mut scratch);
            let rz_next = dot(&r, &z);
            let beta = rz_next / rz;
            rz = rz_next;
            p.iter_mut()
                .zip(&z)
                .for_each(|(pk, zk)| *pk = zk + beta * *pk);
        }
        Err(EnergySolveError::NotConverged {
            steps: MAX_STEPS,
            residual: norm(&r) / (target / relative),
        })
    }

    /// b made to lie in the space solved in: zero on the mask, or
    /// orthogonal to the rigid mode.
    fn restrict_to_space(&self, x: &mut [f64]) {
        zero_on(self.mask.as_deref(), x);
        if let Some(z) = &self.mode {
            let c = dot(x, z);
            axpy(-c, z, x);
        }
    }

    /// out = A x (masked rows zero).
    fn apply(&self, x: &[f64], out: &mut [f64]) {
        let fine = &self.hierarchy.levels.last().expect("a level").a;
        multiply(fine, x, out);
        zero_on(self.mask.as_deref(), out);
    }

    /// out = Q B Q r: one V-cycle, in the space solved in.
    fn precondition(&self, r: &[f64], out: &mut [f64], scratch: &mut [Scratch]) {
        let top = scratch.len() - 1;
        scratch[top].rhs.copy_from_slice(r);
        self.restrict_to_space(&mut scratch[top].rhs);
        self.cycle(top, scratch);
        out.copy_from_slice(&scratch[top].x);
        self.restrict_to_space(out);
    }

    /// x_l ≈ A_l⁻¹ rhs_l: forward Gauss-Seidel, coarse correction,
    /// backward Gauss-Seidel (symmetric), from x_l = 0.
    fn cycle(&self, l: usize, scratch: &mut [Scratch]) {
        let h = &self.hierarchy;
        let (below, here) = scratch.split_at_mut(l);
        let s = &mut here[0];
        s.x.iter_mut().for_each(|x| *x = 0.0);
        if l == 0 {
            let n = s.rhs.len();
            for (i, x) in s.x.iter_mut().enumerate() {
                *x = dot(&h.coarsest[i * n..(i + 1) * n], &s.rhs);
            }
            return;
        }
        let mask = if l + 1 == h.levels.len() {
            self.mask.as_deref()
        } else {
            None
        };
        let level = &h.levels[l];
        gauss_seidel(level, &s.rhs, &mut s.x, mask, false);
        multiply(&level.a, &s.x, &mut s.residual);
        s.residual
            .iter_mut()
            .zip(&s.rhs)
            .for_each(|(d, b)| *d = b - *d);
        zero_on(mask, &mut s.residual);
        let coarse = &mut below[l - 1];
        multiply(&h.restrictions[l - 1], &s.residual, &mut coarse.rhs);
        self.cycle(l - 1, below);
        let coarse = &below[l - 1];
        // x += P x_c, masked.
        let p = &h.prolongations[l - 1];
        for i in 0..s.x.len() {
            if mask.is_some_and(|m| m[i]) {
                continue;
            }
            let (start, end) = (p.row_offsets()[i], p.row_offsets()[i + 1]);
            let mut sum = 0.0;
            for k in start..end {
                sum += p.values()[k] * coarse.x[p.col_indices()[k]];
            }
            s.x[i] += sum;
        }
        gauss_seidel(level, &s.rhs, &mut s.x, mask, true);
    }
}

impl Hierarchy {
    fn new(problem: &ContactProblem) -> Result<Self, EnergySolveError> {
        let prolongations: Vec<CsrMatrix<f64>> = problem
            .prolongations()
            .iter()
            .map(|p| p.to_nalgebra())
            .collect();
        let restrictions: Vec<CsrMatrix<f64>> =
            prolongations.iter().map(|p| p.transpose()).collect();
        let mut operators = vec![problem.a().to_nalgebra()];
        for (p, pt) in prolongations.iter().zip(&restrictions).rev() {
            let fine = operators.last().expect("the finest level");
            let ap = fine * p;
            operators.push(pt * &ap);
        }
        operators.reverse();
        let levels = operators
            .into_iter()
            .map(|a| {
                let mut inverse_diagonal = vec![0.0; a.nrows()];
                for (i, d) in inverse_diagonal.iter_mut().enumerate() {
                    let row = a.row(i);
                    let diagonal = row
                        .col_indices()
                        .iter()
                        .zip(row.values())
                        .find(|&(c, _)| *c == i)
                        .map_or(0.0, |(_, v)| *v);
                    // A zero diagonal (a coarse unknown no fine one sees)
                    // is skipped by the sweeps.
                    *d = if diagonal > 0.0 { 1.0 / diagonal } else { 0.0 };
                }
                Level {
                    a,
                    inverse_diagonal,
                }
            })
            .collect::<Vec<_>>();
        let coarsest = pseudo_inverse(&levels[0].a)?;
        Ok(Self {
            levels,
            prolongations,
            restrictions,
            coarsest,
        })
    }
}

/// The dense pseudo-inverse of a small symmetric positive semidefinite
/// matrix, row-major: Σ u_k u_kᵀ / λ_k over λ_k > KERNEL·λ_max.
fn pseudo_inverse(a: &CsrMatrix<f64>) -> Result<Vec<f64>, EnergySolveError> {
    let n = a.nrows();
    let mut dense = Mat::<f64>::zeros(n, n);
    for (i, j, v) in a.triplet_iter() {
        dense[(i, j)] = *v;
    }
    let eigen = dense
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| EnergySolveError::Analysis(format!("coarsest level: {e:?}")))?;
    let (u, s) = (eigen.U(), eigen.S().column_vector());
    let largest = (0..n).map(|k| s[k].abs()).fold(0.0, f64::max);
    let mut inverse = vec![0.0; n * n];
    for k in 0..n {
        let lambda = s[k];
        if lambda < -KERNEL * largest {
            return Err(EnergySolveError::NotDefinite(k));
        }
        if lambda <= KERNEL * largest {
            continue;
        }
        for i in 0..n {
            let ui = u[(i, k)] / lambda;
            for j in 0..n {
                inverse[i * n + j] += ui * u[(j, k)];
            }
        }
    }
    Ok(inverse)
}

/// One Gauss-Seidel sweep on A x = b, forward or backward, skipping the
/// masked unknowns (held where they are) and those of zero diagonal.
fn gauss_seidel(level: &Level, b: &[f64], x: &mut [f64], mask: Option<&[bool]>, backward: bool) {
    let a = &level.a;
    let (offsets, cols, vals) = (a.row_offsets(), a.col_indices(), a.values());
    let n = x.len();
    for step in 0..n {
        let i = if backward { n - 1 - step } else { step };
        let inverse = level.inverse_diagonal[i];
        if inverse == 0.0 || mask.is_some_and(|m| m[i]) {
            continue;
        }
        let mut sum = b[i];
        for k in offsets[i]..offsets[i + 1] {
            sum -= vals[k] * x[cols[k]];
        }
        x[i] += sum * inverse;
    }
}

/// x set to zero on the masked unknowns (none without a mask).
fn zero_on(mask: Option<&[bool]>, x: &mut [f64]) {
    if let Some(mask) = mask {
        x.iter_mut()
            .zip(mask)
            .filter(|(_, m)| **m)
            .for_each(|(v, _)| *v = 0.0);
    }
}

fn multiply(a: &CsrMatrix<f64>, x: &[f64], out: &mut [f64]) {
    let (offsets, cols, vals) = (a.row_offsets(), a.col_indices(), a.values());
    for (i, o) in out.iter_mut().enumerate() {
        let mut sum = 0.0;
        for k in offsets[i]..offsets[i + 1] {
            sum += vals[k] * x[cols[k]];
        }
        *o = sum;
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

fn axpy(alpha: f64, x: &[f64], y: &mut [f64]) {
    y.iter_mut().zip(x).for_each(|(yk, xk)| *yk += alpha * xk);
}
