//! An upper bound on an answer's error, from the duality gap (issue 51): how
//! far the displacements and pressures can be from the exact solution of
//! the discrete problem, computed from the answer alone.
//!
//! The given-friction problem (paper (10), in the unknowns of
//! [`ContactProblem`]) is
//!
//! ```text
//! minimize J(v) = ½ vᵀA v − fᵀv + Σ_i w_i g_i |s_i|   over t_i ≤ 0.
//! ```
//!
//! For multipliers (p, q) with p ≥ 0 and |q_i| ≤ g_i, the Lagrangian
//! L(v; p, q) = ½ vᵀA v − rᵀv with r = f − Σ w_i p_i e_{t_i} + Σ w_i q_i e_{s_i}
//! is below J on the admissible set, so its minimum over all v, the dual
//! value D(p, q) = −½ rᵀA⁺r, is below J(v*) (weak duality). It is finite
//! only if r carries no load along the rigid mode z: zᵀr = 0, the balance
//! (13) of the semicoercive problem. And since J is ½‖·‖²_A plus convex
//! terms and v* minimizes it over a convex set, J(v) − J(v*) ≥ ½‖v − v*‖²_A
//! for every admissible v. Hence
//!
//! ```text
//! ½‖v − v*‖²_A ≤ J(v) − D(p, q) = C + ½ ρᵀA⁺ρ,
//! C = Σ_i w_i (g_i |s_i| + q_i s_i − p_i t_i) ≥ 0   (the complementarity gap),
//! ρ = A v − r                                        (the stationarity residual),
//! ```
//!
//! which needs one solve with A ([`EnergySolve`], the certificate's own).
//! An answer is first repaired into that setting, each step keeping the
//! bound valid (`ErrorBounder::energy`):
//! - p is clipped to p ≥ 0 and q to |q| ≤ g; where a local estimate says it
//!   is cheaper than closing the gap, a pressure against an open jump is
//!   dropped and a traction at a slipping node turned to its bound;
//! - the pressures are scaled (or, failing that, shifted) so that the load
//!   along z is balanced exactly;
//! - v is shifted along z, to which the energy norm is blind;
//! - every jump and slip still at odds with (p, q) (a penetration, an open
//!   jump under pressure, a slip against or beside its traction) is closed,
//!   so that C = 0 for the repaired v_c; the change at Γ_K is extended into
//!   the bodies with least energy, and ‖v − v*‖_A ≤ ‖v − v_c‖_A +
//!   ‖v_c − v*‖_A (the first term computed);
//! - both the forces given and those the displacements imply are tried,
//!   shifted and not, and the smallest bound kept (each is an upper bound).
//!
//! The pressure follows by Cauchy–Schwarz in the A inner product: at the
//! exact solution w_i p*_i = −(A v* − f)_{t_i}, so for the pressure the
//! displacements imply, |p_i(v) − p*_i| = |e_{t_i}ᵀA(v − v*)| / w_i ≤
//! √A_{t_i t_i} ‖v − v*‖_A / w_i, and the answer's own pressure adds its
//! distance from the implied one.
//!
//! For the Coulomb law the bound is that of the given-friction problem at
//! the answer's own bound g = 𝓕 max(p, 0) ([`BoundKind::AtOwnBound`]): it
//! is rigorous for that problem; the distance from there to the Coulomb
//! solution (the fixed point's part) is not included.
//!
//! The energy seminorm does not see the rigid translation z: a bound on
//! ‖v − v*‖_A says nothing about how far the upper body sits along z.
//!
//! Rounding: ρ is a difference of terms far larger than itself, so each of
//! its rows (and the refinement's residual ρ − A y) is summed by Dot2
//! ([`super::accurate_sum`]: as if in twice the working precision), and the
//! rows' error bounds b enter as an allowance ‖b‖_{A⁺} (an estimate of the
//! largest ‖δρ‖_{A⁺} over |δρ| ≤ b: b's signs taken alike). The solve is
//! refined once and the refinement's change added; the long sums of ‖d‖_A
//! carry an allowance of 32 ε |d|ᵀ|A| |d|, and the shift along z one for
//! the rounding of v + τ z. Summed plainly, ρ's rounding grew with A's
//! condition number and was the bound's floor (1.4e-9 √K·U at h = 1/128);
//! by Dot2 the reference's own bound there is 3.4e-12 (`tests/error_bound.rs`).
//!
//! A Coulomb answer of a fixed point also gets the fixed point's part
//! estimated from its contraction factor ([`FixedPointEstimate`]).

use contactlab_solvers::{ContactProblem, Friction, Law, Solution};
use serde::{Deserialize, Serialize};

