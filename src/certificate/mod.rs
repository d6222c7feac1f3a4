//! The certificate: every answer, whoever computed it, is checked against
//! the problem by this code, which no solver shares (solvers cannot depend on
//! this crate). A solver's claim of convergence stands only if it passes.
//!
//! With nodal forces λ_i = w_i p_i (contact) and μ_i = w_i q_i (friction on
//! the lower body), a solution (v, p, q) of the contact problem satisfies
//!
//! ```text
//! A v − f + Σ_i λ_i e_{t_i} − Σ_i μ_i e_{s_i} = 0        stationarity
//! zᵀ(f − Σ λ_i e_{t_i} + Σ μ_i e_{s_i}) = 0               force balance, z a rigid mode
//! t_i ≤ 0,  p_i ≥ 0,  p_i t_i = 0                         Signorini, paper (5)-(6)
//! |q_i| ≤ g_i, s_i = 0 where |q_i| < g_i,
//! q_i = −g_i sign(s_i) where s_i ≠ 0                       friction, paper (7)
//! ```
//!
//! with g_i the given bound (given-friction subproblem, paper (10)) or
//! g_i = 𝓕_i p_i (the Coulomb problem: the certificate of a fixed point's
//! answer is taken at the bound its own pressure gives, not at the bound of
//! its last step). For a semicoercive problem the force balance is the
//! statement that the contact forces carry the whole applied load.
//!
//! Each condition's violation is dimensionless, in the problem's own scales
//! ([`contactlab_solvers::Scales`]: displacement U, pressure P), so the
//! verdict does not change with the units: jumps and slips over U = F/K
//! (the gross load F over the stiffness: displacements follow the whole
//! load), pressures and tractions over P = N/L, the mean pressure of the
//! load N that the contact must carry (the net load along the rigid mode,
//! not the gross load: a load nearly balanced by an upward one leaves
//! contact forces of the size of the net load, and a wrong contact force
//! must not hide in the scale of a load the contact does not carry), nodal
//! force residuals at a contact node's rows over P·w_i (a pressure error
//! of that node, whatever its weight: the end nodes of Γ_K have half the
//! weight of the others), at every other row over P·w_max (the force a node
//! carries at that mean pressure), and the balance over the load along the
//! rigid mode |zᵀf|. The contact law and the balance are checked with the
//! forces given and with those the displacements imply, so that one answer
//! gets one verdict however it is handed in ([`certify`]).
//! Complementarity-type conditions are measured in natural-map form
//! (the smaller of the two quantities that may not both be nonzero).
//! A value that is not finite, or a residual that overflows (inf − inf),
//! is an infinite violation: every maximum here counts a NaN as infinite.

pub mod accurate_sum;
pub mod energy_multigrid;
pub mod energy_solve;
pub mod error_bound;
pub mod problem_checks;

pub use error_bound::{
    BoundError, BoundKind, BoundReport, BoundSolve, ErrorBound, ErrorBounder, FixedPointEstimate,
    SOLVE_BOUND_MAX_UNKNOWNS, bound_room, error_bound,
};

use contactlab_solvers::{ContactProblem, Friction, Law, Solution, Status};
use serde::{Deserialize, Serialize};

/// Default tolerance: every condition's violation at most this. At 1e-5 the
/// exact solvers pass even at the paper's absolute ε = 1e-4 (their answers
/// violate the Coulomb law there by about 4e-6, the fixed point's own stopping
/// error), while the paper's relaxation at its own settings fails (it leaves
/// about 3e-4 of the load unbalanced on problem 1 at h = 1/64).
pub const DEFAULT_TOLERANCE: f64 = 1e-5;

/// The largest tolerance the certificate may be given, wherever it is set
/// (a scene file, `--certify-tol`, `certify --certify-tol`, benchmark
/// targets): a violation of 1 % of the load is already a wrong answer, and
/// a tolerance of 1e300 switched the certificate off (contact force 0
/// against a load of 20 was `converged`).
pub const MAX_TOLERANCE: f64 = 1e-2;

