//! `contactlab bench`: medians of repeated runs after a warm-up, one thread,
//! every figure also as a ratio to one sparse Cholesky factorization and
//! solve of the stiffness matrix (semicoercive mode removed) measured in the
//! same run: nothing that solves this elasticity problem to full accuracy can
//! be much cheaper than that.

use std::time::Instant;

use anyhow::Result;
use contactlab_solvers::linalg::{SparseCholesky, spmv_into};
use contactlab_solvers::registry;
use contactlab_solvers::relaxation::Resolved;
use contactlab_solvers::relaxation::pointwise::{RelaxationOperator, SweepData};
use contactlab_solvers::{ContactProblem, RelaxationSettings, Silent};
use nalgebra_sparse::{CooMatrix, CsrMatrix};
use serde::Serialize;

use crate::coulomb::driver::solve_scene;
use crate::io::charts::{Chart, Series};
use crate::io::output::csv_bytes;
use crate::mechanics::discretization::Discretization;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::compare::solve_given_friction;
use crate::study::stability::fit_slope;
use crate::study::table1::PAPER_TABLE_1;

/// What to measure.
#[derive(Clone, Debug, Serialize)]
pub struct BenchSpec {
    pub problem: u32,
    pub meshes: Vec<MeshSize>,
    /// Timed runs after the warm-up (the median is reported).
    pub runs: usize,
    /// A solver whose run takes longer than this (seconds), or is predicted
    /// to on the next mesh, is not run on finer meshes.
    pub budget: f64,
}

impl BenchSpec {
    pub fn standard() -> Self {
        Self {
            problem: 1,
            meshes: (3..=8)
                .map(|k| MeshSize::from_level(k).expect("in range"))
                .collect(),
            runs: 3,
            budget: 15.0,
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
        }
    }
}

/// The state one relaxation sweep is timed in, by `contactlab bench` and the
/// criterion bench alike: H = A + ρM, multipliers l = 1 and friction bounds
/// g = ½ on every contact node, so that every branch of the sweep runs.
pub struct SweepFixture {
    pub op: RelaxationOperator,
    resolved: Resolved,
    l: Vec<f64>,
    wg: Vec<f64>,
}

impl SweepFixture {
    pub fn new(p: &ContactProblem, s: &RelaxationSettings) -> Self {
        let resolved = s.resolve(p);
        Self {
            op: RelaxationOperator::new(p.a(), p.mass(), resolved.proximal, p.contacts()),
            resolved,
            l: vec![1.0; p.contacts().len()],
            wg: p.contacts().iter().map(|c| 0.5 * c.weight).collect(),
        }
    }

    /// The sweep's data for problem `p` (the one the fixture was built from).
    pub fn data<'a>(&'a self, p: &'a ContactProblem) -> SweepData<'a> {
        SweepData {
            b: p.f(),
            l: &self.l,
            wg: &self.wg,
            r: self.resolved.r,
            smoothing: self.resolved.smoothing,
        }
    }
}

/// One measurement.
#[derive(Clone, Debug, Serialize)]
pub struct PerfRow {
    /// `factorization`, `assembly`, `sweep`, `spmv`, `given_friction` or `coulomb`.
    pub what: String,
    pub solver: String,
    pub h: String,
    pub unknowns: usize,
    pub runs: usize,
    pub median_seconds: f64,
    pub min_seconds: f64,
    /// median / the factorization's median on the same mesh.
    pub ratio_to_factorization: f64,
    pub status: String,
    /// Iterations (outer / inner) and the KKT residual, or why it was skipped.
    pub note: String,
    pub kkt: f64,
    pub sweeps: usize,
}

fn median(mut x: Vec<f64>) -> f64 {
    x.sort_by(f64::total_cmp);
    let n = x.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        x[n / 2]
    } else {
        0.5 * (x[n / 2 - 1] + x[n / 2])
    }
}

/// Times `f` once as a warm-up and `runs` more times; returns (first result, times).
fn timed<T>(runs: usize, mut f: impl FnMut() -> Result<T>) -> Result<(T, Vec<f64>)> {
    let t = Instant::now();
    let first = f()?;
    let warm = t.elapsed().as_secs_f64();
    let mut times = Vec::with_capacity(runs);
    for _ in 0..runs {
        let t = Instant::now();
        f()?;
        times.push(t.elapsed().as_secs_f64());
    }
    if times.is_empty() {
        times.push(warm);
    }
    Ok((first, times))
}

