//! Resuming an interrupted `reproduce`. A run writes into its partial
//! folder ([`crate::io::run_folder::RunFolder::create_partial`]); after
//! each study its files are there and a record of it in `.resume/`: the
//! README's section computed from its findings, the files it wrote, the
//! seconds it took and what later studies read from it ([`Handoff`]).
//! `reproduce --resume` skips the studies recorded, provided the partial
//! folder was started by the same binary with the same spec and settings
//! ([`RunKey`]): otherwise the trials would not be one run's.

use std::hash::Hasher as _;
use std::io::Read as _;
use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result, bail};
use serde::{Deserialize, Serialize};

use crate::io::guarded;
use crate::io::output::{json_bytes, write_atomic};
use crate::settings::Settings;
use crate::study::lab::Handoff;
use crate::study::reproduce::ReproduceSpec;
use crate::study::reproduce::sections::Section;

/// The checkpoint's folder inside the partial folder.
pub const DIR: &str = ".resume";

/// The run's key file in [`DIR`].
const KEY: &str = "run.json";

/// The largest record read back (a study's README section and file list).
const MAX_RECORD_BYTES: u64 = 64 << 20;

/// What makes two processes' studies one run: the same binary (a hash of
/// its bytes, so that a rebuild with other code is not mixed in), the same
/// spec and the same resolved settings.
#[derive(Debug, PartialEq, Serialize, Deserialize)]
pub struct RunKey {
    pub binary: String,
    pub spec: serde_json::Value,
    pub settings: serde_json::Value,
}

impl RunKey {
    pub fn of(spec: &ReproduceSpec, settings: &Settings) -> Result<Self> {
        Ok(Self {
            binary: binary_hash()?,
            spec: serde_json::to_value(spec)?,
            settings: settings.resolved(),
        })
    }

    /// What differs between `self` (this process) and `other` (the
    /// partial folder's), in words.
    fn difference(&self, other: &Self) -> &'static str {
        if self.binary != other.binary {
            "another build of contactlab"
        } else if self.spec != other.spec {
            "another choice of studies (--quick or --long)"
        } else {
            "other settings"
        }
    }
}

/// A hash of this process' own executable, read in pieces.
fn binary_hash() -> Result<String> {
    let exe = std::env::current_exe().context("cannot find contactlab's own executable")?;
    let (mut file, _) = guarded::open(&exe)
        .map_err(anyhow::Error::msg)
        .with_context(|| format!("cannot read {}", exe.display()))?;
    let mut hasher = std::hash::DefaultHasher::new();
    let mut buffer = vec![0u8; 1 << 20];
    loop {
        let n = file.read(&mut buffer)?;
        if n == 0 {
            break;
        }
        hasher.write(&buffer[..n]);
    }
    Ok(format!("{:016x}", hasher.finish()))
}

/// One finished study of the run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StudyRecord {
    pub study: String,
    pub seconds: f64,
    /// When it finished (UTC).
    pub finished: String,
    pub section: Section,
    /// The files it wrote, relative to the run's folder.
    pub files: Vec<String>,
    /// The names of its charts.
    pub charts: Vec<String>,
    /// What later studies read, as it stood after this study.
    pub handoff: Handoff,
}

/// The records of a run's finished studies, in order.
pub struct Checkpoint {
    dir: PathBuf,
    /// The studies finished, in the order they ran.
    pub done: Vec<StudyRecord>,
}

