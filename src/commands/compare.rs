//! `contactlab compare`: every solver on one scene against the earned
//! reference; a Markdown table on stdout, files with --out.

use anyhow::Result;

use crate::cli::CompareArgs;
use crate::commands::{run_study, solver_list};
use crate::io::output::print;
use crate::io::run_folder::RunFolder;
use crate::study::compare::{self, Compare};
use crate::study::lab::write_artifacts;

pub fn run(args: &CompareArgs) -> Result<()> {
    let (scene, base) = args.scene.load()?;
    let solvers = solver_list(&args.solvers)?;
    let settings = args.settings.resolve_for(base, &solvers)?;
    let folder = args.out.as_deref().map(RunFolder::create).transpose()?;
    let study = Compare {
        scene,
        solvers,
        repeats: args.repeats as usize,
    };
    let (findings, artifacts) = run_study(&study, settings)?;
    let measured = &findings;
    let mut report = compare::markdown_of(measured);
    if let Some(folder) = folder {
        let files = write_artifacts(folder.path(), &artifacts)?;
        let target = folder.commit()?;
        report += &format!("\nwrote {} into {}\n", files.join(", "), target.display());
    }
    print(&report)
}