/// A with one jump pinned by a spring: the stiffness with the semicoercive
/// mode removed, same size and pattern.
pub fn pinned(d: &Discretization) -> CsrMatrix<f64> {
    let a = d.problem.a();
    let t = d.problem.contacts()[0].t;
    let k = a
        .diagonal_as_csr()
        .values()
        .iter()
        .fold(0.0f64, |m, v| m.max(*v));
    let mut coo = CooMatrix::new(a.nrows(), a.ncols());
    for (i, j, &v) in a.triplet_iter() {
        coo.push(i, j, v);
    }
    coo.push(t, t, k);
    CsrMatrix::from(&coo)
}

/// Runs every measurement; `log` gets a line per mesh and solver.
pub fn bench(spec: &BenchSpec, settings: &Settings, log: &dyn Fn(&str)) -> Result<Vec<PerfRow>> {
    faer::set_global_parallelism(faer::Par::Seq);
    let mut rows = Vec::new();
    // Per (what, solver): seconds on the last two meshes, or why it stopped.
    let mut history: std::collections::HashMap<(String, String), (Vec<f64>, Option<String>)> =
        Default::default();
    for &h in &spec.meshes {
        let mut scene = Scene::paper_problem(spec.problem)?;
        scene.set_finest(h);
        let (d, assembly) = timed(spec.runs, || Ok(Discretization::new(&scene, h)?))?;
        let n = d.problem.n();
        let a = pinned(&d);
        let (_, factor) = timed(spec.runs, || {
            let c = SparseCholesky::new(&a)?;
            let mut b = d.problem.f().to_vec();
            c.solve_vec(&mut b);
            Ok(b[0])
        })?;
        let reference = median(factor.clone());
        let push = |rows: &mut Vec<PerfRow>,
                    what: &str,
                    solver: &str,
                    times: &[f64],
                    status: &str,
                    note: String,
                    kkt: f64,
                    sweeps: usize| {
            let m = median(times.to_vec());
            rows.push(PerfRow {
                what: what.into(),
                solver: solver.into(),
                h: h.to_string(),
                unknowns: n,
                runs: times.len(),
                median_seconds: m,
                min_seconds: times.iter().copied().fold(f64::INFINITY, f64::min),
                ratio_to_factorization: m / reference,
                status: status.into(),
                note,
                kkt,
                sweeps,
            });
        };
        push(
            &mut rows,
            "factorization",
            "faer LLᵀ",
            &factor,
            "done",
            "symbolic + numeric + one solve".into(),
            f64::NAN,
            0,
        );
        push(
            &mut rows,
            "assembly",
            "-",
            &assembly,
            "done",
            String::new(),
            f64::NAN,
            0,
        );
        // One sweep and one SpMV of the same matrix H = A + M.
        let fixture = SweepFixture::new(&d.problem, &RelaxationSettings::default());
        let (op, data) = (&fixture.op, fixture.data(&d.problem));
        let reps = (2_000_000 / n.max(1)).clamp(5, 2000);
        let mut v = vec![0.0; n];
        let mut y = vec![0.0; n];
        // Interleaved (sweeps, products, sweeps, ...) so that whatever else the
        // machine does affects both alike; the first pair is a warm-up.
        let (mut sweep, mut product) = (Vec::new(), Vec::new());
        for k in 0..=spec.runs.max(5) {
            let t = Instant::now();
            for _ in 0..reps {
                op.sweep(&mut v, &data);
            }
            let ts = t.elapsed().as_secs_f64();
            let t = Instant::now();
            for _ in 0..reps {
                spmv_into(&op.h, &v, &mut y);
            }
            let tp = t.elapsed().as_secs_f64();
            if k > 0 {
                sweep.push(ts);
                product.push(tp);
            }
        }
        let per = |t: &[f64]| t.iter().map(|x| x / reps as f64).collect::<Vec<f64>>();
        let (sweep, product) = (per(&sweep), per(&product));
        let ratio = median(sweep.clone()) / median(product.clone());
        push(
            &mut rows,
            "sweep",
            "relaxation",
            &sweep,
            "done",
            format!("{ratio:.2} × one SpMV"),
            f64::NAN,
            0,
        );
        push(
            &mut rows,
            "spmv",
            "-",
            &product,
            "done",
            String::new(),
            f64::NAN,
            0,
        );
        log(&format!(
            "h = {h}: factorization {reference:.4} s, sweep/SpMV {ratio:.2}"
        ));
        // The operating point g: the Coulomb solution of the fastest exact solver.
        let g = solve_scene(&scene, settings, "newton", &mut Silent)?
            .coulomb
            .g;
        for entry in registry::SOLVERS {
            for what in ["given_friction", "coulomb"] {
                let key = (what.to_string(), entry.name.to_string());
                let (past, stopped) = history.entry(key.clone()).or_default().clone();
                if let Some(why) = stopped {
                    push(
                        &mut rows,
                        what,
                        entry.name,
                        &[f64::NAN],
                        "skipped",
                        why,
                        f64::NAN,
                        0,
                    );
                    continue;
                }
                if let [.., a, b] = past[..] {
                    let predicted = b * (b / a).max(4.0);
                    if predicted > spec.budget {
                        let why = format!("predicted {predicted:.0} s > budget {} s", spec.budget);
                        history.insert(key, (past, Some(why.clone())));
                        push(
                            &mut rows,
                            what,
                            entry.name,
                            &[f64::NAN],
                            "skipped",
                            why,
                            f64::NAN,
                            0,
                        );
                        continue;
                    }
                }
                log(&format!("h = {h}: {} {what}", entry.name));
                let one = || -> Result<(String, String, f64, usize, f64)> {
                    if what == "coulomb" {
                        let run = solve_scene(&scene, settings, entry.name, &mut Silent)?;
                        let it = run.coulomb.total_iterations();
                        Ok((
                            run.status.to_string(),
                            format!(
                                "{} friction iterations, {} outer, {} inner",
                                run.coulomb.history.len(),
                                it.outer,
                                it.inner
                            ),
                            run.certificate.residual(),
                            it.inner,
                            run.coulomb.seconds,
                        ))
                    } else {
                        let (dd, s, _) =
                            solve_given_friction(&scene, settings, entry.name, &g, &mut Silent)?;
                        let r = crate::certificate::certify(
                            &dd.problem,
                            contactlab_solvers::Law::GivenFriction,
                            &s.v,
                            &s.pressure,
                            &s.friction_traction,
                            settings.certificate.tolerance,
                        );
                        Ok((
                            r.verdict(s.status).to_string(),
                            format!("{} outer, {} inner", s.iterations.outer, s.iterations.inner),
                            r.residual(),
                            s.iterations.inner,
                            s.timing.total(),
                        ))
                    }
                };
                // Solver time only (assembly excluded): the runs report their own.
                let (status, note, kkt, sweeps, t0) = one()?;
                let mut times = Vec::new();
                if t0 <= spec.budget {
                    for _ in 0..spec.runs {
                        times.push(one()?.4);
                    }
                }
                if times.is_empty() {
                    times.push(t0);
                }
                let m = median(times.clone());
                let mut past = past;
                past.push(m);
                let stop = (t0 > spec.budget)
                    .then(|| format!("one run took {t0:.1} s > budget {} s", spec.budget));
                history.insert(key, (past, stop));
                push(
                    &mut rows, what, entry.name, &times, &status, note, kkt, sweeps,
                );
            }
        }
    }
    Ok(rows)
}

