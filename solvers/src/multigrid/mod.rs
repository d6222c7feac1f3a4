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
//!
//! Several cores (`threads`, default every core): above
//! [`crate::numerics::linalg::PARALLEL_NNZ`] stored entries (h ≤ 1/128 for
//! the paper's scenes) the products split their rows in as many chunks, and
//! the Gauss-Seidel sweeps, nonlinear and linear, run in the ordering of
//! [`parts`]: bands of unknowns that do not couple, one thread each, then
//! their separator. The line search and the coarse correction are
//! unchanged, so J still never increases.

mod galerkin;
pub(crate) mod iteration;
mod kernel;
mod parts;
pub use kernel::BOUND_OF_SCALE;
pub(crate) mod laws;
mod line_search;
pub(crate) mod smoother;
pub(crate) mod vcycle;

use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::entry::{Accuracy, Entry, Knob, Memory, Role, StageInfo};

use crate::numerics::linalg::Csr;

use crate::numerics::linalg::row_dot_at;
use crate::numerics::resolution::Resolution;
use crate::numerics::threads::Threads;
use crate::observer::{Control, Observer, Progress};
use crate::problem::ContactProblem;
use crate::settings::{Kind, Validate, from_tree, to_tree};
use crate::solution::{Iterations, Solution, Status, Timing};
use crate::solver::{Friction, Law, Solver, Start};
use iteration::{Cycle, Energy, Phases, Workspace, iterate};
use laws::Laws;
use line_search::closing_translation;
use smoother::{Local, diagonal_places};
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
    // Measured, problem 1 (single runs): 1/256 revisit 0.84 s (211
    // iterations), nested 0.21 s (44); 1/1024 revisit 32 s, nested 5.5 s.
    // The same answer: each schedule runs the fixed point to its ε.
    schedule: crate::schedule::Schedule::Nested,
    schedule_when: None,
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
            help: "linear Gauss-Seidel sweeps before and after each coarse correction of the V-cycle, below the finest level",
            kind: Kind::Count,
        },
        Knob {
            name: "finest_sweeps",
            fields: &["finest_sweeps"],
            help: "the same on the finest level, where a sweep costs three times all the levels below",
            kind: Kind::Count,
        },
        Knob {
            name: "threads",
            fields: &["threads"],
            help: "threads of the Gauss-Seidel sweeps (in as many bands of unknowns and their separator) and of the products, above 2^18 stored entries; 0: every core; 1: the sequential method",
            kind: Kind::Whole,
        },
    ],
    defaults: |_| to_tree(&TnnmgSettings::default()),
    build: crate::entry::Build::Fn(|tree| Ok(Box::new(Tnnmg::new(from_tree(tree)?)))),
    accuracy: Accuracy {
        knob: "tolerance",
        reference: 1e-13,
        exact: false,
    },
    role: Role::Other,
    kernel: Some(kernel::iteration_kernel),
    max_unknowns: None,
    uses_mass: false,
    memory: Memory {
        // Measured (nested schedule, the stencils and rows of A and of the
        // Galerkin levels kept once, 32-bit row offsets, the unknowns'
        // map by formula, the start handed over, six vectors of n in the
        // iteration, the Galerkin levels built into shared storage),
        // beyond the 96 MiB every run holds: 96 B per unknown at 1/1024
        // (0.28 GiB in all), 121 at 1/2048 (1.04 GiB) and at 1/4096
        // (3.87 GiB); a fifth above that.
        per_unknown: 145.0,
        per_unknown_log2: 0.0,
    },
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
    pub finest_sweeps: usize,
    /// Threads of the sweeps and products (0: every core the machine
    /// offers; 1: sequential). More threads change the sweeps' ordering,
    /// so the iterates' bits, not the method.
    pub threads: usize,
}

impl Default for TnnmgSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iter: 500,
            presmoothing: 1,
            linear_steps: 3,
            linear_sweeps: 2,
            finest_sweeps: DEFAULT_FINEST_SWEEPS,
            threads: 0,
        }
    }
}

