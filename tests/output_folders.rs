//! Output folders, as a new user's runs met them: an interrupted or
//! concurrent run into an existing folder, a symbolic link where a file is
//! written, a folder contactlab did not write. Each ends with a whole
//! folder (the previous run or the new one, never a mix) or one line on
//! stderr and a non-zero exit; nothing contactlab did not write is removed.
//! (`reproduce`'s partial runs: `resume.rs`.)

mod common;

use std::path::Path;
use std::process::Stdio;
use std::time::Duration;

use common::{contactlab, one_line_error, solve_into, staging_folders};

const SOLVE: [&str; 5] = ["solve", "--problem", "1", "--h", "1/8"];

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = walk(dir)
        .into_iter()
        .map(|p| {
            let bytes = std::fs::read(&p).unwrap();
            (p.strip_prefix(dir).unwrap().display().to_string(), bytes)
        })
        .collect();
    out.sort();
    out
}

fn walk(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

#[test]
fn an_interrupted_run_leaves_the_previous_run_whole() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("results");
    let first = solve_into("1/8", "newton", &out).output().unwrap();
    assert!(first.status.success());
    let before = files(&out);
    // A long run into the same folder, killed while it computes.
    let mut child = solve_into("1/128", "relaxation", &out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(700));
    child.kill().unwrap();
    let _ = child.wait();
    assert_eq!(
        files(&out),
        before,
        "the folder must still hold the first run, whole"
    );
    // The next run cleans the killed run's staging folder up.
    let o = solve_into("1/8", "newton", &out).output().unwrap();
    assert!(o.status.success());
    let leftovers = staging_folders(dir.path());
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// Ctrl-C (SIGINT) and SIGTERM: the run says it was not written, exits
/// with 130, and leaves neither its staging folder nor a change behind.
#[test]
fn ctrl_c_removes_the_staging_folder_and_exits_130() {
    for signal in [libc::SIGINT, libc::SIGTERM] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("results");
        let child = solve_into("1/128", "relaxation", &out)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Wait until the run has made its staging folder.
        let staging = || staging_folders(dir.path()).len();
        let start = std::time::Instant::now();
        while staging() == 0 && start.elapsed() < Duration::from_secs(20) {
            std::thread::sleep(Duration::from_millis(20));
        }
        assert_eq!(staging(), 1, "the run never made its staging folder");
        // SAFETY: kill with a valid pid of our own child and a valid signal.
        assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, signal) }, 0);
        let o = child.wait_with_output().unwrap();
        assert_eq!(o.status.code(), Some(130), "signal {signal}");
        assert!(String::from_utf8_lossy(&o.stderr).contains("interrupted"));
        assert_eq!(staging(), 0, "signal {signal} left the staging folder");
        assert!(!out.exists());
    }
}

#[test]
fn two_runs_at_once_leave_one_whole_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let spawn = |h: &str| {
        solve_into(h, "newton", &out)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (spawn("1/8"), spawn("1/16"));
    for c in [a, b] {
        let o = c.wait_with_output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let rows = std::fs::read_to_string(out.join("profile.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    let nodes = match summary["h"].as_str().unwrap() {
        "1/8" => 9,
        "1/16" => 17,
        h => panic!("unexpected h {h}"),
    };
    assert_eq!(
        rows, nodes,
        "profile.csv and summary.json come from one run"
    );
}

#[test]
fn a_symbolic_link_is_never_written_through() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("precious");
    std::fs::write(&target, b"keep me").unwrap();
    // A link where a new file is created exclusively: refused.
    let link = dir.path().join("link");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    assert!(contactlab::io::output::write_new(&link, b"x").is_err());
    // A link at a destination written atomically: the link is replaced, its
    // target is untouched.
    contactlab::io::output::write_atomic(&link, b"new").unwrap();
    assert_eq!(std::fs::read(&target).unwrap(), b"keep me");
    assert_eq!(std::fs::read(&link).unwrap(), b"new");
    assert!(
        !std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    // An output folder that is a link, or a folder contactlab did not write: refused.
    let mine = dir.path().join("mine");
    std::fs::create_dir(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), b"mine").unwrap();
    let o = contactlab()
        .args(SOLVE)
        .arg("--out")
        .arg(&mine)
        .output()
        .unwrap();
    one_line_error(&o, "--out a folder of the user's", "did not write");
    assert_eq!(std::fs::read(mine.join("notes.txt")).unwrap(), b"mine");
}

/// Only a folder with contactlab's own mark is replaced: a folder holding a
/// manifest.json of someone else's (a browser extension) lost its
/// background.js to `solve --out`. A run leaves no lock file beside its
/// folder, and `--out newdir/.` is the folder newdir.
#[test]
fn only_contactlabs_own_folders_are_replaced_and_nothing_is_left_beside_them() {
    let dir = tempfile::tempdir().unwrap();
    let webext = dir.path().join("webext");
    std::fs::create_dir(&webext).unwrap();
    std::fs::write(webext.join("manifest.json"), b"{\"manifest_version\": 3}").unwrap();
    std::fs::write(webext.join("background.js"), b"chrome.runtime").unwrap();
    let o = contactlab()
        .args(SOLVE)
        .arg("--out")
        .arg(&webext)
        .output()
        .unwrap();
    one_line_error(&o, "--out a folder with a manifest.json", "did not write");
    assert_eq!(
        std::fs::read(webext.join("background.js")).unwrap(),
        b"chrome.runtime"
    );
    // A marker with other content is not the mark.
    std::fs::write(webext.join(".contactlab-run"), b"not ours").unwrap();
    let o = contactlab()
        .args(SOLVE)
        .arg("--out")
        .arg(&webext)
        .output()
        .unwrap();
    one_line_error(&o, "--out a folder with a forged marker", "did not write");
    assert!(webext.join("background.js").is_file());
    // newdir/. is newdir; twice, so that the second replaces the first.
    let here = dir.path().join("runs");
    std::fs::create_dir(&here).unwrap();
    for _ in 0..2 {
        let o = contactlab()
            .args(SOLVE)
            .arg("--out")
            .arg(here.join("newdir").join("."))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let left: Vec<String> = std::fs::read_dir(&here)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, ["newdir"], "only the run, no lock or staging file");
    assert!(here.join("newdir/summary.json").is_file());
}