/// Columns of `performance.csv`.
pub const PERFORMANCE_COLUMNS: [&str; 12] = [
    "what",
    "solver",
    "h",
    "unknowns",
    "runs",
    "median_seconds",
    "min_seconds",
    "ratio_to_factorization",
    "status",
    "kkt",
    "sweeps",
    "note",
];

pub fn performance_csv(rows: &[PerfRow]) -> Result<Vec<u8>> {
    let num = |x: f64| {
        if x.is_finite() {
            format!("{x:.6e}")
        } else {
            String::new()
        }
    };
    csv_bytes(
        &PERFORMANCE_COLUMNS,
        rows.iter().map(|r| {
            vec![
                r.what.clone(),
                r.solver.clone(),
                r.h.clone(),
                r.unknowns.to_string(),
                r.runs.to_string(),
                num(r.median_seconds),
                num(r.min_seconds),
                num(r.ratio_to_factorization),
                r.status.clone(),
                num(r.kkt),
                r.sweeps.to_string(),
                r.note.clone(),
            ]
        }),
    )
}

/// Time against unknowns (log-log), one series per solver with its fitted slope.
pub fn performance_charts(rows: &[PerfRow]) -> Vec<(String, Chart)> {
    let mut out = Vec::new();
    for what in ["coulomb", "given_friction"] {
        let mut series = Vec::new();
        let mut names: Vec<&str> = vec!["faer LLᵀ"];
        names.extend(registry::names());
        for name in names {
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| {
                    r.solver == name
                        && (r.what == what || (name == "faer LLᵀ" && r.what == "factorization"))
                })
                .filter(|r| r.median_seconds.is_finite())
                .map(|r| (r.unknowns as f64, r.median_seconds))
                .collect();
            if pts.is_empty() {
                continue;
            }
            let slope = fit_slope(&pts)
                .map(|s| format!("{s:.2}"))
                .unwrap_or_else(|| "n/a".into());
            let label = if name == "faer LLᵀ" {
                format!("one factorization + solve (slope {slope})")
            } else {
                format!("{name} (slope {slope})")
            };
            let s = Series::line(label, pts).with_markers();
            series.push(if name == "faer LLᵀ" { s.dashed() } else { s });
        }
        let title = if what == "coulomb" {
            "Whole Coulomb problem: time against unknowns (problem 1)"
        } else {
            "Given-friction subproblem: time against unknowns (problem 1)"
        };
        out.push((
            format!("performance_{what}"),
            Chart {
                title: title.into(),
                x_label: "unknowns".into(),
                y_label: "median time [s], one thread".into(),
                log_x: true,
                log_y: true,
                series,
                legend: crate::io::charts::Legend::UpperLeft,
            },
        ));
    }
    out
}

