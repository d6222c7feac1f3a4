//! `contactlab compare`: every solver on one scene against the earned
//! reference; a Markdown table on stdout, files with --out.

use std::path::Path;

use anyhow::Result;

use crate::cli::CompareArgs;
use crate::commands::{StudyProgress, solver_list};
use crate::io::csv::to_csv;
use crate::io::output::{print, write_atomic};
use crate::io::run_folder::RunFolder;
use crate::study::compare;
use crate::study::reference::References;
use crate::study::runner::{Measured, write_trials};

pub fn run(args: &CompareArgs) -> Result<()> {
    let (scene, base) = args.scene.load()?;
    let settings = args.settings.resolve_on(base)?;
    let solvers = solver_list(&args.solvers)?;
    args.settings.check_used_by(&solvers)?;
    let folder = args.out.as_deref().map(RunFolder::create).transpose()?;
    let specs = compare::plan(&scene, &settings, &solvers, args.repeats as usize);
    let bar = StudyProgress::new(specs.len() as u64, "compare");
    let mut references = References::default();
    let measured = compare::run(
        &scene,
        &settings,
        &solvers,
        args.repeats as usize,
        &mut references,
        &|t| bar.tick(t),
    )?;
    bar.finish();
    let mut report = markdown(&measured);
    if let Some(folder) = folder {
        write_files(folder.path(), &measured, &references)?;
        let target = folder.commit()?;
        report += &format!(
            "\nwrote {}/compare.csv, compare_timing.csv and references.csv\n",
            target.display()
        );
    }
    print(&report)
}

/// The comparison's Markdown table.
pub fn markdown(measured: &[Measured]) -> String {
    let trials: Vec<_> = measured.iter().map(|m| m.trial.clone()).collect();
    let seconds: Vec<f64> = measured.iter().map(|m| m.timing.seconds_min).collect();
    compare::markdown(&trials, &seconds)
}

/// compare.csv, compare_timing.csv and references.csv.
pub fn write_files(dir: &Path, measured: &[Measured], references: &References) -> Result<()> {
    write_trials(dir, "compare", measured)?;
    write_atomic(
        &dir.join("references.csv"),
        &to_csv(&references.candidates(), &[])?,
    )
}
