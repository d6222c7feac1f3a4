//! `contactlab reproduce`: every study on the paper's problems into one
//! output folder, as a list of studies run in one lab: Table 1 at the
//! paper's settings, the comparison of every solver (and the paper's method
//! at the paper's settings) against the earned reference with the
//! contact-zone profiles, a sweep, the stability map, the speed
//! measurements, the benchmark, the discretization error; then a manifest
//! and a README that is a view of the findings ([`readme`]). The files it
//! writes are the studies' artifacts.

pub mod intents;
pub mod readme;
mod separation_text;
mod sweep_text;

use anyhow::Result;
use serde::Serialize;

use contactlab_solvers::registry;

use crate::coulomb::continuation::Schedule;
use crate::mechanics::material::PlaneModel;
use crate::mechanics::mesh_size::MeshSize;
use crate::settings::Settings;
use crate::study::bench::BenchSpec;
use crate::study::bench::goals::Bench;
use crate::study::benchmark::{Benchmark, BenchmarkSpec};
use crate::study::compare::paper::PaperCompare;
use crate::study::discretization_error::{ErrorSpec, Errors};
use crate::study::lab::{Artifact, Findings, Lab, Study};
use crate::study::stability::{Stability, StabilitySpec};
use crate::study::sweep::{Sweep, SweepSpec};
use crate::study::table1::Table1;

/// What `reproduce` runs.
#[derive(Clone, Serialize)]
pub struct ReproduceSpec {
    pub quick: bool,
    /// Finest mesh of the problems (continuation from 1/8).
    pub h: MeshSize,
    pub problems: Vec<u32>,
    /// Timed runs per comparison trial, after the first.
    pub repeats: usize,
    #[serde(skip)]
    pub sweep: SweepSpec,
    pub sweep_h: MeshSize,
    pub stability: StabilitySpec,
    pub bench: BenchSpec,
    /// The benchmark over the problem collection (its solvers: all).
    #[serde(skip)]
    pub benchmark: BenchmarkSpec,
    /// The discretization-error study.
    pub errors: ErrorSpec,
}

impl ReproduceSpec {
    /// The full run.
    pub fn full() -> Self {
        let sweep_h = MeshSize::from_level(5).expect("in range");
        Self {
            quick: false,
            h: MeshSize::from_level(6).expect("in range"),
            problems: vec![1, 2, 3],
            repeats: 2,
            sweep: SweepSpec {
                meshes: vec![sweep_h],
                ..SweepSpec::default()
            },
            sweep_h,
            stability: StabilitySpec::standard(),
            bench: BenchSpec::standard(),
            benchmark: BenchmarkSpec::new(false, registry::solvers()),
            errors: ErrorSpec::standard(),
        }
    }

    /// A small run for tests (seconds).
    pub fn quick() -> Self {
        let h = MeshSize::from_level(4).expect("in range");
        Self {
            quick: true,
            h,
            problems: vec![1, 2, 3],
            repeats: 0,
            sweep: SweepSpec {
                meshes: vec![h],
                quick: true,
                repeats: 0,
                work_scale: 0.2,
                ..SweepSpec::default()
            },
            sweep_h: h,
            stability: StabilitySpec::quick(),
            bench: BenchSpec::quick(),
            benchmark: BenchmarkSpec::new(true, registry::solvers()),
            errors: ErrorSpec::quick(),
        }
    }
}

/// The studies of a run, in order: each runs in the one lab (one runner,
/// one reference cache) and gives its artifacts.
pub fn studies(spec: &ReproduceSpec, settings: &Settings) -> Vec<Box<dyn Study>> {
    let mut paper = Settings::paper();
    paper.certificate = settings.certificate;
    vec![
        Box::new(Table1 {
            problems: vec![1, 2, 3],
            schedules: vec![Schedule::Revisit, Schedule::FinestOnly],
            h: spec.h,
            plane: PlaneModel::Strain,
            settings: paper,
        }),
        Box::new(PaperCompare {
            h: spec.h,
            problems: spec.problems.clone(),
            repeats: spec.repeats,
        }),
        Box::new(Sweep {
            spec: spec.sweep.clone(),
            extra: Vec::new(),
            references_file: "sweep_references.csv",
        }),
        Box::new(Stability {
            spec: spec.stability.clone(),
            references_file: Some("stability_references.csv"),
        }),
        Box::new(Bench {
            spec: spec.bench.clone(),
        }),
        Box::new(Benchmark {
            spec: spec.benchmark.clone(),
        }),
        Box::new(Errors {
            spec: spec.errors.clone(),
        }),
    ]
}

/// Runs every study of `spec` in `lab`; gives their findings and their
/// artifacts (the charts, the manifest and the README are the caller's).
pub fn run(spec: &ReproduceSpec, lab: &mut Lab) -> Result<(Findings, Vec<Artifact>)> {
    let mut findings = Findings::default();
    let mut artifacts = Vec::new();
    for study in studies(spec, &lab.settings) {
        artifacts.extend(lab.run(study.as_ref(), &mut findings)?);
    }
    Ok((findings, artifacts))
}