/// Checks a certificate tolerance: in (0, [`MAX_TOLERANCE`]].
pub fn check_tolerance(t: f64) -> Result<f64, String> {
    if t > 0.0 && t <= MAX_TOLERANCE {
        Ok(t)
    } else {
        Err(format!(
            "{} is invalid: the certificate's tolerance must lie in (0, {MAX_TOLERANCE:e}] (default {DEFAULT_TOLERANCE:e})",
            crate::mechanics::scene::Shown::shown(&t)
        ))
    }
}

/// The conditions a solution must satisfy.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Condition {
    /// t_i ≤ 0: max t_i⁺ / U.
    Nonpenetration,
    /// p_i ≥ 0: max p_i⁻ / P.
    PressureSign,
    /// p_i t_i = 0: max min(p_i⁺/P, t_i⁻/U).
    Complementarity,
    /// |q_i| ≤ g_i: max (|q_i| − g_i)⁺ / P.
    FrictionBound,
    /// No slip below the bound: max min(|s_i|/U, (g_i − |q_i|)⁺/P).
    Stick,
    /// Slip opposes the traction at its bound: max over s_i ≠ 0 of
    /// min(|s_i|/U, |q_i + g_i sign(s_i)|/P).
    SlipDirection,
    /// A v − f + Σλ e_t − Σμ e_s row by row: at the rows of contact node
    /// i over P·w_i (how far the given forces are from those the
    /// displacements imply, as a pressure), elsewhere over P·w_max.
    Stationarity,
    /// max over rigid modes z of |zᵀ(f − Σλ e_t + Σμ e_s)| / |zᵀf|: the
    /// part of the load along the rigid mode that the contact forces leave
    /// unbalanced, relative to that load (F where it is zero).
    ForceBalance,
}

impl Condition {
    pub const ALL: [Condition; 8] = [
        Condition::Nonpenetration,
        Condition::PressureSign,
        Condition::Complementarity,
        Condition::FrictionBound,
        Condition::Stick,
        Condition::SlipDirection,
        Condition::Stationarity,
        Condition::ForceBalance,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            Condition::Nonpenetration => "nonpenetration",
            Condition::PressureSign => "pressure_sign",
            Condition::Complementarity => "complementarity",
            Condition::FrictionBound => "friction_bound",
            Condition::Stick => "stick",
            Condition::SlipDirection => "slip_direction",
            Condition::Stationarity => "stationarity",
            Condition::ForceBalance => "force_balance",
        }
    }
}

/// Each condition's violation (0 at an exact solution; infinite where a
/// value is not finite) and the tolerance they are held to.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Certificate {
    pub law: Law,
    pub nonpenetration: f64,
    pub pressure_sign: f64,
    pub complementarity: f64,
    pub friction_bound: f64,
    pub stick: f64,
    pub slip_direction: f64,
    pub stationarity: f64,
    pub force_balance: f64,
    pub tolerance: f64,
}

impl Certificate {
    /// The certificate of an answer that does not exist (a trial not run):
    /// every violation infinite.
    pub fn not_run(law: Law, tolerance: f64) -> Self {
        let inf = f64::INFINITY;
        Certificate {
            law,
            nonpenetration: inf,
            pressure_sign: inf,
            complementarity: inf,
            friction_bound: inf,
            stick: inf,
            slip_direction: inf,
            stationarity: inf,
            force_balance: inf,
            tolerance,
        }
    }

    /// Every condition with its violation.
    pub fn measures(&self) -> [(Condition, f64); 8] {
        Condition::ALL.map(|c| (c, self.get(c)))
    }

    pub fn get(&self, c: Condition) -> f64 {
        match c {
            Condition::Nonpenetration => self.nonpenetration,
            Condition::PressureSign => self.pressure_sign,
            Condition::Complementarity => self.complementarity,
            Condition::FrictionBound => self.friction_bound,
            Condition::Stick => self.stick,
            Condition::SlipDirection => self.slip_direction,
            Condition::Stationarity => self.stationarity,
            Condition::ForceBalance => self.force_balance,
        }
    }

    /// The largest violation and its condition (a NaN counts as infinite).
    pub fn worst(&self) -> (Condition, f64) {
        self.measures()
            .into_iter()
            .map(|(c, x)| (c, if x.is_nan() { f64::INFINITY } else { x }))
            .fold((Condition::Nonpenetration, 0.0), |a, b| {
                if b.1 > a.1 { b } else { a }
            })
    }

