//! `contactlab bench`: speed, as medians of repeated runs after a warm-up on
//! one thread, every figure also as a ratio to the best sparse Cholesky
//! factorization and solve of the stiffness matrix (semicoercive mode
//! removed) available here, measured in the same run: faer's numeric LLᵀ and
//! one solve on one thread or on both cores, whichever is faster on the
//! mesh, with the symbolic analysis done once (the slower thread count and
//! the symbolic analysis also timed apart, and the whole factorization on
//! one thread). Nothing that solves this
//! elasticity problem directly can be much cheaper than that. CHOLMOD
//! (Debian's SuiteSparse 5.12, OpenBLAS on two threads) was timed on the
//! same matrix at h = 1/1024 outside the project and is slower (7.4 s
//! against faer's 5.3 s: README), so it is not among the candidates. Solvers are the
//! study engine's trials (certified, with a wall-clock budget: this is a
//! timing study, its file is a timing file); each solver's inner kernel
//! (from its registry entry) is timed against one product with its operator.

mod charts;
pub mod equal_accuracy;
pub mod exact_bound;
pub mod goal;
pub mod goals;
pub mod memory;
pub mod multigrid;
pub mod section;
mod set_up;

pub use set_up::{FACTORIZATION_THREADS, pinned};
use set_up::{MeshRows, assemble_and_factor, push_set_up};

use std::time::Instant;

use anyhow::Result;
use contactlab_solvers::numerics::linalg::spmv_into;
use contactlab_solvers::{Law, registry};
use serde::{Deserialize, Serialize};

use crate::io::csv::fixed;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::reference::{Among, References};
use crate::study::runner::{Keep, measure, median};
use crate::study::trial::TrialSpec;

/// The study's name in trial records.
pub const STUDY: &str = "bench";

/// What to measure: the study's parameters (its flags, the ones a user
/// types: --runs and --time-limit; and Python's keywords, every field).
#[derive(Clone, Debug, Serialize, Deserialize, clap::Args)]
pub struct BenchSpec {
    #[arg(skip)]
    pub problem: u32,
    #[arg(skip)]
    pub meshes: Vec<MeshSize>,
    /// Timed runs after the first, warm-up run (the median is reported)
    /// [default: 1; --long: 3].
    #[arg(long, value_name = "RUNS", required = false)]
    pub runs: usize,
    /// Wall-clock limit per run in seconds; a solver slower than this on one
    /// mesh (or predicted to be on the next) is not run on finer meshes
    /// [default: 5; --long: 15].
    #[arg(
        long = "time-limit",
        value_name = "SECONDS",
        allow_hyphen_values = true,
        required = false
    )]
    #[serde(rename = "time_limit")]
    pub budget: f64,
    /// Finer meshes where only assembly, the factorization (the median of
    /// `large_factorization_runs` after a warm-up) and the registry's
    /// direct Coulomb solver are timed, the others once each and cold (a
    /// solve at 1/1024 takes a minute and 6 GB).
    #[arg(skip)]
    pub large: Vec<MeshSize>,
    /// Timed runs of the factorization on a large mesh after its warm-up
    /// (the long run's [`LARGE_FACTORIZATION_RUNS`]; at 1/1024 each is
    /// 5-8 s a thread count).
    #[arg(skip)]
    pub large_factorization_runs: usize,
    /// Fresh-process runs of the multigrid's whole Coulomb problem on each
    /// large mesh, and on one thread on the last (the median is reported;
    /// the long run's [`multigrid::COULOMB_RUNS`]).
    #[arg(skip)]
    pub fresh_runs: usize,
    /// Meshes finer still, where only the multigrid solver runs (the
    /// others factor A and are refused there: `Entry::max_unknowns`), on
    /// the whole Coulomb problem, once, in a fresh process.
    #[arg(skip)]
    pub multigrid_only: Vec<MeshSize>,
    /// Meshes where the paper's method runs to a certified accuracy with and
    /// without over-relaxation, beside the fastest oracle variant, once each
    /// ([`equal_accuracy`]).
    #[arg(skip)]
    pub equal_accuracy: Vec<MeshSize>,
    /// The tolerance of that certified stop, in the certificate's measure.
    #[arg(skip)]
    pub accuracy_target: f64,
    /// The mesh of the oracle's time goal (run once, without the budget).
    #[arg(skip)]
    pub oracle_mesh: Option<MeshSize>,
    /// Seconds a run on a large mesh may take: beyond, it is stopped (a
    /// cross on the performance chart), and a solver whose last two meshes
    /// predict more is not run there.
    #[arg(skip)]
    pub large_budget: f64,
}

