//! The `contactlab` command line. Logs go to stderr, data to files or stdout.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};

use crate::coulomb::continuation::Schedule;
use crate::io::output::{csv_bytes, fixed, json_bytes, write_atomic};
use crate::mechanics::contact_zone::PROFILE_COLUMNS;
use crate::mechanics::discretization::Discretization;
use crate::mechanics::material::PlaneModel;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::bench::BenchSpec;
use crate::study::reproduce::ReproduceSpec;
use crate::study::stability::StabilitySpec;
use crate::study::sweep::{Factor, SweepSpec};
use contactlab_solvers::{Control, Observer, Progress};

mod scene_args;
mod settings_args;

use crate::coulomb::fixed_point;
pub use scene_args::SceneArgs;
pub use settings_args::{SettingsArgs, knob_flag};

/// contactlab: verify a fast iterative contact solver against a conic oracle on
/// the semicoercive two-body contact problem with Coulomb friction of
/// Zhiltsov & Namm (2019).
#[derive(Debug, Parser)]
#[command(name = "contactlab", version, propagate_version = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Print the sizes of a discretized scene: nodes, elements, free unknowns,
    /// nonzeros of A, contact nodes, the applied load and the measured
    /// dimension of the kernel of A.
    Info(InfoArgs),
    /// Solve a scene: the Coulomb fixed point around a given-friction solver.
    /// Prints a summary; with --out writes profile.csv and summary.json.
    Solve(SolveArgs),
    /// Reproduce the paper's Table 1: the relaxation solver with mesh
    /// continuation on problems 1-3, our iteration counts beside the
    /// paper's. Writes DIR/table1.csv and prints a Markdown table.
    Table1(Table1Args),
    /// Compare every registered solver with the oracle on one scene: the
    /// given-friction subproblem at the oracle's g and the whole Coulomb
    /// problem. Writes DIR/compare.csv (accuracy) and DIR/compare_timing.csv;
    /// prints a Markdown table.
    Compare(CompareArgs),
    /// Sweep the paper's solver over r, ε, the smoothing of |s| and the
    /// continuation schedule (whole Coulomb problem), and every solver over
    /// its tolerance (given-friction subproblem, a work-precision diagram).
    /// Writes DIR/sweep.csv, DIR/sweep_timing.csv and charts in DIR/charts.
    Sweep(SweepArgs),
    /// The main job: the paper's three problems with every solver, Table 1,
    /// the contact-zone profiles, the comparison, a reduced sweep, charts,
    /// a manifest and a README, all into DIR.
    Reproduce(ReproduceArgs),
    /// The stability map: each method across stress conditions (r, ε,
    /// smoothing, the proximal term, the friction coefficient, loads near
    /// condition (13), fine meshes, Clarabel's tolerances), every run
    /// classified converged, slow, stalled, diverged, wrong or refused.
    /// Writes DIR/stability.csv, DIR/stability_friction.csv and charts.
    Stability(StabilityArgs),
    /// Measure speed: assembly, one sweep against one SpMV, each solver on
    /// the given-friction subproblem and on the whole Coulomb problem, for
    /// h = 1/8 to 1/256, as medians after a warm-up on one thread and as
    /// ratios to one sparse factorization. Writes DIR/performance.csv,
    /// DIR/performance_goals.md and charts.
    Bench(BenchArgs),
    /// (internal) Solve one scene and print time and peak memory as JSON.
    #[command(hide = true)]
    BenchOne(BenchOneArgs),
}

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "results")]
    pub out: PathBuf,
    /// A small run for tests (h = 1/8, 1/16, one run each).
    #[arg(long)]
    pub quick: bool,
    /// Timed runs after the warm-up (the median is reported).
    #[arg(long, allow_hyphen_values = true)]
    pub runs: Option<usize>,
    /// Seconds: a solver slower than this on one mesh (or predicted to be on
    /// the next) is not run on finer meshes.
    #[arg(long, allow_hyphen_values = true)]
    pub budget: Option<f64>,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

#[derive(Debug, Args)]
pub struct BenchOneArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[arg(long, default_value = "newton")]
    pub solver: String,
}

