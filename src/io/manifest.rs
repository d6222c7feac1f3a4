//! `manifest.json`: what produced a results directory (commit, compiler,
//! machine, date, command line, every setting).

use std::process::Command;

use serde::Serialize;

use crate::settings::Settings;

#[derive(Debug, Serialize)]
pub struct Manifest {
    pub command: Vec<String>,
    pub contactlab_version: &'static str,
    pub git_commit: String,
    /// Whether the working tree had uncommitted changes.
    pub git_dirty: Option<bool>,
    pub rustc: &'static str,
    pub cpu: String,
    pub cores: usize,
    /// UTC, ISO 8601.
    pub date: String,
    /// Every setting, resolved.
    pub settings: serde_json::Value,
    /// Everything else the run was given (spec of the reduced sweep, meshes, ...).
    pub run: serde_json::Value,
}

/// A git command's output in the working directory, if it succeeds.
fn git(args: &[&str]) -> Option<String> {
    Command::new("git")
        .args(args)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
}

/// The commit of the source this binary runs from (`unknown` outside a git
/// checkout).
pub fn git_commit() -> String {
    git(&["rev-parse", "HEAD"]).unwrap_or_else(|| "unknown".into())
}

impl Manifest {
    /// `out`: the results directory, left out of the dirty check (it is
    /// being rewritten).
    pub fn collect(settings: &Settings, run: serde_json::Value, out: &std::path::Path) -> Self {
        Self {
            command: std::env::args().collect(),
            contactlab_version: env!("CARGO_PKG_VERSION"),
            git_commit: git_commit(),
            git_dirty: {
                let mut args = vec![
                    "status".to_string(),
                    "--porcelain".into(),
                    "--untracked-files=no".into(),
                ];
                if out.is_relative() {
                    args.extend([
                        "--".into(),
                        ".".into(),
                        format!(":(exclude){}", out.display()),
                    ]);
                }
                git(&args.iter().map(String::as_str).collect::<Vec<_>>()).map(|s| !s.is_empty())
            },
            rustc: env!("CONTACTLAB_RUSTC_VERSION"),
            cpu: cpu_model(),
            cores: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            date: utc_now(),
            settings: settings.resolved(),
            run,
        }
    }
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|text| {
            text.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string())
}

/// The current UTC time as `YYYY-MM-DDThh:mm:ssZ`.
pub fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let (y, m, d) = civil_from_days(days);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

/// Proleptic Gregorian date of a day count since 1970-01-01 (H. Hinnant's algorithm).
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + if m <= 2 { 1 } else { 0 };
    (y, m, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn civil_dates() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert_eq!(civil_from_days(20_778), (2026, 11, 21));
    }
}
