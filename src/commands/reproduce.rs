//! `contactlab reproduce`: the main job, into one output folder that is
//! replaced whole when everything is written.

use std::time::Instant;

use anyhow::Result;

use crate::cli::ReproduceArgs;
use crate::io::manifest::Manifest;
use crate::io::output::{json_bytes, log, print, write_atomic};
use crate::io::run_folder::RunFolder;
use crate::study::report::write_all;
use crate::study::reproduce::{self, ReproduceSpec, readme};

pub fn run(args: &ReproduceArgs) -> Result<()> {
    let settings = args.settings.resolve()?;
    let spec = if args.quick {
        ReproduceSpec::quick()
    } else {
        ReproduceSpec::full()
    };
    let folder = RunFolder::create(&args.out)?;
    let started = Instant::now();
    let dir = folder.path().to_path_buf();
    let outputs = reproduce::run(&dir, &spec, &settings, &|l| {
        log(format!(
            "reproduce [{:.0} s]: {l}",
            started.elapsed().as_secs_f64()
        ))
    })?;
    log(format!(
        "reproduce [{:.0} s]: charts and README",
        started.elapsed().as_secs_f64()
    ));
    write_all(&dir.join("charts"), &outputs.charts)?;
    let seconds = started.elapsed().as_secs_f64();
    let manifest = Manifest::collect(
        &settings,
        serde_json::json!({
            "reproduce": spec,
            "solvers": contactlab_solvers::registry::names(),
            "wall_seconds": seconds,
        }),
    );
    write_atomic(&dir.join("manifest.json"), &json_bytes(&manifest)?)?;
    let text = readme::render(&spec, &manifest, &outputs, seconds)?;
    write_atomic(&dir.join("README.md"), text.as_bytes())?;
    let target = folder.commit()?;
    print(&format!(
        "wrote {} in {seconds:.0} s (see {}/README.md)\n",
        target.display(),
        target.display()
    ))
}