#[derive(Debug, Args)]
pub struct StabilityArgs {
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "results")]
    pub out: PathBuf,
    /// A small map for tests (h = 1/8, few values).
    #[arg(long)]
    pub quick: bool,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

#[derive(Debug, Args)]
pub struct ReproduceArgs {
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "results")]
    pub out: PathBuf,
    /// A small run for tests and smoke checks (h = 1/16, fewer points).
    #[arg(long)]
    pub quick: bool,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

#[derive(Debug, Args)]
pub struct SweepArgs {
    /// Problems of the paper to sweep.
    #[arg(long, value_delimiter = ',', default_values_t = [1], conflicts_with = "scene")]
    pub problems: Vec<u32>,
    /// A scene file to sweep instead of the paper's problems (its material,
    /// friction and loads; its settings are the sweep's base settings).
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Finest meshes (each with continuation from 1/8).
    #[arg(long = "h", value_name = "1/2^k", value_delimiter = ',', default_values_t = [MeshSize::from_level(5).expect("in range")])]
    pub meshes: Vec<MeshSize>,
    /// Factors to vary, one at a time around the paper's settings.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [Factor::R, Factor::Epsilon, Factor::Smoothing, Factor::Schedule, Factor::Tolerance])]
    pub vary: Vec<Factor>,
    /// Values of r (default 1e0, 1e1, ..., 1e14).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub r_values: Vec<f64>,
    /// Values of ε (default 1e-2, ..., 1e-8).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub epsilon_values: Vec<f64>,
    /// Smoothing values: `exact` or Huber widths (default exact, 1e-6, 1e-8, 1e-10, 1e-12).
    #[arg(long, value_delimiter = ',')]
    pub smoothing_values: Vec<String>,
    /// Solvers of the tolerance sweep (default: every registered solver).
    #[arg(long, value_delimiter = ',')]
    pub solvers: Vec<String>,
    /// Wall-clock budget of one given-friction solve, in seconds.
    #[arg(long, default_value_t = 30.0, allow_hyphen_values = true)]
    pub time_limit: f64,
    /// Run in parallel on all cores (times are then not recorded).
    #[arg(long)]
    pub parallel: bool,
    /// Extra timed runs of each tolerance-sweep solve (time: their minimum).
    #[arg(long, default_value_t = 2)]
    pub repeats: usize,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "results")]
    pub out: PathBuf,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

impl SweepArgs {
    /// The sweep described by these flags.
    pub fn spec(&self) -> Result<SweepSpec> {
        let scenes = match &self.scene {
            Some(path) => vec![crate::io::scene_file::load(path)?.0],
            None => self
                .problems
                .iter()
                .map(|&p| Scene::paper_problem(p))
                .collect::<Result<_, _>>()?,
        };
        let mut spec = SweepSpec {
            scenes,
            meshes: self.meshes.clone(),
            factors: self.vary.clone(),
            solvers: solver_list(&self.solvers)?,
            time_limit: self.time_limit,
            parallel: self.parallel,
            repeats: self.repeats,
            ..SweepSpec::default()
        };
        if !self.r_values.is_empty() {
            spec.r_values = self.r_values.clone();
        }
        if !self.epsilon_values.is_empty() {
            spec.epsilon_values = self.epsilon_values.clone();
        }
        if !self.smoothing_values.is_empty() {
            spec.smoothing_values = self
                .smoothing_values
                .iter()
                .map(|s| {
                    contactlab_solvers::relaxation::pointwise::parse_smoothing(s)
                        .and_then(|v| serde_json::from_value(v).map_err(|e| e.to_string()))
                        .map_err(|m| anyhow::anyhow!("--smoothing-values: {m}"))
                })
                .collect::<Result<_>>()?;
        }
        if !(self.time_limit.is_finite() && self.time_limit > 0.0) {
            anyhow::bail!(
                "--time-limit = {} is invalid: give a positive number of seconds",
                self.time_limit
            );
        }
        for (name, values) in [
            ("--r-values", &spec.r_values),
            ("--epsilon-values", &spec.epsilon_values),
        ] {
            if let Some(v) = values.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
                anyhow::bail!("{name} holds {v}: every value must be a positive number");
            }
        }
        Ok(spec)
    }
}