impl BenchSpec {
    /// The main job's (issue 76: `reproduce` in 20 min): the solvers timed
    /// once after a warm-up, 5 s a run (10 s on 1/512 and 1/1024), the
    /// factorization there once after its warm-up, the multigrid once in a
    /// fresh process, the paper's method at equal accuracy to 1/32, no
    /// multigrid-only meshes.
    pub fn main() -> Self {
        let mut spec = Self::long();
        spec.equal_accuracy.retain(|h| h.level() <= 5);
        spec.large_factorization_runs = 1;
        spec.fresh_runs = 1;
        spec.runs = 1;
        spec.budget = 5.0;
        spec.large_budget = 10.0;
        spec.multigrid_only.clear();
        spec
    }

    /// The long run's (`--long`): three timed runs, 15 s a run, the
    /// multigrid alone to 1/8192, the paper's method at equal accuracy to
    /// 1/256 (about 2 h).
    pub fn long() -> Self {
        Self {
            problem: 1,
            meshes: (3..=8)
                .map(|k| MeshSize::from_level(k).expect("in range"))
                .collect(),
            runs: 3,
            budget: 15.0,
            large: (9..=10)
                .map(|k| MeshSize::from_level(k).expect("in range"))
                .collect(),
            large_factorization_runs: LARGE_FACTORIZATION_RUNS,
            fresh_runs: multigrid::COULOMB_RUNS,
            multigrid_only: (11..=crate::mechanics::mesh_size::MAX_LEVEL)
                .map(|k| MeshSize::from_level(k).expect("in range"))
                .collect(),
            equal_accuracy: (5..=8)
                .map(|k| MeshSize::from_level(k).expect("in range"))
                .collect(),
            accuracy_target: 1e-6,
            oracle_mesh: MeshSize::from_level(8).ok(),
            large_budget: LARGE_BUDGET,
        }
    }

    pub fn quick() -> Self {
        Self {
            problem: 1,
            meshes: (3..=4)
                .map(|k| MeshSize::from_level(k).expect("in range"))
                .collect(),
            runs: 1,
            budget: 5.0,
            large: Vec::new(),
            large_factorization_runs: 1,
            fresh_runs: 1,
            multigrid_only: Vec::new(),
            equal_accuracy: vec![MeshSize::from_level(3).expect("in range")],
            accuracy_target: 1e-6,
            oracle_mesh: MeshSize::from_level(4).ok(),
            large_budget: LARGE_BUDGET,
        }
    }
}

/// One measurement (a row of the timing file `performance.csv`).
#[derive(Clone, Debug, Serialize)]
pub struct PerfRow {
    /// `factorization`, `assembly`, `output` (a fresh copy of A and M, the
    /// floor under assembly), `kernel` (a solver's inner iteration),
    /// `spmv`, `given_friction` or `coulomb`.
    pub what: String,
    pub solver: String,
    /// Settings varied from the solver's defaults, as `path=value` (empty:
    /// none).
    pub variant: String,
    pub h: String,
    pub unknowns: usize,
    pub runs: usize,
    #[serde(serialize_with = "fixed")]
    pub median_seconds: f64,
    #[serde(serialize_with = "fixed")]
    pub min_seconds: f64,
    /// median / the factorization's median on the same mesh.
    #[serde(serialize_with = "fixed")]
    pub ratio_to_factorization: f64,
    /// median / one product A·v on the same mesh (the assembled problem's
    /// A, as the solvers get it, on the machine's cores): the time in work
    /// units, which the machine's speed divides out of.
    #[serde(serialize_with = "fixed")]
    pub work_units: f64,
    /// Certified status (`done` for the measurements without one, `skipped`).
    pub status: String,
    #[serde(serialize_with = "fixed")]
    pub certificate: f64,
    #[serde(serialize_with = "fixed")]
    pub pressure_error: f64,
    pub work: usize,
    pub note: String,
}

