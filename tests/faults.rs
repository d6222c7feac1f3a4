//! Faults seen when the tool was tried as a new user would: a closed or full
//! standard output, an interrupted or concurrent run into an existing output
//! folder, a symbolic link where a file is written, a FIFO or a device as a
//! scene file, unbounded counts, and a certificate that fails. Each must end
//! with one line on stderr and a non-zero exit, or a whole folder, never a
//! panic, a hang or a mix of two runs.

use std::path::Path;
mod common;

use std::process::{Command, Stdio};
use std::time::Duration;

use common::{contactlab, one_line_error, run_with_deadline};

const SOLVE: [&str; 5] = ["solve", "--problem", "1", "--h", "1/8"];

#[test]
fn a_failing_certificate_turns_convergence_into_inaccurate_and_a_nonzero_exit() {
    let o = contactlab()
        .args(SOLVE)
        .args(["--solver", "clarabel", "--clarabel-tol", "1"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("status              inaccurate (solver's claim: converged"),
        "{stdout}"
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains("the answer is inaccurate") && stderr.contains("force_balance"),
        "{stderr}"
    );
}

#[test]
fn a_closed_or_full_stdout_is_an_error_after_the_files_are_written() {
    let dir = tempfile::tempdir().unwrap();
    // A pipe whose reader is gone: `solve --out D | true`.
    let out = dir.path().join("piped");
    let o = Command::new("bash")
        .args([
            "-c",
            &format!(
                "set -o pipefail; '{}' solve --problem 1 --h 1/8 --solver newton --out '{}' 2>'{}' | true",
                env!("CARGO_BIN_EXE_contactlab"),
                out.display(),
                dir.path().join("stderr").display()
            ),
        ])
        .output()
        .unwrap();
    let stderr = std::fs::read_to_string(dir.path().join("stderr")).unwrap();
    assert!(!stderr.contains("panicked"), "{stderr}");
    // The reader may or may not be gone before the report is printed; either
    // way the files are there, and a failed print is a one-line error.
    assert!(out.join("profile.csv").is_file() && out.join("summary.json").is_file());
    if !o.status.success() {
        assert!(stderr.contains("standard output was closed"), "{stderr}");
    }
    // A full device: `solve --out D > /dev/full`.
    if Path::new("/dev/full").exists() {
        let out = dir.path().join("full");
        let o = contactlab()
            .args([
                "solve",
                "--problem",
                "1",
                "--h",
                "1/8",
                "--solver",
                "newton",
                "--out",
            ])
            .arg(&out)
            .stdout(std::fs::File::create("/dev/full").unwrap())
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        // The progress log is on stderr; the error is its last line.
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && !stderr.contains("panicked"),
            "{stderr}"
        );
        let last = stderr.lines().last().unwrap_or_default();
        assert!(
            last.starts_with("error: cannot write to standard output"),
            "{stderr}"
        );
        assert!(out.join("profile.csv").is_file() && out.join("summary.json").is_file());
    }
}

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
    let first = contactlab()
        .args([
            "solve",
            "--problem",
            "1",
            "--h",
            "1/8",
            "--solver",
            "newton",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(first.status.success());
    let before = files(&out);
    // A long run into the same folder, killed while it computes.
    let mut child = contactlab()
        .args([
            "solve",
            "--problem",
            "1",
            "--h",
            "1/128",
            "--solver",
            "relaxation",
            "--out",
        ])
        .arg(&out)
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
    let o = contactlab()
        .args([
            "solve",
            "--problem",
            "1",
            "--h",
            "1/8",
            "--solver",
            "newton",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success());
    let leftovers: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("staging"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// Ctrl-C (SIGINT) and SIGTERM: the run says it was not written, exits
/// with 130, and leaves neither its staging folder nor a change behind.
#[test]
fn ctrl_c_removes_the_staging_folder_and_exits_130() {
    for signal in [libc::SIGINT, libc::SIGTERM] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("results");
        let child = contactlab()
            .args([
                "solve",
                "--problem",
                "1",
                "--h",
                "1/128",
                "--solver",
                "relaxation",
                "--out",
            ])
            .arg(&out)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Wait until the run has made its staging folder.
        let staging = || {
            std::fs::read_dir(dir.path())
                .unwrap()
                .filter(|e| {
                    e.as_ref()
                        .unwrap()
                        .file_name()
                        .to_string_lossy()
                        .contains("staging")
                })
                .count()
        };
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
        contactlab()
            .args([
                "solve",
                "--problem",
                "1",
                "--h",
                h,
                "--solver",
                "newton",
                "--out",
            ])
            .arg(&out)
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

#[test]
fn a_fifo_or_a_device_as_scene_file_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("scene.toml");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    for path in [fifo.as_path(), Path::new("/dev/zero")] {
        let mut cmd = contactlab();
        cmd.args(["info", "--scene"]).arg(path);
        let o = run_with_deadline(cmd, 20);
        one_line_error(&o, &path.display().to_string(), "not a regular file");
    }
}

#[test]
fn extreme_values_and_counts_get_one_line_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("inf.toml");
    std::fs::write(
        &scene,
        "name = \"x\"\n[[loads]]\nfrom = 0.0\nto = 1.0\np2 = -1e308\n[[loads]]\nfrom = 0.0\nto = 1.0\np2 = -1e308\n",
    )
    .unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec!["info".into(), "--scene".into(), scene.display().to_string()],
            "loads",
        ),
        (
            ["info", "--problem", "1", "--young", "1e-320"]
                .map(String::from)
                .to_vec(),
            "material.young",
        ),
        (
            ["info", "--problem", "1", "--young", "1e308"]
                .map(String::from)
                .to_vec(),
            "material.young",
        ),
        (
            [
                "compare",
                "--problem",
                "1",
                "--repeats",
                "18446744073709551615",
            ]
            .map(String::from)
            .to_vec(),
            "--runs",
        ),
        (
            [
                "bench",
                "--quick",
                "--runs",
                "0",
                "--out",
                "/tmp/contactlab-never-written",
            ]
            .map(String::from)
            .to_vec(),
            "--runs",
        ),
        (
            [
                "solve",
                "--problem",
                "1",
                "--relaxation-smoothing",
                "-1e-10",
            ]
            .map(String::from)
            .to_vec(),
            "relaxation.smoothing",
        ),
        (["solve"].map(String::from).to_vec(), "--problem N"),
        // A sweep that plans nothing says why instead of writing an empty
        // study.
        (
            [
                "sweep",
                "--solvers",
                "newton-coulomb",
                "--no-work-precision",
                "--out",
                "/tmp/contactlab-never-written",
            ]
            .map(String::from)
            .to_vec(),
            "plans no trials",
        ),
    ];
    for (args, expected) in cases {
        let o = contactlab().args(&args).output().unwrap();
        one_line_error(&o, &args.join(" "), expected);
    }
    let o = contactlab().args(["solve"]).output().unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("--scene FILE"));
}

