//! Merging the shards of one benchmark run: each shard folder's
//! `manifest.json` says which run it belongs to (commit, collection, targets,
//! solvers, time limit, settings, shard K/N), and the merge refuses what does
//! not make one whole run: shards of other runs, a shard missing or given
//! twice, a shard whose rows are not exactly its planned runs, and rows that
//! are not what a run writes (a success the certificate does not give, NaN
//! or negative seconds). A merge of shards is then the same as one run.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde::Deserialize;

use crate::io::guarded;
use crate::study::benchmark::{BenchmarkRow, Shard, collection};

/// What a shard's manifest says of its run.
#[derive(Clone, Debug, Deserialize, PartialEq)]
struct ShardManifest {
    git_commit: String,
    git_dirty: Option<bool>,
    settings: serde_json::Value,
    run: RunPart,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
struct RunPart {
    benchmark: BenchmarkPart,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
struct BenchmarkPart {
    quick: bool,
    targets: Vec<f64>,
    time_limit: f64,
    shard: Shard,
    solvers: Vec<String>,
}

impl ShardManifest {
    /// Whether two shards belong to one run: everything equal but the
    /// shard's index.
    fn same_run(&self, other: &Self) -> bool {
        let mut a = self.clone();
        a.run.benchmark.shard.index = 0;
        let mut b = other.clone();
        b.run.benchmark.shard.index = 0;
        a == b
    }
}

/// The largest manifest read (a few kB are written).
const MAX_MANIFEST_BYTES: u64 = 16 << 20;

fn read_manifest(dir: &Path) -> Result<ShardManifest> {
    let path = dir.join("manifest.json");
    let text = guarded::read_small_text(&path, MAX_MANIFEST_BYTES).map_err(|reason| {
        anyhow::anyhow!(
            "cannot read {} ({reason}): give folders written by `contactlab benchmark`",
            path.display()
        )
    })?;
    serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: not the manifest of a `contactlab benchmark` run",
            path.display()
        )
    })
}

/// Reads the rows of `benchmark.csv` in `dir`, guarded and line-bounded.
pub fn read_csv(dir: &Path) -> Result<Vec<BenchmarkRow>> {
    let path = dir.join("benchmark.csv");
    let (file, _) = guarded::open(&path).map_err(|reason| {
        anyhow::anyhow!(
            "cannot read {} ({reason}): give folders written by `contactlab benchmark`",
            path.display()
        )
    })?;
    rows_from(file, &path.display().to_string())
}

/// The rows of a `benchmark.csv` read from `source` (named `shown`).
pub fn rows_from(source: impl std::io::Read, shown: &str) -> Result<Vec<BenchmarkRow>> {
    let mut rows = Vec::new();
    for (i, rec) in guarded::csv_reader(source)
        .deserialize::<BenchmarkRow>()
        .enumerate()
    {
        rows.push(rec.with_context(|| format!("{shown}: row {} does not parse", i + 1))?);
    }
    Ok(rows)
}

/// Checks that a row is what a run writes: success exactly when the
/// certified status is `converged` with a certificate at most the target,
/// a refused claim exactly when the solver claimed convergence without
/// success, and finite, non-negative seconds.
fn check_row(r: &BenchmarkRow, path: &Path) -> Result<()> {
    let where_ = || {
        format!(
            "{}: {} on {} at {:e}",
            path.display(),
            r.solver,
            r.instance,
            r.target
        )
    };
    let success = r.status == "converged" && r.certificate <= r.target;
    if r.success != success {
        bail!(
            "{}: success = {} but the status is {} with certificate {:e}: the file was edited or is damaged",
            where_(),
            r.success,
            r.status,
            r.certificate
        );
    }
    let refused = r.solver_status == "converged" && !success;
    if r.claimed_but_failed != refused {
        bail!(
            "{}: claimed_but_failed = {} disagrees with the solver's claim {} and the certificate: the file was edited or is damaged",
            where_(),
            r.claimed_but_failed,
            r.solver_status
        );
    }
    if !(r.seconds >= 0.0 && r.seconds.is_finite()) {
        bail!(
            "{}: seconds = {} is not a time: the file was edited or is damaged",
            where_(),
            r.seconds
        );
    }
    Ok(())
}

