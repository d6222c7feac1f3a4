//! `contactlab table1`: the paper's Table 1 at the paper's settings.

use anyhow::Result;

use crate::cli::Table1Args;
use crate::commands::StudyProgress;
use crate::io::csv::to_csv;
use crate::io::output::{print, write_atomic};
use crate::io::run_folder::RunFolder;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::table1;

pub fn run(args: &Table1Args) -> Result<()> {
    let settings = args.settings.resolve_on(Settings::paper())?;
    for &p in &args.problems {
        Scene::paper_problem(p)?;
    }
    let folder = args.out.as_deref().map(RunFolder::create).transpose()?;
    let specs = table1::plan(
        &args.problems,
        &args.schedules,
        &settings,
        args.h,
        args.plane,
    )?;
    let bar = StudyProgress::new(specs.len() as u64, "table1");
    let (measured, rows) = table1::run(&specs, &args.problems, &|t| bar.tick(t))?;
    bar.finish();
    let mut report = table1::markdown(&rows);
    if let Some(folder) = folder {
        let trials: Vec<_> = measured.iter().map(|m| m.trial.row()).collect();
        write_atomic(&folder.path().join("table1.csv"), &to_csv(&rows, &[])?)?;
        write_atomic(
            &folder.path().join("table1_trials.csv"),
            &to_csv(&trials, &[])?,
        )?;
        let target = folder.commit()?;
        report += &format!(
            "\nwrote {}/table1.csv and table1_trials.csv\n",
            target.display()
        );
    }
    print(&report)
}