#[test]
fn a_huge_load_is_solved_not_called_unbounded() {
    // The problem written in its own scales: −60e9 is problem 1 in other units.
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("big.toml");
    std::fs::write(
        &scene,
        "name = \"big\"\n[[loads]]\nfrom = 0.0\nto = \"1/3\"\np2 = -60e9\n",
    )
    .unwrap();
    let o = contactlab()
        .args(["solve", "--h", "1/16", "--solver", "clarabel", "--scene"])
        .arg(&scene)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.contains("status              converged") && stdout.contains("12.50% of Γ_K"),
        "{stdout}"
    );
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

/// The commit recorded is the one the binary was built from, not the HEAD
/// of whatever repository the user runs it in.
#[test]
fn provenance_is_the_binarys_commit_wherever_it_runs() {
    let dir = tempfile::tempdir().unwrap();
    let git = |args: &[&str]| {
        Command::new("git")
            .args(args)
            .current_dir(dir.path())
            .env("GIT_AUTHOR_NAME", "x")
            .env("GIT_AUTHOR_EMAIL", "x@x")
            .env("GIT_COMMITTER_NAME", "x")
            .env("GIT_COMMITTER_EMAIL", "x@x")
            .output()
            .unwrap()
    };
    git(&["init", "-q"]);
    std::fs::write(dir.path().join("a"), b"a").unwrap();
    git(&["add", "a"]);
    git(&["commit", "-qm", "other"]);
    let other = String::from_utf8_lossy(&git(&["rev-parse", "HEAD"]).stdout)
        .trim()
        .to_string();
    let o = contactlab()
        .current_dir(dir.path())
        .args(SOLVE)
        .args(["--out", "run"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("run/summary.json")).unwrap(),
    )
    .unwrap();
    let recorded = summary["git_commit"].as_str().unwrap();
    assert_eq!(recorded, contactlab::io::manifest::git_commit());
    assert_ne!(recorded, other);
}
