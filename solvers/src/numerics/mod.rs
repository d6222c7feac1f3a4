//! Numerics that more than one solver family uses: sparse linear algebra
//! and factorizations, the NCP functions of the Newton methods and their
//! globalization, roots of monotone functions, pseudo-random numbers, and
//! the test every iterative loop makes for a stall at floating-point
//! resolution.
//! Each lives here once, with its source and its constants named.

pub(crate) mod globalization;
pub mod linalg;
pub(crate) mod ncp;
pub(crate) mod random;
pub mod resolution;
pub(crate) mod roots;
pub mod threads;
