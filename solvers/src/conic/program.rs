//! The conic program that [`super::ConicSolver`] hands to Clarabel: the
//! given-friction subproblem (10) on all of v or on the contact unknowns,
//! written in the problem's own scales, and the way back to the problem's
//! units.

use std::sync::{Arc, Mutex};
use std::time::Instant;

use super::{ConicSettings, Formulation, INTERIOR_POINT};
use crate::observer::{Observer, Progress};
use crate::problem::ContactProblem;
use crate::reduction::condensed::Ending;
use crate::{Status, Timing};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSolver, IPSolver, SolverStatus, SupportedConeT};

/// Maps every Clarabel status explicitly.
pub(crate) fn map_status(status: SolverStatus) -> Status {
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

/// The given-friction subproblem (10) on some unknowns u: all of v, or the
/// contact unknowns after the condensation.
pub(super) struct Program<'a> {
    /// Number of unknowns u.
    pub(super) unknowns: usize,
    /// The upper triangle of the quadratic form's matrix, (row, col, value).
    pub(super) upper: Vec<(usize, usize, f64)>,
    /// The load on u.
    pub(super) load: &'a [f64],
    /// The positions of (t_i, s_i) in u, per contact node.
    pub(super) contact: Vec<(usize, usize)>,
    /// The given friction bound g_i per contact node.
    pub(super) bound: &'a [f64],
}

/// What Clarabel returned, back in the problem's units.
pub(super) struct Answer {
    pub(super) unknowns: Vec<f64>,
    /// (λ_i, μ_i): the nodal normal force and friction force of each node.
    pub(super) forces: Vec<(f64, f64)>,
    pub(super) end: Ending,
}

impl Program<'_> {
    /// Writes the program for Clarabel in the problem's scales (u = U û,
    /// objective over F·U, g the bound given), solves it and scales back.
    pub(super) fn solve(
        self,
        settings: &ConicSettings,
        problem: &ContactProblem,
        t0: Instant,
        observer: &mut dyn Observer,
    ) -> Result<Answer, String> {
        let (n, m) = (self.unknowns, self.contact.len());
        let contacts = problem.contacts();
        // u = U û; the objective is divided by F·U; forces come back over F.
        let (force, stiffness) = if settings.scale_unknowns {
            let s = problem.scales();
            (s.force, s.stiffness)
        } else {
            (1.0, 1.0)
        };
        let displacement = force / stiffness;
        // P: the upper triangle over K; the cone variables z_i have no quadratic term.
        let p_trip = self
            .upper
            .into_iter()
            .map(|(i, j, v)| (i, j, v / stiffness))
            .collect();
        let p = csc_from_triplets(n + m, n + m, p_trip);
        let mut q: Vec<f64> = self.load.iter().map(|f| -f / force).collect();
        q.extend(
            contacts
                .iter()
                .zip(self.bound)
                .map(|(c, g)| c.weight * g / force),
        );
        // Rows 0..m: t_i + slack = d_i (slack ≥ 0). SOC: rows m+2i, m+2i+1:
        // −(z_i, s_i) + slack = (0, −σ_i) in SOC(2), the slack (z_i, s_i −
        // σ_i). QP: s_i − z_i + slack = σ_i and −s_i − z_i + slack = −σ_i,
        // slacks ≥ 0 (z_i ≥ |s_i − σ_i|).
        let qp = settings.formulation == Formulation::Qp;
        let mut a_trip = Vec::with_capacity(5 * m);
        for (i, &(t, s)) in self.contact.iter().enumerate() {
            a_trip.push((i, t, 1.0));
            if qp {
                a_trip.push((m + 2 * i, s, 1.0));
                a_trip.push((m + 2 * i, n + i, -1.0));
                a_trip.push((m + 2 * i + 1, s, -1.0));
                a_trip.push((m + 2 * i + 1, n + i, -1.0));
            } else {
                a_trip.push((m + 2 * i, n + i, -1.0));
                a_trip.push((m + 2 * i + 1, s, -1.0));
            }
        }
        let a = csc_from_triplets(3 * m, n + m, a_trip);
        // t_i + slack = d_i: the initial gap, in the unknowns' units (zero
        // in the paper's scene). Posed here rather than by a shift of the
        // load (crate::reduction::gap), whose f − A D is 5e4 times the load
        // on Hertz's far field, where the interior point's dual residual,
        // relative to its data, then stalled at 7e-8 and the answer failed.
        let mut b = vec![0.0; 3 * m];
        for (bi, d) in b.iter_mut().zip(problem.gap()) {
            *bi = d / displacement;
        }
        // The slip offset likewise: its shift of the load strains the
        // layer of elements at Γ_K, and Clarabel ended AlmostSolved on the
        // paper's problem with σ = 1e-3 posed that way.
        for (i, sigma) in problem.slip_offset().iter().enumerate() {
            let sigma = sigma / displacement;
            if qp {
                b[m + 2 * i] = sigma;
                b[m + 2 * i + 1] = -sigma;
            } else {
                b[m + 2 * i + 1] = -sigma;
            }
        }
        let mut cones = Vec::with_capacity(m + 1);
        if m > 0 {
            if qp {
                cones.push(SupportedConeT::NonnegativeConeT(3 * m));
            } else {
                cones.push(SupportedConeT::NonnegativeConeT(m));
                cones.extend((0..m).map(|_| SupportedConeT::SecondOrderConeT(2)));
            }
        }
        let clarabel_settings = settings.clarabel(&observer.limits());
        let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, clarabel_settings)
            .map_err(|e| format!("Clarabel set-up failed: {e}"))?;
        let history: Arc<Mutex<Vec<Progress>>> = Arc::default();
        if observer.wants(INTERIOR_POINT) {
            let sink = Arc::clone(&history);
            let started = Instant::now();
            solver.set_termination_callback(move |info: &clarabel::solver::DefaultInfo<f64>| {
                if let Ok(mut h) = sink.lock() {
                    h.push(Progress {
                        stage: INTERIOR_POINT,
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
                // Clarabel has finished: its budget was passed in its settings.
                let _ = observer.observe(event);
            }
        }
        let sol = &solver.solution;
        // The duals: λ_i of the row t_i ≤ d_i; μ_i the tail of the cone's dual
        // (SOC) or the difference of the two half-planes' duals (QP, from
        // stationarity in s: (Au − f)_s + γ_a − γ_b = 0).
        let forces = (0..m)
            .map(|i| {
                let mu = if qp {
                    sol.z[m + 2 * i + 1] - sol.z[m + 2 * i]
                } else {
                    sol.z[m + 2 * i + 1]
                };
                (sol.z[i] * force, mu * force)
            })
            .collect();
        Ok(Answer {
            unknowns: sol.x[..n].iter().map(|x| x * displacement).collect(),
            forces,
            end: Ending {
                status: map_status(sol.status),
                detail: format!(
                    "Clarabel {:?} after {} iterations (gap_rel {:.1e}, r_prim {:.1e}, r_dual {:.1e})",
                    sol.status, sol.iterations, solver.info.gap_rel, sol.r_prim, sol.r_dual
                ),
                steps: sol.iterations as usize,
                timing: Timing { setup, solve },
            },
        })
    }
}