#[derive(Debug, Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Solvers to compare (default: every registered solver).
    #[arg(long, value_delimiter = ',')]
    pub solvers: Vec<String>,
    /// Timed runs per solver after the first (the first is a warm-up and
    /// gives the accuracy figures); times are their minimum.
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "results")]
    pub out: PathBuf,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

#[derive(Debug, Args)]
pub struct Table1Args {
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "results")]
    pub out: PathBuf,
    /// Finest mesh (continuation runs 1/8, ..., h).
    #[arg(long, value_name = "1/2^k", default_value = "1/64")]
    pub h: MeshSize,
    /// Problems to run.
    #[arg(long, value_delimiter = ',', default_values_t = [1, 2, 3])]
    pub problems: Vec<u32>,
    /// Continuation schedules to run.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [Schedule::Revisit, Schedule::FinestOnly])]
    pub schedules: Vec<Schedule>,
    /// Plane strain or plane stress (default strain).
    #[arg(long, value_enum)]
    pub plane: Option<PlaneModel>,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

#[derive(Debug, Args)]
pub struct SolveArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Given-friction solver: clarabel (conic oracle) or relaxation (the
    /// paper's prox-Uzawa with pointwise relaxation and mesh continuation).
    #[arg(long, default_value = "clarabel")]
    pub solver: String,
    /// Directory for profile.csv and summary.json (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

#[derive(Debug, Args)]
pub struct InfoArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
}

/// Parses the command line and runs it; errors are one line on stderr with a
/// non-zero exit code.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind::*;
            if matches!(
                e.kind(),
                DisplayHelp | DisplayVersion | DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                e.exit();
            }
            let text = e.to_string();
            let first = text.lines().next().unwrap_or("invalid command line");
            eprintln!("{first} (see --help)");
            return ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Info(args) => info(&args),
        Command::Solve(args) => solve(&args),
        Command::Table1(args) => table1(&args),
        Command::Compare(args) => compare(&args),
        Command::Sweep(args) => sweep(&args),
        Command::Reproduce(args) => reproduce(&args),
        Command::Stability(args) => stability(&args),
        Command::Bench(args) => bench(&args),
        Command::BenchOne(args) => bench_one(&args),
    }
}

/// Logs the friction loop to stderr.
pub struct LogObserver;

impl Observer for LogObserver {
    fn observe(&mut self, p: &Progress) -> Control {
        if p.stage == fixed_point::STAGE {
            eprintln!(
                "friction iteration {:>3}: max|Δg| = {:.3e}  ({:.2} s)",
                p.iteration, p.residual, p.seconds
            );
        }
        Control::Continue
    }

    fn wants(&self, stage: &str) -> bool {
        stage == fixed_point::STAGE
    }
}

fn solve(args: &SolveArgs) -> Result<()> {
    let (scene, base) = args.scene.load()?;
    let settings = args.settings.resolve_on(base)?;
    crate::coulomb::driver::solver_entry(&args.solver)?;
    if let Some(dir) = &args.out {
        ensure_writable(dir)?;
    }
    eprintln!(
        "solving {} at h = {} with {}",
        scene.name,
        scene.finest(),
        args.solver
    );
    let run =
        crate::coulomb::driver::solve_scene(&scene, &settings, &args.solver, &mut LogObserver)?;
    let summary = run.summary(&settings);
    print_summary(&summary);
    if let Some(dir) = &args.out {
        let rows = run
            .profile
            .iter()
            .map(|r| r.values().iter().map(|v| fixed(*v)).collect::<Vec<_>>());
        write_atomic(
            &dir.join("profile.csv"),
            &csv_bytes(&PROFILE_COLUMNS, rows)?,
        )?;
        write_atomic(&dir.join("summary.json"), &json_bytes(&summary)?)?;
        println!(
            "wrote {} and {}",
            dir.join("profile.csv").display(),
            dir.join("summary.json").display()
        );
    }
    if run.status == contactlab_solvers::Status::Inaccurate {
        anyhow::bail!(
            "the answer is inaccurate: {} claims convergence but the certificate {}",
            run.solver,
            run.certificate.summary()
        );
    }
    if !run.status.is_converged() {
        anyhow::bail!(
            "the solve did not converge: {} ({})",
            run.status,
            run.coulomb.detail
        );
    }
    Ok(())
}

