//! Splitting methods on the condensed problem: [`nsgs`], nonsmooth
//! Gauss-Seidel on the contact forces; [`apgd`], accelerated projected
//! gradient on the dual; [`admm`], the alternating direction method of
//! multipliers on the primal.

pub mod admm;
pub mod apgd;
pub mod nsgs;
