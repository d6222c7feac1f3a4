//! The benchmark over the problem collection ([`collection`]), in the manner
//! of the field's solver benchmarks (Dolan & Moré 2002, performance
//! profiles; Mittelmann's and qpbenchmark's shifted geometric means; Acary,
//! Brémond & Huber 2018 on FCLIB): every solver on every instance at each
//! target accuracy, one Coulomb solve with a time limit.
//!
//! A target accuracy τ is read in the certificate's measure: the solver's
//! accuracy knob and every ε (the fixed point's, and a solver's own) are set
//! to [`SAFETY`]·τ (a stopping test measures something else than the
//! certificate's largest violation: one rule for every solver), and the run
//! succeeds only if its answer passes the certificate at tolerance τ. A solver that claims success on an answer that fails it
//! counts as a failure, and is listed as such ([`views`]).
//!
//! The collection is embarrassingly parallel: a shard K/N runs every N-th
//! instance from the K-th, and [`views`] reads any set of shards' rows.

pub mod collection;
pub mod merge;
pub mod views;

use anyhow::Result;
use contactlab_solvers::registry::Entry;
use contactlab_solvers::{Law, Status};
use serde::{Deserialize, Serialize};

use crate::io::csv::{fixed, fixed_or_nan};
use crate::mechanics::dofs::{DofExpansion, DofMap};
use crate::mechanics::mesh::Mesh;
use crate::mechanics::mesh_size::MeshSize;
use crate::settings::Settings;
use crate::study::lab::{Artifact, Lab, Ran, RunLength, Section, Study};
use crate::study::runner::{Keep, Measured, measure};
use crate::study::template;
use crate::study::trial::{Setting, TrialSpec};

pub use collection::{Instance, collection};

/// The study's name in trial records.
pub const STUDY: &str = "benchmark";

/// Which part of the collection a run covers: every `of`-th instance from
/// the `index`-th (1-based, as `--shard K/N` is written).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: usize,
    pub of: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("--shard '{s}': write it K/N with 1 ≤ K ≤ N, e.g. 2/8");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, of): (usize, usize) = (
            k.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if index == 0 || of == 0 || index > of {
            return Err(bad());
        }
        Ok(Self { index, of })
    }
}

impl Shard {
    pub const WHOLE: Shard = Shard { index: 1, of: 1 };

    /// Whether instance `i` (0-based, in collection order) is in the shard.
    pub fn contains(&self, i: usize) -> bool {
        i % self.of == self.index - 1
    }
}

/// What a benchmark run covers.
#[derive(Clone)]
pub struct BenchmarkSpec {
    pub quick: bool,
    /// Only the collection's core ([`collection::in_core`]): every instance
    /// up to h = 1/32, the collection of a default `reproduce`, which must
    /// finish in minutes.
    pub core: bool,
    /// Target accuracies, in the certificate's measure.
    pub targets: Vec<f64>,
    /// Wall-clock limit per run, seconds.
    pub time_limit: f64,
    pub shard: Shard,
    pub solvers: Vec<&'static Entry>,
    /// The instances to run instead of the collection (the problems a
    /// Python benchmark is given); `core` and `quick` then choose nothing.
    pub instances: Option<Vec<Instance>>,
}

impl BenchmarkSpec {
    /// The documented run: targets 1e-4 and 1e-8, 20 s per run (quick: 5 s).
    pub fn new(quick: bool, solvers: Vec<&'static Entry>) -> Self {
        Self {
            quick,
            core: false,
            targets: vec![1e-4, 1e-8],
            time_limit: if quick { 5.0 } else { 20.0 },
            shard: Shard::WHOLE,
            solvers,
            instances: None,
        }
    }
}

