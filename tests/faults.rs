//! Faults seen when the tool was tried as a new user would: a closed or full
//! standard output, a FIFO or a device as a scene file, unbounded counts,
//! and a certificate that fails (output folders: `output_folders.rs`). Each
//! must end with one line on stderr and a non-zero exit, never a panic or a
//! hang.

use std::path::Path;
mod common;

use std::process::{Command, Stdio};

use common::{contactlab, one_line_error, run_with_deadline, solve_into};

const SOLVE: [&str; 5] = ["solve", "--problem", "1", "--h", "1/8"];

#[test]
fn a_failing_certificate_turns_convergence_into_inaccurate_and_a_nonzero_exit() {
    let o = contactlab()
        .args(SOLVE)
        .args(["--solver", "clarabel", "--set", "clarabel.tol=1"])
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
        let o = solve_into("1/8", "newton", &out)
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
                "--runs",
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
                "--set",
                "relaxation.smoothing=-1e-10",
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