    /// The certificate's measure: the largest violation.
    pub fn residual(&self) -> f64 {
        self.worst().1
    }

    pub fn passed(&self) -> bool {
        self.residual() <= self.tolerance
    }

    /// The conditions violated beyond the tolerance, worst first.
    pub fn failing(&self) -> Vec<Condition> {
        let mut bad: Vec<(Condition, f64)> = self
            .measures()
            .into_iter()
            .map(|(c, x)| (c, if x.is_nan() { f64::INFINITY } else { x }))
            .filter(|&(_, x)| x > self.tolerance)
            .collect();
        bad.sort_by(|a, b| b.1.total_cmp(&a.1));
        bad.into_iter().map(|(c, _)| c).collect()
    }

    /// One line: `certified (largest violation 3.1e-9: stationarity)` or
    /// `fails: force_balance 1.0e0, stationarity 2.3e-1 > 1e-6`.
    pub fn summary(&self) -> String {
        let failing = self.failing();
        if failing.is_empty() {
            let (c, x) = self.worst();
            format!(
                "certified at {:e} (largest violation {x:.1e}: {})",
                self.tolerance,
                c.as_str()
            )
        } else {
            let list: Vec<String> = failing
                .iter()
                .map(|&c| format!("{} {:.1e}", c.as_str(), self.get(c)))
                .collect();
            format!("fails: {} > {:e}", list.join(", "), self.tolerance)
        }
    }

    /// The certified status of an answer whose solver claimed `claim`: a
    /// claim of convergence that fails the certificate is `inaccurate`;
    /// every other claim stands as it is.
    pub fn verdict(&self, claim: Status) -> Status {
        if claim.is_converged() && !self.passed() {
            Status::Inaccurate
        } else {
            claim
        }
    }
}

/// Checks a solver's answer against `problem` under `friction`.
pub fn certify_solution(
    problem: &ContactProblem,
    friction: Friction<'_>,
    s: &Solution,
    tolerance: f64,
) -> Certificate {
    certify(
        problem,
        friction,
        &s.v,
        &s.pressure,
        &s.friction_traction,
        tolerance,
    )
}

/// Row i of the residual of stationarity, (A v − f)_i, summed over A's
/// stored row in order by the certificate's own loop (no solver's
/// product).
fn stationarity_residual(problem: &ContactProblem, v: &[f64], i: usize) -> f64 {
    row_product(problem, v, i) - problem.f()[i]
}

/// Row i of A times x, (A x)_i, summed over A's stored row in order: the
/// certificate's own product, shared by the residual and the error bound.
fn row_product(problem: &ContactProblem, x: &[f64], i: usize) -> f64 {
    let (cols, vals) = problem.a().row(i);
    cols.iter()
        .zip(vals)
        .map(|(c, a_ic)| a_ic * x[c])
        .sum::<f64>()
}

/// Whether an answer (v, p, q) and the law `friction` fit `problem`: its
/// sizes, the law's bound, and every value finite. An answer that does
/// not fit gets infinite violations ([`certify`]) and no error bound.
fn fits(problem: &ContactProblem, friction: Friction<'_>, v: &[f64], p: &[f64], q: &[f64]) -> bool {
    let m = problem.contacts().len();
    let finite = |x: &[f64]| x.iter().all(|y| y.is_finite());
    v.len() == problem.n()
        && p.len() == m
        && q.len() == m
        && friction.check(problem).is_ok()
        && finite(v)
        && finite(p)
        && finite(q)
}

/// The contact forces that displacements `v` imply: stationarity at the
/// contact rows read as forces, p_i = −(A v − f)_{t_i} / w_i and
/// q_i = (A v − f)_{s_i} / w_i ([`stationarity_residual`] at those rows
/// alone). An answer given as displacements alone is completed with them
/// ([`crate::formats::instance::complete_answer`]), and every answer is
/// also judged with them ([`certify`]).
pub fn implied_forces(problem: &ContactProblem, v: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let r = |i| stationarity_residual(problem, v, i);
    problem
        .contacts()
        .iter()
        .map(|c| (-r(c.t) / c.weight, r(c.s) / c.weight))
        .unzip()
}

