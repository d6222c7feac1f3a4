//! The bottom layer: files written whole, guarded reads, run folders, CSV,
//! Matrix Market, LaTeX, charts and the manifest. Nothing here knows the
//! mechanics or the Coulomb problem beyond plain numbers (the formats that
//! do live in [`crate::formats`]).

pub mod charts;
pub mod csv;
pub mod guarded;
pub mod heatmap;
pub mod latex;
pub mod manifest;
pub mod matrix_market;
pub mod output;
pub mod run_folder;
