//! One TNNMG iteration as the registry's inner kernel: `bench` times it
//! against one product with A, so that the cost of an iteration is read in
//! products on the same run (a quantity the machine's noise barely moves),
//! and its passes over A can be counted against the code: one nonlinear
//! sweep that leaves the defect, and per conjugate-gradient step one
//! V-cycle whose finest level is one fused presmoothing sweep and one
//! fused postsmoothing sweep (see [`super::iteration`]).
//!
//! The problem is the given-friction subproblem at the uniform bound
//! g_i = ½ 𝓕_i P (P the problem's pressure scale), iterated from zero with
//! the default settings; after the first few iterations the truncated set
//! settles and each step does the same work.

use std::hint::black_box;

use super::iteration::{Energy, Workspace, iterate};
use super::laws::Laws;
use super::smoother::diagonal_places;
use super::vcycle::Hierarchy;
use super::{TnnmgSettings, dot, given_friction_laws};
use crate::entry::InnerKernel;
use crate::problem::ContactProblem;

/// The given bound of the kernel's subproblem and of `bench`'s iteration
/// counts, as a fraction of the Coulomb scale 𝓕P at every node: half of
/// it, so that slip, stick and separation all occur on problem 1.
pub const BOUND_OF_SCALE: f64 = 0.5;

/// The kernel (None for a problem without a mesh hierarchy).
pub(crate) fn iteration_kernel(problem: &ContactProblem) -> Option<InnerKernel> {
    if problem.prolongations().is_empty() {
        return None;
    }
    let problem = problem.clone();
    let n = problem.n();
    let mut hierarchy = Hierarchy::new(
        problem.a(),
        diagonal_places(problem.a()).ok()?,
        problem.prolongations(),
    )
    .ok()?;
    let pressure = problem.scales().pressure;
    let bound: Vec<f64> = problem
        .contacts()
        .iter()
        .map(|c| BOUND_OF_SCALE * c.coefficient * pressure)
        .collect();
    let mut laws = Laws::free(n);
    let contact = given_friction_laws(&problem, &bound, &mut laws);
    let z = problem.rigid_modes().first().cloned();
    let zz = z.as_deref().map_or(0.0, |z| dot(z, z));
    let cycle = TnnmgSettings::default().cycle();
    let mut ws = Workspace::new(n);
    let mut v = vec![0.0; n];
    Some(InnerKernel {
        name: super::ITERATION,
        matrix: problem.a().clone(),
        step: Box::new(move || {
            let energy = Energy {
                a: problem.a(),
                b: problem.f(),
                laws: &laws,
                contact: &contact,
                kernel: z.as_deref().map(|z| (z, zz)),
            };
            iterate(
                &energy,
                &mut hierarchy,
                problem.prolongations(),
                cycle,
                &mut ws,
                &mut v,
            );
            black_box(&v);
        }),
    })
}
