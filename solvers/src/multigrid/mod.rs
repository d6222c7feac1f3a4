//! Truncated nonsmooth Newton multigrid (TNNMG) for the given-friction
//! subproblem (paper (10)): Gräser, Sack & Sander (2009), "Truncated
//! nonsmooth Newton multigrid methods for convex minimization problems";
//! Gräser & Sander (2019), "Truncated nonsmooth Newton multigrid methods
//! for block-separable minimization problems", IMA J. Numer. Anal. 39,
//! Algorithm 1; for two-body contact on nested meshes, Kornhuber & Krause
//! (2001).
//!
//! One iteration on J(v) = ½ vᵀAv − fᵀv + Σ w_i g_i |s_i|, t_i ≤ 0:
//!
//! 1. nonlinear presmoothing: the paper's pointwise relaxation with exact
//!    local minimizers ([`smoother`]);
//! 2. truncation: the coordinates at a kink (t_i = 0: closed; s_i = 0 with
//!    g_i > 0: stick) are frozen; J is a quadratic in the others;
//! 3. its Newton step by a few conjugate-gradient steps preconditioned by a
//!    linear V-cycle on the truncated Galerkin hierarchy of the problem's
//!    nested meshes ([`vcycle`]), the defect made orthogonal to the rigid
//!    mode when that mode is still free (the linear system is then singular
//!    but consistent). One bare V-cycle (Gräser & Sander's choice) reduced
//!    the linear residual only to 0.3-0.5 here (elasticity, symmetric
//!    Gauss-Seidel), and the iteration then contracted by 0.5;
//! 4. an exact line search on J along the correction, within t ≤ 0
//!    ([`line_search`]): J never increases;
//! 5. the exact minimization along the rigid mode of the upper body (the
//!    closing translation): the semicoercive mode is treated exactly, with
//!    no regularization, also when every contact node is open.
//!
//! The hierarchy comes with the problem ([`ContactProblem::prolongations`]),
//! built by the mechanics for the meshes 1/2 … h. Across the continuation
//! the harness hands over the coarse level's answer as the start (nested
//! iteration), and across the friction fixed point the last step's answer.
//! It stops when an iteration moves no unknown by more than tolerance · U
//! (U the problem's displacement scale).

mod line_search;
mod smoother;
mod vcycle;

use std::time::Instant;

use nalgebra_sparse::CsrMatrix;
use serde::{Deserialize, Serialize};

use crate::entry::{Accuracy, Entry, Knob, Role, StageInfo};
use crate::numerics::linalg::spmv_into;
use crate::observer::{Control, Observer, Progress};
use crate::problem::ContactProblem;
use crate::reduction::condensed::Kept;
use crate::settings::{Kind, Validate, from_tree, to_tree};
use crate::solution::{Iterations, Solution, Status, Timing};
use crate::solver::{Friction, Law, Solver, Start};
use line_search::{closing_translation, exact_step};
use smoother::{Local, diagonal_positions, nonlinear_sweep};
use vcycle::Hierarchy;

/// The progress stage of one TNNMG iteration (its unit of work).
pub(crate) const ITERATION: &str = "tnnmg_iteration";

/// The registry entry of TNNMG.
pub(crate) const ENTRY: Entry = Entry {
    name: "tnnmg",
    about: "truncated nonsmooth Newton multigrid: the paper's pointwise relaxation as smoother, a V-cycle on the truncated Galerkin hierarchy of the nested meshes, exact line search; O(n) per iteration",
    source: "Gräser & Sander (2019), IMA J. Numer. Anal. 39, Algorithm 1; Gräser, Sack & Sander (2009); Kornhuber & Krause (2001) for two bodies",
    laws: &[Law::GivenFriction],
    warm_starts: true,
    stages: &[StageInfo {
        name: ITERATION,
        about: "one TNNMG iteration (nonlinear presmoothing, truncated V-cycle, line search, rigid-mode translation); residual: the largest change of an unknown over U",
        history: true,
    }],
    work_stage: ITERATION,
    knobs: &[
        Knob {
            name: "tolerance",
            fields: &["tolerance"],
            help: "stop when an iteration changes no unknown by more than tolerance·U (relative)",
            kind: Kind::Positive,
        },
        Knob {
            name: "max_iter",
            fields: &["max_iter"],
            help: "cap on iterations per solve",
            kind: Kind::Count,
        },
        Knob {
            name: "presmoothing",
            fields: &["presmoothing"],
            help: "nonlinear Gauss-Seidel sweeps before each truncated V-cycle",
            kind: Kind::Count,
        },
        Knob {
            name: "linear_steps",
            fields: &["linear_steps"],
            help: "conjugate-gradient steps on the truncated Newton system per iteration, each preconditioned by one V-cycle",
            kind: Kind::Count,
        },
        Knob {
            name: "linear_sweeps",
            fields: &["linear_sweeps"],
            help: "linear Gauss-Seidel sweeps before and after each coarse correction of the V-cycle",
            kind: Kind::Count,
        },
    ],
    defaults: |_| to_tree(&TnnmgSettings::default()),
    build: |tree| Ok(Box::new(Tnnmg::new(from_tree(tree)?))),
    accuracy: Accuracy {
        knob: "tolerance",
        reference: 1e-13,
        exact: false,
    },
    role: Role::Other,
    kernel: None,
};