#[cfg(test)]
impl PerfRow {
    /// A row for tests: one run of `solver` on `what` with `status`.
    pub(crate) fn sample(
        what: &str,
        solver: &str,
        unknowns: usize,
        seconds: f64,
        status: &str,
    ) -> Self {
        Self {
            what: what.into(),
            solver: solver.into(),
            variant: String::new(),
            h: String::new(),
            unknowns,
            runs: 1,
            median_seconds: seconds,
            min_seconds: seconds,
            ratio_to_factorization: f64::NAN,
            work_units: f64::NAN,
            status: status.into(),
            certificate: f64::NAN,
            pressure_error: f64::NAN,
            work: 0,
            note: String::new(),
        }
    }
}

/// A solver's median seconds on the meshes so far, or why it was stopped.
type Past = (Vec<f64>, Option<String>);

/// Why a solver with this past is not run on the next mesh: it was
/// stopped, or its last two meshes (a, b seconds) predict b·max(b/a, 4)
/// seconds, more than `budget`. None: it runs.
fn why_not_run((past, stopped): &Past, budget: f64) -> Option<String> {
    stopped.clone().or_else(|| match past[..] {
        [.., a, b] if b * (b / a).max(4.0) > budget => Some(format!(
            "predicted {:.0} s > budget {budget} s",
            b * (b / a).max(4.0)
        )),
        _ => None,
    })
}

