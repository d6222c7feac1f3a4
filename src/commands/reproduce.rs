//! `contactlab reproduce`: the main job, into one output folder that is
//! replaced whole when everything is written.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;

use crate::cli::ReproduceArgs;
use crate::commands::Bars;
use crate::io::manifest::Manifest;
use crate::io::output::{json_bytes, log, print, write_atomic};
use crate::io::run_folder::RunFolder;
use crate::study::lab::Tracker as _;
use crate::study::lab::{Lab, write_artifacts};
use crate::study::reproduce::{self, ReproduceSpec, readme};

/// The committed study's folder, the default of a full run.
pub const FULL_FOLDER: &str = "results";
/// The default folder of `--quick`: never the committed study.
pub const QUICK_FOLDER: &str = "results-quick";

pub fn run(args: &ReproduceArgs) -> Result<()> {
    let settings = args.settings.resolve()?;
    let spec = if args.quick {
        ReproduceSpec::quick()
    } else if args.long {
        ReproduceSpec::long()
    } else {
        ReproduceSpec::standard()
    };
    // A smoke run never writes over the committed study unless told to.
    let out = args.out.clone().unwrap_or_else(|| {
        PathBuf::from(if args.quick {
            QUICK_FOLDER
        } else {
            FULL_FOLDER
        })
    });
    let folder = RunFolder::create(&out)?;
    let started = Instant::now();
    let dir = folder.path().to_path_buf();
    let log_line = |l: &str| {
        log(format!(
            "reproduce [{:.0} s]: {l}",
            started.elapsed().as_secs_f64()
        ))
    };
    let (_, estimate) = reproduce::estimate(&spec, &settings);
    log_line(&format!(
        "{estimate}{}",
        if spec.long || spec.quick {
            ""
        } else {
            "; --long adds the studies that take hours"
        }
    ));
    let bars = Bars::new("reproduce");
    let mut lab = Lab::new(settings.clone(), &log_line, &bars);
    let (findings, artifacts, study_seconds) = reproduce::run(&spec, &mut lab)?;
    bars.finish();
    let mut artifacts = artifacts;
    if spec.quick {
        // A smoke run cannot be mistaken for the study: every chart says so.
        for a in &mut artifacts {
            if let crate::study::lab::Content::Chart(c) = &mut a.content {
                c.title = format!("SMOKE RUN (--quick), not results: {}", c.title);
            }
        }
    }
    log_line("charts and README");
    let files = write_artifacts(&dir, &artifacts)?;
    let charts: Vec<String> = artifacts
        .iter()
        .filter_map(|a| a.chart_name().map(str::to_string))
        .collect();
    let seconds = started.elapsed().as_secs_f64();
    let manifest = Manifest::collect(
        &settings,
        serde_json::json!({
            "reproduce": spec,
            "solvers": contactlab_solvers::registry::names(),
            "wall_seconds": seconds,
            "study_seconds": study_seconds
                .iter()
                .map(|(n, s)| (n.clone(), serde_json::json!(s)))
                .collect::<serde_json::Map<_, _>>(),
        }),
    );
    write_atomic(&dir.join("manifest.json"), &json_bytes(&manifest)?)?;
    let mut files = files;
    files.splice(0..0, ["README.md".to_string(), "manifest.json".to_string()]);
    let text = readme::render(
        &spec,
        &manifest,
        &findings,
        &lab.references,
        &files,
        &charts,
        seconds,
    )?;
    write_atomic(&dir.join("README.md"), text.as_bytes())?;
    let target = folder.commit()?;
    print(&format!(
        "wrote {} in {seconds:.0} s (see {}/README.md)\n",
        target.display(),
        target.display()
    ))
}
