//! The `contactlab` command line: parsing and dispatch only; each command
//! lives in [`crate::commands`]. Logs and progress go to stderr, data to
//! files or stdout; an error is one line on stderr and a non-zero exit.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::{Args, Parser, Subcommand};
use contactlab_solvers::registry;

use crate::mechanics::mesh_size::MeshSize;

pub mod scene_args;
pub mod settings_args;

pub use scene_args::SceneArgs;
pub use settings_args::{
    AllSolvers, PapersMethod, SettingsArgs, SolverSet, knob_set, old_spelling, with_flag,
};

/// contactlab: verify a fast iterative contact solver against a conic oracle on
/// the semicoercive two-body contact problem with Coulomb friction of
/// Zhiltsov & Namm (2019). Every answer is certified against the problem.
#[derive(Debug, Parser)]
#[command(name = "contactlab", version, propagate_version = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Print the sizes of a discretized scene: nodes, elements, free unknowns,
    /// nonzeros of A, contact nodes, the applied load, the measured dimension
    /// of the kernel of A and the problem's scales.
    Info(InfoArgs),
    /// Every setting of the fixed point and of each solver (or of one): its
    /// path for --set and scene files, its flag, its default and the paper's
    /// value. `solve --help` leaves these out.
    Settings(SettingsListArgs),
    /// Solve a scene's Coulomb problem with one solver and certify the answer.
    /// Prints a summary; with --out writes profile.csv, summary.json and the
    /// answer (displacements.mtx, forces.csv; field.vtu with --vtu).
    Solve(SolveArgs),
    /// Compare every registered solver on one scene, against the most
    /// accurate certified answer (the reference): the given-friction
    /// subproblem at the reference's g and the whole Coulomb problem. Prints
    /// a Markdown table; with --out writes compare.csv, compare_timing.csv and
    /// references.csv.
    Compare(CompareArgs),
    /// One-factor sweeps of each solver's settings (from the registry, or
    /// --vary) on the Coulomb problem, and every solver through its accuracy
    /// knob on the subproblem (a work-precision diagram). Writes sweep.csv,
    /// sweep_timing.csv, references.csv and charts into --out.
    Sweep(SweepArgs),
    /// The main job: Table 1, the comparison of every solver on the paper's
    /// three problems, profiles, a sweep, the stability map, the speed
    /// measurements of `bench`, the benchmark, the discretization error, the
    /// oracle at 1/128, the error bound's validity and sharpness, a
    /// side-by-side at 1/64, r × ε maps, the verification against closed
    /// forms (h = 1/32 ... 1/128, 6 s a solve), charts, a manifest and a
    /// README, all into --out (default results/). About 20 min on 2
    /// cores (19.8 measured); --long adds what takes longer (each
    /// study's long budget: the paper's method by sweeps at equal accuracy
    /// on 1/128 and 1/256, bench to 1/8192, the whole benchmark collection,
    /// the oracle at 1/256, the error bound and the closed forms to 1/1024):
    /// about 2.5 h. It states its estimate as it starts; the manifest
    /// records each study's time (--quick: a minute).
    Reproduce(ReproduceArgs),
    /// Success over a problem collection (not to be confused with `bench`,
    /// speed against the mesh size), the paper's problems over
    /// 𝓕 and h, sideways loads, nearly unbounded loads and fine meshes: every
    /// solver on every instance at each target accuracy, with a time limit
    /// per run. Writes benchmark.csv (one row per run), success rates,
    /// shifted geometric means and performance profiles into --out. With
    /// --shard K/N it runs every N-th instance; merge shards with
    /// benchmark-merge.
    Benchmark(BenchmarkArgs),
    /// Merge the folders of benchmark shards into one set of tables and
    /// charts.
    BenchmarkMerge(BenchmarkMergeArgs),
    /// Write a scene's problem (its finest level) as files any scientific
    /// code reads: A, M, f and the rigid mode in Matrix Market, the contact
    /// nodes' indices, weights, bounds and coefficients as CSV, the condensed
    /// form on the contact unknowns, and problem.json (statement, signs,
    /// units, scales).
    Export(ExportArgs),
    /// Certify an answer computed elsewhere for an exported problem:
    /// displacements, contact forces per node, or both. Prints every
    /// condition's violation; an answer that fails is a non-zero exit.
    Certify(CertifyArgs),
    /// (internal) Solve one scene and print time and peak memory as JSON.
    #[command(hide = true)]
    BenchOne(BenchOneArgs),
    /// The catalogued studies, one command each (`study::catalog`).
    #[command(flatten)]
    Study(crate::commands::study::StudyCommand),
}

