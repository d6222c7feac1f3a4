//! One TNNMG iteration on a block-separable energy
//! J(v) = ½ vᵀAv − bᵀv + Σ_k φ_k(v_k) (Gräser & Sander 2019, Algorithm 1):
//!
//! 1. nonlinear presmoothing: Gauss-Seidel with exact local minimizers
//!    (the paper's pointwise relaxation, [`smoother`]);
//! 2. truncation: the coordinates at a kink of φ_k (closed jump, sticking
//!    slip) are frozen; J is then twice differentiable in the others, with
//!    Hessian A + D, D = diag φ_k'' (nonzero only for the C¹ laws of the
//!    modified Lagrangian);
//! 3. its Newton step by a few conjugate-gradient steps preconditioned by a
//!    linear V-cycle on the truncated Galerkin hierarchy ([`vcycle`]), the
//!    defect made orthogonal to A's kernel (the rigid mode) while that mode
//!    is free (the system is then singular but consistent). One bare
//!    V-cycle (Gräser & Sander's choice) reduced the linear residual only to
//!    0.3-0.5 here (elasticity, symmetric Gauss-Seidel), and the iteration
//!    then contracted by 0.5;
//! 4. the projection of the correction onto t ≤ 0 and an exact line search
//!    on J along it ([`line_search`]): J never increases.
//!
//! [`smoother`]: super::smoother
//! [`vcycle`]: super::vcycle
//! [`line_search`]: super::line_search

use std::time::Instant;

use crate::numerics::linalg::Csr;

use super::laws::Laws;
use super::line_search::exact_step;
use super::smoother::{Local, nonlinear_sweep};
use super::vcycle::{Hierarchy, truncated_product};
use crate::numerics::linalg::spmv_into;
use crate::numerics::threads::{Disjoint, axpy, copy, dot, fill, for_each_chunk, scale};

/// The energy: its quadratic part, its laws and A's kernel.
pub(crate) struct Energy<'a> {
    pub a: &'a Csr,
    pub b: &'a [f64],
    /// φ_k of every unknown (`Local::Free` without a contact term).
    pub laws: &'a Laws,
    /// The unknowns whose law is not `Free`.
    pub contact: &'a [usize],
    /// A's kernel vector z with zᵀz, when A is singular (the upper body's
    /// rigid mode of the given-friction problem).
    pub kernel: Option<(&'a [f64], f64)>,
}

/// The work of one iteration.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cycle {
    /// Nonlinear Gauss-Seidel sweeps before the truncated Newton step.
    pub presmoothing: usize,
    /// Conjugate-gradient steps on the truncated Newton system.
    pub linear_steps: usize,
    /// Linear Gauss-Seidel sweeps before and after each coarse correction
    /// below the finest level.
    pub linear_sweeps: usize,
    /// The same on the finest level.
    pub finest_sweeps: usize,
}

/// Where the seconds of TNNMG went, by phase (a clock read a few times per
/// iteration: tens of nanoseconds against milliseconds): the work units of
/// `bench` are these divided by one product A·v on the finest level.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Phases {
    /// The Galerkin hierarchies built (once per operator).
    pub setup: f64,
    /// The nonlinear presmoothing and the V-cycles' work on the finest
    /// level (its linear sweeps and the transfers to and from it).
    pub smoothing: f64,
    /// The V-cycles below the finest level, and the truncation's updates
    /// of the coarse matrices.
    pub coarse: f64,
    /// The conjugate gradients' vector updates and inner products, and the
    /// product A_T c after them.
    pub krylov: f64,
    /// The projection, the exact line searches (the correction's and the
    /// rigid mode's) and the stopping test.
    pub line_search: f64,
}

impl Phases {
    /// Their names as diagnostics: each ends in `_seconds`, which keeps
    /// them out of the trials' reproducible columns.
    pub(crate) const NAMES: [&'static str; 5] = [
        "tnnmg_setup_seconds",
        "tnnmg_smoothing_seconds",
        "tnnmg_coarse_seconds",
        "tnnmg_krylov_seconds",
        "tnnmg_line_search_seconds",
    ];