/// Checks (v, p, q) against `problem` under `friction` (the given-friction
/// law at its bound g, or the Coulomb law at g = 𝓕p). Sizes that do not
/// fit the problem (the answer's or the bound's), and any non-finite value,
/// give infinite violations.
///
/// One answer, one verdict: the contact law and the balance are checked
/// twice, with the forces (p, q) as given and with the forces the
/// displacements imply ([`implied_forces`]), and each condition keeps the
/// larger violation; stationarity measures how far the given forces are
/// from the implied ones. So an answer handed in as displacements alone
/// (completed with its implied forces) and the same answer with its forces
/// get the same measures, and handing in forces beside the displacements
/// can only add conditions, never excuse one. Every scale is the
/// problem's, never the answer's: a force residual at a contact row is
/// measured per unit length of that node (P·w_i, a pressure error, as the
/// contact law measures pressures), at any other row per P·w_max; so a
/// pressure error at an end node of Γ_K (w = h/2) counts in full.
pub fn certify(
    problem: &ContactProblem,
    friction: Friction<'_>,
    v: &[f64],
    p: &[f64],
    q: &[f64],
    tolerance: f64,
) -> Certificate {
    let mut out = Certificate::not_run(friction.law(), tolerance);
    if !fits(problem, friction, v, p, q) {
        return out;
    }
    for c in Condition::ALL {
        out.set(c, 0.0);
    }
    // The residual A v − f is read row by row as it is summed, and the
    // nodal contact forces, filled for each reading in turn, are kept at
    // the contact rows alone: neither is a vector of n (at h = 1/4096 such
    // a vector is 270 MB, beside the solver's at the peak of a solve that
    // certifies its answer before it goes on).
    let (p_implied, q_implied) = implied_forces(problem, v);
    let mut force = Vec::with_capacity(2 * problem.contacts().len());
    contact_forces(problem, p, q, &mut force);
    stationarity(&mut out, problem, v, &force);
    for (pr, qr) in [(p, q), (&p_implied[..], &q_implied[..])] {
        contact_forces(problem, pr, qr, &mut force);
        contact_law(&mut out, problem, friction, v, pr, qr);
        force_balance(&mut out, problem, &force);
    }
    out
}

/// The conditions of the contact law at each node (Signorini, paper
/// (5)-(6); friction, paper (7)) for the answer's jumps and slips and the
/// forces (p, q), in natural-map form.
fn contact_law(
    out: &mut Certificate,
    problem: &ContactProblem,
    friction: Friction<'_>,
    v: &[f64],
    p: &[f64],
    q: &[f64],
) {
    let s = problem.scales();
    let (u, pr) = (s.displacement, s.pressure);
    for (i, c) in problem.contacts().iter().enumerate() {
        // The jump past the gap, t_i − d_i ≤ 0, and the slip past its
        // offset, s_i − σ_i (d = σ = 0 in the paper's scene).
        let (t, sl, pi, qi) = (problem.jump(v, i), problem.slip(v, i), p[i], q[i]);
        let g = friction.bound(i, c.coefficient, pi);
        raise(&mut out.nonpenetration, t.max(0.0) / u);
        raise(&mut out.pressure_sign, (-pi).max(0.0) / pr);
        raise(
            &mut out.complementarity,
            smaller(pi.max(0.0) / pr, (-t).max(0.0) / u),
        );
        raise(&mut out.friction_bound, (qi.abs() - g).max(0.0) / pr);
        raise(
            &mut out.stick,
            smaller(sl.abs() / u, (g - qi.abs()).max(0.0) / pr),
        );
        if sl != 0.0 {
            raise(
                &mut out.slip_direction,
                smaller(sl.abs() / u, (qi + g * sl.signum()).abs() / pr),
            );
        }
    }
}

/// The nodal contact forces of (p, q) into `force` as (row, force),
/// ascending by row: w_i p_i at t_i, −w_i q_i at s_i (zero at every other
/// row, [`each_row`]).
fn contact_forces(problem: &ContactProblem, p: &[f64], q: &[f64], force: &mut Vec<(usize, f64)>) {
    force.clear();
    for (i, c) in problem.contacts().iter().enumerate() {
        force.push((c.t, 0.0 + c.weight * p[i]));
        force.push((c.s, 0.0 - c.weight * q[i]));
    }
    force.sort_unstable_by_key(|&(row, _)| row);
}

