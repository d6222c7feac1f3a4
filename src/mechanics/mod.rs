//! The mechanics: the paper's two-body scene, its mesh, the P1 stiffness,
//! mass and loads, the change of variables at Γ_K, and the contact zone of a
//! solution. Everything here knows meshes; nothing here solves.

pub mod assembly;
pub mod closed_forms;
pub mod contact_zone;
pub mod discretization;
pub mod dofs;
pub mod element;
pub mod gap;
pub mod hierarchy;
pub mod material;
pub mod mesh;
pub mod mesh_size;
pub mod scene;
