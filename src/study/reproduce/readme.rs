//! The README of a results folder: a template (`readme.md`) filled with
//! findings computed from the trials, never typed in. Each finding is a
//! threshold crossed, a ratio or a best value; explanations appear only
//! beside the data that support them.

use anyhow::Result;
use contactlab_solvers::registry::{self, Role};
use serde::Serialize;

use crate::io::manifest::Manifest;
use crate::study::class::WRONG_PRESSURE;
use crate::study::lab::Section;
use crate::study::reproduce::ReproduceSpec;

const TEMPLATE: &str = include_str!("readme.md");

#[derive(Serialize)]
struct SolverInfo {
    name: &'static str,
    role: &'static str,
    about: &'static str,
    source: &'static str,
}

#[derive(Serialize)]
struct Context {
    quick: bool,
    long: bool,
    seconds: String,
    /// The studies an earlier, interrupted process ran (`--resume`).
    resumed: String,
    cpu: String,
    cores: usize,
    date: String,
    commit: String,
    dirty: bool,
    rustc: String,
    h: String,
    tol: String,
    wrong_pressure: String,
    solvers: Vec<SolverInfo>,
    /// Each study's section, in the order they ran.
    sections: Vec<String>,
    files: Vec<String>,
}

/// What the README says of the run as a whole.
pub struct RunFacts<'a> {
    pub files: &'a [String],
    /// Wall seconds of the whole run (its earlier processes included).
    pub seconds: f64,
    /// The studies run by an earlier, interrupted process.
    pub resumed: &'a [String],
    /// The certificate's tolerance of the run.
    pub tolerance: f64,
}

/// Renders the README: what the run was, how to read it, every study's
/// section in the order they ran, and the files.
///
/// `files` are the paths the run wrote (its artifacts).
pub fn render(
    spec: &ReproduceSpec,
    m: &Manifest,
    sections: &[Section],
    run: &RunFacts,
) -> Result<String> {
    let context = Context {
        quick: spec.quick,
        long: spec.long,
        seconds: format!("{:.0}", run.seconds),
        resumed: run
            .resumed
            .iter()
            .map(|s| format!("`{s}`"))
            .collect::<Vec<_>>()
            .join(", "),
        cpu: m.cpu.clone(),
        cores: m.cores,
        date: m.date.clone(),
        commit: m.git_commit.clone(),
        dirty: m.git_dirty == Some(true),
        rustc: m.rustc.to_string(),
        h: spec.h.to_string(),
        tol: format!("{:e}", run.tolerance),
        wrong_pressure: format!("{WRONG_PRESSURE:e}"),
        solvers: registry::solvers()
            .iter()
            .map(|e| SolverInfo {
                name: e.name,
                role: match e.role {
                    Role::PapersMethod => "the paper's method",
                    Role::Oracle => "the conic oracle",
                    Role::Other => "",
                },
                about: e.about,
                source: e.source,
            })
            .collect(),
        sections: sections.iter().map(|s| s.markdown.clone()).collect(),
        files: run
            .files
            .iter()
            .filter(|f| !f.starts_with("charts/") && !f.starts_with("profiles/"))
            .cloned()
            .collect(),
    };
    let mut env = minijinja::Environment::new();
    env.add_template("readme", TEMPLATE)?;
    Ok(env.get_template("readme")?.render(context)?)
}
