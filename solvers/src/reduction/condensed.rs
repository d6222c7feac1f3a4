//! Condensation onto the contact unknowns. With C the jumps and slips
//! (t_i, s_i) and I everything else, the block A_II is positive definite
//! whenever fixing the contact unknowns removes every rigid motion (in the
//! paper's scene the lower body is clamped and holds the upper one through
//! the contact nodes). Then
//!
//! ```text
//! S = A_CC − A_CI A_II⁻¹ A_IC,    b̂ = f_C − A_CI A_II⁻¹ f_I,
//! ```
//!
//! and the given-friction problem is the same problem in the 2m contact
//! unknowns y alone: minimize ½ yᵀS y − b̂ᵀy + Σ w_i g_i |s_i| subject to
//! t_i ≤ 0, with v_I = A_II⁻¹(f_I − A_IC y). S keeps the semicoercive mode
//! (t = −1, s = 0). The factorization, S and b̂ depend on A and f only, so
//! they serve every friction iteration and every solver setting.

use faer::Mat;

use crate::numerics::linalg::{LinalgError, SparseCholesky};
use crate::problem::ContactProblem;
use crate::solution::{Iterations, SetupError, Solution, Status, Timing};

/// The condensed problem and what is needed to go back to all unknowns.
pub struct Condensed {
    /// A_II, factored.
    factor: SparseCholesky,
    /// Unknowns of I in the order of the factor.
    interior: Vec<usize>,
    /// A_CI as sparse rows: for contact position k, (interior index, value).
    a_ci: Vec<Vec<(usize, f64)>>,
    /// Schur complement S (2m × 2m), positions 2i (t_i) and 2i+1 (s_i).
    pub s: Mat<f64>,
    /// b̂ = f_C − A_CI A_II⁻¹ f_I.
    pub b: Vec<f64>,
    /// A_II⁻¹ f_I.
    interior_load: Vec<f64>,
    /// Nonzeros of the factor of A_II.
    pub factor_nnz: usize,
}