/// One goal of the issue, measured.
#[derive(Clone, Debug, Serialize)]
pub struct Goal {
    pub goal: String,
    pub measured: String,
    pub pass: Option<bool>,
}

/// The goals, checked against the rows of one run (and a peak memory in KiB
/// of the fastest solver on the given mesh).
pub fn goals(rows: &[PerfRow], peak: Option<(MeshSize, u64)>) -> Vec<Goal> {
    let find = |what: &str, solver: &str, h: &str| {
        rows.iter()
            .find(|r| r.what == what && r.solver == solver && r.h == h)
    };
    let fastest = |h: &str| {
        rows.iter()
            .filter(|r| {
                r.what == "coulomb"
                    && r.h == h
                    && r.median_seconds.is_finite()
                    && r.status == "converged"
            })
            .min_by(|a, b| a.median_seconds.total_cmp(&b.median_seconds))
    };
    let mut out = Vec::new();
    for (h, limit) in [("1/64", 10.0), ("1/256", 20.0)] {
        match fastest(h) {
            Some(f) => {
                out.push(Goal {
                    goal: format!("whole Coulomb problem at h = {h}, fastest solver: at most {limit} × one factorization"),
                    measured: format!("{}: {:.4} s = {:.1} × factorization", f.solver, f.median_seconds, f.ratio_to_factorization),
                    pass: Some(f.ratio_to_factorization <= limit),
                });
                if let Some(c) =
                    find("coulomb", "clarabel", h).filter(|c| c.median_seconds.is_finite())
                {
                    let ratio = c.median_seconds / f.median_seconds;
                    out.push(Goal {
                        goal: format!("at h = {h}, at least 10 × faster than Clarabel at equal or better residuals"),
                        measured: format!(
                            "{ratio:.1} × faster; KKT residual {:.1e} vs Clarabel's {:.1e}",
                            f.kkt, c.kkt
                        ),
                        pass: Some(ratio >= 10.0 && f.kkt <= c.kkt),
                    });
                }
            }
            None => out.push(Goal {
                goal: format!("whole Coulomb problem at h = {h}"),
                measured: "not measured in this run".into(),
                pass: None,
            }),
        }
    }
    if let Some((h, kb)) = peak {
        out.push(Goal {
            goal: format!("peak memory of the fastest solver at h = {h} under 2 GiB"),
            measured: format!("{:.0} MiB", kb as f64 / 1024.0),
            pass: Some((kb as f64) < 2.0 * 1024.0 * 1024.0),
        });
    }
    if let Some(s) = find("sweep", "relaxation", "1/64") {
        let ratio = rows
            .iter()
            .find(|r| r.what == "spmv" && r.h == "1/64")
            .map(|p| s.median_seconds / p.median_seconds)
            .unwrap_or(f64::NAN);
        out.push(Goal {
            goal: "one relaxation sweep: at most 2 × one sparse matrix-vector product (h = 1/64)"
                .into(),
            measured: format!("{ratio:.2} ×"),
            pass: Some(ratio <= 2.0),
        });
    }
    if let Some(r) = find("coulomb", "relaxation", "1/64").filter(|r| r.status == "converged") {
        let paper = PAPER_TABLE_1[0].3;
        out.push(Goal {
            goal: format!("the paper's relaxation at h = 1/64, problem 1: no more sweeps than Table 1 ({paper})"),
            measured: format!("{} sweeps", r.sweeps),
            pass: Some(r.sweeps <= paper),
        });
    }
    out
}

