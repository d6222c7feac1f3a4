//! Numerics that more than one solver family uses: sparse linear algebra
//! and factorizations, the NCP functions of the Newton methods and their
//! globalization, roots of monotone functions, and pseudo-random numbers.
//! Each lives here once, with its source and its constants named.

pub mod globalization;
pub mod linalg;
pub mod ncp;
pub mod random;
pub mod roots;