/// Settings of TNNMG (relative in both stopping modes).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TnnmgSettings {
    pub tolerance: f64,
    pub max_iter: usize,
    pub presmoothing: usize,
    pub linear_steps: usize,
    pub linear_sweeps: usize,
}

impl Default for TnnmgSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iter: 500,
            presmoothing: 1,
            linear_steps: 3,
            linear_sweeps: 2,
        }
    }
}

impl Validate for TnnmgSettings {
    /// Checked by the kinds of its registry entry's knobs.
    fn validate(&self) -> Result<(), String> {
        ENTRY.check(&to_tree(self))
    }
}

/// What depends on A and the prolongations only: A's diagonal positions
/// and the restrictions Pᵀ.
struct Operator {
    diag: Vec<usize>,
    restrict: Vec<CsrMatrix<f64>>,
}

/// TNNMG. Keeps the operator's data and the last truncated hierarchy
/// across calls on the same problem operator (the friction fixed point).
#[derive(Default)]
pub struct Tnnmg {
    pub settings: TnnmgSettings,
    operator: Kept<u64, Operator>,
    hierarchy: Option<(u64, Hierarchy)>,
}

impl Tnnmg {
    pub fn new(settings: TnnmgSettings) -> Self {
        Self {
            settings,
            ..Self::default()
        }
    }
}

