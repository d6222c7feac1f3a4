//! The one shape of every study: a study plans trials, has them measured
//! in a [`Lab`] (the one runner, with the one reference cache), and turns
//! them into typed findings, [`Artifact`]s (tables, charts) and its
//! [`Section`] of a run's README. A command runs one study; `reproduce`
//! runs a list of them in one lab, and the files it writes are the
//! artifacts' paths. This module knows no study: studies depend on it,
//! never the other way.

use std::path::Path;

use anyhow::{Result, bail};
use serde::{Deserialize, Serialize};

use crate::io::charts::{Chart, Panels};
use crate::io::csv::{records, to_csv};
use crate::io::heatmap::HeatMap;
use crate::io::output::write_atomic;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::reference::{Candidate, Reference, References};
use crate::study::runner::{Keep, Measured, measure_all};
use crate::study::trial::TrialSpec;

/// A file a study gives: its path in the output folder and its content.
pub struct Artifact {
    pub path: String,
    pub content: Content,
    /// A table's rows as typed records (a JSON array of objects in column
    /// order, numbers as numbers: [`crate::io::csv::records`]), the data its CSV file
    /// holds as text: what Python's studies return, so that no caller
    /// parses a file back.
    pub records: Option<String>,
}

/// What an artifact holds: bytes as written, or a chart or heat map drawn
/// when written.
pub enum Content {
    Bytes(Vec<u8>),
    Chart(Chart),
    HeatMap(HeatMap),
    Panels(Panels),
}

impl Artifact {
    /// A CSV table of `rows` (with `header` when there are none).
    pub fn csv<T: Serialize>(path: &str, rows: &[T], header: &[&str]) -> Result<Self> {
        Ok(Self::bytes(path, to_csv(rows, header)?).with_records(records(rows)?))
    }

    pub fn bytes(path: &str, bytes: Vec<u8>) -> Self {
        Self::of(path, Content::Bytes(bytes))
    }

    fn of(path: &str, content: Content) -> Self {
        Self {
            path: path.to_string(),
            content,
            records: None,
        }
    }

    /// This file with its rows as typed records (see [`Artifact::records`]).
    pub fn with_records(mut self, records: String) -> Self {
        self.records = Some(records);
        self
    }

    pub fn text(path: &str, text: &str) -> Self {
        Self::bytes(path, text.as_bytes().to_vec())
    }

    /// A chart, drawn as `charts/NAME.svg`.
    pub fn chart(name: &str, chart: Chart) -> Self {
        Self::of(&format!("charts/{name}.svg"), Content::Chart(chart))
    }

    /// A heat map, drawn as `charts/NAME.svg`.
    pub fn heat_map(name: &str, map: HeatMap) -> Self {
        Self::of(&format!("charts/{name}.svg"), Content::HeatMap(map))
    }

    /// Small multiples, drawn as `charts/NAME.svg`.
    pub fn panels(name: &str, panels: Panels) -> Self {
        Self::of(&format!("charts/{name}.svg"), Content::Panels(panels))
    }

    /// Charts given as (name, chart).
    pub fn charts(charts: Vec<(String, Chart)>) -> Vec<Self> {
        charts
            .into_iter()
            .map(|(name, c)| Self::chart(&name, c))
            .collect()
    }

    /// A study's trials and their times: `STEM.csv` and `STEM_timing.csv`.
    pub fn trials(stem: &str, measured: &[Measured]) -> Result<Vec<Self>> {
        let rows: Vec<_> = measured.iter().map(|m| m.trial.row()).collect();
        let timing: Vec<_> = measured.iter().map(|m| &m.timing).collect();
        Ok(vec![
            Self::csv(&format!("{stem}.csv"), &rows, &[])?,
            Self::csv(&format!("{stem}_timing.csv"), &timing, &[])?,
        ])
    }

    /// Whether it is a chart (its name without folder and extension then).
    pub fn chart_name(&self) -> Option<&str> {
        match self.content {
            Content::Chart(_) | Content::HeatMap(_) | Content::Panels(_) => self
                .path
                .strip_prefix("charts/")
                .and_then(|p| p.strip_suffix(".svg")),
            Content::Bytes(_) => None,
        }
    }
}

impl Content {
    /// A drawing's SVG (None: bytes, written as they are).
    pub fn svg(&self) -> Option<Result<String>> {
        match self {
            Content::Bytes(_) => None,
            Content::Chart(c) => Some(c.to_svg()),
            Content::HeatMap(m) => Some(m.to_svg()),
            Content::Panels(p) => Some(p.to_svg()),
        }
    }

    /// A drawing's title (None: bytes).
    pub fn title_mut(&mut self) -> Option<&mut String> {
        match self {
            Content::Bytes(_) => None,
            Content::Chart(c) => Some(&mut c.title),
            Content::HeatMap(m) => Some(&mut m.title),
            Content::Panels(p) => Some(&mut p.title),
        }
    }
}

