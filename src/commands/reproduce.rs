//! `contactlab reproduce`: the main job, into one output folder that is
//! replaced whole when everything is written. It writes into the folder's
//! partial copy, study by study, so that an interrupted run can be
//! continued (`--resume`) instead of started again.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;

use crate::cli::ReproduceArgs;
use crate::commands::Bars;
use crate::io::manifest::Manifest;
use crate::io::output::{json_bytes, log, print, write_atomic};
use crate::io::run_folder::{Earlier, RunFolder};
use crate::study::lab::Lab;
use crate::study::lab::Tracker as _;
use crate::study::reproduce::checkpoint::{Checkpoint, RunKey};
use crate::study::reproduce::readme::RunFacts;
use crate::study::reproduce::{self, ReproduceSpec, duration, readme};

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
    let (folder, earlier) = RunFolder::create_partial(&out, args.resume)?;
    let started = Instant::now();
    let dir = folder.path().to_path_buf();
    let log_line = |l: &str| {
        log(format!(
            "reproduce [{:.0} s]: {l}",
            started.elapsed().as_secs_f64()
        ))
    };
    let key = RunKey::of(&spec, &settings)?;
    let mut checkpoint = match earlier {
        Earlier::Continued => {
            let resumed = Checkpoint::resume(&dir, &key, &reproduce::plan(&spec, &settings))?;
            for note in &resumed.notes {
                log_line(note);
            }
            resumed
        }
        Earlier::Replaced => {
            log_line(&format!(
                "the interrupted run in {} is started anew (`--resume` would have continued it)",
                dir.display()
            ));
            Checkpoint::start(&dir, &key)?
        }
        Earlier::None => {
            if args.resume {
                log_line(&format!(
                    "--resume: no interrupted run in {}; starting anew",
                    dir.display()
                ));
            }
            Checkpoint::start(&dir, &key)?
        }
    };
    let finished = checkpoint.done.len();
    if finished > 0 {
        log_line(&format!(
            "resuming the run in {}: {finished} studies finished earlier ({})",
            dir.display(),
            checkpoint
                .done
                .iter()
                .map(|r| r.study.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    let (_, estimate) = reproduce::estimate(&spec, &settings, finished);
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
    // The cause first, then where the finished studies are.
    let done = reproduce::run(&spec, &mut lab, &dir, &mut checkpoint).map_err(|e| {
        anyhow::anyhow!(
            "{e:#} (the studies finished before it are kept in {}: `--resume` continues the run from there)",
            dir.display()
        )
    })?;
    bars.finish();
    log_line("manifest and README");
    // The resumed studies are the first ones (see `reproduce::run`).
    let earlier_seconds: f64 = done.seconds[..done.resumed.len()]
        .iter()
        .map(|(_, s)| s)
        .sum();
    let seconds = started.elapsed().as_secs_f64() + earlier_seconds;
    let manifest = Manifest::collect(
        &settings,
        serde_json::json!({
            "reproduce": spec,
            "solvers": contactlab_solvers::registry::names(),
            "wall_seconds": seconds,
            "study_seconds": done
                .seconds
                .iter()
                .map(|(n, s)| (n.clone(), serde_json::json!(s)))
                .collect::<serde_json::Map<_, _>>(),
            // The studies an earlier, interrupted process of the same
            // build and settings ran, and when each finished (`--resume`).
            "resumed": done
                .resumed
                .iter()
                .map(|(n, at)| (n.clone(), serde_json::json!(at)))
                .collect::<serde_json::Map<_, _>>(),
        }),
    );
    write_atomic(&dir.join("manifest.json"), &json_bytes(&manifest)?)?;
    let mut files = done.files.clone();
    files.splice(0..0, ["README.md".to_string(), "manifest.json".to_string()]);
    let resumed: Vec<String> = done.resumed.iter().map(|(n, _)| n.clone()).collect();
    let text = readme::render(
        &spec,
        &manifest,
        &done.sections,
        &RunFacts {
            files: &files,
            seconds,
            resumed: &resumed,
            tolerance: settings.certificate.tolerance,
        },
    )?;
    write_atomic(&dir.join("README.md"), text.as_bytes())?;
    checkpoint.finish()?;
    let target = folder.commit()?;
    print(&format!(
        "wrote {} in {} (see {}/README.md)\n",
        target.display(),
        duration(seconds),
        target.display()
    ))
}
