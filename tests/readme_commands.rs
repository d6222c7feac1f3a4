//! The README's shell blocks as a new user meets them: every `contactlab`
//! command line in them parses as written (a renamed flag or a changed
//! list syntax fails here), and the Quick start's commands run as written
//! and do what their comments say. (The main job, the fuzzers and the
//! cluster script take longer than a test; they are parsed. The Python
//! blocks run in `python/tests/test_readme.py`.)

mod common;

use clap::Parser;
use contactlab::cli::Cli;

/// The lines of every ```sh block, comments dropped, `\` continuations
/// joined.
fn shell_lines(readme: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut inside = false;
    let mut pending = String::new();
    for line in readme.lines() {
        if line.starts_with("```") {
            inside = line.trim() == "```sh";
            continue;
        }
        if !inside {
            continue;
        }
        let code = match line.find(" #") {
            Some(k) => &line[..k],
            None => line,
        };
        if code.trim_start().starts_with('#') {
            continue;
        }
        pending += code.trim_end().trim_end_matches('\\');
        pending.push(' ');
        if !code.trim_end().ends_with('\\') {
            if !pending.trim().is_empty() {
                out.push(pending.trim().to_string());
            }
            pending.clear();
        }
    }
    out
}

/// The arguments of a line that runs contactlab, as a shell would split
/// them (the README quotes nothing), with the cluster script's variables
/// given values.
fn contactlab_args(line: &str) -> Option<Vec<String>> {
    let line = line
        .replace("${SLURM_ARRAY_TASK_ID}", "1")
        .replace("\"", "");
    let line = line
        .split_once("--wrap ")
        .map_or(line.as_str(), |(_, w)| w)
        .to_string();
    let words: Vec<&str> = line.split_whitespace().collect();
    let start = words
        .iter()
        .position(|w| *w == "contactlab" || w.ends_with("/contactlab") || *w == "--")?;
    if words[start] == "--" && !line.contains("cargo run") {
        return None;
    }
    let mut args = vec!["contactlab".to_string()];
    args.extend(words[start + 1..].iter().map(|w| w.to_string()));
    Some(args)
}

#[test]
fn every_command_line_of_the_readme_parses() {
    let readme = include_str!("../README.md");
    let lines = shell_lines(readme);
    let commands: Vec<Vec<String>> = lines.iter().filter_map(|l| contactlab_args(l)).collect();
    assert!(commands.len() >= 5, "{lines:#?}");
    for args in &commands {
        if let Err(e) = Cli::try_parse_from(args) {
            panic!("README: `{}` does not parse:\n{e}", args.join(" "));
        }
    }
}

/// The Quick start: the solve prints a certified status and the contact
/// zone, the comparison writes its folder.
#[test]
fn the_quick_start_runs_as_written() {
    let readme = include_str!("../README.md");
    let quick = readme
        .split("## Quick start")
        .nth(1)
        .and_then(|s| s.split("\n## ").next())
        .expect("a Quick start section");
    let commands: Vec<Vec<String>> = shell_lines(quick)
        .iter()
        .filter_map(|l| contactlab_args(l))
        .collect();
    assert_eq!(commands.len(), 2, "{commands:?}");
    let dir = tempfile::tempdir().unwrap();
    for args in &commands {
        let mut cmd = common::contactlab();
        cmd.args(&args[1..]).current_dir(dir.path());
        let o = common::run_with_deadline(cmd, 300);
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        if args[1] == "solve" {
            assert!(stdout.contains("certified at"), "{stdout}");
            assert!(stdout.contains("separated"), "{stdout}");
        }
        if let Some(k) = args.iter().position(|a| a == "--out") {
            let out = dir.path().join(&args[k + 1]);
            assert!(out.join("compare.csv").is_file(), "{}", out.display());
        }
    }
}

/// The README's example of a tuning map (an inline `--grid … --grid …`)
/// runs as written at the default law, on a coarse mesh: it was refused
/// ("relaxation does not solve the coulomb law") while `reproduce` mapped
/// the paper's method at that law by the friction fixed point.
#[test]
fn the_readmes_tuning_map_example_runs_at_the_default_law() {
    let readme = include_str!("../README.md");
    let examples: Vec<&str> = readme
        .split('`')
        .skip(1)
        .step_by(2)
        .filter(|span| span.starts_with("--grid ") && !span.contains("PATH"))
        .collect();
    assert!(!examples.is_empty(), "no --grid example in the README");
    let dir = tempfile::tempdir().unwrap();
    for (k, example) in examples.iter().enumerate() {
        let mut cmd = common::contactlab();
        cmd.args(["sweep", "--problem", "1", "--h", "1/8", "--runs", "0"])
            .args(example.split_whitespace())
            .arg("--out")
            .arg(dir.path().join(format!("map{k}")));
        let o = common::run_with_deadline(cmd, 300);
        assert!(
            o.status.success(),
            "README example `{example}`: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}
