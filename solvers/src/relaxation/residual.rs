//! The relaxation's own measure of how far an iterate is from solving the
//! given-friction subproblem, for its certified stopping rule: the largest
//! violation of the contact law and of stationarity, each in the problem's
//! scales (jumps and slips over U, pressures over P, nodal forces over
//! P·w_max), the measure of contactlab's certificate. The certificate is
//! still taken after the solve by code the solver does not share; this only
//! decides when to stop.

use crate::problem::ContactProblem;

/// Largest violation at (v, l, q) of, per contact node i with bound g_i:
/// t ≤ 0, l ≥ 0, min(l, −t) = 0, |q| ≤ g, no slip where |q| < g, slip
/// opposite to q where it slides; of stationarity A v − f + Σ w (l e_t −
/// q e_s) = 0; and of the balance of the load along each rigid mode z
/// (zᵀ r over |zᵀ f|: A z = 0, so zᵀ r is the load the contact forces leave
/// unbalanced, which small residuals at many nodes can add up to). `r` is
/// scratch of length n (no allocation).
pub(crate) fn contact_residual(
    problem: &ContactProblem,
    bound: &[f64],
    v: &[f64],
    l: &[f64],
    q: &[f64],
    r: &mut [f64],
) -> f64 {
    let s = problem.scales();
    let (u, p) = (s.displacement, s.pressure);
    let contacts = problem.contacts();
    let w_max = contacts.iter().fold(0.0f64, |m, c| m.max(c.weight));
    crate::numerics::linalg::spmv_into(problem.a(), v, r);
    for (ri, fi) in r.iter_mut().zip(problem.f()) {
        *ri -= fi;
    }
    let mut law = 0.0f64;
    for (((c, &li), &qi), &g) in contacts.iter().zip(l).zip(q).zip(bound) {
        r[c.t] += c.weight * li;
        r[c.s] -= c.weight * qi;
        let (t, slip) = (v[c.t], v[c.s]);
        let sticks = (slip.abs() / u).min((g - qi.abs()).max(0.0) / p);
        let slides = if slip != 0.0 {
            (slip.abs() / u).min((qi + g * slip.signum()).abs() / p)
        } else {
            0.0
        };
        law = law
            .max(t.max(0.0) / u)
            .max((-li).max(0.0) / p)
            .max((li.max(0.0) / p).min((-t).max(0.0) / u))
            .max((qi.abs() - g).max(0.0) / p)
            .max(sticks)
            .max(slides);
    }
    let stationarity = r.iter().fold(0.0f64, |m, x| m.max(x.abs())) / (p * w_max);
    let balance = problem.rigid_modes().iter().fold(0.0f64, |m, z| {
        let load: f64 = z.iter().zip(problem.f()).map(|(a, b)| a * b).sum();
        let unbalanced: f64 = z.iter().zip(r.iter()).map(|(a, b)| a * b).sum();
        let scale = if load != 0.0 { load.abs() } else { s.force };
        m.max(unbalanced.abs() / scale)
    });
    law.max(stationarity).max(balance)
}