/// The names of the registered solvers, for clap.
fn solver_names() -> Vec<&'static str> {
    registry::names()
}

#[derive(Debug, Args)]
pub struct SettingsListArgs {
    /// Only this solver's settings.
    #[arg(value_parser = clap::builder::PossibleValuesParser::new(solver_names()))]
    pub solver: Option<String>,
}

#[derive(Debug, Args)]
pub struct InfoArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
}

#[derive(Debug, Args)]
pub struct SolveArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The solver [default: the conic oracle].
    #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(solver_names()))]
    pub solver: Option<String>,
    /// Folder for profile.csv, summary.json, displacements.mtx and forces.csv (with --vtu also field.vtu; replaced whole).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Also write field.vtu into --out: both bodies for ParaView, with
    /// displacement, stress, von Mises stress and the contact state.
    #[arg(long, requires = "out")]
    pub vtu: bool,
    /// Wall-clock limit on the solve in seconds: past it the solver stops
    /// with the status time_limit, and the answer it had is certified and
    /// written like any other (a non-zero exit says it stopped) [default:
    /// none].
    #[arg(long = "time-limit", value_name = "SECONDS", value_parser = positive_seconds)]
    pub time_limit: Option<f64>,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

#[derive(Debug, Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Solvers to compare [default: every registered solver].
    #[arg(long, value_delimiter = ',', value_parser = clap::builder::PossibleValuesParser::new(solver_names()))]
    pub solvers: Vec<String>,
    /// Timed runs per trial after the first, warm-up run (times: their
    /// minimum and median).
    #[arg(long = "runs", value_name = "RUNS", default_value_t = 3, value_parser = clap::value_parser!(u64).range(0..=100))]
    pub repeats: u64,
    /// Folder for compare.csv, compare_timing.csv, compare_given_friction.tex and compare_coulomb.tex (LaTeX, one table per law) and references.csv (replaced whole); with --side-by-side for side_by_side.csv, side_by_side_<A>_<B>.csv and charts/.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// The reference to measure against, a solver's name: its answer at its
    /// tightest settings, if certified [default: earned, the most accurate
    /// certified answer of the exact solvers].
    #[arg(long, value_name = "SOLVER", value_parser = clap::builder::PossibleValuesParser::new(solver_names()))]
    pub reference: Option<String>,
    /// Instead of every solver against the reference: two answers of the Coulomb problem node by node, `A,B`, each a solver, `reference` (the earned one) or a profile.csv of `contactlab solve --out` (repeatable). Writes side_by_side_<A>_<B>.csv (u, jump, slip, p, q of both at every contact node, their differences over U and P, contact states matched), side_by_side.csv (the largest differences) and two charts per pair (overlay, difference).
    #[arg(long = "side-by-side", value_name = "A,B", conflicts_with = "solvers")]
    pub side_by_side: Vec<String>,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

