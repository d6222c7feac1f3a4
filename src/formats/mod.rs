//! File formats that know the domain, above [`crate::io`]: scene files
//! (TOML), instance folders (the algebraic problem for other codes, and
//! answers read back for the certificate), and VTU field output.

pub mod instance;
pub mod mesh_map;
pub mod scene_file;
pub mod vtu;