fn table1(args: &Table1Args) -> Result<()> {
    let settings = args.settings.resolve()?;
    ensure_writable(&args.out)?;
    for &p in &args.problems {
        Scene::paper_problem(p)?;
    }
    let plane = args.plane.unwrap_or(PlaneModel::Strain);
    let rows = crate::study::table1::table1(
        &args.problems,
        &args.schedules,
        &settings,
        args.h,
        plane,
        |p, s| {
            eprintln!("table1: problem {p}, schedule {s}");
            Box::new(LogObserver)
        },
    )?;
    for r in &rows {
        eprintln!("problem {} ({}): {:.1} s", r.problem, r.schedule, r.seconds);
    }
    let path = args.out.join("table1.csv");
    write_atomic(&path, &crate::study::table1::table1_csv(&rows)?)?;
    print!("{}", crate::study::table1::table1_markdown(&rows));
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// Fails early, before any long computation, if `dir` cannot be written.
pub fn ensure_writable(dir: &std::path::Path) -> Result<()> {
    let probe = dir.join(format!(".contactlab-write-test-{}", std::process::id()));
    std::fs::create_dir_all(dir)
        .and_then(|_| std::fs::write(&probe, b""))
        .and_then(|_| std::fs::remove_file(&probe))
        .with_context(|| {
            format!(
                "--out {}: the output directory cannot be written; choose a writable directory",
                dir.display()
            )
        })
}

/// A progress bar on stderr (hidden when stderr is not a terminal).
pub fn progress_bar(len: u64, what: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{prefix} [{bar:30}] {pos}/{len} {msg} (eta {eta})",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    bar.set_prefix(what.to_string());
    bar
}

/// The solvers named, or every registered one; unknown names are errors.
fn solver_list(names: &[String]) -> Result<Vec<&'static str>> {
    if names.is_empty() {
        return Ok(contactlab_solvers::registry::names());
    }
    names
        .iter()
        .map(|n| crate::coulomb::driver::solver_entry(n).map(|e| e.name))
        .collect()
}

fn compare(args: &CompareArgs) -> Result<()> {
    let (scene, base) = args.scene.load()?;
    let settings = args.settings.resolve_on(base)?;
    let solvers = solver_list(&args.solvers)?;
    ensure_writable(&args.out)?;
    // Two reference solves, then per solver two first runs (the oracle's are
    // the reference solves) and the timed repeats.
    let firsts = solvers
        .iter()
        .filter(|&&s| s != crate::study::compare::ORACLE)
        .count();
    let bar = progress_bar(
        (2 + 2 * firsts + 2 * solvers.len() * args.repeats) as u64,
        "compare",
    );
    let rows = crate::study::compare::compare(&scene, &settings, &solvers, args.repeats, |s| {
        bar.set_message(s.to_string());
        bar.inc(1);
    })?;
    bar.finish_and_clear();
    use crate::study::compare::*;
    write_atomic(
        &args.out.join("compare.csv"),
        &csv_bytes(&COMPARE_COLUMNS, compare_records(&rows))?,
    )?;
    write_atomic(
        &args.out.join("compare_timing.csv"),
        &csv_bytes(&COMPARE_TIMING_COLUMNS, timing_records(&rows))?,
    )?;
    print!("{}", compare_markdown(&rows));
    eprintln!(
        "wrote {}/compare.csv and compare_timing.csv",
        args.out.display()
    );
    Ok(())
}

fn sweep(args: &SweepArgs) -> Result<()> {
    let spec = args.spec()?;
    let base = match &args.scene {
        Some(path) => crate::io::scene_file::load(path)?.1,
        None => Settings::default(),
    };
    let settings = args.settings.resolve_on(base)?;
    ensure_writable(&args.out)?;
    let (rows, _) = run_sweep(&spec, &settings)?;
    write_sweep(&args.out, &rows)?;
    let failed = rows.iter().filter(|r| !r.converged).count();
    eprintln!(
        "wrote {}/sweep.csv ({} runs, {failed} did not converge), sweep_timing.csv and charts",
        args.out.display(),
        rows.len()
    );
    Ok(())
}