#[derive(Debug, Args)]
pub struct SweepArgs {
    /// The paper's problems to sweep, `1,3` (or `1 3`).
    #[arg(long = "problem", value_name = "N", value_delimiter = ',', num_args = 1.., default_values_t = [1], conflicts_with = "scene")]
    pub problems: Vec<u32>,
    /// A scene file to sweep instead (its settings are the base settings).
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Finest meshes (each with continuation from 1/8).
    #[arg(long = "h", value_name = "1/2^k", value_delimiter = ',', default_values_t = [MeshSize::from_level(5).expect("in range")])]
    pub meshes: Vec<MeshSize>,
    /// Fine meshes on which solvers that have a fast form there are swept
    /// in it, measured by their certificates (no reference): the paper's
    /// method with its inner minimization by multigrid, over r and ε
    /// (e.g. --fine-h 1/256; about 30 s at 1/256). Not with --vary.
    #[arg(
        long = "fine-h",
        value_name = "1/2^k",
        value_delimiter = ',',
        conflicts_with = "vary"
    )]
    pub fine_meshes: Vec<MeshSize>,
    /// Solvers to sweep [default: every registered solver].
    #[arg(long, value_delimiter = ',', value_parser = clap::builder::PossibleValuesParser::new(solver_names()))]
    pub solvers: Vec<String>,
    /// Vary one setting instead of the registry's variations:
    /// PATH=V1,V2,... (repeatable), e.g. --vary SOLVER.KNOB=1e3,1e5,1e7.
    #[arg(long, value_name = "PATH=VALUES")]
    pub vary: Vec<String>,
    /// A tuning map instead of the one-factor sweeps: a joint grid over
    /// two or three settings of one solver, PATH=V1,V2,... each (e.g.
    /// --grid relaxation.r=1e3,1e5,1e7 --grid relaxation.epsilon=1e-4,1e-6).
    /// Every point timed over --runs and certified; heat maps of time and
    /// work titled with the form mapped; the best setting by work (then by
    /// time among points of equal work, ties within the timing noise
    /// marked) and how much each axis moves the work. Beyond h = 1/64 a solver is mapped in its fast form (the
    /// paper's method with inner = multigrid) unless --set says otherwise.
    /// Writes tuning_map_<solver>_<law>_h<N>.csv, its trials and charts.
    #[arg(long, value_name = "PATH=VALUES", conflicts_with_all = ["vary", "fine_meshes"])]
    pub grid: Vec<String>,
    /// The law a tuning map solves: the whole Coulomb problem, or the
    /// given-friction subproblem at the reference's bound (faster: one
    /// solve a point).
    #[arg(long, value_enum, default_value = "coulomb", requires = "grid")]
    pub law: MapLaw,
    /// A tuning map's time limit per solve: each point's solve stops after
    /// SECONDS with the status time_limit (its answer certified or not as
    /// it stands, and drawn as not certified when it fails), so that a map
    /// of the paper's form at h = 1/128 and finer fits a budget of at most
    /// points × runs × SECONDS, which the map states before it starts.
    #[arg(long = "time-limit", value_name = "SECONDS", value_parser = positive_seconds, requires = "grid")]
    pub time_limit: Option<f64>,
    /// Skip the work-precision diagram.
    #[arg(long)]
    pub no_work_precision: bool,
    /// The registry's short value lists.
    #[arg(long)]
    pub quick: bool,
    /// Timed runs of each work-precision trial after the first, warm-up
    /// run.
    #[arg(long = "runs", value_name = "RUNS", default_value_t = 2, value_parser = clap::value_parser!(u64).range(0..=100))]
    pub repeats: u64,
    #[command(flatten)]
    pub material: crate::cli::scene_args::MaterialArgs,
    /// Output folder (replaced whole).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

/// The law of a tuning map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MapLaw {
    Coulomb,
    GivenFriction,
}

impl MapLaw {
    pub fn law(self) -> contactlab_solvers::Law {
        match self {
            MapLaw::Coulomb => contactlab_solvers::Law::Coulomb,
            MapLaw::GivenFriction => contactlab_solvers::Law::GivenFriction,
        }
    }
}

