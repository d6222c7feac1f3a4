//! The oracle: the given-friction subproblem as a conic program for Clarabel,
//!
//! ```text
//! minimize ½ vᵀA v − fᵀv + Σ_i w_i g_i z_i
//! subject to t_i ≤ 0 (nonnegative cone),  (z_i, s_i) ∈ SOC(2), i.e. |s_i| ≤ z_i,
//! ```
//!
//! with A left singular (the semicoercive mode): no regularization is added.
//! The duals are the nodal contact forces: λ_i of the row t_i ≤ 0 and the
//! tail μ_i of the i-th cone, so p_i = λ_i / w_i and q_i = μ_i / w_i.
//!
//! Clarabel's relative tolerances are floored by max(1, ·), and this scene's
//! objective is of order 1e-3, so unscaled they act as absolute tolerances
//! and leave the multipliers inaccurate. By default the unknowns are scaled,
//! x̃ = σ v with σ = max_i A_ii, and the objective is multiplied by σ:
//! ½ x̃ᵀ(A/σ)x̃ − fᵀx̃ + Σ w_i g_i z̃_i. The duals (the forces) are unchanged.

use std::sync::{Arc, Mutex};
use std::time::Instant;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use serde::{Deserialize, Serialize};

use crate::observer::{Observer, Progress, Stage};
use crate::problem::GivenFrictionProblem;
use crate::solution::{Iterations, Solution, Status, Timing};
use crate::solver::{GivenFrictionSolver, Start};

/// Clarabel's settings that matter here; the rest keep Clarabel's defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ConicSettings {
    /// Absolute duality gap tolerance.
    pub tol_gap_abs: f64,
    /// Relative duality gap tolerance.
    pub tol_gap_rel: f64,
    /// Feasibility tolerance.
    pub tol_feas: f64,
    /// Interior-point iteration cap.
    pub max_iter: u32,
    /// Time limit in seconds (infinite by default).
    pub time_limit: f64,
    /// Clarabel's Ruiz equilibration of the data.
    pub equilibrate: bool,
    /// Solve for x̃ = σ v (σ = max A_ii) so that the tolerances are relative.
    pub scale_unknowns: bool,
    /// Clarabel's own console output.
    pub verbose: bool,
}

impl Default for ConicSettings {
    fn default() -> Self {
        Self::with_tolerance(DEFAULT_TOLERANCE)
    }
}

/// Default gap and feasibility tolerance: the tightest of 1e-8, 1e-10, 1e-12
/// that solves the paper's three problems reliably (see the closing study in
/// `results/`): 1e-12 ends in reduced accuracy or insufficient progress.
pub const DEFAULT_TOLERANCE: f64 = 1e-10;

impl ConicSettings {
    /// All three tolerances set to `tol`, everything else default.
    pub fn with_tolerance(tol: f64) -> Self {
        Self {
            tol_gap_abs: tol,
            tol_gap_rel: tol,
            tol_feas: tol,
            max_iter: 200,
            time_limit: f64::INFINITY,
            equilibrate: true,
            scale_unknowns: true,
            verbose: false,
        }
    }

    /// Checks ranges; the message names the field and what is valid.
    pub fn validate(&self) -> Result<(), String> {
        for (name, v) in [
            ("tol_gap_abs", self.tol_gap_abs),
            ("tol_gap_rel", self.tol_gap_rel),
            ("tol_feas", self.tol_feas),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!(
                    "clarabel.{name} = {v} is invalid: a tolerance must be a positive number, e.g. 1e-10"
                ));
            }
        }
        if self.max_iter == 0 {
            return Err("clarabel.max_iter = 0 is invalid: the iteration cap must be at least 1 (default 200)".into());
        }
        if self.time_limit.is_nan() || self.time_limit <= 0.0 {
            return Err(format!(
                "clarabel.time_limit = {} is invalid: give a positive number of seconds (default: none)",
                self.time_limit
            ));
        }
        Ok(())
    }

    fn clarabel(&self) -> DefaultSettings<f64> {
        DefaultSettingsBuilder::default()
            .verbose(self.verbose)
            .max_iter(self.max_iter)
            .time_limit(self.time_limit)
            .tol_gap_abs(self.tol_gap_abs)
            .tol_gap_rel(self.tol_gap_rel)
            .tol_feas(self.tol_feas)
            .equilibrate_enable(self.equilibrate)
            .build()
            .expect("all settings have defaults")
    }
}

/// The conic oracle.
#[derive(Clone, Debug, Default)]
pub struct ConicSolver {
    pub settings: ConicSettings,
}

impl ConicSolver {
    pub fn new(settings: ConicSettings) -> Self {
        Self { settings }
    }
}

/// Maps every Clarabel status explicitly.
pub fn map_status(status: SolverStatus) -> Status {
    match status {
        SolverStatus::Solved => Status::Converged,
        SolverStatus::AlmostSolved => Status::ReducedAccuracy,
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => Status::Infeasible,
        SolverStatus::DualInfeasible | SolverStatus::AlmostDualInfeasible => Status::Unbounded,
        SolverStatus::MaxIterations => Status::MaxIterations,
        SolverStatus::MaxTime => Status::TimeLimit,
        SolverStatus::NumericalError => Status::NumericalError,
        SolverStatus::InsufficientProgress => Status::InsufficientProgress,
        SolverStatus::CallbackTerminated => Status::InsufficientProgress,
        SolverStatus::Unsolved => Status::NotRun,
    }
}

