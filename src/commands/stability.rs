//! `contactlab stability`: the stability map.

use anyhow::Result;

use crate::cli::StabilityArgs;
use crate::commands::run_study;
use crate::io::output::print;
use crate::io::run_folder::RunFolder;
use crate::study::lab::write_artifacts;
use crate::study::stability::views::counts_markdown;
use crate::study::stability::{Stability, StabilitySpec};

pub fn run(args: &StabilityArgs) -> Result<()> {
    let settings = args.settings.resolve()?;
    let spec = if args.quick {
        StabilitySpec::quick()
    } else {
        StabilitySpec::standard()
    };
    let folder = RunFolder::create(&args.out)?;
    let study = Stability {
        spec,
        references_file: None,
    };
    let (findings, artifacts) = run_study(&study, settings)?;
    write_artifacts(folder.path(), &artifacts)?;
    let target = folder.commit()?;
    let trials = findings.trials;
    print(&format!(
        "{}\nwrote {}/stability.csv ({} trials; every trial that did not simply converge, with its reason, in stability_summary.md), stability_friction.csv and charts\n",
        counts_markdown(&trials),
        target.display(),
        trials.len()
    ))
}