/// Runs every measurement; `log` gets a line per mesh and solver.
pub fn bench(spec: &BenchSpec, settings: &Settings, log: &dyn Fn(&str)) -> Result<Vec<PerfRow>> {
    faer::set_global_parallelism(faer::Par::Seq);
    let mut rows = Vec::new();
    let mut references = References::default();
    references.candidate_seconds = spec.budget.max(1.0) * 2.0;
    // Bench reports the reference chosen (its pressure errors), not the
    // candidates: they run on both cores, about 25 s less of the main
    // job's 55 s earning them one at a time (the conic candidates at 1/64
    // and 1/128, a few seconds each; the winner, newton or newton-coulomb,
    // takes a fraction of the cap).
    references.candidates_on_cores = Some(true);
    // Per (law, solver): median seconds on the meshes so far, or why it stopped.
    let mut history: std::collections::HashMap<(Law, &str), Past> = Default::default();
    for &h in &spec.meshes {
        let scene = Scene::paper_problem_to(spec.problem, h)?;
        let (d, set_up) = assemble_and_factor(&scene, h, spec.runs, spec.runs)?;
        let mut mesh = MeshRows {
            rows: &mut rows,
            h,
            unknowns: d.problem.n(),
            factorization: median(&set_up.factorization),
            product: memory::product_seconds(d.problem.a()),
        };
        push_set_up(&mut mesh, &set_up, false);
        for entry in registry::solvers() {
            let Some(prepare) = entry.kernel else {
                continue;
            };
            let Some(kernel) = prepare(&d.problem) else {
                continue;
            };
            let (kernel, product) = kernel_against_spmv(kernel, spec.runs)?;
            let ratio = median(&kernel.1) / median(&product);
            mesh.push(
                "kernel",
                entry.name,
                &kernel.1,
                "done",
                format!("{}: {ratio:.2} × one SpMV", kernel.0),
            );
            mesh.push(
                "spmv",
                entry.name,
                &product,
                "done",
                "of the kernel's operator".into(),
            );
        }
        log(&format!(
            "h = {h}: factorization {:.4} s",
            mesh.factorization
        ));
        // The reference is earned among the solvers still timed here, per
        // law: one stopped on a coarser mesh (its times predict more than
        // the budget) would run to its cap for nothing but the reference
        // (at 1/128 and 1/256 earning it took 50 s and 80 s of the main
        // job's bench, most of it the conic variants).
        let timed = |law: Law| -> Vec<&'static str> {
            registry::solvers()
                .into_iter()
                .filter(|e| law == Law::Coulomb || e.solves(law))
                .filter(|e| {
                    history
                        .get(&(law, e.name))
                        .and_then(|p| why_not_run(p, spec.budget))
                        .is_none()
                })
                .map(|e| e.name)
                .collect()
        };
        references.among = Some(Among {
            coulomb: timed(Law::Coulomb),
            given_friction: timed(Law::GivenFriction),
        });
        for entry in registry::solvers() {
            for law in [Law::GivenFriction, Law::Coulomb] {
                if law == Law::GivenFriction && !entry.solves(law) {
                    continue;
                }
                let key = (law, entry.name);
                let so_far = history.entry(key).or_default().clone();
                let why = why_not_run(&so_far, spec.budget);
                let past = so_far.0;
                if let Some(why) = why {
                    history.insert(key, (past, Some(why.clone())));
                    mesh.push(law.as_str(), entry.name, &[f64::NAN], "skipped", why);
                    continue;
                }
                log(&format!("h = {h}: {} {}", entry.name, law.as_str()));
                let t = TrialSpec::new(STUDY, law.as_str(), &scene, entry, law, settings)
                    .with_seconds(Some(spec.budget))
                    .with_repeats(spec.runs)
                    .unbounded();
                let reference = references.get(&scene, settings)?;
                let m = measure(&t, reference, Keep::default())?;
                let seconds = m.timing.seconds_median;
                let mut past = past;
                past.push(seconds);
                let stop = (seconds > spec.budget)
                    .then(|| format!("one run took {seconds:.1} s > budget {} s", spec.budget));
                history.insert(key, (past, stop));
                let tr = &m.trial;
                let note = format!(
                    "{} friction iterations, {} outer, {} inner",
                    tr.friction_iterations, tr.outer_iterations, tr.inner_iterations
                );
                let times = vec![m.timing.seconds_median];
                mesh.push(law.as_str(), entry.name, &times, tr.status.as_str(), note);
                let row = mesh.rows.last_mut().expect("just pushed");
                row.runs = m.timing.runs;
                row.min_seconds = m.timing.seconds_min;
                row.certificate = tr.residual();
                row.pressure_error = tr.pressure_error().unwrap_or(f64::NAN);
                row.work = tr.work;
            }
        }
    }
    equal_accuracy::equal_accuracy(spec, settings, &mut rows, log)?;
    // The large meshes get every solver certified on the whole Coulomb
    // problem on the finest mesh above, fastest first, so that the
    // performance chart follows each of them as far as it goes: each run
    // stopped at `spec.large_budget` seconds, and not run where its last two
    // meshes predict more (the regular meshes' rule). One whose answer is
    // not certified (a failure is a row too) is not run on the finer ones.
    let finest = spec
        .meshes
        .last()
        .map(|h| h.to_string())
        .unwrap_or_default();
    let mut candidates: Vec<(&'static registry::Entry, Vec<f64>)> =
        certified_by_speed(&rows, &finest)
            .into_iter()
            .filter_map(registry::by_name)
            .map(|e| {
                let past = rows
                    .iter()
                    .filter(|r| {
                        r.what == "coulomb" && r.solver == e.name && r.status == "converged"
                    })
                    .map(|r| r.median_seconds)
                    .collect();
                (e, past)
            })
            .collect();
    for &h in &spec.large {
        let (mut run, mut skipped) = (Vec::new(), Vec::new());
        for (e, past) in &candidates {
            match past[..] {
                [.., a, b] if b * (b / a).max(4.0) > spec.large_budget => skipped.push((
                    e.name,
                    format!(
                        "predicted {:.0} s > budget {} s",
                        b * (b / a).max(4.0),
                        spec.large_budget
                    ),
                )),
                _ => run.push(*e),
            }
        }
        if run.is_empty() {
            break;
        }
        let times = large_mesh(spec, h, (&run, &skipped), settings, &mut rows, log)?;
        candidates.retain_mut(|(e, past)| match times.iter().find(|t| t.0 == e.name) {
            Some((_, Some(seconds))) => {
                past.push(*seconds);
                true
            }
            _ => false,
        });
    }
    Ok(rows)
}

