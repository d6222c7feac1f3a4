//! `manifest.json`: what produced a results directory (commit, compiler,
//! machine, date, command line, every setting).

use serde::Serialize;

use crate::settings::Settings;

#[derive(Debug, Serialize)]
pub struct Manifest {
    pub command: Vec<String>,
    pub contactlab_version: &'static str,
    /// The commit the binary was built from.
    pub git_commit: String,
    /// Whether the tracked sources had uncommitted changes when the binary
    /// was built.
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

/// The commit this binary was built from (`unknown` if it was not built
/// in a git checkout), recorded by the build script.
pub fn git_commit() -> String {
    env!("CONTACTLAB_GIT_COMMIT").to_string()
}

/// Whether the tracked sources (results/ aside) differed from that commit
/// when this binary was built; None if unknown.
pub fn git_dirty() -> Option<bool> {
    match env!("CONTACTLAB_GIT_DIRTY") {
        "true" => Some(true),
        "false" => Some(false),
        _ => None,
    }
}

impl Manifest {
    pub fn collect(settings: &Settings, run: serde_json::Value) -> Self {
        Self {
            command: std::env::args().collect(),
            contactlab_version: env!("CARGO_PKG_VERSION"),
            git_commit: git_commit(),
            git_dirty: git_dirty(),
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
