//! contactlab: a testbed for the semicoercive two-body contact problem with
//! Coulomb friction of Zhiltsov & Namm (2019).
//!
//! # The front door
//!
//! A scene (the paper's problems, or a classical scene of `scenes/`), one
//! registered solver, and the certificate that checks the answer against
//! the problem, with an error bound beside it. The types at the crate's
//! root are all that takes:
//!
//! ```
//! use contactlab::{Friction, MeshSize, Scene, Settings, Silent, Status};
//! use contactlab::{answer_bound, solve_scene, solver_entry};
//!
//! // The paper's problem 1 on the meshes 1/8 and 1/16 (mesh continuation).
//! let scene = Scene::paper_problem_to(1, MeshSize::from_level(4)?)?;
//! let settings = Settings::default();
//! let solved = solve_scene(
//!     &scene,
//!     Friction::Coulomb,             // the whole Coulomb problem, g = 𝓕p
//!     solver_entry("tnnmg")?,        // any name of `contactlab settings`
//!     &settings,
//!     &mut Silent,                   // or an Observer for progress
//! )?;
//! let outcome = &solved.outcome;
//! // The status is the certificate's, not the solver's claim.
//! assert_eq!(outcome.status, Status::Converged);
//! assert!(outcome.certificate.passed(), "{}", outcome.certificate.summary());
//! // The pressure p and the friction traction q per contact node.
//! assert_eq!(outcome.solution.pressure.len(), solved.finest.problem.contacts().len());
//! // ‖v − v*‖_A over √K·U, bounded by code no solver shares.
//! let bound = answer_bound(&solved, &settings.certificate);
//! assert!(bound.bound.is_some_and(|b| b.displacement < 1e-4), "{}", bound.line());
//! # Ok::<(), anyhow::Error>(())
//! ```
//!
//! # The layers
//!
//! - [`mechanics`]: the paper's scene, its P1 discretization and the way back
//!   from the algebraic unknowns to both bodies;
//! - [`coulomb`]: the Coulomb problem around a given-friction solver: the
//!   successive approximations of paper (9) and mesh continuation;
//! - [`certificate`]: the independent check of every answer;
//! - [`solve`]: one scene, one solver, certified ([`solve_scene`]);
//! - [`study`]: the study engine (trials, one runner, earned references) and
//!   the studies: comparison, sweeps, the stability map, benchmark, Table 1
//!   and the report;
//! - [`memory`]: what a run will need and what the process may use;
//! - [`io`]: scene files, output files, charts, the manifest;
//! - [`cli`] and [`commands`]: the command line.
//!
//! The solvers of the algebraic subproblem live in `contactlab-solvers`
//! ([`solvers`]): matrices and index sets, never meshes; the
//! [`ContactProblem`] is the one boundary between the two.

pub mod allocator;
pub mod certificate;
pub mod cli;
pub mod commands;
pub mod coulomb;
pub mod formats;
pub mod io;
pub mod mechanics;
pub mod memory;
pub mod settings;
pub mod solve;
pub mod study;

pub use contactlab_solvers as solvers;

// The front door: what a library user needs to pose a scene, solve it
// with a registered solver and read the certified answer.
pub use certificate::{BoundReport, Certificate, ErrorBound};
pub use contactlab_solvers::{
    ContactProblem, Friction, Law, Observer, Progress, Silent, Solution, Status,
};
pub use mechanics::mesh_size::MeshSize;
pub use mechanics::scene::Scene;
pub use settings::Settings;
pub use solve::summary::answer_bound;
pub use solve::{Outcome, Solved, solve_scene, solver_entry};