/// One sweep before and one after the coarse correction on the finest
/// level (two below it). The finest level's sweeps were half of a V-cycle's
/// time there; with one, problem 1 at 1/1024 (nested schedule) took 7
/// iterations on the finest mesh instead of 8 and 7.5 s instead of 9.0-9.5;
/// problem 3 at 1/1024 9.1 -> 6.4 s, problem 2 at 1/512 2.1 -> 1.7 s,
/// problem 1 at 1/2048 33.6 -> 28.7 s, each with the same iterations and
/// answer (single runs). One sweep on every level (`linear_sweeps = 1`)
/// took 10 iterations instead of 8: the cheap coarse levels keep theirs.
pub const DEFAULT_FINEST_SWEEPS: usize = 1;

impl TnnmgSettings {
    /// The work of one iteration these settings ask for.
    pub(crate) fn cycle(&self) -> Cycle {
        Cycle {
            presmoothing: self.presmoothing,
            linear_steps: self.linear_steps,
            linear_sweeps: self.linear_sweeps,
            finest_sweeps: self.finest_sweeps,
        }
    }
}

/// The laws of the given-friction subproblem with nodal bounds `bound`
/// (paper (10)): t_i ≤ d_i on each jump (d the initial gap), w_i g_i |s_i|
/// on each slip, written into `laws`; returns the contact unknowns,
/// ascending.
pub(crate) fn given_friction_laws(
    problem: &ContactProblem,
    bound: &[f64],
    laws: &mut Laws,
) -> Vec<usize> {
    let contacts = problem.contacts();
    let mut contact = Vec::with_capacity(2 * contacts.len());
    for ((c, g), d) in contacts.iter().zip(bound).zip(problem.gap()) {
        laws.set(c.t, Local::Jump(*d));
        laws.set(c.s, Local::Slip(c.weight * g));
        contact.extend([c.t, c.s]);
    }
    contact.sort_unstable();
    contact
}

impl Validate for TnnmgSettings {
    /// Checked by the kinds of its registry entry's knobs.
    fn validate(&self) -> Result<(), String> {
        ENTRY.check(&to_tree(self))
    }
}

/// Hierarchies kept across calls: one per operator of the continuation's
/// levels (the friction fixed point revisits them), at most this many.
const KEPT_HIERARCHIES: usize = 12;

/// TNNMG. Keeps the Galerkin hierarchy of each operator it met, truncated
/// as last used, across calls (the continuation's levels in every step of
/// the friction fixed point).
#[derive(Default)]
pub struct Tnnmg {
    pub settings: TnnmgSettings,
    hierarchies: Vec<(u64, Hierarchy)>,
    /// The last solve's vectors, reused by the next of the same size (the
    /// friction fixed point's steps on one level): at h = 1/1024 each is
    /// 34 MB, above the size that the allocator maps afresh, and faulting
    /// their pages in again took a sixth of a friction step.
    buffers: Option<Buffers>,
    /// The seconds of every solve since it was built, by phase, and in
    /// all: across a Coulomb problem every level and friction step. Each
    /// solve reports them in its diagnostics (`bench`'s work units).
    phases: Phases,
    seconds: f64,
}

/// The diagnostic of all of TNNMG's seconds since it was built (set-up
/// and solves); the rest of a Coulomb solve is the friction fixed point's.
pub const TOTAL_SECONDS: &str = "tnnmg_total_seconds";

/// The vectors of one solve.
struct Buffers {
    ws: Workspace,
    laws: Laws,
}

impl Buffers {
    /// `kept` when of size n, else new ones; the laws all `Free`.
    fn of_size(kept: Option<Buffers>, n: usize) -> Self {
        match kept {
            Some(mut b) if b.ws.n() == n => {
                b.laws.clear();
                b.ws.reset();
                b
            }
            _ => Self {
                ws: Workspace::new(n),
                laws: Laws::free(n),
            },
        }
    }
}