use super::accurate_sum::Dot2;
use super::energy_multigrid::MultigridSolve;
use super::energy_solve::{EnergySolve, EnergySolveError};
use super::{fits, implied_forces};

/// What a bound is a bound on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BoundKind {
    /// On the distance to the exact solution of the given-friction problem
    /// that was solved.
    Rigorous,
    /// On the distance to the given-friction solution at the answer's own
    /// bound g = 𝓕p (a Coulomb answer); the fixed point's part, up to the
    /// Coulomb solution, is not included.
    AtOwnBound,
}

impl BoundKind {
    pub fn as_str(self) -> &'static str {
        match self {
            BoundKind::Rigorous => "rigorous",
            BoundKind::AtOwnBound => "rigorous at g = 𝓕p (fixed-point part not included)",
        }
    }

    /// Its name in tables: `rigorous` or `at-own-bound`.
    pub fn tag(self) -> &'static str {
        match self {
            BoundKind::Rigorous => "rigorous",
            BoundKind::AtOwnBound => "at-own-bound",
        }
    }
}

/// An upper bound on the error of an answer (v, p, q).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorBound {
    /// ‖v − v*‖_A, in the problem's units (√(force·length)).
    pub energy: f64,
    /// The same over √K·U (the problem's stiffness and displacement
    /// scales): dimensionless, unchanged by the units.
    pub displacement: f64,
    /// max_i |p_i − p*_i| over the pressure scale P.
    pub pressure: f64,
    pub kind: BoundKind,
}

/// Why no bound was computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BoundError {
    #[error("the answer does not fit the problem (sizes, or a value that is not finite)")]
    Malformed,
    #[error("the problem has {0} rigid modes; the bound handles at most one")]
    RigidModes(usize),
    #[error(
        "no reading of the answer could be repaired: its pressures cannot balance the load along the rigid mode, or the extension of its change at Γ_K failed"
    )]
    Unbalanced,
    #[error(
        "the bound's sums overflow for this answer (A v or its rounding is not finite): no bound"
    )]
    Overflow,
    #[error("the solve with A: {0}")]
    Solve(#[from] EnergySolveError),
}

/// The certificate's factorizations, kept to bound several answers of one
/// problem: A with one unknown per rigid mode pinned (for A⁺), and A
/// without the contact unknowns (for the least-energy extension of a
/// change made at Γ_K).
pub struct ErrorBounder<'a> {
    problem: &'a ContactProblem,
    solve: Inverse,
    /// Built on first use: an answer that needs no change at Γ_K needs no
    /// extension.
    interior: std::sync::OnceLock<Result<Inverse, EnergySolveError>>,
    room: f64,
    /// An upper bound on ‖z‖_A of the rigid mode as assembled
    /// ([`ErrorBounder::energy_upper`]): zero in exact arithmetic, about
    /// 1e-16·K·max|z| per row in floating point. A shift along z adds
    /// |τ|·‖z‖_A to the bound, so that the bound holds for the matrix as
    /// it is, not only for the exact one, and for any plain evaluation of
    /// ‖τ z‖_A (issue 73: summed plainly, this term was rounding noise
    /// itself and fell below a measured ‖τ z‖_A by up to 5×).
    rigid_energy: f64,
    /// For each unknown, the contact node whose force acts on it in ρ:
    /// 2i + 1 for the normal jump of node i, 2i + 2 for its slip, 0 for
    /// none.
    contact_of: Vec<u32>,
}

/// The most unknowns at which the bound factors A (a sparse
/// Cholesky, [`EnergySolve`]); above, where the problem has a hierarchy of
/// nested meshes, it solves by multigrid-preconditioned conjugate
/// gradients ([`MultigridSolve`]): O(n) memory, where the factors grow as
/// n log n and their cost as n^1.5 (at h = 1/512 they took 1.3 GB).
pub const FACTOR_MAX_UNKNOWNS: usize = 40_000;

/// The relative residual of the solve of ρ and of the extension, by
/// multigrid: the refinement then counts what the first left (ρᵀA⁺ρ equals
/// ρᵀy + ρᵀA⁺(ρ − A y) exactly), and counts it twice over; any extension gives
/// a valid bound (its energy is computed as it is), the least-energy one
/// the sharpest (at 1e-2 the bounds of rough answers came out 2e-4 above
/// the factorization's; at this accuracy they agree to 1e-9).
const MAIN_ACCURACY: f64 = 1e-6;

/// The relative residual of the refinement's solve and of the rounding's
/// allowance, by multigrid: each enters the bound as an allowance, of which
/// two digits are enough.
const CORRECTION_ACCURACY: f64 = 1e-2;