/// The coordinates at a kink of J at v: closed jumps and sticking slips.
fn truncation(laws: &[Local], v: &[f64], out: &mut [bool]) {
    for ((o, law), &vk) in out.iter_mut().zip(laws).zip(v) {
        *o = match *law {
            Local::Free => false,
            Local::Jump => vk >= 0.0,
            Local::Slip(b) => b > 0.0 && vk == 0.0,
        };
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl Solver for Tnnmg {
    fn solve(
        &mut self,
        problem: &ContactProblem,
        friction: Friction<'_>,
        start: Option<Start<'_>>,
        observer: &mut dyn Observer,
    ) -> Solution {
        let (n, contacts) = (problem.n(), problem.contacts());
        let m = contacts.len();
        let bound = match Solution::given_bound(problem, friction, self.settings.validate()) {
            Ok(g) => g,
            Err(refused) => return *refused,
        };
        let p = problem.prolongations();
        if p.is_empty() {
            return Solution::failed(
                n,
                m,
                Status::NotRun,
                "tnnmg needs the problem's mesh hierarchy (problems built from a scene carry one; an imported instance does not)",
            );
        }
        let t0 = Instant::now();
        let a = problem.a();
        let id = problem.operator_id();
        let op = match self.operator.get_or_build(id, || {
            Ok(Operator {
                diag: diagonal_positions(a)?,
                restrict: p.iter().map(|p| p.transpose()).collect(),
            })
        }) {
            Ok(op) => op,
            Err(e) => return Solution::failed(n, m, Status::NumericalError, e),
        };
        let setup = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let mut laws = vec![Local::Free; n];
        for (c, g) in contacts.iter().zip(bound) {
            laws[c.t] = Local::Jump;
            laws[c.s] = Local::Slip(c.weight * g);
        }
        let f = problem.f();
        let z = problem.rigid_modes().first();
        let fz = z.map_or(0.0, |z| dot(f, z));
        let zz = z.map_or(0.0, |z| dot(z, z));
        let u = problem.scales().displacement;
        let tol = self.settings.tolerance;
        // The iteration's vectors, allocated once.
        let mut v = start.map_or_else(|| vec![0.0; n], |s| s.v.to_vec());
        if v.len() != n {
            v = vec![0.0; n];
        }
        let mut previous = v.clone();
        let mut r = vec![0.0; n];
        let mut d = vec![0.0; n];
        let mut c = vec![0.0; n];
        let mut ac = vec![0.0; n];
        let (mut lin_r, mut lin_z, mut lin_p) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let mut truncated = vec![false; n];
        let mut status = Status::MaxIterations;
        let mut detail = format!("iteration cap {} reached", self.settings.max_iter);
        let mut iterations = 0;
        for k in 1..=self.settings.max_iter {
            iterations = k;
            previous.copy_from_slice(&v);
            for _ in 0..self.settings.presmoothing {
                nonlinear_sweep(a, &op.diag, f, &laws, &mut v);
            }
            // The defect of the truncated Newton system.
            truncation(&laws, &v, &mut truncated);
            spmv_into(a, &v, &mut r);
            let mut rigid_free = z.is_some();
            for k in 0..n {
                r[k] = f[k] - r[k];
                d[k] = if truncated[k] {
                    if laws[k] == Local::Jump {
                        rigid_free = false;
                    }
                    0.0
                } else if let Local::Slip(b) = laws[k] {
                    r[k] - b * v[k].signum()
                } else {
                    r[k]
                };
            }
            if let (true, Some(z)) = (rigid_free, z) {
                let along = dot(&d, z) / zz;
                for (dk, zk) in d.iter_mut().zip(z) {
                    *dk -= along * zk;
                }
            }
            let rebuild = !matches!(&self.hierarchy, Some((h_id, h)) if *h_id == id && h.truncated() == truncated);
            if rebuild {
                self.hierarchy = Some((id, Hierarchy::new(a, p, &op.restrict, truncated.clone())));
            }
            let (_, hierarchy) = self.hierarchy.as_mut().expect("just built");
            // The truncated Newton step: conjugate gradients on A_T c = d
            // preconditioned by the V-cycle (its symmetric Gauss-Seidel
            // makes it symmetric positive definite on the free unknowns).
            let mut cycle = |rhs: &[f64], out: &mut [f64]| {
                hierarchy.v_cycle(
                    a,
                    &op.diag,
                    p,
                    &op.restrict,
                    rhs,
                    self.settings.linear_sweeps,
                    out,
                )
            };
            c.fill(0.0);
            lin_r.copy_from_slice(&d);
            cycle(&lin_r, &mut lin_z);
            lin_p.copy_from_slice(&lin_z);
            let mut rz = dot(&lin_r, &lin_z);
            for step in 0..self.settings.linear_steps {
                spmv_into(a, &lin_p, &mut ac);
                for (q, &cut) in ac.iter_mut().zip(&truncated) {
                    if cut {
                        *q = 0.0;
                    }
                }
                let pq = dot(&lin_p, &ac);
                if !(pq > 0.0 && rz > 0.0) {
                    break;
                }
                let step_length = rz / pq;
                for ((ck, rk), (pk, qk)) in c
                    .iter_mut()
                    .zip(lin_r.iter_mut())
                    .zip(lin_p.iter().zip(&ac))
                {
                    *ck += step_length * pk;
                    *rk -= step_length * qk;
                }
                if step + 1 == self.settings.linear_steps {
                    break;
                }
                cycle(&lin_r, &mut lin_z);
                let rz_next = dot(&lin_r, &lin_z);
                let beta = rz_next / rz;
                rz = rz_next;
                for (pk, zk) in lin_p.iter_mut().zip(&lin_z) {
                    *pk = zk + beta * *pk;
                }
            }
            // The projection onto the admissible set: v + c keeps t ≤ 0, so
            // that a full step is admissible (Gräser & Sander 2019,
            // Algorithm 1, step 4).
            for ((ck, law), vk) in c.iter_mut().zip(&laws).zip(&v) {
                if *law == Local::Jump {
                    *ck = (vk + *ck).min(0.0) - vk;
                }
            }
            spmv_into(a, &c, &mut ac);
            let alpha = exact_step(&laws, &v, &c, dot(&c, &ac), dot(&c, &r));
            for (vk, ck) in v.iter_mut().zip(&c) {
                *vk += alpha * ck;
            }
            if let Some((z, beta)) =
                z.and_then(|z| closing_translation(&laws, &v, z, fz).map(|b| (z, b)))
            {
                for (vk, zk) in v.iter_mut().zip(z) {
                    *vk += beta * zk;
                }
            }
            let change = v
                .iter()
                .zip(&previous)
                .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()))
                / u;
            let control = observer.observe(&Progress {
                stage: ITERATION,
                iteration: k,
                residual: change,
                seconds: t1.elapsed().as_secs_f64(),
            });
            if !change.is_finite() {
                status = Status::NonFinite;
                detail = format!("non-finite iterate at iteration {k}");
                break;
            }
            if change <= tol {
                status = Status::Converged;
                detail = format!("largest change {change:.3e}·U ≤ {tol:.0e} after {k} iterations");
                break;
            }
            if let Control::Stop(s) = control {
                status = s;
                detail = format!("stopped by the harness after {k} iterations");
                break;
            }
        }
        // The contact forces are the residual's: λ_i = (f − Av)_{t_i},
        // μ_i = −(f − Av)_{s_i} (the certificate's stationarity).
        spmv_into(a, &v, &mut r);
        let (mut pressure, mut traction) = (Vec::with_capacity(m), Vec::with_capacity(m));
        for cn in contacts {
            pressure.push((f[cn.t] - r[cn.t]) / cn.weight);
            traction.push(-(f[cn.s] - r[cn.s]) / cn.weight);
        }
        Solution {
            v,
            pressure,
            friction_traction: traction,
            status,
            detail,
            iterations: Iterations {
                outer: iterations,
                inner: 0,
            },
            timing: Timing {
                setup,
                solve: t1.elapsed().as_secs_f64(),
            },
            diagnostics: Vec::new(),
        }
        .flag_non_finite()
    }
}