/// The solvers certified on the whole Coulomb problem at `h` in `rows`
/// (directly or inside the fixed point), fastest first.
pub fn certified_by_speed(rows: &[PerfRow], h: &str) -> Vec<&'static str> {
    let mut found: Vec<(&'static str, f64)> = rows
        .iter()
        .filter(|r| r.what == "coulomb" && r.h == h && r.status == "converged")
        .filter_map(|r| Some((registry::by_name(&r.solver)?.name, r.median_seconds)))
        .collect();
    found.sort_by(|a, b| a.1.total_cmp(&b.1));
    found.into_iter().map(|(name, _)| name).collect()
}

/// The long run's seconds a run on a large mesh may take
/// ([`BenchSpec::large_budget`]).
pub const LARGE_BUDGET: f64 = 60.0;

/// The solvers of the Coulomb law itself (no fixed point around them)
/// certified at `h` in `rows`, fastest first.
pub fn direct_by_speed(rows: &[PerfRow], h: &str) -> Vec<&'static str> {
    certified_by_speed(rows, h)
        .into_iter()
        .filter(|name| registry::by_name(name).is_some_and(|e| e.solves(Law::Coulomb)))
        .collect()
}

/// The direct Coulomb solver certified at `h` in `rows`, the fastest if
/// several: the one whose answer on that mesh can be trusted.
pub fn certified_direct(rows: &[PerfRow], h: &str) -> Option<&'static str> {
    direct_by_speed(rows, h).first().copied()
}

/// The fastest direct Coulomb solver `bench` certified on each of its
/// meshes, and its finest regular mesh (the large ones aside).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FastestDirect {
    /// (h, solver) for each mesh `bench` measured with a certified direct
    /// Coulomb solver, in the order of its rows.
    pub by_mesh: Vec<(String, String)>,
    /// Its finest regular mesh.
    pub finest_regular: Option<String>,
}

impl FastestDirect {
    /// From a `bench` run's rows ([`certified_direct`]).
    pub fn of(bench: &goals::BenchOutput) -> Self {
        let mut by_mesh: Vec<(String, String)> = Vec::new();
        for r in &bench.rows {
            if by_mesh.iter().any(|(h, _)| *h == r.h) {
                continue;
            }
            if let Some(s) = certified_direct(&bench.rows, &r.h) {
                by_mesh.push((r.h.clone(), s.to_string()));
            }
        }
        Self {
            by_mesh,
            finest_regular: bench.meshes.last().map(|h| h.to_string()),
        }
    }

    /// The solver certified at `h`, else the one at the finest regular
    /// mesh; None if `bench` has not run or certified none there.
    pub fn at_or_finest(&self, h: &str) -> Option<&'static str> {
        let at = |h: &str| {
            self.by_mesh
                .iter()
                .find(|(m, _)| m == h)
                .and_then(|(_, s)| contactlab_solvers::registry::by_name(s))
                .map(|e| e.name)
        };
        at(h).or_else(|| self.finest_regular.as_deref().and_then(at))
    }
}

/// Timed runs of the factorization on a large mesh, after a warm-up: the
/// unit of the large meshes' ratios. Timed once, it moved by a fifth from
/// one run of `bench` to the next (1/1024: 8.1 s, 6.7 s, 7.1 s).
pub const LARGE_FACTORIZATION_RUNS: usize = 3;

