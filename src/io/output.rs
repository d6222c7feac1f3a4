//! Writing results: every file is written to a fresh temporary name
//! (created exclusively, so a symbolic link planted under that name is never
//! followed) and renamed, so an interrupted run never leaves a half-written
//! file that looks complete. Accuracy files use a fixed float format, so
//! reruns compare byte for byte. Standard output and error are written
//! without panicking when they are closed or full.

use std::io::{self, Write};
use std::path::Path;

use anyhow::{Context, Result};
use serde::Serialize;

/// Writes `bytes` to `path` via an exclusively created temporary file in
/// the same directory and a rename; creates the directory if needed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create output directory {}", dir.display()))?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = (0..100)
        .map(|k| {
            dir.join(format!(
                ".{name}.partial-{}-{:x}",
                std::process::id(),
                crate::io::run_folder::unique(k)
            ))
        })
        .find(|t| !t.exists())
        .with_context(|| format!("cannot find a temporary name for {}", path.display()))?;
    let write = || -> io::Result<()> {
        write_new(&tmp, bytes)?;
        std::fs::rename(&tmp, path)
    };
    write()
        .inspect_err(|_| {
            let _ = std::fs::remove_file(&tmp);
        })
        .with_context(|| format!("cannot write {}", path.display()))
}

/// Writes a file that must not exist yet (never through a symbolic link).
pub fn write_new(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(path)?;
    f.write_all(bytes)?;
    f.sync_data()
}

/// Writes `text` to standard output. A closed pipe or a full device is an
/// error that says so (never a panic); files are written before this.
pub fn print(text: &str) -> Result<()> {
    let mut out = io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|_| out.flush())
        .map_err(|e| match e.kind() {
            io::ErrorKind::BrokenPipe => anyhow::anyhow!(
                "standard output was closed before the report was printed (the files are written)"
            ),
            _ => anyhow::anyhow!("cannot write to standard output: {e} (the files are written)"),
        })
}

/// A line on standard error, for logs: dropped if standard error is closed.
pub fn log(line: impl AsRef<str>) {
    let _ = writeln!(io::stderr().lock(), "{}", line.as_ref());
}

/// A float in the fixed format of accuracy files (10 significant digits).
/// Non-finite values are written as empty fields, never as NaN.
pub fn fixed(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.9e}")
    } else {
        String::new()
    }
}

/// A CSV table as bytes: a header and rows of already formatted fields.
pub fn csv_bytes<S: AsRef<str>>(
    header: &[&str],
    rows: impl IntoIterator<Item = Vec<S>>,
) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header)?;
    for row in rows {
        w.write_record(row.iter().map(|f| f.as_ref()))?;
    }
    w.into_inner().map_err(|e| anyhow::anyhow!("csv: {e}"))
}

/// Pretty JSON (serde_json writes non-finite floats as null).
pub fn json_bytes(value: &impl Serialize) -> Result<Vec<u8>> {
    let mut bytes = serde_json::to_vec_pretty(value)?;
    bytes.push(b'\n');
    Ok(bytes)
}
