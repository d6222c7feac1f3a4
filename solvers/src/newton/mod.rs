//! Semismooth Newton methods on the contact problem's complementarity
//! equations, globalized on the merit ½‖Φ‖² ([`crate::numerics::globalization`]):
//! [`tresca`], the given-friction subproblem condensed onto the contact
//! unknowns; [`coulomb`], the whole Coulomb problem with the bound 𝓕λ among
//! the unknowns.

pub mod coulomb;
pub mod tresca;
mod tresca_system;
