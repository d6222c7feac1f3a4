//! Pure optimization solvers for the algebraic given-friction (Tresca)
//! contact subproblem of contactlab. They know matrices and index sets, never
//! meshes: the mechanics crate builds a [`GivenFrictionProblem`] and every
//! solver here takes it and returns the same [`Solution`] type.

pub mod linalg;
pub mod problem;

pub use problem::{ContactNode, GivenFrictionProblem, ProblemError};
