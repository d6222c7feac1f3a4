//! An output folder that always holds one whole run: a run writes into a
//! fresh staging folder beside the target and, when everything is written,
//! swaps it into place (an atomic exchange of the two directories where the
//! system has one, under a lock so that concurrent runs take turns). An
//! interrupted run leaves the previous run untouched; two runs at once leave
//! the one that finished last, never a mix.
//!
//! A folder that exists, is not empty and does not carry contactlab's own
//! mark ([`MARKER`], with its exact content) is refused: it is replaced
//! whole, so it must be ours. (Any `manifest.json` used to count as the
//! mark, and `solve --out` into a browser extension's folder deleted its
//! `background.js`.)
//!
//! The swap is made under a lock on the parent folder itself, held only
//! for the swap, so that no lock file is left beside the run.
//!
//! An interrupted run (Ctrl-C, SIGTERM, SIGHUP) removes its staging folder
//! before it exits, once the binary asks for it ([`remove_on_interrupt`]);
//! a run killed outright leaves it, and the next run into the same place
//! removes it ([`remove_stale_staging`]).
//!
//! A run that can be resumed (`reproduce`) writes instead into
//! `NAME.partial` beside the target ([`RunFolder::create_partial`]), which
//! it keeps when it does not finish, under a lock while it runs.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, Result, bail};

use crate::io::output::write_new;

/// The file that marks a folder as a contactlab run (it is replaced whole).
pub const MARKER: &str = ".contactlab-run";

/// The marker's content, checked byte for byte.
const MARK: &[u8] = b"written by contactlab\n";

/// The staging folders of this process' runs not yet committed.
static STAGING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// What an interrupt says of this process' partial runs, which it keeps.
static KEPT: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// On Ctrl-C, SIGTERM or SIGHUP: removes every staging folder of this
/// process, says that the target was left as it was, and exits with 130.
/// For the binary only: a library caller (the Python package) keeps its
/// own handling of Ctrl-C.
pub fn remove_on_interrupt() {
    let _ = ctrlc::set_handler(|| {
        // Holding the list, no commit can swap a folder in meanwhile.
        let staging = STAGING.lock().unwrap_or_else(|e| e.into_inner());
        for p in staging.iter() {
            let _ = std::fs::remove_dir_all(p);
        }
        eprintln!(
            "interrupted: the run was not written, and its output folder is as it was before"
        );
        for line in KEPT.lock().unwrap_or_else(|e| e.into_inner()).iter() {
            eprintln!("{line}");
        }
        std::process::exit(130);
    });
}

/// A run being written.
pub struct RunFolder {
    target: PathBuf,
    staging: PathBuf,
    committed: bool,
    /// A partial run ([`RunFolder::create_partial`]): its staging folder
    /// is kept if the run does not finish, and locked while it runs; the
    /// note an interrupt gives of it.
    partial: Option<(File, String)>,
}

/// What a partial run ([`RunFolder::create_partial`]) found beside its
/// target when it started.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Earlier {
    /// No partial run.
    None,
    /// A partial run, continued (`resume`).
    Continued,
    /// A partial run, started anew (not `resume`).
    Replaced,
}

/// A run's target made ready: normalized, its parent folder created, and
/// checked to be replaceable; gives the target, its name and its parent.
fn prepare(target: &Path) -> Result<(PathBuf, String, PathBuf)> {
    let target = normalized(target)?;
    let shown = target.display();
    let name = target
        .file_name()
        .with_context(|| format!("--out {shown}: give a folder name, not a root or `..`"))?
        .to_string_lossy()
        .into_owned();
    let parent = parent_of(&target);
    std::fs::create_dir_all(&parent).with_context(|| {
        format!("--out {shown}: cannot create its parent folder; choose a writable place")
    })?;
    check_replaceable(&target)?;
    Ok((target, name, parent))
}

