//! Pure optimization solvers for the algebraic contact problem of
//! contactlab. They know matrices and index sets, never meshes: the mechanics
//! crate builds a [`ContactProblem`] and every solver here takes it and
//! returns the same [`Solution`] type. The [`registry`] holds everything the
//! harness needs to know about each solver.

pub mod admm;
pub mod apgd;
pub mod condensed;
pub mod conic;
pub mod dual;
pub mod linalg;
pub mod newton;
pub mod newton_coulomb;
pub mod nsgs;
pub mod observer;
pub mod problem;
pub mod registry;
pub mod relaxation;
pub mod settings;
pub mod solution;
pub mod solver;

pub use conic::{ConicSettings, ConicSolver};
pub use newton::{CondensedNewton, NewtonSettings};
pub use observer::{Control, History, Limits, Observer, Progress, Silent};
pub use problem::{ContactNode, ContactProblem, Mass, ProblemError, Scales};
pub use relaxation::pointwise::Smoothing;
pub use relaxation::{ProxUzawa, RelaxationSettings};
pub use settings::Stopping;
pub use solution::{Iterations, Solution, Status, Timing};
pub use solver::{Law, Solver, Start};