/// Reads and checks the shards of one run; gives every row, each shard's
/// in shard order.
pub fn read_shards(dirs: &[PathBuf]) -> Result<Vec<BenchmarkRow>> {
    let mut shards: Vec<(ShardManifest, &PathBuf)> = Vec::new();
    for d in dirs {
        shards.push((read_manifest(d)?, d));
    }
    let (first, first_dir) = shards.first().context("no shard given")?.clone();
    for (m, d) in &shards {
        if !m.same_run(&first) {
            bail!(
                "{} and {} come from different runs (commit, --quick, targets, solvers, time limit, settings or shard count differ): merge the shards of one run",
                first_dir.display(),
                d.display()
            );
        }
    }
    let of = first.run.benchmark.shard.of;
    let mut indices: Vec<usize> = shards
        .iter()
        .map(|(m, _)| m.run.benchmark.shard.index)
        .collect();
    indices.sort();
    if let Some(w) = indices.windows(2).find(|w| w[0] == w[1]) {
        bail!("shard {}/{of} is given twice: merge each shard once", w[0]);
    }
    let missing: Vec<String> = (1..=of)
        .filter(|k| !indices.contains(k))
        .map(|k| format!("{k}/{of}"))
        .collect();
    if !missing.is_empty() {
        bail!(
            "shards {} are missing: a merge needs all {of} shards of the run",
            missing.join(", ")
        );
    }
    let instances = collection(first.run.benchmark.quick)?;
    let mut all = Vec::new();
    for (m, d) in &shards {
        let b = &m.run.benchmark;
        let path = d.join("benchmark.csv");
        let rows = read_csv(d)?;
        let mut planned: Vec<(String, String, String)> = Vec::new();
        for (i, inst) in instances.iter().enumerate() {
            if b.shard.contains(i) {
                for t in &b.targets {
                    for s in &b.solvers {
                        planned.push((inst.id.clone(), s.clone(), format!("{t:e}")));
                    }
                }
            }
        }
        let mut got: Vec<(String, String, String)> = rows
            .iter()
            .map(|r| {
                (
                    r.instance.clone(),
                    r.solver.clone(),
                    format!("{:e}", r.target),
                )
            })
            .collect();
        planned.sort();
        got.sort();
        if got != planned {
            bail!(
                "{}: {} rows, but shard {}/{} of its run plans {} runs (an instance, solver or target is missing, extra or repeated)",
                path.display(),
                rows.len(),
                b.shard.index,
                b.shard.of,
                planned.len()
            );
        }
        for r in &rows {
            check_row(r, &path)?;
            // The row's time limit went through the 10-digit fixed format.
            if (r.time_limit - b.time_limit).abs() > 1e-9 * b.time_limit {
                bail!(
                    "{}: {} on {} ran with time limit {} s, but the run's is {} s",
                    path.display(),
                    r.solver,
                    r.instance,
                    r.time_limit,
                    b.time_limit
                );
            }
        }
        all.extend(rows);
    }
    Ok(all)
}

/// The manifest of a merged folder: the first shard's (the shards agree on
/// everything but the shard) as the manifest of the whole run (shard 1/1),
/// with the folders merged, and `merged_by` (the merge's own command,
/// commit and date, the caller's).
pub fn merged_manifest(
    dirs: &[PathBuf],
    merged_by: serde_json::Value,
) -> Result<serde_json::Value> {
    let first = dirs.first().context("no shard given")?;
    let path = first.join("manifest.json");
    let text = guarded::read_small_text(&path, MAX_MANIFEST_BYTES)
        .map_err(|reason| anyhow::anyhow!("cannot read {} ({reason})", path.display()))?;
    let mut m: serde_json::Value = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a manifest", path.display()))?;
    m["run"]["benchmark"]["shard"] = serde_json::json!(Shard::WHOLE);
    m["merged_from"] = serde_json::json!(dirs);
    m["merged_by"] = merged_by;
    Ok(m)
}
