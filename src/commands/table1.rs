//! `contactlab table1`: the paper's Table 1 at the paper's settings.

use anyhow::Result;

use crate::cli::Table1Args;
use crate::commands::run_study;
use crate::io::output::print;
use crate::io::run_folder::RunFolder;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::lab::write_artifacts;
use crate::study::table1::{self, Table1};

pub fn run(args: &Table1Args) -> Result<()> {
    let settings = args.settings.resolve_on(Settings::paper())?;
    for &p in &args.problems {
        Scene::paper_problem(p)?;
    }
    let folder = args.out.as_deref().map(RunFolder::create).transpose()?;
    let study = Table1 {
        problems: args.problems.clone(),
        schedules: args.schedules.clone(),
        h: args.h,
        plane: args.plane,
        settings: settings.clone(),
    };
    let (findings, artifacts) = run_study(&study, settings)?;
    let mut report = table1::markdown(&findings)?;
    if let Some(folder) = folder {
        let files = write_artifacts(folder.path(), &artifacts)?;
        let target = folder.commit()?;
        report += &format!("\nwrote {} into {}\n", files.join(", "), target.display());
    }
    print(&report)
}
