//! The problem on the contact unknowns alone: [`condensed`], the exact
//! elimination of the interior unknowns (one sparse Cholesky factorization);
//! [`dual`], the problem in the contact forces with the rigid mode kept
//! exactly.

pub mod condensed;
pub mod dual;
pub mod gap;