impl Checkpoint {
    /// Starts a checkpoint in `folder` with the key `key`, empty.
    pub fn start(folder: &Path, key: &RunKey) -> Result<Self> {
        let dir = folder.join(DIR);
        if dir.exists() {
            std::fs::remove_dir_all(&dir)
                .with_context(|| format!("cannot empty {}", dir.display()))?;
        }
        std::fs::create_dir(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
        write_atomic(&dir.join(KEY), &json_bytes(key)?)?;
        Ok(Self {
            dir,
            done: Vec::new(),
        })
    }

    /// Continues the checkpoint in `folder`, if its key is `key`; one that
    /// has none yet (the run was interrupted before it wrote one) is
    /// started anew.
    pub fn resume(folder: &Path, key: &RunKey) -> Result<Self> {
        let dir = folder.join(DIR);
        let shown = folder.display();
        let Ok(bytes) = guarded::read_small(&dir.join(KEY), MAX_RECORD_BYTES) else {
            return Self::start(folder, key);
        };
        let theirs: RunKey = serde_json::from_slice(&bytes).with_context(|| {
            format!("--resume: {shown} holds an unreadable checkpoint; run without --resume to start anew")
        })?;
        if theirs != *key {
            bail!(
                "--resume: the run in {shown} was started by {}; run without --resume to start anew, or resume it with what started it",
                key.difference(&theirs)
            );
        }
        let mut done = Vec::new();
        for k in 0.. {
            let path = dir.join(record_name(k));
            let Ok(bytes) = guarded::read_small(&path, MAX_RECORD_BYTES) else {
                break;
            };
            let record: StudyRecord = serde_json::from_slice(&bytes).with_context(|| {
                format!(
                    "--resume: {} is unreadable; run without --resume to start anew",
                    path.display()
                )
            })?;
            done.push(record);
        }
        Ok(Self { dir, done })
    }

    /// Records the `k`-th study as finished (its files are written).
    pub fn save(&mut self, k: usize, record: StudyRecord) -> Result<()> {
        if k != self.done.len() {
            bail!("study {k} recorded out of order");
        }
        write_atomic(&self.dir.join(record_name(k)), &json_bytes(&record)?)?;
        self.done.push(record);
        Ok(())
    }

    /// Removes the checkpoint once the run is whole (before it is put in
    /// place, so that the results hold no trace of it).
    pub fn finish(self) -> Result<()> {
        std::fs::remove_dir_all(&self.dir)
            .with_context(|| format!("cannot remove {}", self.dir.display()))
    }
}

fn record_name(k: usize) -> String {
    format!("study-{k}.json")
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn key() -> RunKey {
        RunKey::of(&ReproduceSpec::quick(), &Settings::default()).unwrap()
    }

    fn record(study: &str) -> StudyRecord {
        StudyRecord {
            study: study.into(),
            seconds: 1.5,
            finished: "2026-11-26T00:00:00Z".into(),
            section: serde_json::from_value(serde_json::json!(
                {"Table1": {"table1": "| a |", "table1_text": "text"}}
            ))
            .unwrap(),
            files: vec!["table1.csv".into()],
            charts: vec![],
            handoff: Handoff::default(),
        }
    }

    /// What a run saved is what a resumed run reads, in order; a key that
    /// differs (here: the certificate's tolerance) is refused, naming what
    /// differs.
    #[test]
    fn records_come_back_in_order_and_another_runs_key_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let key = key();
        let mut checkpoint = Checkpoint::start(dir.path(), &key).unwrap();
        checkpoint.save(0, record("table1")).unwrap();
        checkpoint.save(1, record("compare")).unwrap();
        assert!(checkpoint.save(3, record("bench")).is_err());
        let resumed = Checkpoint::resume(dir.path(), &key).unwrap();
        let studies: Vec<&str> = resumed.done.iter().map(|r| r.study.as_str()).collect();
        assert_eq!(studies, ["table1", "compare"]);
        assert_eq!(resumed.done[1].files, ["table1.csv"]);
        let mut settings = Settings::default();
        settings.certificate.tolerance *= 10.0;
        let other = RunKey::of(&ReproduceSpec::quick(), &settings).unwrap();
        let refused = Checkpoint::resume(dir.path(), &other).err().unwrap();
        assert!(refused.to_string().contains("other settings"), "{refused}");
        resumed.finish().unwrap();
        assert!(!dir.path().join(DIR).exists());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Any bytes as the key or as a record: an error or the records
        /// before it, never a panic.
        #[test]
        fn any_bytes_in_a_checkpoint_are_an_error_not_a_panic(
            bytes in proptest::collection::vec(any::<u8>(), 0..2000),
            as_key in any::<bool>(),
        ) {
            let dir = tempfile::tempdir().unwrap();
            let key = key();
            let checkpoint = Checkpoint::start(dir.path(), &key).unwrap();
            let target = if as_key { KEY.to_string() } else { record_name(0) };
            std::fs::write(checkpoint.dir.join(target), &bytes).unwrap();
            if let Ok(resumed) = Checkpoint::resume(dir.path(), &key) {
                prop_assert!(resumed.done.len() <= 1);
            }
        }
    }
}
