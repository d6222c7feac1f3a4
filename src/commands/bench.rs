//! The hidden `bench-one` that measures the peak memory of one solve in a
//! fresh process (`bench` itself is a catalogued study, `study::studies`).

use anyhow::Result;

use crate::cli::BenchOneArgs;
use crate::io::output::print;
use crate::settings::Settings;
use crate::study::bench::memory::measure_here;

/// `bench-one`: one solve's memory in this (fresh) process, as JSON.
pub fn run_one(args: &BenchOneArgs) -> Result<()> {
    let scene = args.scene.resolve()?;
    faer::set_global_parallelism(faer::Par::Seq);
    let entry = crate::solve::solver_entry(&args.solver)?;
    let settings = args.settings.resolve_for(Settings::default(), &[entry])?;
    let used = measure_here(&scene, &args.solver, &settings)?;
    print(&format!("{}\n", serde_json::to_string(&used)?))
}