/// The nodal forces `force` (row, force, ascending) at each of n rows in
/// turn, zero where none: the vector they stand for, without storing it.
fn each_row(force: &[(usize, f64)], n: usize) -> impl Iterator<Item = f64> + '_ {
    let mut next = force.iter().peekable();
    (0..n).map(move |k| match next.peek() {
        Some(&&(row, f)) if row == k => {
            next.next();
            f
        }
        _ => 0.0,
    })
}

/// |A v − f + contact forces| row by row, from the displacements `v`
/// ([`stationarity_residual`]) and the nodal contact forces `force`: at a
/// contact row over P·w_i (the pressure error of that node), elsewhere over
/// P·w_max. Every row is first taken over P·w_max, then the contact rows
/// over their own, smaller scale, so the largest is the same and no vector
/// of scales is needed.
fn stationarity(
    out: &mut Certificate,
    problem: &ContactProblem,
    v: &[f64],
    force: &[(usize, f64)],
) {
    let contacts = problem.contacts();
    let pr = problem.scales().pressure;
    let w_max = contacts.iter().fold(0.0f64, |a, c| a.max(c.weight));
    let node_force = pr * w_max.max(f64::MIN_POSITIVE);
    let r = |i| stationarity_residual(problem, v, i);
    for (i, ci) in each_row(force, problem.n()).enumerate() {
        raise(&mut out.stationarity, (r(i) + ci).abs() / node_force);
    }
    for c in contacts {
        for k in [c.t, c.s] {
            let fk = force[force.partition_point(|&(row, _)| row < k)].1;
            raise(&mut out.stationarity, (r(k) + fk).abs() / (pr * c.weight));
        }
    }
}

/// zᵀ(f − contact forces) for every rigid mode z: the load the contact
/// forces `force` leave unbalanced, over the load zᵀf they must carry (F
/// times max|z| where that is zero). A mode that moves slips alone (a body
/// free sideways) is held by friction, whose forces are of the size of
/// the contact load N whatever its own load (which may be zero): over the
/// larger of its load and N·max|z|.
fn force_balance(out: &mut Certificate, problem: &ContactProblem, force: &[(usize, f64)]) {
    let gross = problem.scales().force;
    let contact_load = problem.scales().contact_load;
    for z in problem.rigid_modes() {
        let load: f64 = z.iter().zip(problem.f()).map(|(zk, fk)| zk * fk).sum();
        let unbalanced: f64 = z
            .iter()
            .zip(problem.f())
            .zip(each_row(force, z.len()))
            .map(|((zk, fk), ck)| zk * (fk - ck))
            .sum();
        let size = z.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let scale = if !contactlab_solvers::problem::moves_a_jump(z, problem.contacts()) {
            load.abs().max(contact_load * size)
        } else if load != 0.0 {
            load.abs()
        } else {
            gross * size
        };
        if scale > 0.0 {
            raise(&mut out.force_balance, unbalanced.abs() / scale);
        }
    }
}

/// Raises a violation to `x` if `x` is larger; a NaN (an overflow such as
/// inf − inf in a residual) raises it to infinity. `f64::max` would drop
/// the NaN and let the answer that produced it pass.
fn raise(violation: &mut f64, x: f64) {
    *violation = if x.is_nan() {
        f64::INFINITY
    } else {
        violation.max(x)
    };
}

/// The smaller of two measures of a complementarity pair (natural-map
/// form); NaN if either is NaN, so that [`raise`] counts it as infinite.
fn smaller(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.min(b)
    }
}

impl Certificate {
    fn set(&mut self, c: Condition, x: f64) {
        match c {
            Condition::Nonpenetration => self.nonpenetration = x,
            Condition::PressureSign => self.pressure_sign = x,
            Condition::Complementarity => self.complementarity = x,
            Condition::FrictionBound => self.friction_bound = x,
            Condition::Stick => self.stick = x,
            Condition::SlipDirection => self.slip_direction = x,
            Condition::Stationarity => self.stationarity = x,
            Condition::ForceBalance => self.force_balance = x,
        }
    }
}
