//! `contactlab benchmark`: every solver on the problem collection at each
//! target accuracy (or a shard of it), and `contactlab benchmark-merge`:
//! the same tables and charts from several shards' folders.

use std::path::Path;

use anyhow::{Result, bail};

use crate::cli::{BenchmarkArgs, BenchmarkMergeArgs};
use crate::commands::{StudyProgress, solver_list};
use crate::io::csv::to_csv;
use crate::io::manifest::Manifest;
use crate::io::output::{json_bytes, print, write_atomic};
use crate::io::run_folder::RunFolder;
use crate::study::benchmark::{self, BenchmarkRow, BenchmarkSpec, Shard, views};
use crate::study::report::write_all;
use crate::study::runner::{Measured, write_trials};

pub fn run(args: &BenchmarkArgs) -> Result<()> {
    if args.settings.certificate_tolerance.is_some() {
        bail!(
            "--certify-tol does not apply to the benchmark: each run is certified at its target accuracy; give --targets instead"
        );
    }
    let settings = args.settings.resolve()?;
    let solvers = solver_list(&args.solvers)?;
    args.settings.check_used_by(&solvers)?;
    let mut spec = BenchmarkSpec::new(args.quick, solvers);
    spec.shard = args.shard.unwrap_or(Shard::WHOLE);
    if let Some(t) = args.time_limit {
        spec.time_limit = t;
    }
    if !args.targets.is_empty() {
        spec.targets = args.targets.clone();
    }
    let folder = RunFolder::create(&args.out)?;
    let plan = benchmark::plan(&spec, &settings)?;
    let progress = StudyProgress::new(
        plan.len() as u64,
        &format!("benchmark {}/{}", spec.shard.index, spec.shard.of),
    )
    .with_costs(benchmark::expected_costs(&plan), spec.time_limit);
    let done = benchmark::run(plan, &|t| progress.tick(t))?;
    progress.finish();
    let (rows, measured): (Vec<BenchmarkRow>, Vec<Measured>) = done.into_iter().unzip();
    let dir = folder.path();
    write_run(dir, &rows, &measured)?;
    let manifest = Manifest::collect(
        &settings,
        serde_json::json!({
            "benchmark": {
                "quick": spec.quick,
                "targets": spec.targets,
                "time_limit": spec.time_limit,
                "shard": spec.shard,
                "solvers": spec.solvers.iter().map(|e| e.name).collect::<Vec<_>>(),
            }
        }),
    );
    write_atomic(&dir.join("manifest.json"), &json_bytes(&manifest)?)?;
    let report = views::report(&rows);
    let target = folder.commit()?;
    print(&format!(
        "{report}\nwrote {}/benchmark.csv, its tables and charts\n",
        target.display()
    ))
}

/// A run's files: benchmark.csv (the rows), benchmark_trials.csv and its
/// timing file (every trial in full), and the views.
pub fn write_run(dir: &Path, rows: &[BenchmarkRow], measured: &[Measured]) -> Result<()> {
    write_atomic(&dir.join("benchmark.csv"), &to_csv(rows, &[])?)?;
    write_trials(dir, "benchmark_trials", measured)?;
    let charts = views::write(dir, rows)?;
    write_all(&dir.join("charts"), &charts)?;
    Ok(())
}

pub fn merge(args: &BenchmarkMergeArgs) -> Result<()> {
    let rows = benchmark::merge::read_shards(&args.shards)?;
    let manifest = benchmark::merge::merged_manifest(&args.shards)?;
    let folder = RunFolder::create(&args.out)?;
    let dir = folder.path();
    write_atomic(&dir.join("benchmark.csv"), &to_csv(&rows, &[])?)?;
    write_atomic(&dir.join("manifest.json"), &json_bytes(&manifest)?)?;
    let charts = views::write(dir, &rows)?;
    write_all(&dir.join("charts"), &charts)?;
    let report = views::report(&rows);
    let target = folder.commit()?;
    print(&format!(
        "{report}\nmerged {} shards ({} rows) into {}\n",
        args.shards.len(),
        rows.len(),
        target.display()
    ))
}