    pub(crate) fn add(&mut self, o: &Phases) {
        self.setup += o.setup;
        self.smoothing += o.smoothing;
        self.coarse += o.coarse;
        self.krylov += o.krylov;
        self.line_search += o.line_search;
    }

    /// (name, seconds) of each phase.
    pub(crate) fn diagnostics(&self) -> [(&'static str, f64); 5] {
        let s = [
            self.setup,
            self.smoothing,
            self.coarse,
            self.krylov,
            self.line_search,
        ];
        std::array::from_fn(|k| (Self::NAMES[k], s[k]))
    }
}

/// The iteration's vectors, allocated once per solve.
pub(crate) struct Workspace {
    /// The seconds of the iterations run with it, by phase.
    pub phases: Phases,
    c: Vec<f64>,
    ac: Vec<f64>,
    /// The conjugate gradients' residual; before them, the defect
    /// r = b − A v the presmoothing leaves, and after them r again, rebuilt
    /// for the line search (see [`iterate`]).
    lin_r: Vec<f64>,
    lin_z: Vec<f64>,
    /// A_T z of the V-cycle's z (its last sweep leaves it); after the
    /// conjugate gradients, A_T c for the line search.
    lin_az: Vec<f64>,
    lin_p: Vec<f64>,
    /// The defect r at the contact unknowns, where the conjugate
    /// gradients' right-hand side d differs from it by more than the rigid
    /// mode: with them, r is rebuilt after the conjugate gradients and
    /// needs no vector of its own.
    r_contact: Vec<(usize, f64)>,
    truncated: Vec<bool>,
    /// D's diagonal; empty while every curvature is zero (the
    /// given-friction laws), so that no vector of n is spent on it.
    shift: Vec<f64>,
}

impl Workspace {
    pub(crate) fn new(n: usize) -> Self {
        let zeros = || vec![0.0; n];
        Self {
            phases: Phases::default(),
            c: zeros(),
            ac: zeros(),
            lin_r: zeros(),
            lin_z: zeros(),
            lin_az: zeros(),
            lin_p: zeros(),
            r_contact: Vec::new(),
            truncated: vec![false; n],
            shift: Vec::new(),
        }
    }

    /// As new, for another solve of the same size: the truncated set and
    /// the curvatures cleared (every other vector is written before it is
    /// read).
    pub(crate) fn reset(&mut self) {
        self.truncated.fill(false);
        self.shift.clear();
    }

    /// The number of unknowns it is for.
    pub(crate) fn n(&self) -> usize {
        self.c.len()
    }

