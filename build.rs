//! Records, for `manifest.json`, `summary.json` and `problem.json`, the
//! compiler version and the commit the binary is built from (and whether
//! the tracked sources differed from it), so that a run's provenance is
//! the binary's, not that of whatever folder the user runs it in (asking
//! git at run time gave another repository's HEAD, or "unknown" in /tmp).
use std::path::Path;
use std::process::Command;

fn main() {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let version = Command::new(rustc)
        .arg("--version")
        .output()
        .ok()
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
        .unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=CONTACTLAB_RUSTC_VERSION={version}");
    println!("cargo:rerun-if-env-changed=RUSTC");

    let commit = git(&["rev-parse", "HEAD"]).unwrap_or_else(|| "unknown".into());
    // Tracked files only, results/ aside (a reproduce rewrites it); without
    // optional locks, so that asking does not rewrite the index (which
    // would make the next build run this script again).
    let dirty = git(&[
        "--no-optional-locks",
        "status",
        "--porcelain",
        "--untracked-files=no",
        "--",
        ".",
        ":(exclude)results",
    ])
    .map_or("unknown", |s| if s.is_empty() { "false" } else { "true" });
    println!("cargo:rustc-env=CONTACTLAB_GIT_COMMIT={commit}");
    println!("cargo:rustc-env=CONTACTLAB_GIT_DIRTY={dirty}");
    // Run again when the commit or the sources change.
    if let Some(git_dir) = git(&["rev-parse", "--git-dir"]) {
        let git_dir = Path::new(&git_dir);
        // Only paths that exist: cargo treats a missing one as always changed.
        for name in ["HEAD", "index", "packed-refs", "refs"] {
            let path = Path::new(&std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default())
                .join(git_dir)
                .join(name);
            if path.exists() {
                println!("cargo:rerun-if-changed={}", path.display());
            }
        }
    }
    for path in ["src", "solvers", "Cargo.toml", "Cargo.lock", "build.rs"] {
        println!("cargo:rerun-if-changed={path}");
    }
}

/// A git command's output in the crate's folder, if it succeeds.
fn git(args: &[&str]) -> Option<String> {
    let dir = std::env::var("CARGO_MANIFEST_DIR").ok()?;
    Command::new("git")
        .args(args)
        .current_dir(dir)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
}