/// One run of the benchmark: the tidy row the tables are views of.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BenchmarkRow {
    pub instance: String,
    pub family: String,
    pub h: String,
    pub unknowns: usize,
    pub friction_coefficient: f64,
    pub solver: String,
    /// The target accuracy (certificate tolerance, accuracy knob, ε).
    #[serde(serialize_with = "fixed")]
    pub target: f64,
    /// The certified status at that tolerance.
    pub status: String,
    /// The solver's own claim.
    pub solver_status: String,
    pub success: bool,
    /// Claimed convergence but failed the certificate at the target.
    pub claimed_but_failed: bool,
    #[serde(serialize_with = "fixed", deserialize_with = "fixed_or_nan")]
    pub certificate: f64,
    pub failing: String,
    /// Wall-clock seconds of the whole Coulomb solve (set-up included).
    #[serde(serialize_with = "fixed")]
    pub seconds: f64,
    /// The run's time limit, seconds.
    #[serde(serialize_with = "fixed")]
    pub time_limit: f64,
    pub work: usize,
    pub detail: String,
}

/// The benchmark as a study: benchmark.csv, its trials and their times,
/// and its views.
pub struct Benchmark {
    pub spec: BenchmarkSpec,
}

impl Study for Benchmark {
    /// One row per run.
    type Findings = Vec<BenchmarkRow>;

    fn name(&self) -> &'static str {
        STUDY
    }

    fn estimated_seconds(&self, length: RunLength) -> f64 {
        match length {
            RunLength::Quick => 1.3,
            RunLength::Standard => 170.0,
            RunLength::Long => 2400.0,
        }
    }

    fn section(&self, rows: &Vec<BenchmarkRow>, _: &Lab, charts: &[String]) -> Result<Section> {
        let mut ids: Vec<&str> = rows.iter().map(|r| r.instance.as_str()).collect();
        ids.sort_unstable();
        ids.dedup();
        let report = views::report(rows)?;
        let markdown = template::render(
            "benchmark",
            include_str!("../templates/benchmark.md"),
            template::facts! {
                given => self.spec.instances.is_some(),
                count => ids.len(),
                core => self.spec.core,
                report,
                charts,
            },
        )?;
        Ok(Section { markdown })
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<Vec<BenchmarkRow>>> {
        let plan = plan(&self.spec, &lab.settings)?;
        lab.log(&format!(
            "benchmark over the problem collection: {} runs",
            plan.len()
        ));
        lab.start(
            &format!("benchmark {}/{}", self.spec.shard.index, self.spec.shard.of),
            expected_costs(&plan),
            self.spec.time_limit,
        );
        let tracker = lab.tracker();
        let done = run(plan, &|t| crate::study::lab::ticked(tracker, t))?;
        lab.finish();
        let (rows, measured): (Vec<BenchmarkRow>, Vec<Measured>) = done.into_iter().unzip();
        let mut artifacts = vec![Artifact::csv("benchmark.csv", &rows, &[])?];
        artifacts.extend(Artifact::trials("benchmark_trials", &measured)?);
        artifacts.extend(views::artifacts(&rows)?);
        Ok(Ran {
            findings: rows,
            artifacts,
        })
    }
}

/// Every solver's own tolerances are this fraction of the target: measured
/// at h = 1/8 with the knob at the target itself, 29 of 72 runs at 1e-8
/// stopped with a certificate 1.5 to 30 times the target.
pub const SAFETY: f64 = 0.1;

/// The settings of a solver at target accuracy `target`.
pub fn target_settings(entry: &Entry, base: &Settings, target: f64) -> Result<Settings> {
    let mut s = base.clone();
    let own = SAFETY * target;
    s.set_epsilon(own).map_err(anyhow::Error::msg)?;
    s.set_text(
        &format!("{}.{}", entry.name, entry.accuracy.knob),
        &format!("{own:e}"),
    )
    .map_err(anyhow::Error::msg)?;
    s.certificate.tolerance = target;
    Ok(s)
}

/// The trials of a run, with each instance's family.
/// One planned run: the instance, its trial (with the time limit), the
/// target accuracy.
pub type Planned = (Instance, TrialSpec, f64);

