//! contactlab: a testbed for the semicoercive two-body contact problem with
//! Coulomb friction of Zhiltsov & Namm (2019).
//!
//! - [`mechanics`]: the paper's scene, its P1 discretization and the way back
//!   from the algebraic unknowns to both bodies;
//! - [`coulomb`]: the Coulomb problem around a given-friction solver: the
//!   successive approximations of paper (9) and mesh continuation;
//! - [`certificate`]: the independent check of every answer;
//! - [`study`]: the study engine (trials, one runner, earned references) and
//!   the studies: comparison, sweeps, the stability map, benchmark, Table 1
//!   and the report;
//! - [`memory`]: what a run will need and what the process may use;
//! - [`io`]: scene files, output files, charts, the manifest;
//! - [`cli`] and [`commands`]: the command line.
//!
//! The solvers of the algebraic subproblem live in `contactlab-solvers`.

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
