//! File formats that know the domain, above [`crate::io`]: scene files
//! (TOML), instance folders (the algebraic problem for other codes, and
//! answers read back for the certificate), VTU field output, and the
//! classical scenes committed in `scenes/`.

pub mod classical;
pub mod instance;
pub mod mesh_map;
pub mod scene_file;
pub mod vtu;
