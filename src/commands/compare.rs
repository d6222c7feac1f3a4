//! `contactlab compare`: every solver on one scene against the earned
//! reference; a Markdown table on stdout, files with --out.

use anyhow::{Result, bail};

use crate::cli::CompareArgs;
use crate::commands::{run_study, solver_list};
use crate::io::output::print;
use crate::io::run_folder::RunFolder;
use crate::study::compare::{self, Compare};
use crate::study::lab::write_artifacts;
use crate::study::side_by_side::{self, SideBySide, parse_pair, solvers_of};

pub fn run(args: &CompareArgs) -> Result<()> {
    if !args.side_by_side.is_empty() {
        return side_by_side(args);
    }
    let (scene, base) = args.scene.load()?;
    let solvers = solver_list(&args.solvers)?;
    let settings = args.settings.resolve_for(base, &solvers)?;
    let folder = args.out.as_deref().map(RunFolder::create).transpose()?;
    let study = Compare {
        scene,
        solvers,
        repeats: args.repeats as usize,
        reference: args
            .reference
            .as_deref()
            .map(crate::solve::solver_entry)
            .transpose()?,
    };
    let (findings, artifacts) = run_study(&study, settings)?;
    let measured = &findings;
    let mut report = compare::markdown_of(measured)?;
    if let Some(folder) = folder {
        let files = write_artifacts(folder.path(), &artifacts)?;
        let target = folder.commit()?;
        report += &format!("\nwrote {} into {}\n", files.join(", "), target.display());
    }
    print(&report)
}

/// `compare --side-by-side A,B`: the pairs node by node.
fn side_by_side(args: &CompareArgs) -> Result<()> {
    if args.reference.is_some() {
        bail!(
            "--reference names compare's reference; with --side-by-side name it as a side (e.g. relaxation,newton-coulomb)"
        );
    }
    let (scene, base) = args.scene.load()?;
    let pairs = args
        .side_by_side
        .iter()
        .map(|w| parse_pair(w))
        .collect::<Result<Vec<_>>>()?;
    let study = SideBySide::new(scene, pairs)?;
    let settings = args.settings.resolve_for(base, &solvers_of(&study.pairs))?;
    let folder = args.out.as_deref().map(RunFolder::create).transpose()?;
    let (pairs, artifacts) = run_study(&study, settings)?;
    let charts: Vec<String> = artifacts
        .iter()
        .filter_map(|a| a.chart_name().map(String::from))
        .collect();
    let mut report = side_by_side::markdown(&study.scene, &pairs, &[])?;
    if let Some(folder) = folder {
        let files = write_artifacts(folder.path(), &artifacts)?;
        let target = folder.commit()?;
        report += &format!(
            "\nwrote {} and {} charts into {}\n",
            files
                .iter()
                .filter(|f| !f.starts_with("charts/"))
                .cloned()
                .collect::<Vec<_>>()
                .join(", "),
            charts.len(),
            target.display()
        );
    }
    print(&report)
}