#[derive(Debug, Args)]
pub struct ReproduceArgs {
    /// A small run for tests and smoke checks (h = 1/16, fewer points).
    #[arg(long, conflicts_with = "long")]
    pub quick: bool,
    /// Also the studies that take hours (about 2.5 h on a 2-core machine):
    /// the paper's method by sweeps at equal accuracy on 1/128 and 1/256,
    /// bench's solvers with three timed runs each and 15 s per run and its
    /// multigrid to 1/8192, the whole benchmark collection (81 instances,
    /// not its core 46 up to h = 1/32), and every study at its long budget.
    /// Without it the run takes about 20 min (19.8 measured).
    #[arg(long)]
    pub long: bool,
    /// Output folder (replaced whole) [default: results; with --quick:
    /// results-quick, so that a smoke run never replaces the committed study].
    /// The run is written study by study into DIR.partial beside it, which
    /// an interrupted or failed run leaves for --resume.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Continue the run that was interrupted in DIR.partial: the studies it
    /// finished are kept, the others run. Refused if that run was started
    /// by another build, with other settings or another choice of --quick
    /// and --long. Without it an interrupted run is started anew.
    #[arg(long)]
    pub resume: bool,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

#[derive(Debug, Args)]
pub struct BenchmarkArgs {
    /// A small collection for tests (6 instances at h = 1/8, 5 s per run).
    #[arg(long)]
    pub quick: bool,
    /// Run every N-th instance from the K-th (1-based), e.g. 2/8.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<crate::study::benchmark::Shard>,
    /// Wall-clock limit per run in seconds [default: 20; quick: 5].
    #[arg(long, value_name = "SECONDS", value_parser = positive_seconds)]
    pub time_limit: Option<f64>,
    /// Target accuracies in the certificate's measure [default: 1e-4,1e-8].
    #[arg(long, value_delimiter = ',', value_name = "TOL", value_parser = positive_tolerance)]
    pub targets: Vec<f64>,
    /// Solvers to run [default: every registered solver].
    #[arg(long, value_delimiter = ',', value_parser = clap::builder::PossibleValuesParser::new(solver_names()))]
    pub solvers: Vec<String>,
    /// Instead of the collection: the paper's problems N (e.g. 1 or 1,3),
    /// each on the mesh --h, as the Python package's `benchmark` runs the
    /// problems it is given (instances "problem N, h = 1/64", family
    /// "given").
    #[arg(long, value_delimiter = ',', value_name = "N", value_parser = clap::value_parser!(u32).range(1..=3))]
    pub problem: Vec<u32>,
    /// The finest mesh of the --problem instances [default: 1/64].
    #[arg(long, value_name = "H", requires = "problem")]
    pub h: Option<crate::mechanics::mesh_size::MeshSize>,
    /// Output folder (replaced whole).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

#[derive(Debug, Args)]
pub struct BenchmarkMergeArgs {
    /// The shards' output folders.
    #[arg(required = true, value_name = "SHARD_DIR")]
    pub shards: Vec<PathBuf>,
    /// Output folder (replaced whole).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

pub use crate::study::catalog::MAX_SECONDS;

fn positive_seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x > 0.0 && x <= MAX_SECONDS => Ok(x),
        _ => Err(format!(
            "'{s}': give a positive number of seconds up to a week ({MAX_SECONDS}), e.g. 20"
        )),
    }
}

fn friction_bound(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(g) if g.is_finite() && g >= 0.0 && g < crate::mechanics::scene::MAGNITUDES.1 => Ok(g),
        _ => Err(format!(
            "'{s}': give a friction bound (force per length) ≥ 0, e.g. 10"
        )),
    }
}

fn positive_tolerance(s: &str) -> Result<f64, String> {
    let t = s
        .trim()
        .parse::<f64>()
        .map_err(|_| format!("'{s}': give a tolerance such as 1e-6"))?;
    crate::certificate::check_tolerance(t).map_err(|_| {
        format!(
            "give a tolerance in (0, {:e}]",
            crate::certificate::MAX_TOLERANCE
        )
    })
}