pub fn plan(spec: &BenchmarkSpec, base: &Settings) -> Result<Vec<Planned>> {
    let mut out = Vec::new();
    let instances: Vec<_> = match &spec.instances {
        Some(given) => given.clone(),
        None => collection(spec.quick)?
            .into_iter()
            .filter(|i| !spec.core || collection::in_core(i))
            .collect(),
    };
    if spec.shard.of > instances.len() {
        anyhow::bail!(
            "--shard {}/{}: the {}collection has {} instances, so shards beyond the {}th would be empty; use at most {} shards",
            spec.shard.index,
            spec.shard.of,
            if spec.quick { "quick " } else { "" },
            instances.len(),
            instances.len(),
            instances.len()
        );
    }
    for (i, inst) in instances.into_iter().enumerate() {
        if !spec.shard.contains(i) {
            continue;
        }
        for &target in &spec.targets {
            for &e in &spec.solvers {
                let settings = target_settings(e, base, target)?;
                let mut t = TrialSpec::new(
                    STUDY,
                    inst.id.clone(),
                    &inst.scene,
                    e,
                    Law::Coulomb,
                    &settings,
                )
                .with_seconds(Some(spec.time_limit));
                t.setting = Some(Setting::new("target", &format!("{target:e}")));
                out.push((inst.clone(), t, target));
            }
        }
    }
    Ok(out)
}

/// The expected relative cost of each planned run, for an estimate of the
/// time left: n, the unknowns on the instance's finest mesh (with the time
/// limit as a cap per run). Replayed on the run in `results/` (1460 runs,
/// 2392 s of solves), this estimate was within 0.9-1.6× of the time
/// actually left at every tenth of the run; n^1.5 within 1.1-2.2×, and a
/// count of runs (all alike) 3-7× short.
pub fn expected_costs(plan: &[Planned]) -> Vec<f64> {
    let mut known = Vec::new();
    plan.iter()
        .map(|(inst, ..)| unknowns(inst.scene.finest(), &mut known) as f64)
        .collect()
}

/// The number of unknowns on mesh `h` (from the unknowns' map alone, no
/// assembly), remembered in `known` for the meshes already asked.
fn unknowns(h: MeshSize, known: &mut Vec<(MeshSize, usize)>) -> usize {
    if let Some(&(_, n)) = known.iter().find(|(k, _)| *k == h) {
        return n;
    }
    let n = DofMap::new(&Mesh::new(h)).n();
    known.push((h, n));
    n
}

/// Runs the trials of [`plan`] (the caller plans, to count and weigh them
/// for its progress); returns each row beside its measured trial.
pub fn run(
    plan: Vec<Planned>,
    tick: &dyn Fn(&TrialSpec) -> Result<()>,
) -> Result<Vec<(BenchmarkRow, Measured)>> {
    let mut out = Vec::with_capacity(plan.len());
    let mut known = Vec::new();
    for (inst, t, target) in plan {
        let m = measure(&t, None, Keep::default())?;
        let tr = &m.trial;
        let claimed = tr.solver_status.is_converged();
        // A solver that reports no progress cannot be stopped at the limit
        // (a Python function): a run that overran it failed all the same.
        let limit = t.seconds.unwrap_or(f64::INFINITY);
        let overran = m.timing.seconds_min > limit;
        let row = BenchmarkRow {
            instance: inst.id.clone(),
            family: inst.family.into(),
            h: tr.h.to_string(),
            unknowns: unknowns(inst.scene.finest(), &mut known),
            friction_coefficient: inst.scene.friction,
            solver: tr.solver.name.to_string(),
            target,
            status: if overran {
                Status::TimeLimit.to_string()
            } else {
                tr.status.to_string()
            },
            solver_status: tr.solver_status.to_string(),
            success: tr.certified() && !overran,
            claimed_but_failed: claimed && !tr.certified(),
            certificate: tr.residual(),
            failing: tr.row().failing,
            seconds: m.timing.seconds_min,
            time_limit: limit,
            work: tr.work,
            detail: tr.detail.clone(),
        };
        tick(&t)?;
        out.push((row, m));
    }
    Ok(out)
}