/// Runs a sweep with a progress bar.
/// Runs a sweep with a progress bar; also returns its references.
pub fn run_sweep(
    spec: &SweepSpec,
    settings: &Settings,
) -> Result<(
    Vec<crate::study::sweep::SweepRow>,
    Vec<crate::study::sweep::ReferenceInfo>,
)> {
    let runs = crate::study::sweep::plan(spec, settings);
    let bar = progress_bar(runs.len() as u64, "sweep");
    let rows = crate::study::sweep::sweep(spec, settings, &|run| {
        bar.set_message(format!(
            "{} = {} ({})",
            run.factor.as_str(),
            run.value,
            run.solver
        ));
        bar.inc(1);
    })?;
    bar.finish_and_clear();
    Ok(rows)
}

/// Writes sweep.csv, sweep_timing.csv and the sweep's charts.
pub fn write_sweep(
    out: &std::path::Path,
    rows: &[crate::study::sweep::SweepRow],
) -> Result<Vec<PathBuf>> {
    use crate::study::sweep::*;
    write_atomic(
        &out.join("sweep.csv"),
        &csv_bytes(&SWEEP_COLUMNS, sweep_records(rows))?,
    )?;
    write_atomic(
        &out.join("sweep_timing.csv"),
        &csv_bytes(&SWEEP_TIMING_COLUMNS, sweep_timing_records(rows))?,
    )?;
    crate::study::report::write_all(
        &out.join("charts"),
        &crate::study::report::sweep_charts(rows),
    )
}

fn reproduce(args: &ReproduceArgs) -> Result<()> {
    let settings = args.settings.resolve()?;
    ensure_writable(&args.out)?;
    let spec = if args.quick {
        ReproduceSpec::quick()
    } else {
        ReproduceSpec::full()
    };
    crate::study::reproduce::reproduce(&args.out, &spec, &settings, &|line| {
        eprintln!("reproduce: {line}")
    })?;
    eprintln!(
        "wrote {} (see {}/README.md)",
        args.out.display(),
        args.out.display()
    );
    Ok(())
}

fn stability(args: &StabilityArgs) -> Result<()> {
    let settings = args.settings.resolve()?;
    ensure_writable(&args.out)?;
    let spec = if args.quick {
        StabilitySpec::quick()
    } else {
        StabilitySpec::standard()
    };
    let rows = write_stability(&args.out, &spec, &settings, &|line| {
        eprintln!("stability: {line}")
    })?;
    let mut counts = std::collections::BTreeMap::new();
    for r in &rows {
        *counts.entry(r.class.as_str()).or_insert(0) += 1;
    }
    eprintln!("wrote {}/stability.csv: {counts:?}", args.out.display());
    Ok(())
}

/// Runs the stability map and writes its files; returns the rows.
pub fn write_stability(
    out: &std::path::Path,
    spec: &StabilitySpec,
    settings: &Settings,
    log: &dyn Fn(&str),
) -> Result<Vec<crate::study::stability::StabilityRow>> {
    use crate::study::stability::*;
    let (rows, traces) = crate::study::stability::stability(spec, settings, log)?;
    write_atomic(&out.join("stability.csv"), &stability_csv(&rows)?)?;
    write_atomic(
        &out.join("stability_friction.csv"),
        &friction_trace_csv(&traces)?,
    )?;
    crate::study::report::write_all(&out.join("charts"), &stability_charts(&rows, &traces))?;
    Ok(rows)
}

fn bench(args: &BenchArgs) -> Result<()> {
    let settings = args.settings.resolve()?;
    ensure_writable(&args.out)?;
    let mut spec = if args.quick {
        BenchSpec::quick()
    } else {
        BenchSpec::standard()
    };
    if let Some(r) = args.runs {
        spec.runs = r;
    }
    if let Some(b) = args.budget {
        if !(b.is_finite() && b > 0.0) {
            anyhow::bail!("--budget = {b} is invalid: give a positive number of seconds");
        }
        spec.budget = b;
    }
    let (_, goals, _) = crate::study::bench::write_bench(&args.out, &spec, &settings, &|l| {
        eprintln!("bench: {l}")
    })?;
    print!("{}", crate::study::bench::goals_markdown(&goals));
    eprintln!(
        "wrote {}/performance.csv, performance_goals.md and charts",
        args.out.display()
    );
    Ok(())
}