/// On a large mesh: assembly and each of `solvers` on the whole Coulomb
/// problem, each timed once within the spec's `large_budget` seconds (no
/// warm-up, no reference: the certificate alone judges the answer), and
/// the factorization, the ratios' unit, as the median of the spec's
/// `large_factorization_runs` after a warm-up. Returns each solver's
/// seconds if its answer was certified.
fn large_mesh(
    spec: &BenchSpec,
    h: MeshSize,
    (solvers, skipped): (&[&'static registry::Entry], &[(&'static str, String)]),
    settings: &Settings,
    rows: &mut Vec<PerfRow>,
    log: &dyn Fn(&str),
) -> Result<Vec<(&'static str, Option<f64>)>> {
    let (budget, runs) = (spec.large_budget, spec.large_factorization_runs);
    let scene = Scene::paper_problem_to(spec.problem, h)?;
    log(&format!(
        "h = {h}: assembly and the factorization ({runs} run{} after a warm-up)",
        if runs == 1 { "" } else { "s" }
    ));
    let (d, set_up) = assemble_and_factor(&scene, h, 0, runs)?;
    let unknowns = d.problem.n();
    let product = memory::product_seconds(d.problem.a());
    drop(d);
    let mut mesh = MeshRows {
        rows,
        h,
        unknowns,
        factorization: median(&set_up.factorization),
        product,
    };
    push_set_up(&mut mesh, &set_up, true);
    for (name, why) in skipped {
        mesh.push("coulomb", name, &[f64::NAN], "skipped", why.clone());
    }
    let mut times = Vec::new();
    for &solver in solvers {
        log(&format!("h = {h}: {} coulomb", solver.name));
        let t = TrialSpec::new(STUDY, "coulomb", &scene, solver, Law::Coulomb, settings)
            .with_seconds(Some(budget))
            .unbounded();
        let m = measure(&t, None, Keep::default())?;
        let tr = &m.trial;
        let note = format!(
            "once; {} friction iterations, {} outer, {} inner",
            tr.friction_iterations, tr.outer_iterations, tr.inner_iterations
        );
        mesh.push(
            "coulomb",
            solver.name,
            &[m.timing.seconds_median],
            tr.status.as_str(),
            note,
        );
        let row = mesh.rows.last_mut().expect("just pushed");
        row.certificate = tr.residual();
        row.work = tr.work;
        let certified = tr.status == contactlab_solvers::Status::Converged;
        times.push((solver.name, certified.then_some(m.timing.seconds_median)));
    }
    Ok(times)
}

/// Times a kernel step and one product with its operator, interleaved so
/// that whatever else the machine does affects both alike; the first pair
/// is a warm-up. Returns ((name, seconds per step), seconds per product).
#[allow(clippy::type_complexity)]
fn kernel_against_spmv(
    mut k: contactlab_solvers::registry::InnerKernel,
    runs: usize,
) -> Result<((&'static str, Vec<f64>), Vec<f64>)> {
    let n = k.matrix.nrows();
    let reps = (2_000_000 / n.max(1)).clamp(5, 2000);
    let x = vec![1.0; n];
    let mut y = vec![0.0; n];
    let (mut step, mut product) = (Vec::new(), Vec::new());
    for round in 0..=runs.max(5) {
        let t = Instant::now();
        for _ in 0..reps {
            (k.step)();
        }
        let ts = t.elapsed().as_secs_f64();
        let t = Instant::now();
        for _ in 0..reps {
            spmv_into(&k.matrix, &x, &mut y);
        }
        std::hint::black_box(&y);
        let tp = t.elapsed().as_secs_f64();
        if round > 0 {
            step.push(ts / reps as f64);
            product.push(tp / reps as f64);
        }
    }
    Ok(((k.name, step), product))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The error study's solver: the one certified on its reference mesh,
    /// else on bench's finest regular mesh, and only a registered one.
    #[test]
    fn the_fastest_direct_solver_falls_back_to_the_finest_regular_mesh() {
        let fastest = FastestDirect {
            by_mesh: vec![
                ("1/64".into(), "newton-coulomb".into()),
                ("1/2048".into(), "tnnmg".into()),
                ("1/4096".into(), "no-such-solver".into()),
            ],
            finest_regular: Some("1/64".into()),
        };
        assert_eq!(fastest.at_or_finest("1/2048"), Some("tnnmg"));
        assert_eq!(fastest.at_or_finest("1/1024"), Some("newton-coulomb"));
        // A name the registry does not know counts as none there.
        assert_eq!(fastest.at_or_finest("1/4096"), Some("newton-coulomb"));
        let unknown_finest = FastestDirect {
            finest_regular: Some("1/4096".into()),
            ..fastest.clone()
        };
        assert_eq!(unknown_finest.at_or_finest("1/512"), None);
        assert_eq!(FastestDirect::default().at_or_finest("1/64"), None);
    }
}
