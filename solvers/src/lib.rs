//! Pure optimization solvers for the algebraic contact problem of
//! contactlab. They know matrices and index sets, never meshes: the mechanics
//! crate builds a [`ContactProblem`] and every solver here takes it and
//! returns the same [`Solution`] type. The [`registry`] lists the solvers;
//! each one's [`entry::Entry`] says what the harness needs to know of it.
//!
//! Folders by family: [`conic`] (Clarabel, the oracle), [`newton`]
//! (semismooth Newton), [`splitting`] (nonsmooth Gauss-Seidel, projected
//! gradient and ADMM on the contact forces), [`relaxation`] (the paper's
//! method); with the problem in the contact unknowns in [`reduction`] and
//! the numerics they share in [`numerics`].

pub mod conic;
pub mod entry;
pub mod multigrid;
pub mod newton;
pub mod numerics;
pub mod observer;
pub mod problem;
pub mod reduction;
pub mod registry;
pub mod relaxation;
pub mod schedule;
pub mod settings;
pub mod solution;
pub mod solver;
pub mod splitting;

pub use conic::{ConicSettings, ConicSolver};
pub use newton::tresca::{CondensedNewton, NewtonSettings};
pub use numerics::linalg::{Csr, CsrError, IntoCsr};
pub use observer::{Control, History, Limits, Observer, Progress, Silent};
pub use problem::{ContactNode, ContactProblem, Mass, ProblemError, Scales};
pub use relaxation::pointwise::Smoothing;
pub use relaxation::{ProxUzawa, RelaxationSettings};
pub use settings::Stopping;
pub use solution::{Iterations, SetupError, Solution, Status, Timing};
pub use solver::{Friction, Law, STOPPED_AT_NEED, Solver, Start};