impl Tnnmg {
    pub fn new(settings: TnnmgSettings) -> Self {
        Self {
            settings,
            ..Self::default()
        }
    }
}

/// The largest coarsest level the multigrid solvers take: its exact solve
/// is dense (an eigendecomposition and a pseudo-inverse, O(n³), redone
/// when the truncated set changes), so a problem without a mesh hierarchy
/// is taken on one level up to this size (the identity its one
/// prolongation), and a hierarchy whose coarsest level is larger is
/// refused. The scenes' hierarchies go down to h = 1/2, 12 to 17
/// unknowns; a user hierarchy whose coarsest level had 1721 took 79 s
/// before its first iteration.
pub const ONE_LEVEL_MAX_UNKNOWNS: usize = 256;

/// The prolongations a multigrid solve of `problem` runs on: the
/// problem's own (its mesh hierarchy), or for a problem without one that
/// is small enough ([`ONE_LEVEL_MAX_UNKNOWNS`]: a scene at h = 1/2, whose
/// mesh is the coarsest) the identity, so that the V-cycle's coarse
/// correction is the exact solve. A larger problem without a hierarchy
/// (an imported instance), or a hierarchy whose coarsest level is larger,
/// is refused with the reason.
pub(crate) fn prolongations_of(
    problem: &ContactProblem,
) -> Result<std::borrow::Cow<'_, [Csr]>, String> {
    let p = problem.prolongations();
    if let Some(first) = p.first() {
        let coarsest = first.ncols();
        if coarsest > ONE_LEVEL_MAX_UNKNOWNS {
            return Err(format!(
                "cannot use this hierarchy: its coarsest level has {coarsest} unknowns, more than the {ONE_LEVEL_MAX_UNKNOWNS} its exact coarse solve takes (dense, O(n³), redone when the truncated set changes); give prolongations down to a coarser mesh (a scene's go down to h = 1/2, at most 17 unknowns)"
            ));
        }
        return Ok(std::borrow::Cow::Borrowed(p));
    }
    let n = problem.n();
    if n > ONE_LEVEL_MAX_UNKNOWNS {
        return Err(format!(
            "needs the problem's mesh hierarchy (the prolongations between nested meshes) for {n} unknowns, and this problem carries none: a problem built from a scene does; an imported instance does not (solve it with a solver that factors A, e.g. newton-coulomb)"
        ));
    }
    let identity = Csr::try_from_csr_data(
        n,
        n,
        (0..=n).collect(),
        (0..n as u32).collect(),
        vec![1.0; n],
    )
    .map_err(|e| e.to_string())?;
    Ok(std::borrow::Cow::Owned(vec![identity]))
}

/// The hierarchy of operator `id` in `kept`, built if missing (the oldest
/// dropped beyond [`KEPT_HIERARCHIES`]).
pub(crate) fn kept_hierarchy<'k, K: PartialEq>(
    kept: &'k mut Vec<(K, Hierarchy)>,
    id: K,
    a: &Csr,
    p: &[Csr],
) -> Result<&'k mut Hierarchy, String> {
    let index = match kept.iter().position(|(k, _)| *k == id) {
        Some(i) => i,
        None => {
            if kept.len() >= KEPT_HIERARCHIES {
                kept.remove(0);
            }
            kept.push((id, Hierarchy::new(a, diagonal_places(a)?, p)?));
            kept.len() - 1
        }
    };
    Ok(&mut kept[index].1)
}

/// (f − Av)_i of one row: the contact forces are these residuals at the
/// contact rows (λ_i = (f − Av)_{t_i}/w_i, μ_i = −(f − Av)_{s_i}/w_i, the
/// certificate's stationarity), O(h⁻¹) work for all of them. The row sum is
/// the product's ([`row_dot`]), so it equals (f − spmv(A, v))_i to the bit.
fn residual_at(a: &Csr, f: &[f64], v: &[f64], i: usize) -> f64 {
    let row = a.row(i);
    // SAFETY: a Csr keeps its column indices below ncols = v.len().
    f[i] - unsafe { row_dot_at(row.0, row.1, v) }
}

