//! `contactlab verify`: the classical scenes against their closed forms
//! (issue 74).

use anyhow::Result;

use crate::cli::VerifyArgs;
use crate::commands::{run_study, solver_list};
use crate::io::output::print;
use crate::io::run_folder::RunFolder;
use crate::study::lab::write_artifacts;
use crate::study::verify::views::section;
use crate::study::verify::{VerifySpec, VerifyStudy};

pub fn run(args: &VerifyArgs) -> Result<()> {
    let settings = args.settings.resolve()?;
    let spec = if args.quick {
        VerifySpec::quick()
    } else {
        VerifySpec::standard()
    };
    let mut study = VerifyStudy::new(spec);
    study.solvers = solver_list(&args.solvers)?;
    let folder = RunFolder::create(&args.out)?;
    let (found, artifacts) = run_study(&study, settings)?;
    let files = write_artifacts(folder.path(), &artifacts)?;
    let target = folder.commit()?;
    let charts: Vec<String> = artifacts
        .iter()
        .filter_map(|a| a.chart_name().map(str::to_string))
        .collect();
    let shown: Vec<&String> = files
        .iter()
        .filter(|f| !f.starts_with("profiles/"))
        .collect();
    print(&format!(
        "{}\nwrote {} and {} profiles into {}\n",
        section(&found, &charts),
        shown
            .iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>()
            .join(", "),
        files.len() - shown.len(),
        target.display()
    ))
}