impl Condensed {
    /// What the condensation keeps, in bytes, for a solver's diagnostics:
    /// the values of the factor of A_II (its indices come on top) and the
    /// dense Schur complement S. Where a large solve's memory goes.
    pub(crate) fn memory_diagnostics(&self) -> [(&'static str, f64); 2] {
        let bytes = std::mem::size_of::<f64>();
        [
            ("factor_values_bytes", (bytes * self.factor_nnz) as f64),
            (
                "schur_bytes",
                (bytes * self.s.nrows() * self.s.ncols()) as f64,
            ),
        ]
    }

    /// Factors A_II (the unknowns coupled to Γ_K ordered last) and forms S and b̂.
    pub fn new(problem: &ContactProblem) -> Result<Self, LinalgError> {
        let n = problem.n();
        let contacts = problem.contacts();
        let m2 = 2 * contacts.len();
        // Position of each unknown: Err(k) for contact position k, Ok(i) for interior index i.
        let mut position: Vec<Result<usize, usize>> = vec![Ok(usize::MAX); n];
        for (i, c) in contacts.iter().enumerate() {
            position[c.t] = Err(2 * i);
            position[c.s] = Err(2 * i + 1);
        }
        let mut interior = Vec::with_capacity(n - m2);
        for (j, p) in position.iter_mut().enumerate() {
            if p.is_ok() {
                *p = Ok(interior.len());
                interior.push(j);
            }
        }
        let ni = interior.len();
        let mut a_ci: Vec<Vec<(usize, f64)>> = vec![Vec::new(); m2];
        let mut s = Mat::<f64>::zeros(m2, m2);
        let a = problem.a();
        let (offsets, cols, vals) = a.csr_data();
        for (i, c) in contacts.iter().enumerate() {
            for (k, r) in [(2 * i, c.t), (2 * i + 1, c.s)] {
                let (lo, hi) = a.row_range(r);
                for (&col, &v) in cols[lo..hi].iter().zip(vals.row(r, lo, hi)) {
                    match position[col as usize] {
                        Ok(j) => a_ci[k].push((j, v)),
                        Err(l) => s[(k, l)] += v,
                    }
                }
            }
        }
        // A_II's lower triangle straight from A's rows (A_IC = A_CIᵀ).
        let interior_map: Vec<usize> = position.iter().map(|p| p.unwrap_or(usize::MAX)).collect();
        let a_ii = crate::numerics::linalg::lower_part(ni, offsets, &cols, vals, &interior_map);
        drop(interior_map);
        // B: the interior unknowns coupled to the contact unknowns. Ordered
        // last, A_IC is zero outside them, so the forward solve of A_II⁻¹A_IC
        // stays in the trailing block: A_CI A_II⁻¹ A_IC = WᵀW, W = L_BB⁻¹ A_BC.
        let mut in_b = vec![usize::MAX; ni];
        let mut boundary = Vec::new();
        for row in &a_ci {
            for &(j, _) in row {
                if in_b[j] == usize::MAX {
                    in_b[j] = boundary.len();
                    boundary.push(j);
                }
            }
        }
        let factor = SparseCholesky::with_trailing(a_ii, &boundary)?;
        let l_bb = factor
            .trailing_factor(boundary.len())
            .ok_or_else(|| LinalgError::Faer("no supernodal trailing block".into()))?;
        let mut w = Mat::<f64>::zeros(boundary.len(), m2);
        for (k, row) in a_ci.iter().enumerate() {
            for &(j, v) in row {
                w[(in_b[j], k)] += v;
            }
        }
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(
            l_bb.as_ref(),
            w.as_mut(),
            faer::Par::Seq,
        );
        faer::linalg::matmul::matmul(
            s.as_mut(),
            faer::Accum::Add,
            w.transpose(),
            w.as_ref(),
            -1.0,
            faer::Par::Seq,
        );
        // Symmetrize away round-off.
        for k in 0..m2 {
            for l in 0..k {
                let avg = 0.5 * (s[(k, l)] + s[(l, k)]);
                s[(k, l)] = avg;
                s[(l, k)] = avg;
            }
        }
        let (b, interior_load) = reduce_load(&factor, &interior, &a_ci, contacts, problem.f());
        Ok(Self {
            factor_nnz: factor.factor_nnz(),
            factor,
            interior,
            a_ci,
            s,
            b,
            interior_load,
        })
    }

    /// All unknowns v from the contact unknowns y: v_I = A_II⁻¹(f_I − A_IC y).
    pub fn expand(&self, problem: &ContactProblem, y: &[f64]) -> Vec<f64> {
        let mut rhs = vec![0.0; self.interior.len()];
        for (k, row) in self.a_ci.iter().enumerate() {
            if y[k] != 0.0 {
                for &(j, v) in row {
                    rhs[j] += v * y[k];
                }
            }
        }
        self.factor.solve_vec(&mut rhs);
        let mut v = vec![0.0; problem.n()];
        for (idx, &j) in self.interior.iter().enumerate() {
            v[j] = self.interior_load[idx] - rhs[idx];
        }
        for (i, c) in problem.contacts().iter().enumerate() {
            v[c.t] = y[2 * i];
            v[c.s] = y[2 * i + 1];
        }
        v
    }
}

/// b̂ = f_C − A_CI A_II⁻¹ f_I and A_II⁻¹ f_I.
fn reduce_load(
    factor: &SparseCholesky,
    interior: &[usize],
    a_ci: &[Vec<(usize, f64)>],
    contacts: &[crate::problem::ContactNode],
    f: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let mut interior_load: Vec<f64> = interior.iter().map(|&j| f[j]).collect();
    factor.solve_vec(&mut interior_load);
    let mut b = vec![0.0; 2 * contacts.len()];
    for (i, c) in contacts.iter().enumerate() {
        b[2 * i] = f[c.t];
        b[2 * i + 1] = f[c.s];
    }
    for (k, row) in a_ci.iter().enumerate() {
        b[k] -= row.iter().map(|&(j, v)| v * interior_load[j]).sum::<f64>();
    }
    (b, interior_load)
}

/// Something built from a problem's operator (its condensation, a factor),
/// kept across calls on the same operator: the friction iterations and the
/// repeated runs of a study call a solver many times with one A.
pub(crate) struct Kept<K: PartialEq, T> {
    entry: Option<(K, T)>,
}

impl<K: PartialEq, T> Default for Kept<K, T> {
    fn default() -> Self {
        Self { entry: None }
    }
}

impl<K: PartialEq, T> Kept<K, T> {
    /// The value kept for `key`, built by `build` if the key changed.
    pub(crate) fn get_or_build<E>(
        &mut self,
        key: K,
        build: impl FnOnce() -> Result<T, E>,
    ) -> Result<&T, E> {
        if self.entry.as_ref().is_none_or(|(k, _)| *k != key) {
            self.entry = None;
            self.entry = Some((key, build()?));
        }
        Ok(&self.entry.as_ref().expect("just filled").1)
    }
}

/// How a solve on the condensed problem ended, for [`Condensed::solution`].
pub struct Ending {
    pub status: Status,
    pub detail: String,
    pub steps: usize,
    pub timing: Timing,
}

impl Condensed {
    /// The solution from the contact unknowns y and the nodal contact forces
    /// r = (λ_i, ν_i) with ν_i = −μ_i (pressures λ_i/w_i, friction tractions
    /// μ_i/w_i); [`Status::NonFinite`] if any number is not finite.
    pub fn solution(
        &self,
        problem: &ContactProblem,
        y: &[f64],
        r: &[f64],
        end: Ending,
    ) -> Solution {
        let contacts = problem.contacts();
        let out = Solution {
            v: self.expand(problem, y),
            pressure: contacts
                .iter()
                .enumerate()
                .map(|(i, c)| r[2 * i] / c.weight)
                .collect(),
            friction_traction: contacts
                .iter()
                .enumerate()
                .map(|(i, c)| -r[2 * i + 1] / c.weight)
                .collect(),
            status: end.status,
            detail: end.detail,
            iterations: Iterations {
                outer: end.steps,
                inner: 0,
            },
            timing: end.timing,
            diagnostics: Vec::new(),
        };
        out.flag_non_finite()
    }
}

/// Condenses `problem`, with the error said in terms of the mechanics (an
/// allocation that failed is [`Status::OutOfMemory`]).
pub fn condense(problem: &ContactProblem) -> Result<Condensed, SetupError> {
    Condensed::new(problem).map_err(|e| {
        let mut error = SetupError::from(e.clone());
        error.detail = match e {
            LinalgError::OutOfMemory { .. } => format!("condensation onto the contact unknowns: {e}"),
            _ => format!(
                "condensation needs the part of A away from the contact unknowns to be positive definite: {e}"
            ),
        };
        error
    })
}
