//! `contactlab bench`: speed, and the hidden `bench-one` that measures the
//! peak memory of one solve in a fresh process.

use anyhow::{Result, bail};

use crate::cli::{BenchArgs, BenchOneArgs};
use crate::commands::run_study;
use crate::io::output::print;
use crate::io::run_folder::RunFolder;
use crate::settings::Settings;
use crate::study::bench::BenchSpec;
use crate::study::bench::goals::{Bench, goals_markdown};
use crate::study::bench::memory::measure_here;
use crate::study::lab::write_artifacts;

pub fn run(args: &BenchArgs) -> Result<()> {
    let settings = args.settings.resolve()?;
    let mut spec = if args.quick {
        BenchSpec::quick()
    } else {
        BenchSpec::standard()
    };
    if let Some(r) = args.runs {
        spec.runs = r as usize;
    }
    if let Some(b) = args.budget {
        if !(b > 0.0 && b <= crate::cli::MAX_SECONDS) {
            bail!(
                "--time-limit = {} is invalid: give a positive number of seconds up to a week ({})",
                crate::mechanics::scene::Shown::shown(&b),
                crate::cli::MAX_SECONDS
            );
        }
        spec.budget = b;
    }
    let folder = RunFolder::create(&args.out)?;
    let (findings, artifacts) = run_study(&Bench { spec }, settings)?;
    write_artifacts(folder.path(), &artifacts)?;
    let target = folder.commit()?;
    let goals = findings.goals;
    print(&format!(
        "{}\nwrote {}/performance.csv, performance_goals.md and charts\n",
        goals_markdown(&goals)?,
        target.display()
    ))
}

/// `bench-one`: one solve's memory in this (fresh) process, as JSON.
pub fn run_one(args: &BenchOneArgs) -> Result<()> {
    let scene = args.scene.resolve()?;
    faer::set_global_parallelism(faer::Par::Seq);
    let entry = crate::solve::solver_entry(&args.solver)?;
    let settings = args.settings.resolve_for(Settings::default(), &[entry])?;
    let used = measure_here(&scene, &args.solver, &settings)?;
    print(&format!("{}\n", serde_json::to_string(&used)?))
}
