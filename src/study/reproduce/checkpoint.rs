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
use crate::study::lab::{Handoff, Section};
use crate::study::reproduce::ReproduceSpec;

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

/// A hash of this process' own executable ([`file_hash`]).
fn binary_hash() -> Result<String> {
    let exe = std::env::current_exe().context("cannot find contactlab's own executable")?;
    file_hash(&exe)
}

/// One file a study wrote: its path in the run's folder and a hash of
/// its bytes, so that a resumed run keeps only files that are as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WrittenFile {
    pub path: String,
    pub hash: String,
}

impl WrittenFile {
    /// The record of `path` (relative to `dir`) as it is now.
    pub fn of(dir: &Path, path: &str) -> Result<Self> {
        Ok(Self {
            path: path.to_string(),
            hash: file_hash(&dir.join(path))?,
        })
    }
}

/// One finished study of the run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StudyRecord {
    /// The run it belongs to: the digest of its [`RunKey`].
    pub run: String,
    /// Its place in the run's list of studies (0 first).
    pub index: usize,
    pub study: String,
    pub seconds: f64,
    /// When it finished (UTC).
    pub finished: String,
    pub section: Section,
    /// The files it wrote, relative to the run's folder, with their hashes.
    pub files: Vec<WrittenFile>,
    /// The names of its charts.
    pub charts: Vec<String>,
    /// What later studies read, as it stood after this study.
    pub handoff: Handoff,
}

/// The records of a run's finished studies, in order.
pub struct Checkpoint {
    dir: PathBuf,
    /// The digest of the run's key, which every record must carry.
    pub run: String,
    /// The studies finished, in the order they ran.
    pub done: Vec<StudyRecord>,
    /// Why records were not kept, one line each (for the log).
    pub notes: Vec<String>,
}