/// How the bound solves with A.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundSolve {
    /// A factorization up to [`FACTOR_MAX_UNKNOWNS`], multigrid above it
    /// where the problem has a hierarchy.
    Auto,
    /// A sparse Cholesky ([`EnergySolve`]) at every size.
    Factor,
    /// Multigrid ([`MultigridSolve`]) at every size (a factorization
    /// without a hierarchy).
    Multigrid,
}

/// The certificate's solve with A: a factorization, or multigrid.
enum Inverse {
    Factor(Box<EnergySolve>),
    Multigrid(MultigridSolve),
}

impl Inverse {
    /// A with one unknown per rigid mode pinned (factored), or A on z^⊥
    /// (multigrid, above [`FACTOR_MAX_UNKNOWNS`] with a hierarchy).
    fn new(problem: &ContactProblem, room: f64, how: BoundSolve) -> Result<Self, EnergySolveError> {
        let multigrid = match how {
            BoundSolve::Auto => problem.n() > FACTOR_MAX_UNKNOWNS,
            BoundSolve::Factor => false,
            BoundSolve::Multigrid => true,
        };
        if multigrid && let Some(multigrid) = MultigridSolve::new(problem, room) {
            return multigrid.map(Inverse::Multigrid);
        }
        let pinned = super::problem_checks::pinned_unknowns(problem.rigid_modes());
        EnergySolve::new(problem, &pinned, room).map(|f| Inverse::Factor(Box::new(f)))
    }

    /// The same kind of solve for A without the unknowns `pinned`.
    fn pinned(
        &self,
        problem: &ContactProblem,
        pinned: &[usize],
        room: f64,
    ) -> Result<Self, EnergySolveError> {
        match self {
            Inverse::Factor(_) => {
                EnergySolve::new(problem, pinned, room).map(|f| Inverse::Factor(Box::new(f)))
            }
            Inverse::Multigrid(m) => Ok(Inverse::Multigrid(m.pinned(pinned))),
        }
    }

    /// A⁺b (b balanced) or A_FF⁻¹ b_F; `relative` is the residual asked
    /// of multigrid (a factorization solves to its rounding).
    fn solve(&self, b: &[f64], relative: f64) -> Result<Vec<f64>, EnergySolveError> {
        match self {
            Inverse::Factor(f) => Ok(f.solve(b)),
            Inverse::Multigrid(m) => m.solve(b, relative),
        }
    }
}

/// One way of reading an answer: its forces as given or as its
/// displacements imply them, and the displacements shifted along the
/// rigid mode or not.
struct Reading<'r> {
    p: &'r [f64],
    q: &'r [f64],
    shift: bool,
}

impl<'a> ErrorBounder<'a> {
    /// Prepares the solves with A (one pinned unknown per rigid mode) and
    /// with A without the contact unknowns, by factorization or multigrid
    /// ([`BoundSolve::Auto`]), refusing if either would take more than
    /// `room` bytes.
    pub fn new(problem: &'a ContactProblem, room: f64) -> Result<Self, BoundError> {
        Self::solving(problem, room, BoundSolve::Auto)
    }

    /// The same, with the solve chosen (to compare the two).
    pub fn solving(
        problem: &'a ContactProblem,
        room: f64,
        how: BoundSolve,
    ) -> Result<Self, BoundError> {
        let modes = problem.rigid_modes();
        if modes.len() > 1 {
            return Err(BoundError::RigidModes(modes.len()));
        }
        let solve = Inverse::new(problem, room, how)?;
        let mut contact_of = vec![0u32; problem.n()];
        for (i, c) in problem.contacts().iter().enumerate() {
            contact_of[c.t] = 2 * i as u32 + 1;
            contact_of[c.s] = 2 * i as u32 + 2;
        }
        let mut out = Self {
            problem,
            solve,
            interior: std::sync::OnceLock::new(),
            room,
            rigid_energy: 0.0,
            contact_of,
        };
        if let Some(z) = modes.first() {
            out.rigid_energy = out.energy_upper(z);
        }
        Ok(out)
    }