/// Writes every artifact into `dir` (each atomically); gives their paths.
pub fn write_artifacts(dir: &Path, artifacts: &[Artifact]) -> Result<Vec<String>> {
    for a in artifacts {
        let path = dir.join(&a.path);
        if let Content::Bytes(b) = &a.content {
            write_atomic(&path, b)?;
        }
        if let Some(svg) = a.content.svg() {
            write_atomic(&path, svg?.as_bytes())?;
        }
    }
    Ok(artifacts.iter().map(|a| a.path.clone()).collect())
}

/// What a study hands on to the studies after it, typed: a value is
/// found by its type, never by a name, and kept as JSON so that a resumed
/// run (`reproduce --resume`) hands it on from the checkpoint of a study an
/// earlier process ran.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Handoff(std::collections::BTreeMap<String, serde_json::Value>);

impl Handoff {
    fn key<T>() -> String {
        std::any::type_name::<T>().to_string()
    }

    /// Hands `value` on (replacing one of the same type).
    pub fn put<T: Serialize>(&mut self, value: &T) -> Result<()> {
        self.0
            .insert(Self::key::<T>(), serde_json::to_value(value)?);
        Ok(())
    }

    /// The value of type `T` an earlier study handed on, if any.
    pub fn get<T: serde::de::DeserializeOwned>(&self) -> Option<T> {
        self.0
            .get(&Self::key::<T>())
            .and_then(|v| serde_json::from_value(v.clone()).ok())
    }
}

/// Where a lab's progress goes: a study starts a stretch of trials (with
/// the expected relative cost of each, for an estimate of the time left,
/// and the seconds one may take at most), ticks through them, finishes.
pub trait Tracker {
    fn start(&self, what: &str, costs: Vec<f64>, cap: f64);
    fn tick(&self, trial: &TrialSpec);
    fn finish(&self);
    /// Whether the caller asked the run to stop (Python's Ctrl-C): read
    /// after each trial, so that a study stops at the next one and writes
    /// nothing.
    fn interrupted(&self) -> bool {
        false
    }
}

/// Ticks `tracker` past `trial`; an error if the run was interrupted.
pub fn ticked(tracker: &dyn Tracker, trial: &TrialSpec) -> Result<()> {
    tracker.tick(trial);
    if tracker.interrupted() {
        bail!(
            "interrupted: the study stopped after {} and wrote nothing",
            trial.solver.name
        );
    }
    Ok(())
}

/// A tracker that tells nobody.
pub struct Quiet;

impl Tracker for Quiet {
    fn start(&self, _: &str, _: Vec<f64>, _: f64) {}
    fn tick(&self, _: &TrialSpec) {}
    fn finish(&self) {}
}

/// Where studies run: the settings, the one reference cache, and where
/// logs and progress go.
pub struct Lab<'a> {
    pub settings: Settings,
    pub references: References,
    /// What the studies run so far handed on ([`Handoff`]).
    pub handoff: Handoff,
    /// The keys of the references the current study asked for, in order.
    asked: Vec<String>,
    /// The current study's name (for progress).
    study: &'static str,
    log: &'a dyn Fn(&str),
    tracker: &'a dyn Tracker,
}

impl<'a> Lab<'a> {
    pub fn new(settings: Settings, log: &'a dyn Fn(&str), tracker: &'a dyn Tracker) -> Self {
        Self {
            settings,
            references: References::default(),
            handoff: Handoff::default(),
            asked: Vec::new(),
            study: "",
            log,
            tracker,
        }
    }

    /// Starts a stretch of `costs.len()` trials (see [`Tracker::start`]).
    pub fn start(&self, what: &str, costs: Vec<f64>, cap: f64) {
        self.tracker.start(what, costs, cap);
    }

    /// Ends the stretch started last.
    pub fn finish(&self) {
        self.tracker.finish();
    }

    /// A line for the log.
    pub fn log(&self, line: &str) {
        (self.log)(line)
    }