impl Checkpoint {
    /// Starts a checkpoint in `folder` with the key `key`, empty. The
    /// folder is probed for writing first, so that a run that could not
    /// write its results fails before its first study, not after it.
    pub fn start(folder: &Path, key: &RunKey) -> Result<Self> {
        probe_writable(folder)?;
        let dir = folder.join(DIR);
        if dir.exists() {
            std::fs::remove_dir_all(&dir)
                .with_context(|| format!("cannot empty {}", dir.display()))?;
        }
        std::fs::create_dir(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
        write_atomic(&dir.join(KEY), &json_bytes(key)?)?;
        Ok(Self {
            dir,
            run: key.digest()?,
            done: Vec::new(),
            notes: Vec::new(),
        })
    }

    /// Continues the checkpoint in `folder` if its key is `key`: another
    /// run's key is refused, and so is a partial run with studies but no
    /// key (which run they belong to cannot be told); one with neither (a
    /// run interrupted before it wrote anything) is started anew. Of the
    /// records, those of the studies `plan` names, in order, are kept
    /// while each is whole ([`Checkpoint::check`]); from the first that is
    /// not, that study and every later one run again, their files are
    /// removed, and `notes` says which and why.
    pub fn resume(folder: &Path, key: &RunKey, plan: &[&str]) -> Result<Self> {
        let dir = folder.join(DIR);
        let shown = folder.display();
        if let Some(link) = first_link(folder, 0) {
            bail!(
                "--resume: {} is a symbolic link: a partial run holds only what contactlab wrote, and a link could lead its files' checks and removals into a folder of yours; remove the link (nothing behind it is touched), or run without --resume to start anew",
                link.display()
            );
        }
        let key_path = dir.join(KEY);
        if !key_path.exists() {
            let has_studies = std::fs::read_dir(folder)
                .map(|entries| {
                    entries.flatten().any(|e| {
                        let name = e.file_name();
                        name != DIR && !name.to_string_lossy().starts_with('.')
                    })
                })
                .unwrap_or(false);
            if has_studies {
                bail!(
                    "--resume: {shown} holds files but no run key ({DIR}/{KEY}), so which run they belong to cannot be told; run without --resume to start anew"
                );
            }
            let mut fresh = Self::start(folder, key)?;
            fresh.notes.push(format!(
                "--resume: {shown} holds no finished study; starting anew"
            ));
            return Ok(fresh);
        }
        let bytes = guarded::read_small(&key_path, MAX_RECORD_BYTES).map_err(|reason| {
            anyhow::anyhow!(
                "--resume: cannot read {}: {reason}; run without --resume to start anew",
                key_path.display()
            )
        })?;
        let theirs: RunKey = serde_json::from_slice(&bytes).with_context(|| {
            format!("--resume: {shown} holds an unreadable checkpoint; run without --resume to start anew")
        })?;
        if theirs != *key {
            bail!(
                "--resume: the run in {shown} was started by {}; run without --resume to start anew, or resume it with what started it",
                key.difference(&theirs)
            );
        }
        probe_writable(folder)?;
        let mut checkpoint = Self {
            dir,
            run: key.digest()?,
            done: Vec::new(),
            notes: Vec::new(),
        };
        // From the first record that is not whole on, records are dropped
        // and the files they name removed: they do not belong to the run.
        let mut discarding = false;
        let mut stale: Vec<WrittenFile> = Vec::new();
        for (k, study) in plan.iter().enumerate() {
            let path = checkpoint.dir.join(record_name(k));
            if !path.exists() {
                break;
            }
            let record = guarded::read_small(&path, MAX_RECORD_BYTES)
                .map_err(|reason| reason.to_string())
                .and_then(|bytes| {
                    serde_json::from_slice::<StudyRecord>(&bytes).map_err(|e| e.to_string())
                });
            if !discarding {
                let verdict = match &record {
                    Ok(r) => checkpoint.check(folder, k, study, r),
                    Err(e) => Err(format!("its record is unreadable ({e})")),
                };
                match verdict {
                    Ok(()) => {
                        checkpoint.done.extend(record.ok());
                        continue;
                    }
                    Err(why) => {
                        checkpoint.notes.push(format!(
                            "--resume: {study} runs again, and every study after it: {why}"
                        ));
                        discarding = true;
                    }
                }
            }
            stale.extend(record.map(|r| r.files).unwrap_or_default());
        }
        for f in &stale {
            if let Some(path) = inside(folder, &f.path) {
                let _ = std::fs::remove_file(path);
            }
        }
        for k in checkpoint.done.len().. {
            let path = checkpoint.dir.join(record_name(k));
            if !path.exists() {
                break;
            }
            let _ = std::fs::remove_file(&path);
        }
        Ok(checkpoint)
    }

    /// Whether `record` is the whole record of study `k`, `study`, of this
    /// run: it carries this run's digest, its place and name, a time that
    /// is a time, and every file it names is in `folder` as it was written.
    pub fn check(
        &self,
        folder: &Path,
        k: usize,
        study: &str,
        record: &StudyRecord,
    ) -> Result<(), String> {
        if record.run != self.run {
            return Err(format!(
                "its record ({}) belongs to another run (key {} is not this run's {})",
                record_name(k),
                record.run,
                self.run
            ));
        }
        if record.index != k || record.study != study {
            return Err(format!(
                "{} records study {} '{}' where study {k} is '{study}' (records moved or swapped)",
                record_name(k),
                record.index,
                record.study
            ));
        }
        if !(record.seconds.is_finite() && (0.0..=MAX_STUDY_SECONDS).contains(&record.seconds)) {
            return Err(format!(
                "its record's time, {} s, is not a time",
                record.seconds
            ));
        }
        for f in &record.files {
            let Some(path) = inside(folder, &f.path) else {
                return Err(format!(
                    "its record names a file outside the run's folder ({})",
                    f.path
                ));
            };
            match file_hash(&path) {
                Ok(hash) if hash == f.hash => {}
                Ok(_) => return Err(format!("{} was changed after it was written", f.path)),
                Err(_) => return Err(format!("{} is missing", f.path)),
            }
        }
        Ok(())
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

impl RunKey {
    /// A digest of the key (its JSON), which every record of the run carries.
    pub fn digest(&self) -> Result<String> {
        let mut hasher = std::hash::DefaultHasher::new();
        hasher.write(&json_bytes(self)?);
        Ok(format!("{:016x}", hasher.finish()))
    }
}

/// A hash of a file's bytes, read in pieces.
pub fn file_hash(path: &Path) -> Result<String> {
    let (mut file, _) = guarded::open(path)
        .map_err(anyhow::Error::msg)
        .with_context(|| format!("cannot read {}", path.display()))?;
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

/// The longest a study may have taken, as a record states it: 30 days (the
/// longest, `--long`'s, takes hours). A record of 1e308 s was kept and the
/// run said "in inf h".
pub const MAX_STUDY_SECONDS: f64 = 30.0 * 86_400.0;

/// `relative` inside `folder`, if it is a plain relative path that stays
/// there (no `..`, not absolute) and no part of it is a symbolic link (a
/// link would lead a check or a removal out of the folder).
fn inside(folder: &Path, relative: &str) -> Option<PathBuf> {
    let path = Path::new(relative);
    let plain = path
        .components()
        .all(|c| matches!(c, std::path::Component::Normal(_)));
    if !plain || relative.is_empty() {
        return None;
    }
    let mut at = folder.to_path_buf();
    for c in path.components() {
        at.push(c);
        if std::fs::symlink_metadata(&at).is_ok_and(|m| m.file_type().is_symlink()) {
            return None;
        }
    }
    Some(at)
}

/// The first symbolic link in `folder` and its subfolders (links are not
/// followed), at most 8 levels down.
fn first_link(folder: &Path, depth: usize) -> Option<PathBuf> {
    if depth > 8 {
        return None;
    }
    let entries = std::fs::read_dir(folder).ok()?;
    for e in entries.flatten() {
        let Ok(kind) = e.file_type() else { continue };
        if kind.is_symlink() {
            return Some(e.path());
        }
        if kind.is_dir()
            && let Some(link) = first_link(&e.path(), depth + 1)
        {
            return Some(link);
        }
    }
    None
}

/// Creates and removes a file in `folder`: a run that cannot write its
/// results is refused before it computes anything.
fn probe_writable(folder: &Path) -> Result<()> {
    let probe = folder.join(".write-probe");
    std::fs::write(&probe, b"probe")
        .and_then(|()| std::fs::remove_file(&probe))
        .with_context(|| {
            format!(
                "cannot write into {} (a read-only file system, or no permission): the run would have nowhere to put its results",
                folder.display()
            )
        })
}

fn record_name(k: usize) -> String {
    format!("study-{k}.json")
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const PLAN: [&str; 3] = ["table1", "compare", "sweep"];

    fn key() -> RunKey {
        RunKey::of(&ReproduceSpec::quick(), &Settings::default()).unwrap()
    }

    /// Writes study `k`'s file and saves its record.
    fn finish(dir: &Path, checkpoint: &mut Checkpoint, k: usize) {
        let file = format!("{}.csv", PLAN[k]);
        std::fs::write(dir.join(&file), format!("rows of {}", PLAN[k])).unwrap();
        let record = StudyRecord {
            run: checkpoint.run.clone(),
            index: k,
            study: PLAN[k].into(),
            seconds: 1.5,
            finished: "2026-11-26T00:00:00Z".into(),
            section: Section {
                markdown: format!("## {}\n", PLAN[k]),
            },
            files: vec![WrittenFile::of(dir, &file).unwrap()],
            charts: vec![],
            handoff: Handoff::default(),
        };
        checkpoint.save(k, record).unwrap();
    }

    /// A partial run with the first two studies finished.
    fn two_done() -> (tempfile::TempDir, RunKey) {
        let dir = tempfile::tempdir().unwrap();
        let key = key();
        let mut checkpoint = Checkpoint::start(dir.path(), &key).unwrap();
        finish(dir.path(), &mut checkpoint, 0);
        finish(dir.path(), &mut checkpoint, 1);
        (dir, key)
    }

    fn record_path(dir: &Path, k: usize) -> PathBuf {
        dir.join(DIR).join(record_name(k))
    }

    fn edit_record(dir: &Path, k: usize, edit: impl FnOnce(&mut serde_json::Value)) {
        let path = record_path(dir, k);
        let mut v: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        edit(&mut v);
        std::fs::write(&path, serde_json::to_vec(&v).unwrap()).unwrap();
    }

    /// A folder of the partial run replaced by a link to a user's folder
    /// holding files of the run's names: `--resume` refuses, and the
    /// user's files are all still there (once 66 were deleted behind the
    /// link). A record of 1e308 s is not a time: that study runs again.
    #[test]
    fn a_link_in_the_partial_run_is_refused_and_nothing_behind_it_removed() {
        let (dir, key) = two_done();
        let user = tempfile::tempdir().unwrap();
        for name in ["table1.csv", "compare.csv", "a.svg"] {
            std::fs::write(user.path().join(name), "the user's own").unwrap();
        }
        std::os::unix::fs::symlink(user.path(), dir.path().join("profiles")).unwrap();
        let e = Checkpoint::resume(dir.path(), &key, &PLAN)
            .err()
            .expect("refused");
        assert!(e.to_string().contains("is a symbolic link"), "{e}");
        for name in ["table1.csv", "compare.csv", "a.svg"] {
            assert_eq!(
                std::fs::read_to_string(user.path().join(name)).unwrap(),
                "the user's own"
            );
        }
        std::fs::remove_file(dir.path().join("profiles")).unwrap();
        edit_record(dir.path(), 1, |v| v["seconds"] = 1e308.into());
        let resumed = Checkpoint::resume(dir.path(), &key, &PLAN).unwrap();
        assert_eq!(resumed.done.len(), 1);
        assert!(
            resumed.notes[0].contains("is not a time"),
            "{:?}",
            resumed.notes
        );
        // A record's file path through a link is outside the folder.
        std::os::unix::fs::symlink(user.path(), dir.path().join("linked")).unwrap();
        assert!(inside(dir.path(), "linked/a.svg").is_none());
        assert!(inside(dir.path(), "table1.csv").is_some());
    }

    /// What a run saved is what a resumed run reads, in order; a key that
    /// differs (here: the certificate's tolerance) is refused, naming what
    /// differs.
    #[test]
    fn records_come_back_in_order_and_another_runs_key_is_refused() {
        let (dir, key) = two_done();
        let resumed = Checkpoint::resume(dir.path(), &key, &PLAN).unwrap();
        let studies: Vec<&str> = resumed.done.iter().map(|r| r.study.as_str()).collect();
        assert_eq!(studies, ["table1", "compare"]);
        assert!(resumed.notes.is_empty(), "{:?}", resumed.notes);
        assert_eq!(resumed.done[1].files[0].path, "compare.csv");
        let mut settings = Settings::default();
        settings.certificate.tolerance *= 10.0;
        let other = RunKey::of(&ReproduceSpec::quick(), &settings).unwrap();
        let refused = Checkpoint::resume(dir.path(), &other, &PLAN).err().unwrap();
        assert!(refused.to_string().contains("other settings"), "{refused}");
        resumed.finish().unwrap();
        assert!(!dir.path().join(DIR).exists());
    }

    /// Each way a record can fail to belong to the run (issue 47): the
    /// study and every later one run again, a note says which and why, and
    /// the files of the dropped records are removed.
    #[test]
    fn a_record_that_does_not_belong_is_rerun_with_the_reason() {
        type Tamper = fn(&Path);
        let cases: [(&str, Tamper, usize, &str); 6] = [
            (
                "a record copied from another run",
                |d| edit_record(d, 0, |v| v["run"] = "0123456789abcdef".into()),
                0,
                "belongs to another run",
            ),
            (
                "an output file deleted",
                |d| std::fs::remove_file(d.join("compare.csv")).unwrap(),
                1,
                "compare.csv is missing",
            ),
            (
                "an output file changed",
                |d| std::fs::write(d.join("table1.csv"), "other rows").unwrap(),
                0,
                "was changed",
            ),
            (
                "negative seconds",
                |d| edit_record(d, 1, |v| v["seconds"] = (-5.0).into()),
                1,
                "is not a time",
            ),
            (
                "records swapped",
                |d| {
                    let (a, b) = (record_path(d, 0), record_path(d, 1));
                    let tmp = d.join("swap");
                    std::fs::rename(&a, &tmp).unwrap();
                    std::fs::rename(&b, &a).unwrap();
                    std::fs::rename(&tmp, &b).unwrap();
                },
                0,
                "swapped",
            ),
            (
                "a file outside the run's folder",
                |d| edit_record(d, 1, |v| v["files"][0]["path"] = "../elsewhere.csv".into()),
                1,
                "outside the run's folder",
            ),
        ];
        for (what, tamper, kept, reason) in cases {
            let (dir, key) = two_done();
            tamper(dir.path());
            let resumed = Checkpoint::resume(dir.path(), &key, &PLAN).unwrap();
            assert_eq!(resumed.done.len(), kept, "{what}");
            assert_eq!(resumed.notes.len(), 1, "{what}: {:?}", resumed.notes);
            assert!(
                resumed.notes[0].contains(reason),
                "{what}: {}",
                resumed.notes[0]
            );
            assert!(
                resumed.notes[0].contains(PLAN[kept]),
                "{what}: {}",
                resumed.notes[0]
            );
            // The dropped studies' records are gone.
            assert!(!record_path(dir.path(), kept).exists(), "{what}");
            if kept == 0 && what != "records swapped" {
                assert!(
                    !dir.path().join("compare.csv").exists(),
                    "{what}: a dropped study's file stayed"
                );
            }
        }
    }

    /// A deleted run key with --resume is refused when the folder holds
    /// studies (which run they belong to cannot be told); with nothing in
    /// it the run starts anew and says so.
    #[test]
    fn a_missing_key_is_refused_where_there_are_studies() {
        let (dir, key) = two_done();
        std::fs::remove_file(dir.path().join(DIR).join(KEY)).unwrap();
        let refused = Checkpoint::resume(dir.path(), &key, &PLAN).err().unwrap();
        assert!(refused.to_string().contains("no run key"), "{refused}");
        let empty = tempfile::tempdir().unwrap();
        let fresh = Checkpoint::resume(empty.path(), &key, &PLAN).unwrap();
        assert!(fresh.done.is_empty());
        assert!(
            fresh.notes[0].contains("starting anew"),
            "{:?}",
            fresh.notes
        );
    }

    /// A folder that cannot be written is refused before any study runs:
    /// /proc, where no file can be created (whoever runs the test).
    #[test]
    fn an_unwritable_folder_is_refused_up_front() {
        let refused = Checkpoint::start(Path::new("/proc"), &key()).err().unwrap();
        assert!(
            format!("{refused:#}").contains("cannot write into /proc"),
            "{refused:#}"
        );
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
            let (dir, key) = two_done();
            let target = if as_key { KEY.to_string() } else { record_name(0) };
            std::fs::write(dir.path().join(DIR).join(target), &bytes).unwrap();
            if let Ok(resumed) = Checkpoint::resume(dir.path(), &key, &PLAN) {
                prop_assert!(resumed.done.len() <= 2);
            }
        }
    }
}
