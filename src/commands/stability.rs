//! `contactlab stability`: the stability map.

use std::path::Path;

use anyhow::Result;

use crate::cli::StabilityArgs;
use crate::io::csv::to_csv;
use crate::io::output::{log, print, write_atomic};
use crate::io::run_folder::RunFolder;
use crate::settings::Settings;
use crate::study::reference::References;
use crate::study::report::write_all;
use crate::study::stability::{self, Map, StabilitySpec, views};

pub fn run(args: &StabilityArgs) -> Result<()> {
    let settings = args.settings.resolve()?;
    let spec = if args.quick {
        StabilitySpec::quick()
    } else {
        StabilitySpec::standard()
    };
    let folder = RunFolder::create(&args.out)?;
    let map = run_map(&spec, &settings)?;
    write_files(folder.path(), &map)?;
    let target = folder.commit()?;
    let mut counts = std::collections::BTreeMap::new();
    for t in &map.trials {
        *counts
            .entry(t.class.map_or("", |c| c.as_str()))
            .or_insert(0) += 1;
    }
    print(&format!(
        "wrote {}/stability.csv ({} trials: {counts:?}), stability_friction.csv and charts\n",
        target.display(),
        map.trials.len()
    ))
}

/// Runs the map with logs on stderr.
pub fn run_map(spec: &StabilitySpec, settings: &Settings) -> Result<Map> {
    let mut references = References::default();
    let progress = crate::commands::StudyProgress::new(0, "stability");
    let map = stability::run(
        spec,
        settings,
        &mut references,
        &|l| log(format!("stability: {l}")),
        &|t| progress.tick(t),
    );
    progress.finish();
    map
}

/// The map's files: stability.csv, stability_friction.csv,
/// stability_uniqueness.csv (the charts are the caller's).
pub fn write_tables(dir: &Path, map: &Map) -> Result<()> {
    let rows: Vec<_> = map.trials.iter().map(|t| t.row()).collect();
    write_atomic(&dir.join("stability.csv"), &to_csv(&rows, &[])?)?;
    write_atomic(
        &dir.join("stability_friction.csv"),
        &to_csv(&map.steps, &[])?,
    )?;
    write_atomic(
        &dir.join("stability_uniqueness.csv"),
        &to_csv(&map.uniqueness, &[])?,
    )
}

/// The map's files and charts.
pub fn write_files(dir: &Path, map: &Map) -> Result<()> {
    write_tables(dir, map)?;
    write_all(&dir.join("charts"), &views::charts(&map.trials, &map.steps))?;
    Ok(())
}
