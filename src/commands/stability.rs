//! `contactlab stability`: the stability map.

use anyhow::Result;

use crate::cli::StabilityArgs;
use crate::commands::run_study;
use crate::io::output::print;
use crate::io::run_folder::RunFolder;
use crate::study::lab::write_artifacts;
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
    let trials = findings.stability.map(|m| m.trials).unwrap_or_default();
    let mut counts = std::collections::BTreeMap::new();
    for t in &trials {
        *counts
            .entry(t.class.map_or("", |c| c.as_str()))
            .or_insert(0) += 1;
    }
    print(&format!(
        "wrote {}/stability.csv ({} trials: {counts:?}), stability_friction.csv and charts\n",
        target.display(),
        trials.len()
    ))
}
