//! `contactlab benchmark`: every solver on the problem collection at each
//! target accuracy (or a shard of it), and `contactlab benchmark-merge`:
//! the same tables and charts from several shards' folders.

use anyhow::{Result, bail};

use crate::cli::{BenchmarkArgs, BenchmarkMergeArgs};
use crate::commands::{run_study, solver_list};
use crate::io::manifest::Manifest;
use crate::io::output::{json_bytes, print, write_atomic};
use crate::io::run_folder::RunFolder;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::benchmark::{self, Benchmark, BenchmarkSpec, Instance, Shard, views};
use crate::study::lab::{Artifact, write_artifacts};

pub fn run(args: &BenchmarkArgs) -> Result<()> {
    if args.settings.changes.sets("certificate.tolerance") {
        bail!(
            "--certify-tol does not apply to the benchmark: each run is certified at its target accuracy; give --targets instead"
        );
    }
    let solvers = solver_list(&args.solvers)?;
    let settings = args.settings.resolve_for(Settings::default(), &solvers)?;
    let mut spec = BenchmarkSpec::new(args.quick, solvers);
    spec.shard = args.shard.unwrap_or(Shard::WHOLE);
    if let Some(t) = args.time_limit {
        spec.time_limit = t;
    }
    if !args.targets.is_empty() {
        spec.targets = args.targets.clone();
    }
    if !args.problem.is_empty() {
        let mut seen = Vec::new();
        for &n in &args.problem {
            if seen.contains(&n) {
                anyhow::bail!(
                    "--problem: problem {n} is given twice; give each once (an instance counted twice would weigh twice in the success rates)"
                );
            }
            seen.push(n);
        }
        let h = args.h.unwrap_or(MeshSize::from_level(6)?);
        spec.instances = Some(
            args.problem
                .iter()
                .map(|&n| Ok(Instance::given(Scene::paper_problem_to(n, h)?)))
                .collect::<Result<Vec<_>>>()?,
        );
    }
    let folder = RunFolder::create(&args.out)?;
    let study = Benchmark { spec: spec.clone() };
    let (findings, artifacts) = run_study(&study, settings.clone())?;
    let dir = folder.path();
    write_artifacts(dir, &artifacts)?;
    let manifest = Manifest::collect(
        &settings,
        serde_json::json!({
            "benchmark": {
                "quick": spec.quick,
                "targets": spec.targets,
                "time_limit": spec.time_limit,
                "shard": spec.shard,
                "solvers": spec.solvers.iter().map(|e| e.name).collect::<Vec<_>>(),
            }
        }),
    );
    write_atomic(&dir.join("manifest.json"), &json_bytes(&manifest)?)?;
    let report = views::report(&findings)?;
    let target = folder.commit()?;
    print(&format!(
        "{report}\nwrote {}/benchmark.csv, its tables and charts\n",
        target.display()
    ))
}

pub fn merge(args: &BenchmarkMergeArgs) -> Result<()> {
    let rows = benchmark::merge::read_shards(&args.shards)?;
    let manifest = benchmark::merge::merged_manifest(
        &args.shards,
        serde_json::json!({
            "command": std::env::args().collect::<Vec<_>>(),
            "git_commit": crate::io::manifest::git_commit(),
            "date": crate::io::manifest::utc_now(),
        }),
    )?;
    let folder = RunFolder::create(&args.out)?;
    let dir = folder.path();
    let mut artifacts = vec![Artifact::csv("benchmark.csv", &rows, &[])?];
    artifacts.extend(views::artifacts(&rows)?);
    write_artifacts(dir, &artifacts)?;
    write_atomic(&dir.join("manifest.json"), &json_bytes(&manifest)?)?;
    let report = views::report(&rows)?;
    let target = folder.commit()?;
    print(&format!(
        "{report}\nmerged {} shards ({} rows) into {}\n",
        args.shards.len(),
        rows.len(),
        target.display()
    ))
}