    /// The bound for the answer (v, p, q) under `friction`.
    pub fn bound(
        &self,
        friction: Friction<'_>,
        v: &[f64],
        p: &[f64],
        q: &[f64],
    ) -> Result<ErrorBound, BoundError> {
        let problem = self.problem;
        if !fits(problem, friction, v, p, q) {
            return Err(BoundError::Malformed);
        }
        let contacts = problem.contacts();
        // The bound of the given-friction problem: the problem's g, or the
        // answer's own g = 𝓕 max(p, 0) for the Coulomb law.
        let g: Vec<f64> = contacts
            .iter()
            .enumerate()
            .map(|(i, c)| friction.bound(i, c.coefficient, p[i]))
            .collect();
        let implied = implied_forces(problem, v);
        let mut readings = Vec::with_capacity(4);
        for (pr, qr) in [(p, q), (&implied.0[..], &implied.1[..])] {
            for shift in [false, true] {
                readings.push(Reading {
                    p: pr,
                    q: qr,
                    shift,
                });
            }
        }
        let mut best: Option<f64> = None;
        let mut overflow = false;
        for energy in self.energies(v, &g, &readings) {
            match energy? {
                Some(e) if e.is_nan() => overflow = true,
                Some(e) if best.is_none_or(|b| e < b) => best = Some(e),
                _ => {}
            }
        }
        let energy = best.ok_or(if overflow {
            BoundError::Overflow
        } else {
            BoundError::Unbalanced
        })?;
        let s = problem.scales();
        let pressure = contacts
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let diagonal = self.entry(c.t, c.t).max(0.0);
                ((p[i] - implied.0[i]).abs() + diagonal.sqrt() * energy / c.weight) / s.pressure
            })
            .fold(0.0, f64::max);
        if energy.is_nan() || pressure.is_nan() {
            return Err(BoundError::Overflow);
        }
        Ok(ErrorBound {
            energy,
            displacement: energy / (s.stiffness.sqrt() * s.displacement),
            pressure,
            kind: match friction.law() {
                Law::GivenFriction => BoundKind::Rigorous,
                Law::Coulomb => BoundKind::AtOwnBound,
            },
        })
    }

    /// Each reading's bound ([`Self::energy`]): by multigrid, where each
    /// takes a few dozen V-cycles, the readings are shared among the cores
    /// (they are independent); a factorization's solves are parallel
    /// themselves.
    fn energies(
        &self,
        v: &[f64],
        g: &[f64],
        readings: &[Reading<'_>],
    ) -> Vec<Result<Option<f64>, EnergySolveError>> {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let workers = cores.min(readings.len());
        if workers < 2 || !matches!(self.solve, Inverse::Multigrid(_)) {
            return readings.iter().map(|r| self.energy(v, g, r)).collect();
        }
        std::thread::scope(|scope| {
            let handles: Vec<_> = (0..workers)
                .map(|w| {
                    scope.spawn(move || {
                        readings
                            .iter()
                            .skip(w)
                            .step_by(workers)
                            .map(|r| self.energy(v, g, r))
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            handles
                .into_iter()
                .flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                .collect()
        })
    }

    /// The bound ‖v_c − v‖_A + √(2 (J(v_c) − D(p̂, q̂))) of one reading:
    /// (p, q) repaired into the dual-feasible set, v moved to an admissible
    /// v_c; None if the pressures cannot balance the load.
    ///
    /// Each contact node's share of the complementarity gap C is first
    /// weighed against what removing it would cost, estimated from the
    /// diagonal of A: a pressure p̂ > 0 against an open jump t < 0 costs
    /// w p̂ |t| in C, ½ A_tt t² if the jump is closed (v_c), or about
    /// ½ (w p̂)²/A_tt if the pressure is dropped (in ρ); likewise a traction
    /// short of its bound at a slipping node. The cheapest is taken. The
    /// choice only sharpens the bound: any choice gives an upper bound.
    fn energy(
        &self,
        v: &[f64],
        g: &[f64],
        reading: &Reading<'_>,
    ) -> Result<Option<f64>, EnergySolveError> {
        let problem = self.problem;
        let contacts = problem.contacts();
        // The jump past the initial gap, t_i − d_i ≤ 0, is the cone's
        // coordinate: the residual A v − f does not see the gap, only the
        // cone and the complementarity do.
        let gap = problem.gap();
        let z = problem.rigid_modes().first();
        let mut vs = v.to_vec();
        let mut shifted = 0.0;
        if reading.shift
            && let Some(z) = z
        {
            // Along z the energy norm is blind: shift v so that the jumps
            // at nodes that carry pressure are closed on average, weighed
            // by the force each carries (an interior-point answer carries
            // a little pressure everywhere, on open nodes too: weighed
            // alike, they would pull the body into penetration).
            let mut force: Vec<f64> = contacts
                .iter()
                .enumerate()
                .map(|(i, c)| c.weight * reading.p[i].max(0.0))
                .collect();
            let mean_shift = |force: &[f64]| {
                let (mut num, mut den) = (0.0, 0.0);
                for ((c, f), gap) in contacts.iter().zip(force).zip(gap) {
                    num -= f * (v[c.t] - gap) * z[c.t];
                    den += f * z[c.t] * z[c.t];
                }
                num / den
            };
            // Once more without the pressures that the repair below would
            // drop after that shift (small ones on clearly open jumps).
            let first = mean_shift(&force);
            for (i, c) in contacts.iter().enumerate() {
                let t = v[c.t] - gap[i] + first * z[c.t];
                if t < 0.0 && drops(self.entry(c.t, c.t), c.weight * reading.p[i], t) {
                    force[i] = 0.0;
                }
            }
            let second = mean_shift(&force);
            let tau = if second.is_finite() { second } else { first };
            if !(tau.is_finite()) {
                return Ok(None);
            }
            vs.iter_mut().zip(z).for_each(|(x, zk)| *x += tau * zk);
            // ‖v − v_s‖_A ≤ |τ| ‖z‖_A + ‖e‖_A, e the rounding of v + τ z
            // (|e| ≤ 2u (|v| + |τ z|), ‖e‖²_A ≤ |e|ᵀ|A| |e|).
            let size: Vec<f64> = v
                .iter()
                .zip(z)
                .map(|(a, zk)| a.abs() + (tau * zk).abs())
                .collect();
            shifted = tau.abs() * self.rigid_energy
                + f64::EPSILON * (1.0 + f64::EPSILON) * self.absolute_energy(&size);
        }
        let mut ph: Vec<f64> = reading.p.iter().map(|x| x.max(0.0)).collect();
        let mut qh: Vec<f64> = reading
            .q
            .iter()
            .zip(g)
            .map(|(x, gi)| x.clamp(-gi, *gi))
            .collect();
        // Pressures against open jumps and tractions short of their bound
        // at slipping nodes: drop them where that is cheapest.
        for (i, c) in contacts.iter().enumerate() {
            let (att, ass) = (self.entry(c.t, c.t), self.entry(c.s, c.s));
            let t = vs[c.t] - gap[i];
            if t < 0.0 && ph[i] > 0.0 && drops(att, c.weight * ph[i], t) {
                ph[i] = 0.0;
            }
            // The slip past its offset, s_i − σ_i, is the cone's other
            // coordinate.
            let s = problem.slip(&vs, i);
            let slack = g[i] * s.abs() + qh[i] * s;
            if s != 0.0 && slack > 0.0 {
                let keep = c.weight * slack;
                let stop = 0.5 * ass * s * s;
                let full = -g[i] * s.signum();
                let turn = 0.5 * (c.weight * (full - qh[i])).powi(2) / ass;
                if turn < keep.min(stop) {
                    qh[i] = full;
                }
            }
        }
        if let Some(z) = z
            && balance(problem, z, &mut ph, &qh).is_none()
        {
            return Ok(None);
        }
        // v_c: complementary to (p̂, q̂) at every node, so that the gap's
        // C is zero: a jump closed where a pressure acts on it or where it
        // penetrates, a slip stopped where the traction is short of its
        // bound or points along it. The change at Γ_K is extended into
        // the bodies with least energy.
        let mut d = vec![0.0; vs.len()];
        for (i, c) in contacts.iter().enumerate() {
            let t = vs[c.t] - gap[i];
            if t > 0.0 || (t < 0.0 && ph[i] > 0.0) {
                d[c.t] = -t;
            }
            let s = problem.slip(&vs, i);
            if g[i] * s.abs() + qh[i] * s > 0.0 {
                d[c.s] = -s;
            }
        }
        self.extend(&mut d)?;
        let correction = self.energy_upper(&d);
        // ρ = A (v_s + d) − f + Σ w p̂ e_t − Σ w q̂ e_s, each row by Dot2 with
        // a bound on its rounding.
        let (mut rho, mut rounding) = self.residual(&vs, &d, &ph, &qh);
        if let Some(z) = z {
            // Balanced exactly above, up to rounding.
            orthogonal_to(z, &mut rho);
            orthogonal_to(z, &mut rounding);
        }
        let y = self.solve.solve(&rho, MAIN_ACCURACY)?;
        // One refinement: the residual ρ − A y (by Dot2) solved again; its
        // change to ρᵀy is counted as rounding allowance.
        let residual: Vec<f64> = (0..rho.len())
            .map(|i| {
                let mut acc = Dot2::default();
                acc.add(1.0, rho[i]);
                let (cols, vals) = problem.a().row(i);
                for (c, a) in cols.iter().zip(vals) {
                    acc.add(-a, y[c]);
                }
                acc.value().0
            })
            .collect();
        let dy = self.solve.solve(&residual, CORRECTION_ACCURACY)?;
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let first = dot(&rho, &y);
        let change = dot(&rho, &dy);
        let quadratic = (first + change).max(0.0) + change.abs();
        let quadratic = quadratic * (1.0 + 4.0 * f64::EPSILON);
        // ρ's rounding, measured as ρ is: ‖b‖_{A⁺} for the rows' error
        // bounds b (an estimate of ‖δρ‖_{A⁺} over |δρ| ≤ b: its signs taken
        // alike, which A⁺ damps least).
        let by = self.solve.solve(&rounding, CORRECTION_ACCURACY)?;
        let allowance = dot(&rounding, &by).max(0.0).sqrt();
        Ok(Some(quadratic.sqrt() + allowance + correction + shifted))
    }

    /// Extends `d`, given at the contact unknowns (zero elsewhere on
    /// entry), into the bodies with least energy: d_F = −A_FF⁻¹ A_FS d_S.
    fn extend(&self, d: &mut [f64]) -> Result<(), EnergySolveError> {
        let support: Vec<usize> = (0..d.len()).filter(|&k| d[k] != 0.0).collect();
        if support.is_empty() {
            return Ok(());
        }
        let interior = self
            .interior
            .get_or_init(|| {
                let contact: Vec<usize> = self
                    .problem
                    .contacts()
                    .iter()
                    .flat_map(|c| [c.t, c.s])
                    .collect();
                self.solve.pinned(self.problem, &contact, self.room)
            })
            .as_ref()
            .map_err(Clone::clone)?;
        let mut rhs = self.product_on(d, &support);
        rhs.iter_mut().for_each(|x| *x = -*x);
        let inside = interior.solve(&rhs, MAIN_ACCURACY)?;
        for (k, x) in inside.iter().enumerate() {
            if *x != 0.0 {
                d[k] = *x;
            }
        }
        Ok(())
    }

    /// An upper bound on ‖x‖_A for the stored A, whichever way it is
    /// evaluated: xᵀA x by Dot2 (each row's (A x)_i and the outer sum,
    /// with their error bounds), plus γ_{m+n} |x|ᵀ|A| |x| (m the longest
    /// row, n the unknowns: the worst-case rounding of a plain evaluation,
    /// Higham, *Accuracy and Stability of Numerical Algorithms*, 2002,
    /// §3.1), so that the bound is not below ‖x‖_A computed plainly. For a
    /// rigid shift, where xᵀA x is zero in exact arithmetic, the allowance
    /// is the whole.
    fn energy_upper(&self, x: &[f64]) -> f64 {
        let a = self.problem.a();
        let mut outer = Dot2::default();
        let (mut size, mut row_error, mut longest) = (0.0, 0.0, 0usize);
        for i in 0..x.len() {
            if x[i] == 0.0 {
                continue;
            }
            let (cols, vals) = a.row(i);
            let mut row = Dot2::default();
            let mut row_size = 0.0;
            let mut len = 0;
            for (c, v) in cols.iter().zip(vals) {
                row.add(*v, x[c]);
                row_size += (v * x[c]).abs();
                len += 1;
            }
            longest = longest.max(len);
            let (ax, e) = row.value();
            outer.add(x[i], ax);
            row_error += x[i].abs() * e;
            size += x[i].abs() * row_size;
        }
        let (value, outer_error) = outer.value();
        let terms = (longest + x.len()) as f64;
        let u = f64::EPSILON / 2.0;
        let gamma = terms * u / (1.0 - terms * u).max(0.5);
        let upper = value.max(0.0) + outer_error + row_error + gamma * size;
        (upper * (1.0 + 4.0 * f64::EPSILON)).sqrt()
    }

    /// ρ = A (v + d) − f + Σ w p̂ e_t − Σ w q̂ e_s, row by row by Dot2 (the
    /// terms of A v and A d kept apart, never v + d rounded), and each
    /// row's error bound.
    fn residual(&self, v: &[f64], d: &[f64], p: &[f64], q: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let problem = self.problem;
        let (f, contacts) = (problem.f(), problem.contacts());
        let mut rho = vec![0.0; v.len()];
        let mut error = vec![0.0; v.len()];
        for i in 0..v.len() {
            let mut acc = Dot2::default();
            let (cols, vals) = problem.a().row(i);
            for (c, &a) in cols.iter().zip(vals) {
                acc.add(a, v[c]);
                if d[c] != 0.0 {
                    acc.add(a, d[c]);
                }
            }
            acc.add(-1.0, f[i]);
            match self.contact_of[i] {
                0 => {}
                k if k % 2 == 1 => {
                    let j = (k as usize - 1) / 2;
                    acc.add(contacts[j].weight, p[j]);
                }
                k => {
                    let j = (k as usize - 2) / 2;
                    acc.add(-contacts[j].weight, q[j]);
                }
            }
            (rho[i], error[i]) = acc.value();
        }
        (rho, error)
    }

    /// √(xᵀ|A| x) for x ≥ 0 (plain sums, with a factor for their rounding):
    /// a bound on ‖e‖_A for every |e| ≤ x.
    fn absolute_energy(&self, x: &[f64]) -> f64 {
        let a = self.problem.a();
        let sum: f64 = (0..x.len())
            .map(|i| {
                let (cols, vals) = a.row(i);
                x[i] * cols
                    .iter()
                    .zip(vals)
                    .map(|(c, v)| (v * x[c]).abs())
                    .sum::<f64>()
            })
            .sum();
        (sum * (1.0 + 64.0 * f64::EPSILON)).sqrt()
    }

    /// A x for an x that is zero outside `support` (a few entries).
    fn product_on(&self, x: &[f64], support: &[usize]) -> Vec<f64> {
        let mut out = vec![0.0; x.len()];
        for &j in support {
            // A is symmetric: column j is row j.
            let (cols, vals) = self.problem.a().row(j);
            for (c, a) in cols.iter().zip(vals) {
                out[c] += a * x[j];
            }
        }
        out
    }

    fn entry(&self, i: usize, j: usize) -> f64 {
        let (cols, vals) = self.problem.a().row(i);
        cols.iter()
            .zip(vals)
            .find(|&(c, _)| c == j)
            .map_or(0.0, |(_, &a)| a)
    }
}

/// Whether a force w p > 0 against an open jump t < 0 costs least dropped:
/// it costs w p |t| kept (in the gap C), ½ A_tt t² with the jump closed,
/// about ½ (w p)²/A_tt dropped (in ρ).
fn drops(att: f64, force: f64, t: f64) -> bool {
    let keep = force * -t;
    let close = 0.5 * att * t * t;
    let drop = 0.5 * force * force / att;
    drop < keep.min(close)
}

/// Takes off x's part along z: the part A⁺ is not defined on (A z = 0),
/// which a balanced residual has only up to rounding.
fn orthogonal_to(z: &[f64], x: &mut [f64]) {
    let zz: f64 = z.iter().map(|a| a * a).sum();
    let zx: f64 = z.iter().zip(x.iter()).map(|(a, b)| a * b).sum();
    for (xk, zk) in x.iter_mut().zip(z) {
        *xk -= zx / zz * zk;
    }
}

/// Makes the pressures `p` (≥ 0) carry the load along the rigid mode z
/// with the tractions `q`: zᵀ(f − Σ w p e_t + Σ w q e_s) = 0, by scaling p
/// or, if that cannot keep p ≥ 0, by adding one pressure to every node.
fn balance(problem: &ContactProblem, z: &[f64], p: &mut [f64], q: &[f64]) -> Option<()> {
    let load: f64 = z.iter().zip(problem.f()).map(|(a, b)| a * b).sum();
    let (mut carried, mut unit, mut traction) = (0.0, 0.0, 0.0);
    for (i, c) in problem.contacts().iter().enumerate() {
        carried += c.weight * p[i] * z[c.t];
        unit += c.weight * z[c.t];
        traction += c.weight * q[i] * z[c.s];
    }
    let need = load + traction;
    let scale = need / carried;
    if scale.is_finite() && scale >= 0.0 {
        p.iter_mut().for_each(|x| *x *= scale);
        return Some(());
    }
    let shift = (need - carried) / unit;
    if shift.is_finite() && p.iter().all(|x| x + shift >= 0.0) {
        p.iter_mut().for_each(|x| *x += shift);
        return Some(());
    }
    None
}

/// The bound for one answer, with a factorization of its own (see
/// [`ErrorBounder`] to bound several answers of one problem).
pub fn error_bound(
    problem: &ContactProblem,
    friction: Friction<'_>,
    v: &[f64],
    p: &[f64],
    q: &[f64],
    room: f64,
) -> Result<ErrorBound, BoundError> {
    ErrorBounder::new(problem, room)?.bound(friction, v, p, q)
}

/// The largest problem whose bound `solve` and every trial compute beside
/// the answer (h = 1/512 has 526 082 unknowns). Above 40 000 unknowns
/// ([`FACTOR_MAX_UNKNOWNS`]) the bound solves by multigrid, O(n): on
/// problem 1 with tnnmg (wall time and peak memory of the whole `solve`,
/// without → with the bound) 1/256: 0.35 → 1.11 s, 28 → 127 MB; 1/512:
/// 1.46 → 4.75 s, 83 → 412 MB; 1/1024: 3.5 → 16.9 s, 0.30 → 1.57 GB
/// (by factorization it had added 4.6 s and 1.3 GB at 1/512). Finer, the
/// bound costs several times the fastest solve; `certify` bounds an answer
/// at any h that fits in memory.
pub const SOLVE_BOUND_MAX_UNKNOWNS: usize = 600_000;

/// The fixed point's part of a Coulomb answer's error, estimated from the
/// fixed point's observed contraction factor k (paper (9): g ↦ 𝓕 p(S(g)),
/// S the given-friction solution). The bound at the answer's own g bounds
/// ‖v − Φ(v)‖_A for the fixed point's map Φ(v) = S(𝓕 p(v)); if Φ
/// contracts with factor k, ‖v − v*‖ ≤ ‖v − Φ(v)‖ + ‖Φ(v) − Φ(v*)‖ gives
/// ‖v − v*‖_A ≤ E/(1 − k). For the pressure, |g − g*| ≤ |g − T(g)|/(1 −
/// k) in max norm for T(g) = 𝓕 p(S(g)), and |g − T(g)| ≤ 𝓕 P_b, so
/// |p − p*| ≤ P_b + k 𝓕 P_b/((1 − k) 𝓕) = P_b/(1 − k) (one coefficient
/// 𝓕). An estimate, not a bound: k is observed on max|Δg| over the last
/// friction iterations, not proved, and the energy's contraction is taken
/// to be the same.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FixedPointEstimate {
    /// The contraction factor the estimate assumes.
    pub contraction: f64,
    /// ‖v − v*‖_A, the same over √K·U, and max|p − p*| over P (the
    /// Coulomb solution v*, p*), estimated.
    pub energy: f64,
    pub displacement: f64,
    pub pressure: f64,
}

/// The bound of an answer as reported beside its certificate: the bound,
/// or why there is none, and for a Coulomb answer of a fixed point the
/// estimate of the whole error.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BoundReport {
    pub bound: Option<ErrorBound>,
    pub not_computed: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed_point: Option<FixedPointEstimate>,
}

impl BoundReport {
    /// No bound, and why.
    pub fn skipped(why: impl Into<String>) -> Self {
        Self {
            bound: None,
            not_computed: Some(why.into()),
            fixed_point: None,
        }
    }

    /// With the fixed point's part estimated ([`FixedPointEstimate`]) for
    /// a bound at the answer's own g and a contraction factor k in [0, 1)
    /// (none otherwise: a direct Coulomb solver observes no k).
    pub fn with_contraction(mut self, k: Option<f64>) -> Self {
        self.fixed_point = match (self.bound, k) {
            (Some(b), Some(k)) if b.kind == BoundKind::AtOwnBound && (0.0..1.0).contains(&k) => {
                let factor = 1.0 / (1.0 - k);
                Some(FixedPointEstimate {
                    contraction: k,
                    energy: b.energy * factor,
                    displacement: b.displacement * factor,
                    pressure: b.pressure * factor,
                })
            }
            _ => None,
        };
        self
    }

    /// The bound of (v, p, q), with factors allowed at most `room` bytes.
    pub fn of(
        problem: &ContactProblem,
        friction: Friction<'_>,
        v: &[f64],
        p: &[f64],
        q: &[f64],
        room: f64,
    ) -> Self {
        match error_bound(problem, friction, v, p, q, room) {
            Ok(b) => Self {
                bound: Some(b),
                not_computed: None,
                fixed_point: None,
            },
            Err(e) => Self::skipped(e.to_string()),
        }
    }

    /// The bound of a solver's answer (its v, pressures and tractions).
    pub fn of_solution(
        problem: &ContactProblem,
        friction: Friction<'_>,
        s: &Solution,
        room: f64,
    ) -> Self {
        Self::of(
            problem,
            friction,
            &s.v,
            &s.pressure,
            &s.friction_traction,
            room,
        )
    }

    /// One line: the bounds in the problem's scales and what they bound.
    pub fn line(&self) -> String {
        match (&self.bound, &self.not_computed) {
            (Some(b), _) => {
                let mut line = format!(
                    "‖v − v*‖_A ≤ {:.2e} (= {:.2e} √K·U), max|p − p*| ≤ {:.2e} P; {}",
                    b.energy,
                    b.displacement,
                    b.pressure,
                    b.kind.as_str()
                );
                if let Some(e) = self.fixed_point {
                    line += &format!(
                        "; with the fixed point's part, estimated from its contraction factor k = {:.2}: ‖v − v*‖_A ≲ {:.2e} √K·U, max|p − p*| ≲ {:.2e} P",
                        e.contraction, e.displacement, e.pressure
                    );
                }
                line
            }
            (None, Some(why)) => format!("not computed: {why}"),
            (None, None) => "not computed".to_string(),
        }
    }
}

/// Half the memory free now: the room the bound's factors may take.
pub fn bound_room() -> f64 {
    crate::memory::room().map_or(f64::INFINITY, |r| 0.5 * r.bytes)
}
