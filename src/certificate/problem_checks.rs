//! The problem's own checks, for a problem given from outside (an exported
//! instance, `Problem.from_matrices`): that it has a solution at all.
//!
//! `ContactProblem::new` checks what one pass can (sizes, symmetry, a
//! positive diagonal, A z = 0 for each rigid mode, the modes independent,
//! the load along each mode carried by the contact: paper condition (13),
//! at least one contact node). What it cannot is that A is positive
//! semidefinite with exactly the declared rigid modes as its kernel:
//! otherwise the energy ½vᵀAv − fᵀv is unbounded below (a negated or
//! indefinite A) or has a flat direction no constraint holds (a rigid mode
//! left undeclared), there is no minimizer, and an answer that satisfies
//! the contact conditions pointwise (stationarity holds at a saddle point)
//! is no solution. Here it is checked as follows: with one unknown per
//! rigid mode pinned (chosen by pivoting on the modes, so that the modes
//! restricted to the pinned unknowns are invertible), A ⪰ 0 with kernel
//! exactly span(Z) if and only if the reduced A_FF is positive definite
//! (for x = y + Z c with y zero at the pinned unknowns, xᵀA x = y_FᵀA_FF
//! y_F). A_FF is factored by the certificate's own Cholesky
//! ([`EnergySolve`]): a non-positive pivot refuses the problem, and so does
//! a smallest eigenvalue below 1e-12·max A_ii, bounded from above by a few
//! steps of inverse iteration (‖A_FF⁻¹x‖/‖x‖ ≤ 1/λ_min: a refusal is
//! sound; a kernel left undeclared gives λ_min at the rounding level).

use contactlab_solvers::ContactProblem;
use serde::{Deserialize, Serialize};

use super::energy_solve::{EnergySolve, EnergySolveError};

/// The smallest eigenvalue of A_FF, relative to max A_ii, below which A is
/// taken to have a kernel beyond the declared rigid modes. The paper's
/// problem at h = 1/1024 has about 1e-7.
pub const MIN_RELATIVE_EIGENVALUE: f64 = 1e-12;

/// How far A's definiteness was checked.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Definiteness {
    /// Assembled by contactlab from elements with E > 0 and 0 ≤ ν < ½:
    /// positive semidefinite with the rigid modes as kernel by construction.
    ByAssembly,
    /// A_FF factored, and its smallest eigenvalue at least this (an
    /// estimate from above, relative to max A_ii).
    Factored { smallest_eigenvalue: f64 },
    /// Not checked, and why (its factorization does not fit in memory).
    NotChecked(String),
}

impl Definiteness {
    /// One line for the certificate's report.
    pub fn line(&self) -> String {
        match self {
            Definiteness::ByAssembly => {
                "A positive semidefinite with the rigid modes as kernel: by assembly".into()
            }
            Definiteness::Factored {
                smallest_eigenvalue,
            } => format!(
                "A positive semidefinite with exactly the declared rigid modes as kernel: checked by Cholesky with the modes pinned (smallest eigenvalue ≲ {smallest_eigenvalue:.1e}·max A_ii)"
            ),
            Definiteness::NotChecked(why) => {
                format!("A's definiteness NOT checked: {why}")
            }
        }
    }
}

/// Why a problem has no solution.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NoSolution {
    #[error(
        "A is not positive semidefinite with exactly the declared rigid modes as kernel (with one unknown per mode pinned, the Cholesky factorization meets a non-positive pivot at {0}): the energy is unbounded below and the problem has no solution; is A negated or indefinite, or a rigid mode not declared?"
    )]
    Indefinite(usize),
    #[error(
        "A has a kernel beyond the {modes} declared rigid mode(s): with them pinned its smallest eigenvalue is at most {relative:.1e}·max A_ii (below {MIN_RELATIVE_EIGENVALUE:e}); declare every rigid motion of the bodies (rigid_modes), or hold them"
    )]
    UndeclaredKernel { modes: usize, relative: f64 },
}

/// One unknown per rigid mode, by pivoting: mode j, less its parts on the
/// unknowns pinned before it, pinned at its largest remaining entry.
pub fn pinned_unknowns(modes: &[Vec<f64>]) -> Vec<usize> {
    let mut reduced: Vec<Vec<f64>> = Vec::new();
    let mut pinned: Vec<usize> = Vec::new();
    for z in modes {
        let mut w = z.clone();
        for (r, &k) in reduced.iter().zip(&pinned) {
            let factor = w[k] / r[k];
            w.iter_mut().zip(r).for_each(|(x, y)| *x -= factor * y);
        }
        let k = (0..w.len())
            .max_by(|&a, &b| w[a].abs().total_cmp(&w[b].abs()))
            .unwrap_or(0);
        pinned.push(k);
        reduced.push(w);
    }
    pinned
}

/// Checks that A is positive semidefinite with exactly the problem's rigid
/// modes as kernel (module doc), with its factor allowed `room` bytes.
pub fn check_definite(problem: &ContactProblem, room: f64) -> Result<Definiteness, NoSolution> {
    let pinned = pinned_unknowns(problem.rigid_modes());
    let solve = match EnergySolve::new(problem, &pinned, room) {
        Ok(s) => s,
        Err(EnergySolveError::NotDefinite(pivot)) => return Err(NoSolution::Indefinite(pivot)),
        Err(e) => return Ok(Definiteness::NotChecked(e.to_string())),
    };
    // Inverse iteration from a fixed, rough start (zero at the pinned
    // unknowns): ‖A_FF⁻¹x‖/‖x‖ grows towards 1/λ_min and never passes it.
    let n = problem.n();
    let mut x: Vec<f64> = (0..n)
        .map(|i| ((i as f64) * 0.618_034).fract() - 0.5)
        .collect();
    pinned.iter().for_each(|&k| x[k] = 0.0);
    let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
    let mut growth: f64 = 0.0;
    for _ in 0..4 {
        let size = norm(&x);
        if size.is_nan() || size <= 0.0 {
            break;
        }
        let y = solve.solve(&x);
        let ny = norm(&y);
        if !ny.is_finite() {
            growth = f64::INFINITY;
            break;
        }
        growth = growth.max(ny / size);
        x = y.iter().map(|a| a / ny).collect();
    }
    let relative = 1.0 / (growth * problem.scales().stiffness);
    if relative < MIN_RELATIVE_EIGENVALUE {
        return Err(NoSolution::UndeclaredKernel {
            modes: problem.rigid_modes().len(),
            relative,
        });
    }
    Ok(Definiteness::Factored {
        smallest_eigenvalue: relative,
    })
}
