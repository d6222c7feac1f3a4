//! contactlab: a testbed for the semicoercive two-body contact problem with
//! Coulomb friction of Zhiltsov & Namm (2019). This crate holds the mechanics
//! (mesh, P1 assembly, scenes, the friction fixed point, the comparison
//! harness, the CLI); the solvers of the algebraic given-friction subproblem
//! live in `contactlab-solvers`.

pub mod assembly;
pub mod bench;
pub mod charts;
pub mod cli;
pub mod compare;
pub mod continuation;
pub mod discretization;
pub mod dofs;
pub mod friction;
pub mod manifest;
pub mod material;
pub mod mesh;
pub mod mesh_size;
pub mod output;
pub mod profile;
pub mod report;
pub mod reproduce;
pub mod run;
pub mod scene;
pub mod scene_file;
pub mod settings;
pub mod stability;
pub mod sweep;
pub mod table1;

pub use contactlab_solvers as solvers;