pub fn goals_markdown(goals: &[Goal]) -> String {
    let mut s = String::from("| goal | measured | result |\n|---|---|---|\n");
    for g in goals {
        let result = match g.pass {
            Some(true) => "pass",
            Some(false) => "falls short",
            None => "not measured",
        };
        s += &format!("| {} | {} | {result} |\n", g.goal, g.measured);
    }
    s
}

/// Peak resident memory of this process so far, in KiB (Linux).
pub fn peak_memory_kb() -> Option<u64> {
    std::fs::read_to_string("/proc/self/status")
        .ok()?
        .lines()
        .find(|l| l.starts_with("VmHWM:"))?
        .split_whitespace()
        .nth(1)?
        .parse()
        .ok()
}

/// Runs the benchmark, measures the fastest solver's peak memory on the
/// finest mesh in a fresh process, and writes the files; returns the goals.
pub fn write_bench(
    out: &std::path::Path,
    spec: &BenchSpec,
    settings: &Settings,
    log: &dyn Fn(&str),
) -> Result<(Vec<PerfRow>, Vec<Goal>, Option<u64>)> {
    let rows = bench(spec, settings, log)?;
    let finest = spec.meshes.last().copied();
    let fastest = finest.and_then(|h| {
        rows.iter()
            .filter(|r| r.what == "coulomb" && r.h == h.to_string() && r.median_seconds.is_finite())
            .min_by(|a, b| a.median_seconds.total_cmp(&b.median_seconds))
            .map(|r| (h, r.solver.clone()))
    });
    let peak = match &fastest {
        Some((h, solver)) => {
            log(&format!(
                "peak memory of {solver} at h = {h} (fresh process)"
            ));
            let o = std::process::Command::new(std::env::current_exe()?)
                .args([
                    "bench-one",
                    "--problem",
                    &spec.problem.to_string(),
                    "--h",
                    &h.to_string(),
                    "--solver",
                    solver,
                ])
                .output()?;
            let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap_or_default();
            v.get("peak_kb").and_then(|x| x.as_u64())
        }
        None => None,
    };
    let goals = goals(&rows, fastest.as_ref().map(|f| f.0).zip(peak));
    crate::io::output::write_atomic(&out.join("performance.csv"), &performance_csv(&rows)?)?;
    let mut md = goals_markdown(&goals);
    if let (Some(kb), Some((h, solver))) = (peak, fastest) {
        md += &format!(
            "\nPeak resident memory of `{solver}` on the whole Coulomb problem at h = {h}, in a fresh process: {:.0} MiB.\n",
            kb as f64 / 1024.0
        );
    }
    crate::io::output::write_atomic(&out.join("performance_goals.md"), md.as_bytes())?;
    crate::study::report::write_all(&out.join("charts"), &performance_charts(&rows))?;
    Ok((rows, goals, peak))
}
