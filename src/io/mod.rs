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

/// A duration for people: seconds, minutes or hours.
pub fn duration(seconds: f64) -> String {
    if seconds < 90.0 {
        format!("{seconds:.0} s")
    } else if seconds < 5400.0 {
        format!("{:.0} min", seconds / 60.0)
    } else {
        format!("{:.1} h", seconds / 3600.0)
    }
}
