//! `reproduce --resume`: an interrupted run keeps the studies it finished
//! in `DIR.partial` and a later run continues it, refused when it would
//! mix two builds' or two settings' trials; a second run into the same
//! folder at once is refused.

mod common;

use std::io::{BufRead, BufReader};
use std::process::Stdio;

use common::{contactlab, one_line_error};

#[test]
#[ignore = "heavy (a smoke run and a half: 60-90 s): `cargo test --release -- --ignored` runs it, and CI does"]
fn an_interrupted_reproduce_resumes_where_it_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("q");
    let partial = dir.path().join("q.partial");
    let mut child = contactlab()
        .args(["reproduce", "--quick", "--out"])
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Read the log until the second study is done, then interrupt.
    let mut reader = BufReader::new(child.stderr.take().unwrap());
    let log = read_until(&mut reader, "table1 done in");
    // Meanwhile a second run into the same folder is refused, not mixed in.
    let second = contactlab()
        .args(["reproduce", "--quick", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    one_line_error(&second, "a second run at once", "another run is writing");
    interrupt(&child);
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut reader, &mut rest).unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{log}{rest}");
    assert!(rest.contains("--resume"), "{rest}");
    assert!(!out.exists(), "an interrupted run was put in place");
    let compared = std::fs::read(partial.join("compare.csv")).expect("compare.csv kept");
    let table1 = std::fs::read(partial.join("table1.csv")).expect("table1.csv kept");

    // Another choice of settings would mix two runs: refused, kept.
    let o = contactlab()
        .args(["reproduce", "--quick", "--resume", "--certify-tol", "1e-7"])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    one_line_error(&o, "--resume with other settings", "other settings");
    assert!(partial.join("compare.csv").is_file());

    // Resumed: the two studies are kept (their files to the byte), the
    // others run, and the run is put in place whole.
    let o = contactlab()
        .args(["reproduce", "--quick", "--resume", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{log}");
    assert!(
        log.contains("table1 kept from the interrupted run"),
        "{log}"
    );
    assert!(
        log.contains("compare kept from the interrupted run"),
        "{log}"
    );
    assert!(log.contains("sweep done in"), "{log}");
    assert!(!partial.exists(), "the partial folder was left behind");
    assert!(!out.join(".resume").exists(), "the checkpoint was left in");
    assert_eq!(std::fs::read(out.join("compare.csv")).unwrap(), compared);
    assert_eq!(std::fs::read(out.join("table1.csv")).unwrap(), table1);
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("manifest.json")).unwrap()).unwrap();
    let resumed = manifest["run"]["resumed"].as_object().unwrap();
    let names: Vec<&str> = resumed.keys().map(String::as_str).collect();
    assert_eq!(names, ["compare", "table1"], "{resumed:?}");
    // Every study of the run, once.
    let planned = contactlab::study::reproduce::studies(
        &contactlab::study::reproduce::ReproduceSpec::quick(),
        &contactlab::settings::Settings::default(),
    )
    .len();
    assert_eq!(
        manifest["run"]["study_seconds"].as_object().unwrap().len(),
        planned
    );
    // The README says so, and lists every file of the run, both
    // processes' (besides charts and profiles, listed by pattern).
    let readme = std::fs::read_to_string(out.join("README.md")).unwrap();
    assert!(
        readme.contains("`--resume`: `compare`, `table1` ran in an earlier process"),
        "{}",
        &readme[..800.min(readme.len())]
    );
    let listed = common::readme_lists_every_file(&out);
    assert!(listed.contains("compare.csv") && listed.contains("stability.csv"));

    // An unreadable checkpoint is refused with --resume, and without it
    // the partial folder is started anew (what it held is gone).
    let fresh = dir.path().join("fresh");
    let kept = dir.path().join("fresh.partial");
    std::fs::create_dir_all(kept.join(".resume")).unwrap();
    std::fs::write(kept.join(".contactlab-run"), "written by contactlab\n").unwrap();
    std::fs::write(kept.join(".resume/run.json"), "not a checkpoint").unwrap();
    std::fs::write(kept.join("stale.csv"), "from another run").unwrap();
    let o = contactlab()
        .args(["reproduce", "--quick", "--resume", "--out"])
        .arg(&fresh)
        .output()
        .unwrap();
    one_line_error(&o, "--resume from garbage", "unreadable checkpoint");
    // Started anew: interrupted once its second study is done (the rest
    // of a run is what the first half of this test checked), the stale
    // file is gone and the checkpoint is this run's.
    let mut child = contactlab()
        .args(["reproduce", "--quick", "--out"])
        .arg(&fresh)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut reader = BufReader::new(child.stderr.take().unwrap());
    let log = read_until(&mut reader, "table1 done in");
    assert!(log.contains("started anew"), "{log}");
    interrupt(&child);
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut reader, &mut rest).unwrap();
    assert_eq!(child.wait().unwrap().code(), Some(130), "{log}{rest}");
    assert!(!kept.join("stale.csv").exists(), "a stale file was kept");
    assert!(!fresh.exists(), "an interrupted run was put in place");
    let checkpoint = std::fs::read_to_string(kept.join(".resume/run.json")).unwrap();
    assert!(
        serde_json::from_str::<serde_json::Value>(&checkpoint).is_ok(),
        "{checkpoint}"
    );
    assert!(kept.join("compare.csv").is_file());
}

/// The log of `reader` up to and including the first line holding
/// `marker` (a failure if the run ends first).
fn read_until(reader: &mut impl BufRead, marker: &str) -> String {
    let mut log = String::new();
    let mut line = Vec::new();
    loop {
        line.clear();
        let n = reader.read_until(b'\n', &mut line).unwrap();
        assert!(n > 0, "the run ended before {marker:?}:\n{log}");
        log += &String::from_utf8_lossy(&line);
        if log.contains(marker) {
            return log;
        }
    }
}

/// Ctrl-C to `child`.
fn interrupt(child: &std::process::Child) {
    // SAFETY: kill with a valid pid of our own child and a valid signal.
    assert_eq!(
        unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) },
        0
    );
}

/// A `.partial` folder contactlab did not write is never removed.
#[test]
fn a_foreign_partial_folder_is_refused_and_left_alone() {
    let dir = tempfile::tempdir().unwrap();
    let theirs = dir.path().join("mine.partial");
    std::fs::create_dir(&theirs).unwrap();
    std::fs::write(theirs.join("notes.txt"), "a user's notes").unwrap();
    let o = contactlab()
        .args(["reproduce", "--quick", "--out"])
        .arg(dir.path().join("mine"))
        .output()
        .unwrap();
    one_line_error(&o, "a foreign .partial", "contactlab did not write it");
    assert_eq!(
        std::fs::read_to_string(theirs.join("notes.txt")).unwrap(),
        "a user's notes"
    );
}
