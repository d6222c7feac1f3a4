//! Pure optimization solvers for the algebraic given-friction (Tresca)
//! contact subproblem of contactlab. They know matrices and index sets, never
//! meshes: the mechanics crate builds a [`GivenFrictionProblem`] and every
//! solver here takes it and returns the same [`Solution`] type.

pub mod condensed;
pub mod conic;
pub mod linalg;
pub mod newton;
pub mod observer;
pub mod problem;
pub mod registry;
pub mod relaxation;
pub mod residuals;
pub mod solution;
pub mod solver;

pub use conic::{ConicSettings, ConicSolver};
pub use newton::{CondensedNewton, NewtonSettings};
pub use observer::{History, Observer, Progress, Silent, Stage};
pub use problem::{ContactNode, GivenFrictionProblem, ProblemError};
pub use relaxation::pointwise::Smoothing;
pub use relaxation::{ProxUzawa, RelaxationSettings};
pub use residuals::Residuals;
pub use solution::{Iterations, Solution, Status, Timing};
pub use solver::{GivenFrictionSolver, Start};