/// The contact pressure λ_i of every contact node into `out`.
fn contact_pressure(
    a: &Csr,
    f: &[f64],
    contacts: &[crate::problem::ContactNode],
    v: &[f64],
    out: &mut [f64],
) {
    for (o, c) in out.iter_mut().zip(contacts) {
        *o = residual_at(a, f, v, c.t) / c.weight;
    }
}

/// (max_k |s_k + β z_k|, max_k |v_k|) for the step s and the translation
/// β z (none: β = 0).
fn max_step_and_size(s: &[f64], translation: Option<(f64, &[f64])>, v: &[f64]) -> (f64, f64) {
    let size = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let after = match translation {
        Some((beta, z)) => s
            .iter()
            .zip(z)
            .fold(0.0f64, |m, (sk, zk)| m.max((sk + beta * zk).abs())),
        None => s.iter().fold(0.0f64, |m, sk| m.max(sk.abs())),
    };
    (after, size)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl Solver for Tnnmg {
    /// Two rigid modes, measured: Cattaneo–Mindlin with the upper body free
    /// to slide (`scenes/cattaneo_mindlin_sliding.toml`) certifies.
    fn rigid_modes_handled(&self) -> usize {
        2
    }

    /// The gap is each jump's obstacle, t_i ≤ d_i (`Local::Jump`).
    fn poses_gaps(&self) -> bool {
        true
    }

    /// The hierarchies and vectors: at h = 1/1024 those of the nested
    /// schedule's coarse levels held about 130 MB through the finest
    /// level's solves.
    fn release(&mut self) {
        self.hierarchies.clear();
        self.buffers = None;
    }

    fn solve(
        &mut self,
        problem: &ContactProblem,
        friction: Friction<'_>,
        start: Option<Start<'_>>,
        observer: &mut dyn Observer,
    ) -> Solution {
        let (n, contacts) = (problem.n(), problem.contacts());
        let m = contacts.len();
        let _threads = Threads::set(self.settings.threads);
        let bound = match Solution::given_bound(problem, friction, self.settings.validate()) {
            Ok(g) => g,
            Err(refused) => return *refused,
        };
        let levels = match prolongations_of(problem) {
            Ok(levels) => levels,
            Err(why) => return Solution::failed(n, m, Status::NotRun, format!("tnnmg {why}")),
        };
        let p = &levels[..];
        let t0 = Instant::now();
        let a = problem.a();
        let hierarchy = match kept_hierarchy(&mut self.hierarchies, problem.operator_id(), a, p) {
            Ok(h) => h,
            Err(e) => return Solution::failed(n, m, Status::NumericalError, e),
        };
        let setup = t0.elapsed().as_secs_f64();
        self.phases.setup += setup;
        let t1 = Instant::now();
        let Buffers { mut ws, mut laws } = Buffers::of_size(self.buffers.take(), n);
        let contact = given_friction_laws(problem, bound, &mut laws);
        let f = problem.f();
        let z = problem.rigid_modes().first().map(|z| &z[..]);
        let fz = z.map_or(0.0, |z| dot(f, z));
        let energy = Energy {
            a,
            b: f,
            laws: &laws,
            contact: &contact,
            kernel: z.map(|z| (z, dot(z, z))),
        };
        let cycle = self.settings.cycle();
        let scales = problem.scales();
        let (u, tol) = (scales.displacement, self.settings.tolerance);
        // The caller's need, when looser than its own tolerance, is an
        // accuracy of the pressure (the friction fixed point's g = 𝓕p):
        // measured on the pressure's change itself, relative to P. The
        // displacement's change relative to U understates the pressure's
        // error, the more so the finer the mesh (p is A v at the contact
        // rows): asked for 1e-2 from zero it left 1.6e-2·P at 1/256 and
        // 2.7e-2·P at 1/512, and the fixed point with the forcing 0.1
        // diverged at 1/512.
        let pressure_tol = start
            .as_ref()
            .and_then(|s| s.accuracy)
            .filter(|&a| a > tol && scales.pressure > 0.0);
        let mut v = start.map_or_else(|| vec![0.0; n], |s| s.v.into_owned());
        if v.len() != n {
            v = vec![0.0; n];
        }
        // A start interpolated from a coarser mesh keeps t ≤ 0, but not
        // t ≤ d under a convex gap (the chord lies above the parabola):
        // projected, so that the iteration starts admissible.
        for (c, d) in contacts.iter().zip(problem.gap()) {
            v[c.t] = v[c.t].min(*d);
        }
        let mut pressure_now = vec![0.0; m];
        let mut pressure_before = vec![0.0; m];
        if pressure_tol.is_some() {
            contact_pressure(a, f, contacts, &v, &mut pressure_before);
        }
        let mut status = Status::MaxIterations;
        let mut detail = format!("iteration cap {} reached", self.settings.max_iter);
        let mut iterations = 0;
        let mut stopped_at_need = None;
        let mut stall = Resolution::default();
        for k in 1..=self.settings.max_iter {
            iterations = k;
            let smoothing_moved = iterate(&energy, hierarchy, p, cycle, &mut ws, &mut v);
            let stop_clock = Instant::now();
            // The exact minimization along the rigid mode.
            let translation = z.and_then(|z| {
                closing_translation(&laws, &contact, &v, z, fz).map(|beta| (beta, z))
            });
            if let Some((beta, z)) = translation {
                for (vk, zk) in v.iter_mut().zip(z) {
                    *vk += beta * zk;
                }
            }
            // The change max|Δv|, bounded by the presmoothing's largest
            // move plus that of the step after it (the correction, the
            // near-kernel step and the translation, taken exactly): a copy
            // of v to subtract was a vector of n, 8 bytes per unknown. The
            // bound is at least the change, so the test is no looser.
            let (after, size) = max_step_and_size(ws.step(), translation, &v);
            let moved = smoothing_moved + after;
            let change = moved / u;
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
            if let Some(need) = pressure_tol {
                contact_pressure(a, f, contacts, &v, &mut pressure_now);
                let moved = pressure_now
                    .iter()
                    .zip(&pressure_before)
                    .fold(0.0f64, |c, (x, y)| c.max((x - y).abs()))
                    / scales.pressure;
                std::mem::swap(&mut pressure_now, &mut pressure_before);
                if moved <= need {
                    stopped_at_need = Some(need);
                    status = Status::Converged;
                    detail = format!(
                        "largest change of the pressure {moved:.3e}·P ≤ {need:.1e} (the caller's need) after {k} iterations"
                    );
                    break;
                }
            }
            if stall.stalled(moved, size) {
                status = Status::InsufficientProgress;
                detail = format!(
                    "largest change {change:.3e}·U > {tol:.0e} after {k} iterations: {}",
                    Resolution::detail("v", moved, size)
                );
                break;
            }
            ws.phases.line_search += stop_clock.elapsed().as_secs_f64();
            if let Control::Stop(s) = control {
                status = s;
                detail = format!("stopped by the harness after {k} iterations");
                break;
            }
        }
        let mut pressure = vec![0.0; m];
        contact_pressure(a, f, contacts, &v, &mut pressure);
        self.phases.add(&std::mem::take(&mut ws.phases));
        self.seconds += t0.elapsed().as_secs_f64();
        self.buffers = Some(Buffers { ws, laws });
        let traction = contacts
            .iter()
            .map(|c| -residual_at(a, f, &v, c.s) / c.weight)
            .collect();
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
            diagnostics: stopped_at_need
                .map(|need| (crate::solver::STOPPED_AT_NEED, need))
                .into_iter()
                .chain(self.phases.diagnostics())
                .chain([(TOTAL_SECONDS, self.seconds)])
                .collect(),
        }
        .flag_non_finite()
    }
}
