//! Input and output: scene files, output files written whole, charts and the
//! manifest of a results directory.

pub mod charts;
pub mod csv;
pub mod export;
pub mod guarded;
pub mod latex;
pub mod manifest;
pub mod matrix_market;
pub mod output;
pub mod run_folder;
pub mod scene_file;
pub mod vtu;
