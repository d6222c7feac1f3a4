//! `contactlab error-bound`: whether the certificate's error bound holds,
//! and how sharp it is (issue 51).

use anyhow::{Result, bail};

use crate::cli::ErrorBoundArgs;
use crate::commands::run_study;
use crate::io::output::print;
use crate::io::run_folder::RunFolder;
use crate::study::error_bound::views::section;
use crate::study::error_bound::{BoundSpec, ErrorBoundStudy};
use crate::study::lab::write_artifacts;

pub fn run(args: &ErrorBoundArgs) -> Result<()> {
    let settings = args.settings.resolve()?;
    if settings.certificate.bound_max_unknowns == 0 {
        bail!(
            "certificate.bound_max_unknowns = 0 turns off the error bounds, which are all this study measures (it bounds every answer, whatever its size): drop the setting"
        );
    }
    let spec = if args.quick {
        BoundSpec::quick()
    } else {
        BoundSpec::standard()
    };
    let folder = RunFolder::create(&args.out)?;
    let study = ErrorBoundStudy { spec: spec.clone() };
    let (points, artifacts) = run_study(&study, settings)?;
    let files = write_artifacts(folder.path(), &artifacts)?;
    let target = folder.commit()?;
    let charts: Vec<String> = artifacts
        .iter()
        .filter_map(|a| a.chart_name().map(str::to_string))
        .collect();
    print(&format!(
        "{}\nwrote {} into {}\n",
        section(&spec, &points, &charts),
        files.join(", "),
        target.display()
    ))
}