/// The folder `target` lies in (`.` for a bare name).
fn parent_of(target: &Path) -> PathBuf {
    match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

impl RunFolder {
    /// Starts a run into `target`: checks that it may be replaced and
    /// creates the staging folder beside it (so that an unwritable place
    /// fails at once, before any computation).
    pub fn create(target: &Path) -> Result<Self> {
        let (target, name, parent) = &prepare(target)?;
        let shown = target.display();
        remove_stale_staging(parent, name);
        let staging = (0..100)
            .map(|k| {
                parent.join(format!(
                    ".{name}.staging-{}-{}",
                    std::process::id(),
                    unique(k)
                ))
            })
            .find(|p| std::fs::create_dir(p).is_ok())
            .with_context(|| {
                format!(
                    "--out {shown}: the output folder cannot be written; choose a writable place"
                )
            })?;
        STAGING
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(staging.clone());
        let folder = Self {
            target: target.to_path_buf(),
            staging,
            committed: false,
            partial: None,
        };
        write_new(&folder.staging.join(MARKER), MARK)
            .with_context(|| format!("--out {shown}: the output folder cannot be written"))?;
        Ok(folder)
    }

    /// Starts a run into `target` whose finished parts outlive it: it is
    /// written into `NAME.partial` beside the target, which an interrupt,
    /// an error or a kill leaves in place (and says so), so that a later
    /// run can continue it. With `resume` an existing partial folder is
    /// continued (the caller checks what it holds), else it is started
    /// anew. The folder is locked while the run lasts: a second run into
    /// the same target at once is refused. Gives the folder and what it
    /// found there.
    pub fn create_partial(target: &Path, resume: bool) -> Result<(Self, Earlier)> {
        let (target, name, parent) = prepare(target)?;
        let shown = target.display();
        let partial = parent.join(format!("{name}.partial"));
        let shown_partial = partial.display();
        let exists = std::fs::symlink_metadata(&partial).is_ok();
        if exists && !carries_mark(&partial) {
            bail!(
                "--out {shown}: {shown_partial} exists and contactlab did not write it (it lacks the {MARKER} mark); move it away or choose another --out"
            );
        }
        let lock = |dir: &Path| -> Result<File> {
            let f = File::open(dir).with_context(|| format!("cannot open {}", dir.display()))?;
            match f.try_lock() {
                Ok(()) => Ok(f),
                Err(std::fs::TryLockError::WouldBlock) => bail!(
                    "--out {shown}: another run is writing {} now; wait for it or choose another --out",
                    dir.display()
                ),
                Err(std::fs::TryLockError::Error(e)) => {
                    Err(e).with_context(|| format!("cannot lock {}", dir.display()))
                }
            }
        };
        let earlier = match (exists, resume) {
            (false, _) => Earlier::None,
            (true, true) => Earlier::Continued,
            (true, false) => Earlier::Replaced,
        };
        let held = if earlier == Earlier::Continued {
            lock(&partial)?
        } else {
            if earlier == Earlier::Replaced {
                // Ours and not in use (the lock says so): started anew.
                drop(lock(&partial)?);
                std::fs::remove_dir_all(&partial)
                    .with_context(|| format!("cannot remove {shown_partial}"))?;
            }
            std::fs::create_dir(&partial).with_context(|| {
                format!("--out {shown}: {shown_partial} cannot be written; choose a writable place")
            })?;
            write_new(&partial.join(MARKER), MARK)
                .with_context(|| format!("--out {shown}: {shown_partial} cannot be written"))?;
            lock(&partial)?
        };
        let note = format!(
            "the studies finished so far are kept in {shown_partial}: `--resume` continues the run from there"
        );
        KEPT.lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(note.clone());
        Ok((
            Self {
                target: target.clone(),
                staging: partial,
                committed: false,
                partial: Some((held, note)),
            },
            earlier,
        ))
    }

    /// Where the run's files go until it is committed.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// The folder the run will be in.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Puts the finished run in place of whatever the target held.
    pub fn commit(mut self) -> Result<PathBuf> {
        let parent = parent_of(&self.target);
        let lock = File::open(&parent)
            .with_context(|| format!("cannot open {} to lock it", parent.display()))?;
        lock.lock()
            .with_context(|| format!("cannot lock {}", parent.display()))?;
        check_replaceable(&self.target)?;
        // An interrupt waits until the swap is done (and then exits).
        let mut staging = STAGING.lock().unwrap_or_else(|e| e.into_inner());
        staging.retain(|p| *p != self.staging);
        let mut old = None;
        if self.target.exists() {
            if exchange(&self.staging, &self.target).is_ok() {
                // The staging path now holds the previous run.
                old = Some(self.staging.clone());
            } else {
                // No atomic exchange here: move the old run aside first.
                let aside = self.staging.with_extension("old");
                std::fs::rename(&self.target, &aside)
                    .with_context(|| format!("cannot replace {}", self.target.display()))?;
                std::fs::rename(&self.staging, &self.target)
                    .with_context(|| format!("cannot move the run to {}", self.target.display()))?;
                old = Some(aside);
            }
        } else {
            std::fs::rename(&self.staging, &self.target)
                .with_context(|| format!("cannot move the run to {}", self.target.display()))?;
        }
        self.committed = true;
        if let Some((_, note)) = self.partial.take() {
            KEPT.lock()
                .unwrap_or_else(|e| e.into_inner())
                .retain(|l| *l != note);
        }
        drop(staging);
        drop(lock);
        if let Some(old) = old {
            let _ = std::fs::remove_dir_all(old);
        }
        Ok(self.target.clone())
    }
}

impl Drop for RunFolder {
    fn drop(&mut self) {
        // A partial run keeps what it wrote for `--resume`.
        if !self.committed && self.partial.is_none() {
            let mut staging = STAGING.lock().unwrap_or_else(|e| e.into_inner());
            staging.retain(|p| *p != self.staging);
            let _ = std::fs::remove_dir_all(&self.staging);
        }
    }
}

/// The target with `.` components dropped (`newdir/.` is `newdir`, which
/// the final rename can replace), refused if it ends in `..` or is a root.
fn normalized(target: &Path) -> Result<PathBuf> {
    use std::path::Component;
    let kept: PathBuf = target
        .components()
        .filter(|c| !matches!(c, Component::CurDir))
        .collect();
    match kept.components().next_back() {
        Some(Component::Normal(_)) => Ok(kept),
        _ => bail!(
            "--out {}: give a folder name, not a root, `.` or `..`",
            target.display()
        ),
    }
}

/// A target may be replaced if it does not exist, is an empty folder, or
/// carries contactlab's mark (the marker file with its exact content).
fn check_replaceable(target: &Path) -> Result<()> {
    let shown = target.display();
    let meta = match std::fs::symlink_metadata(target) {
        Err(_) => return Ok(()),
        Ok(m) => m,
    };
    if !meta.is_dir() {
        bail!("--out {shown} exists and is not a folder; choose a new folder name");
    }
    let mut entries = std::fs::read_dir(target)
        .with_context(|| format!("--out {shown}: cannot read the existing folder"))?;
    let empty = entries.next().is_none();
    if empty || carries_mark(target) {
        Ok(())
    } else {
        bail!(
            "--out {shown} is a folder that contactlab did not write (it lacks contactlab's {MARKER} mark, and each run replaces its output folder whole); choose a new or empty folder"
        )
    }
}

/// Whether `dir` is a folder with contactlab's mark (the marker file with
/// its exact content).
fn carries_mark(dir: &Path) -> bool {
    std::fs::symlink_metadata(dir).is_ok_and(|m| m.is_dir())
        && crate::io::guarded::read_small(&dir.join(MARKER), MARK.len() as u64)
            .is_ok_and(|bytes| bytes == MARK)
}

/// Swaps two directories atomically (Linux `renameat2` with
/// `RENAME_EXCHANGE`); an error where the system or file system has none.
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    {
        use std::ffi::CString;
        use std::os::unix::ffi::OsStrExt;
        let ca = CString::new(a.as_os_str().as_bytes())?;
        let cb = CString::new(b.as_os_str().as_bytes())?;
        // SAFETY: both paths are valid NUL-terminated strings that outlive the call.
        let rc = unsafe {
            libc::renameat2(
                libc::AT_FDCWD,
                ca.as_ptr(),
                libc::AT_FDCWD,
                cb.as_ptr(),
                libc::RENAME_EXCHANGE,
            )
        };
        if rc == 0 {
            Ok(())
        } else {
            Err(std::io::Error::last_os_error())
        }
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = (a, b);
        Err(std::io::Error::from(std::io::ErrorKind::Unsupported))
    }
}

/// Removes staging folders of runs whose process is gone (Linux: no /proc/PID).
fn remove_stale_staging(parent: &Path, name: &str) {
    let prefix = format!(".{name}.staging-");
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        let Some(rest) = file.strip_prefix(&prefix) else {
            continue;
        };
        let pid = rest.split('-').next().unwrap_or("");
        let alive = Path::new("/proc").join(pid).exists();
        if !alive && Path::new("/proc/self").exists() {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// A number that differs between calls and between processes.
pub fn unique(salt: u64) -> u64 {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0);
    nanos ^ salt.wrapping_mul(0x9E37_79B9_7F4A_7C15)
}