#[derive(Debug, Args)]
pub struct ExportArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// A uniform friction bound g (force per length) to state in
    /// contact.csv, making the instance a given-friction subproblem that
    /// `certify --given-friction` checks; without it the column g is empty.
    #[arg(long, value_name = "G", value_parser = friction_bound)]
    pub friction_bound: Option<f64>,
    /// Output folder (replaced whole).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

#[derive(Debug, Args)]
pub struct CertifyArgs {
    /// A folder written by `contactlab export`.
    #[arg(long, value_name = "DIR")]
    pub instance: PathBuf,
    /// The displacements v, n values in the order of the exported unknowns:
    /// Matrix Market (.mtx, one column) or one number per line.
    #[arg(long, value_name = "FILE")]
    pub displacements: Option<PathBuf>,
    /// The contact forces: CSV with columns pressure,friction_traction, one
    /// row per contact node in the order of contact.csv.
    #[arg(long, value_name = "FILE")]
    pub forces: Option<PathBuf>,
    /// Check the given-friction subproblem at the exported bounds g
    /// instead of the Coulomb problem.
    #[arg(long)]
    pub given_friction: bool,
    /// The certificate's tolerance: the largest violation of any condition,
    /// in the problem's scales, that certifies the answer (as `--certify-tol`
    /// everywhere else).
    #[arg(long = "certify-tol", value_name = "TOL", default_value = "1e-5", value_parser = positive_tolerance)]
    pub tolerance: f64,
}

#[derive(Debug, Args)]
pub struct BenchOneArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[arg(long)]
    pub solver: String,
    /// The settings flags of every command (--schedule, --set, …).
    #[command(flatten)]
    pub settings: SettingsArgs,
}

/// Parses the command line and runs it; errors are one line on stderr with a
/// non-zero exit code.
pub fn main() -> ExitCode {
    crate::allocator::keep_freed_memory();
    let args: Vec<String> = std::env::args().collect();
    if let Some(hint) = settings_args::old_spelling(&args[1..]) {
        crate::io::output::log(format!("error: {hint}"));
        return ExitCode::from(2);
    }
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind::*;
            if matches!(
                e.kind(),
                DisplayHelp | DisplayVersion | DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                let _ = e.print();
                return ExitCode::SUCCESS;
            }
            // One line: clap's message up to its usage, e.g. "error: the
            // following required arguments were not provided: --out <DIR>".
            let text = e.to_string();
            let line = text
                .lines()
                .take_while(|l| !l.starts_with("Usage:"))
                .map(str::trim)
                .filter(|l| {
                    !l.is_empty()
                        && !l.starts_with("tip:")
                        && !l.starts_with("For more information")
                })
                .collect::<Vec<_>>()
                .join(" ");
            crate::io::output::log(format!("{line} (see --help)"));
            return ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            crate::io::output::log(format!("error: {e:#}"));
            ExitCode::FAILURE
        }
    }
}

/// Runs a parsed command.
pub fn run(cli: Cli) -> Result<()> {
    use crate::commands as c;
    match cli.command {
        Command::Info(a) => c::info::run(&a),
        Command::Settings(a) => c::settings::run(&a),
        Command::Solve(a) => c::solve::run(&a),
        Command::Compare(a) => c::compare::run(&a),
        Command::Sweep(a) => c::sweep::run(&a),
        Command::Reproduce(a) => c::reproduce::run(&a),
        Command::Benchmark(a) => c::benchmark::run(&a),
        Command::BenchmarkMerge(a) => c::benchmark::merge(&a),
        Command::Export(a) => c::export::run(&a),
        Command::Certify(a) => c::certify::run(&a),
        Command::BenchOne(a) => c::bench::run_one(&a),
        Command::Study(a) => c::study::run(&a),
    }
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    /// clap's own checks of the whole command line, every command with
    /// its flags (the catalogued studies' made from their specs beside the
    /// settings' flags): a flag two sources declare, a default that does
    /// not parse, or a conflict naming no flag fails here, in release too.
    #[test]
    fn the_command_line_passes_clap_s_checks() {
        super::Cli::command().debug_assert();
    }
}