    /// The step v took after the presmoothing of the last iteration: the
    /// projected correction and the near-kernel step, times their step
    /// lengths.
    pub(crate) fn step(&self) -> &[f64] {
        &self.c
    }
}

impl Cycle {
    /// The V-cycle's sweeps: (below the finest level, on it).
    fn sweeps(&self) -> (usize, usize) {
        (self.linear_sweeps, self.finest_sweeps)
    }
}

/// One iteration from v (see the module); `p` the hierarchy's
/// prolongations. Returns a bound on the presmoothing's largest move of an
/// unknown (the sum of its sweeps' largest); the step after it is left in
/// [`Workspace::step`]. Their sum bounds max|Δv| without a copy of v.
pub(crate) fn iterate(
    energy: &Energy<'_>,
    hierarchy: &mut Hierarchy,
    p: &[Csr],
    cycle: Cycle,
    ws: &mut Workspace,
    v: &mut [f64],
) -> f64 {
    let (a, laws, contact) = (energy.a, energy.laws, energy.contact);
    let n = v.len();
    // The presmoothing; its last sweep leaves the defect r = b − A v
    // behind (without one, a product computes it), in the conjugate
    // gradients' residual: their first residual d is r but at the contact
    // unknowns and along the rigid mode.
    let clock = Instant::now();
    let parts = hierarchy.parts.as_ref();
    let mut smoothing_moved = 0.0;
    for sweep in 1..=cycle.presmoothing {
        let last = (sweep == cycle.presmoothing).then_some(&mut ws.lin_r[..]);
        smoothing_moved += nonlinear_sweep(a, &hierarchy.diag, parts, energy.b, laws, v, last);
    }
    if cycle.presmoothing == 0 {
        spmv_into(a, v, &mut ws.lin_r);
        for (rk, bk) in ws.lin_r.iter_mut().zip(energy.b) {
            *rk = bk - *rk;
        }
    }
    let mut lap = lap_timer(clock);
    ws.phases.smoothing += lap();
    // The truncated set, the Newton step's curvature and its defect d (the
    // conjugate gradients' first residual, kept in their vector).
    let mut kernel_free = energy.kernel.is_some();
    ws.r_contact.clear();
    for &k in contact {
        let law = laws[k];
        let cut = law.at_kink(v[k]);
        ws.truncated[k] = cut;
        let curvature = if cut { 0.0 } else { law.curvature(v[k]) };
        if curvature != 0.0 && ws.shift.is_empty() {
            ws.shift.resize(v.len(), 0.0);
        }
        if let Some(d) = ws.shift.get_mut(k) {
            *d = curvature;
        }
        let rk = ws.lin_r[k];
        ws.r_contact.push((k, rk));
        ws.lin_r[k] = if cut {
            kernel_free &= !matches!(law, Local::Jump(_));
            0.0
        } else {
            rk - law.slope(v[k], 1.0)
        };
    }
    let mut along = None;
    if let (true, Some((z, zz))) = (kernel_free, energy.kernel) {
        let a = dot(&ws.lin_r, z) / zz;
        axpy(&mut ws.lin_r, -a, z);
        along = Some((a, z));
    }
    hierarchy.truncate(a, p, &ws.truncated, &ws.shift);
    ws.phases.coarse += lap();
    // Conjugate gradients on T(A + D)T c = d preconditioned by the V-cycle
    // (its symmetric Gauss-Seidel makes it symmetric positive definite on
    // the free unknowns).
    let Workspace {
        c,
        ac,
        lin_r,
        lin_z,
        lin_az,
        lin_p,
        r_contact,
        truncated,
        shift,
        phases,
    } = ws;
    fill(c, 0.0);
    // Each V-cycle also returns A_T z (its last sweep leaves it), and the
    // search directions' products follow: A_T p = A_T z + β A_T p.
    hierarchy.v_cycle(a, p, truncated, lin_r, cycle.sweeps(), lin_z, lin_az);
    copy(lin_p, lin_z);
    copy(ac, lin_az);
    let mut rz = dot(lin_r, lin_z);
    for step in 0..cycle.linear_steps {
        let pq = dot(lin_p, ac);
        if !(pq > 0.0 && rz > 0.0) {
            break;
        }
        let step_length = rz / pq;
        let (dc, dr) = (Disjoint::of(c), Disjoint::of(lin_r));
        let (ps, qs) = (&*lin_p, &*ac);
        for_each_chunk(n, |k| {
            // SAFETY: each chunk once.
            let (c, r) = unsafe { (dc.slice(k.clone()), dr.slice(k.clone())) };
            for ((ck, rk), (pk, qk)) in c
                .iter_mut()
                .zip(r.iter_mut())
                .zip(ps[k.clone()].iter().zip(&qs[k]))
            {
                *ck += step_length * pk;
                *rk -= step_length * qk;
            }
        });
        if step + 1 == cycle.linear_steps {
            break;
        }
        hierarchy.v_cycle(a, p, truncated, lin_r, cycle.sweeps(), lin_z, lin_az);
        let rz_next = dot(lin_r, lin_z);
        let beta = rz_next / rz;
        rz = rz_next;
        let (dp, dq) = (Disjoint::of(lin_p), Disjoint::of(ac));
        let (zs, azs) = (&*lin_z, &*lin_az);
        for_each_chunk(n, |k| {
            // SAFETY: each chunk once.
            let (p, q) = unsafe { (dp.slice(k.clone()), dq.slice(k.clone())) };
            for ((pk, zk), (qk, azk)) in p
                .iter_mut()
                .zip(&zs[k.clone()])
                .zip(q.iter_mut().zip(&azs[k]))
            {
                *pk = zk + beta * *pk;
                *qk = azk + beta * *qk;
            }
        });
    }
    // w = A_T c by a product, and r rebuilt in the conjugate gradients'
    // residual, d − A_T c: r = d + (A_T c) + a z but at the contact
    // unknowns, whose r was kept aside. Rebuilding w instead (from r kept
    // in a vector of its own, w = d − their residual) cost that vector, a
    // fifth of TNNMG's vectors of n; the product costs one A·v per
    // iteration.
    let w = lin_az;
    truncated_product(a, truncated, shift, c, w);
    let r = lin_r;
    axpy(r, 1.0, w);
    if let Some((a, z)) = along {
        axpy(r, a, z);
    }
    for &(k, rk) in r_contact.iter() {
        r[k] = rk;
    }
    // The conjugate gradients' time: the V-cycles' (finest level and
    // coarse levels) and their own vector work, and the product.
    let cg = lap();
    let finest = hierarchy.take_finest_seconds();
    let cycles = hierarchy.take_cycle_seconds();
    phases.smoothing += finest;
    phases.coarse += cycles - finest;
    phases.krylov += cg - cycles;
    // The projection onto the admissible set: v + c keeps t ≤ 0, so that a
    // full step is admissible (Gräser & Sander 2019, Algorithm 1, step 4).
    // A c follows the few entries the projection moved: A is symmetric, so
    // its column k is its row k.
    for &k in contact {
        if let Local::Jump(d) = laws[k] {
            let projected = (v[k] + c[k]).min(d) - v[k];
            let moved = projected - c[k];
            if moved != 0.0 {
                c[k] = projected;
                let row = a.row(k);
                for (j, &akj) in row.0.iter().zip(row.1) {
                    w[j] += akj * moved;
                }
            }
        }
    }
    let alpha = exact_step(laws, contact, v, c, dot(c, w), dot(c, r));
    axpy(v, alpha, c);
    axpy(r, -alpha, w);
    // From here on c holds the step this correction took (see
    // [`Workspace::step`]).
    scale(c, alpha);
    // The near-kernel step: while a few closed jumps hold the upper body,
    // T z (the rigid mode without the truncated unknowns) is a direction
    // of very low energy that the V-cycle barely sees (a point constraint
    // has no capacity in the coarse spaces); an exact line search along it
    // moves the body as a whole until the next jump closes. From a start
    // with every node open (problem 1 at 1/32) it took TNNMG from 56 to 35
    // iterations.
    //
    // Its curvature needs no product: A z = 0, so with e = z − T z (z on
    // the truncated set only) (T z)ᵀ A (T z) = eᵀ A e, a sum over the
    // truncated rows, and free of the cancellation of the product's
    // (T z is the low-energy direction).
    if let (false, Some((z, _))) = (kernel_free, energy.kernel) {
        // Its direction in a vector the conjugate gradients are done with.
        let tz = lin_p;
        for ((tk, zk), &cut) in tz.iter_mut().zip(z).zip(&*truncated) {
            *tk = if cut { 0.0 } else { *zk };
        }
        let cac: f64 = contact
            .iter()
            .filter(|&&k| truncated[k] && z[k] != 0.0)
            .map(|&k| {
                let row = a.row(k);
                let ae_k: f64 = row
                    .0
                    .iter()
                    .zip(row.1)
                    .filter(|&(j, _)| truncated[j])
                    .map(|(j, &akj)| akj * z[j])
                    .sum();
                z[k] * ae_k
            })
            .sum();
        let cr = dot(tz, r);
        if cr < 0.0 {
            for tk in tz.iter_mut() {
                *tk = -*tk;
            }
        }
        let beta = exact_step(laws, contact, v, tz, cac, cr.abs());
        axpy(v, beta, tz);
        axpy(c, beta, tz);
    }
    phases.line_search += lap();
    smoothing_moved
}

/// A lap clock from `start`: each call returns the seconds since the last
/// (or since `start`).
fn lap_timer(start: Instant) -> impl FnMut() -> f64 {
    let mut last = start;
    move || {
        let now = Instant::now();
        let lap = (now - last).as_secs_f64();
        last = now;
        lap
    }
}

#[cfg(test)]
mod tests {
    use super::super::smoother::diagonal_places;
    use super::super::vcycle::tests::csr;
    use super::*;