    /// The log (to call while the lab is borrowed elsewhere).
    pub fn logger(&self) -> &'a dyn Fn(&str) {
        self.log
    }

    /// Where progress goes (to call while the lab is borrowed elsewhere).
    pub fn tracker(&self) -> &'a dyn Tracker {
        self.tracker
    }

    /// The study running now (what progress is reported under).
    pub fn current(&self) -> &'static str {
        self.study
    }

    /// Starts study `name`: the references it asks for are listed anew.
    pub fn begin(&mut self, name: &'static str) {
        self.asked.clear();
        self.study = name;
    }

    /// Runs `study` in this lab (see [`Study::run`]).
    pub fn run<S: Study + ?Sized>(&mut self, study: &S) -> Result<Ran<S::Findings>> {
        self.begin(study.name());
        study.run(self)
    }

    /// Records that the current study asked for `scene`'s reference (its
    /// references file lists the candidates of each, in the order asked):
    /// for work that earned it elsewhere, on both cores
    /// (the `cores` module).
    pub fn ask(&mut self, scene: &Scene) -> Result<()> {
        let key = References::key(scene)?;
        if !self.asked.contains(&key) {
            self.asked.push(key);
        }
        Ok(())
    }

    /// Measures trials in order, each against the reference of its scene
    /// and mesh (earned on first use, kept for every later study).
    pub fn measure(&mut self, specs: &[TrialSpec], keep: Keep) -> Result<Vec<Measured>> {
        for s in specs.iter().filter(|s| s.wants_reference()) {
            self.ask(&s.scene)?;
            // Earned before the count starts, so that its minutes are not
            // the first trial's: a tuning map once predicted 6852 s left at
            // its point 1 of 20, and ended 38 s later.
            self.references.get(&s.scene, &s.settings)?;
        }
        let tracker = self.tracker;
        tracker.start(self.study, vec![1.0; specs.len()], f64::INFINITY);
        let measured = measure_all(specs, &mut self.references, keep, &|t| ticked(tracker, t));
        tracker.finish();
        measured
    }

    /// Measures trials that need no reference (counts, not differences).
    pub fn measure_alone(&mut self, specs: &[TrialSpec], keep: Keep) -> Result<Vec<Measured>> {
        let tracker = self.tracker;
        tracker.start(self.study, vec![1.0; specs.len()], f64::INFINITY);
        let measured = measure_all(specs, &mut References::none(), keep, &|t| {
            ticked(tracker, t)
        });
        tracker.finish();
        measured
    }

    /// Takes `entry`'s answer as the reference of every scene (the user
    /// named it), instead of earning it among the exact solvers.
    pub fn name_reference(&mut self, entry: &'static contactlab_solvers::registry::Entry) {
        self.references.named = Some(entry);
    }

    /// The reference of `scene`, earned on first use.
    pub fn reference(&mut self, scene: &Scene, settings: &Settings) -> Result<Option<&Reference>> {
        self.ask(scene)?;
        self.references.get(scene, settings)
    }

    /// The keys of the references the current study asked for, in order.
    pub fn asked(&self) -> &[String] {
        &self.asked
    }

    /// The candidates of the references the current study asked for, in
    /// the order it asked: its references file.
    pub fn candidates(&self) -> Vec<Candidate> {
        self.references.candidates_for(&self.asked)
    }
}

/// What a study's run gives: its typed findings (what its command prints
/// and its README section is made of) and its files.
pub struct Ran<F> {
    pub findings: F,
    pub artifacts: Vec<Artifact>,
}

/// How long a run of studies is meant to be: a smoke run (`--quick`), the
/// default run, or the long one (`--long`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunLength {
    Quick,
    Standard,
    Long,
}

/// A study's part of a run's README: Markdown under its own heading,
/// computed from its findings as soon as it has run and saved with the
/// run's checkpoint, so that a resumed run renders the README without the
/// trials of the studies an earlier process ran.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Section {
    pub markdown: String,
}

/// A chart of a README section: its file stem and what it is for, in one
/// sentence (its intent), written under it.
pub fn chart_markdown(name: &str, intent: &str) -> String {
    format!("![{name}](charts/{name}.svg)\n\n*{intent}*\n\n")
}

/// A study: the unit of extension. It owns everything a study has: its
/// name, its time estimate, its run (a plan of trials measured in a
/// [`Lab`]), its typed findings, its files and charts, and its section of
/// a run's README. Adding one to `contactlab reproduce` is one line in
/// `reproduce::studies`; `tests/toy_study.rs` adds one in
/// a test.
pub trait Study {
    /// What it found, typed.
    type Findings;

    /// Its name in logs, in the manifest and in the checkpoint.
    fn name(&self) -> &'static str;

    /// Seconds it takes on the 2-core machine of `results/` in a run of
    /// `length` (the manifest's `study_seconds` records the measured ones
    /// to refresh these): what a run states as it starts.
    fn estimated_seconds(&self, length: RunLength) -> f64;

    /// Plans and measures its trials in `lab`; gives its findings and files.
    fn run(&self, lab: &mut Lab) -> Result<Ran<Self::Findings>>;

    /// Its section of a run's README, from its findings, the references it
    /// asked `lab` for, and the names of the charts it wrote (as the files
    /// `charts/NAME.svg`).
    fn section(&self, findings: &Self::Findings, lab: &Lab, charts: &[String]) -> Result<Section>;
}

/// A study with its findings' type erased, as a run of several holds it:
/// it runs and gives its files and its README section.
pub trait Planned {
    fn name(&self) -> &'static str;
    fn estimated_seconds(&self, length: RunLength) -> f64;
    /// Runs in `lab`; gives its files and its README section.
    fn run_for_report(&self, lab: &mut Lab) -> Result<(Vec<Artifact>, Section)>;
}

impl<S: Study> Planned for S {
    fn name(&self) -> &'static str {
        Study::name(self)
    }

    fn estimated_seconds(&self, length: RunLength) -> f64 {
        Study::estimated_seconds(self, length)
    }

    fn run_for_report(&self, lab: &mut Lab) -> Result<(Vec<Artifact>, Section)> {
        let ran = lab.run(self)?;
        let charts: Vec<String> = ran
            .artifacts
            .iter()
            .filter_map(|a| a.chart_name().map(str::to_string))
            .collect();
        let section = self.section(&ran.findings, lab, &charts)?;
        Ok((ran.artifacts, section))
    }
}