/// Builds a Clarabel CSC matrix from (row, col, value) triplets.
fn csc_from_triplets(
    nrows: usize,
    ncols: usize,
    mut t: Vec<(usize, usize, f64)>,
) -> CscMatrix<f64> {
    t.sort_by_key(|&(r, c, _)| (c, r));
    let mut colptr = vec![0usize; ncols + 1];
    for &(_, c, _) in &t {
        colptr[c + 1] += 1;
    }
    for c in 0..ncols {
        colptr[c + 1] += colptr[c];
    }
    let rowval = t.iter().map(|&(r, _, _)| r).collect();
    let nzval = t.iter().map(|&(_, _, v)| v).collect();
    CscMatrix::new(nrows, ncols, colptr, rowval, nzval)
}

impl GivenFrictionSolver for ConicSolver {
    fn name(&self) -> &'static str {
        "clarabel"
    }

    fn solve(
        &mut self,
        problem: &GivenFrictionProblem,
        _start: Option<Start<'_>>,
        observer: &mut dyn Observer,
    ) -> Solution {
        let (n, contacts) = (problem.n(), problem.contacts());
        let m = contacts.len();
        if let Err(e) = self.settings.validate() {
            return Solution::failed(n, m, Status::NotRun, e);
        }
        let t0 = Instant::now();
        let sigma = if self.settings.scale_unknowns {
            let d = problem.a().diagonal_as_csr();
            d.values()
                .iter()
                .fold(0.0f64, |s, x| s.max(x.abs()))
                .max(f64::MIN_POSITIVE)
        } else {
            1.0
        };
        // P: upper triangle of A/σ; the cone variables z_i have no quadratic term.
        let (offsets, cols, vals) = problem.a().csr_data();
        let mut p_trip = Vec::with_capacity(vals.len() / 2 + n);
        for j in 0..n {
            for k in offsets[j]..offsets[j + 1] {
                if cols[k] <= j {
                    p_trip.push((cols[k], j, vals[k] / sigma));
                }
            }
        }
        let p = csc_from_triplets(n + m, n + m, p_trip);
        let mut q: Vec<f64> = problem.f().iter().map(|f| -f).collect();
        q.extend(contacts.iter().map(|c| c.weight * c.g));
        // Rows 0..m: t_i + slack = 0 (slack ≥ 0); rows m+2i, m+2i+1: −(z_i, s_i) + slack = 0.
        let mut a_trip = Vec::with_capacity(3 * m);
        for (i, c) in contacts.iter().enumerate() {
            a_trip.push((i, c.t, 1.0));
            a_trip.push((m + 2 * i, n + i, -1.0));
            a_trip.push((m + 2 * i + 1, c.s, -1.0));
        }
        let a = csc_from_triplets(3 * m, n + m, a_trip);
        let b = vec![0.0; 3 * m];
        let mut cones = Vec::with_capacity(m + 1);
        if m > 0 {
            cones.push(SupportedConeT::NonnegativeConeT(m));
            cones.extend((0..m).map(|_| SupportedConeT::SecondOrderConeT(2)));
        }
        let mut solver = match DefaultSolver::new(&p, &q, &a, &b, &cones, self.settings.clarabel())
        {
            Ok(s) => s,
            Err(e) => {
                return Solution::failed(
                    n,
                    m,
                    Status::NumericalError,
                    format!("Clarabel set-up failed: {e}"),
                );
            }
        };
        let history: Arc<Mutex<Vec<Progress>>> = Arc::default();
        if observer.wants(Stage::InteriorPoint) {
            let sink = Arc::clone(&history);
            let started = Instant::now();
            solver.set_termination_callback(move |info: &clarabel::solver::DefaultInfo<f64>| {
                if let Ok(mut h) = sink.lock() {
                    h.push(Progress {
                        stage: Stage::InteriorPoint,
                        iteration: info.iterations as usize,
                        residual: info
                            .res_primal
                            .max(info.res_dual)
                            .max(info.gap_rel.min(info.gap_abs)),
                        seconds: started.elapsed().as_secs_f64(),
                    });
                }
                false
            });
        }
        let setup = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        solver.solve();
        let solve = t1.elapsed().as_secs_f64();
        if let Ok(h) = history.lock() {
            for event in h.iter() {
                observer.observe(event);
            }
        }
        let sol = &solver.solution;
        let status = map_status(sol.status);
        let v: Vec<f64> = sol.x[..n].iter().map(|x| x / sigma).collect();
        let pressure = contacts
            .iter()
            .enumerate()
            .map(|(i, c)| sol.z[i] / c.weight)
            .collect();
        let friction_traction = contacts
            .iter()
            .enumerate()
            .map(|(i, c)| sol.z[m + 2 * i + 1] / c.weight)
            .collect();
        let mut out = Solution {
            v,
            pressure,
            friction_traction,
            status,
            detail: format!(
                "Clarabel {:?} after {} iterations (gap_rel {:.1e}, r_prim {:.1e}, r_dual {:.1e})",
                sol.status, sol.iterations, solver.info.gap_rel, sol.r_prim, sol.r_dual
            ),
            iterations: Iterations {
                outer: sol.iterations as usize,
                inner: 0,
            },
            timing: Timing { setup, solve },
        };
        if !out.is_finite() && out.status.is_converged() {
            out.status = Status::NonFinite;
        }
        out
    }
}