    /// The 1D Laplacian on 2^k + 1 nodes with free ends: singular, its
    /// kernel the constants (a rigid translation).
    fn free_laplacian(k: u32) -> Csr {
        let n = (1usize << k) + 1;
        let mut t = Vec::new();
        for i in 0..n {
            t.push((i, i, if i == 0 || i == n - 1 { 1.0 } else { 2.0 }));
            if i > 0 {
                t.push((i, i - 1, -1.0));
                t.push((i - 1, i, -1.0));
            }
        }
        csr(&t, n, n).shared()
    }

    /// Linear interpolation from 2^(k−1) + 1 to 2^k + 1 nodes.
    fn interpolation(k: u32) -> Csr {
        let nc = (1usize << (k - 1)) + 1;
        let mut t = vec![(0, 0, 1.0)];
        for j in 1..nc {
            t.extend([
                (2 * j - 1, j - 1, 0.5),
                (2 * j - 1, j, 0.5),
                (2 * j, j, 1.0),
            ]);
        }
        csr(&t, 2 * nc - 1, nc).shared()
    }

    /// The stopping test's bound, the presmoothing's largest move plus the
    /// largest entry of the step after it, is at least the change of v
    /// over each iteration: with jumps that close (so that the near-kernel
    /// step along the translation runs) and slips that stick and slide, up
    /// to the rounding of v's own additions.
    /// A step left out of [`Workspace::step`], or a sweep that reports
    /// less than it moved, makes the change exceed it; a step reported
    /// longer than taken makes it exceed the change plus the smoothing's.
    #[test]
    fn the_change_bound_holds_every_iteration() {
        let k = 6;
        let a = free_laplacian(k);
        let n = a.nrows();
        let p: Vec<Csr> = (2..=k).map(interpolation).collect();
        let z = vec![1.0; n];
        let mut laws = Laws::free(n);
        // One jump closed at the left end holds the whole bar (its
        // truncation is a single point, which the coarse spaces barely
        // see); another, open, in the middle; two slips.
        let jumps = [0, 32];
        let mut contact = vec![0, 20, 32, 40];
        for j in jumps {
            laws.set(j, Local::Jump(0.0));
        }
        laws.set(20, Local::Slip(0.02));
        laws.set(40, Local::Slip(0.5));
        contact.sort_unstable();
        // A net load along +z, which the closed jump holds.
        let b: Vec<f64> = (0..n)
            .map(|i| 0.02 + 0.1 * (0.37 * i as f64).sin())
            .collect();
        let energy = Energy {
            a: &a,
            b: &b,
            laws: &laws,
            contact: &contact,
            kernel: Some((&z, n as f64)),
        };
        // Without presmoothing the bound is the step alone, and equals the
        // change: every part of the step is checked.
        for presmoothing in [1, 0] {
            let mut hierarchy = Hierarchy::new(&a, diagonal_places(&a).unwrap(), &p).unwrap();
            let cycle = Cycle {
                presmoothing,
                linear_steps: 2,
                linear_sweeps: 1,
                finest_sweeps: 1,
            };
            let mut ws = Workspace::new(n);
            let mut v = vec![-1.0; n];
            v[0] = 0.0;
            let mut closed = 0;
            for _ in 0..30 {
                let before = v.clone();
                let smoothing = iterate(&energy, &mut hierarchy, &p, cycle, &mut ws, &mut v);
                let change = v
                    .iter()
                    .zip(&before)
                    .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
                let step = ws.step().iter().fold(0.0f64, |m, s| m.max(s.abs()));
                let bound = smoothing + step;
                // Up to the rounding of the additions to v (a few ulps of it).
                let size = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                let ulps = 4.0 * f64::EPSILON * size;
                assert!(
                    change <= bound + ulps,
                    "change {change:e} > bound {bound:e} (smoothing {smoothing:e}, step {step:e})"
                );
                // And the step is the one taken: v − v_before − step is the
                // presmoothing's move.
                assert!(
                    step <= change + smoothing + ulps,
                    "step {step:e} > change {change:e} + smoothing {smoothing:e}"
                );
                closed += usize::from(v[0] == 0.0);
            }
            assert!(
                closed > 0,
                "the jump stayed closed: the near-kernel step ran"
            );
            assert!(
                jumps.iter().all(|&j| v[j] <= 0.0),
                "the jumps stay admissible"
            );
        }
    }
}