fn bench_one(args: &BenchOneArgs) -> Result<()> {
    let scene = args.scene.resolve()?;
    faer::set_global_parallelism(faer::Par::Seq);
    let run = crate::coulomb::driver::solve_scene(
        &scene,
        &Settings::default(),
        &args.solver,
        &mut contactlab_solvers::Silent,
    )?;
    let peak = crate::study::bench::peak_memory_kb();
    println!(
        "{}",
        serde_json::json!({"seconds": run.coulomb.seconds, "status": run.coulomb.status.to_string(), "peak_kb": peak})
    );
    Ok(())
}

fn print_summary(s: &crate::coulomb::driver::Summary) {
    let intervals: Vec<String> = s
        .separated_intervals
        .iter()
        .map(|[a, b]| format!("[{a:.4}, {b:.4}]"))
        .collect();
    println!(
        "{}, h = {}, solver {}, plane {}, friction coefficient {}",
        s.problem, s.h, s.solver, s.plane, s.friction_coefficient
    );
    println!(
        "status              {} (solver's claim: {}; {})",
        s.status, s.solver_status, s.detail
    );
    println!("friction iterations {}", s.friction_iterations);
    println!(
        "separated           {} = {:.2}% of Γ_K (jump < -{:.1e})",
        if intervals.is_empty() {
            "none".to_string()
        } else {
            intervals.join(" ∪ ")
        },
        100.0 * s.separated_fraction,
        s.separation_tolerance
    );
    println!("max pressure        {:.6}", s.max_pressure);
    println!(
        "contact force       {:.10} (applied load {})",
        s.total_contact_force, s.total_applied_load
    );
    println!("objective           {:.10e}", s.objective);
    println!("certificate         {}", s.certificate_summary);
    println!(
        "iterations          {} outer, {} inner",
        s.iterations_outer, s.iterations_inner
    );
    println!(
        "time                {:.3} s (set-up {:.3} s)",
        s.seconds, s.seconds_setup
    );
}

fn info(args: &InfoArgs) -> Result<()> {
    let scene = args.scene.resolve()?;
    let h = scene.finest();
    let d = Discretization::new(&scene, h).context("building the discretization")?;
    let p = &d.problem;
    let kernel = crate::solvers::linalg::kernel_dimension(p.a(), KERNEL_PIVOT_TOL)
        .context("measuring the kernel of A")?;
    let applied: f64 = d.forces.iter().map(|f| f[1]).sum();
    println!(
        "scene              {} (plane {}, E = {}, ν = {}, 𝓕 = {})",
        scene.name,
        scene.material.plane,
        scene.material.young,
        scene.material.poisson,
        scene.friction
    );
    println!("h                  {h}");
    println!(
        "nodes              {} (n = {}, N = n² + n)",
        d.mesh.num_nodes(),
        d.mesh.n()
    );
    println!("elements           {}", d.mesh.num_elements());
    println!("free unknowns      {}", p.n());
    println!("nonzeros of A      {}", p.a().nnz());
    println!("contact nodes      {}", p.contacts().len());
    println!(
        "applied load       {applied:.12} (vertical, on the upper body; scene total {:.12})",
        d.total_load
    );
    println!(
        "dim ker A          {kernel} (measured: Cholesky pivots below {KERNEL_PIVOT_TOL:e}·max diag)"
    );
    let sc = p.scales();
    println!(
        "scales             load F = {:.6e}, length L = {:.6e}, stiffness K = {:.6e}, pressure P = {:.6e}, displacement U = {:.6e}",
        sc.force, sc.length, sc.stiffness, sc.pressure, sc.displacement
    );
    Ok(())
}

/// Relative pivot threshold for the measured kernel dimension.
pub const KERNEL_PIVOT_TOL: f64 = 1e-9;
