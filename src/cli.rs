//! The `contactlab` command line. Logs go to stderr, data to files or stdout.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};

use crate::discretization::Discretization;
use crate::material::PlaneModel;
use crate::mesh_size::MeshSize;
use crate::scene::Scene;

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
}

/// Which scene, on which mesh, with which material: a built-in problem of the
/// paper or a scene file, with optional overrides.
#[derive(Debug, Clone, Args)]
pub struct SceneArgs {
    /// The paper's problem: 1 (P''_2 = -60 on the left third of the top side),
    /// 2 (-120 on the left third) or 3 (-60 on the whole top side).
    #[arg(
        long,
        value_name = "N",
        required_unless_present = "scene",
        conflicts_with = "scene"
    )]
    pub problem: Option<u32>,
    /// A scene file (TOML) instead of a built-in problem.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Finest mesh size h = 1/2^k in the paper's notation (e.g. 1/64); the
    /// continuation levels run 1/8, 1/16, ..., h. Default: the scene's levels
    /// (the paper's 1/8 to 1/64).
    #[arg(long, value_name = "1/2^k")]
    pub h: Option<MeshSize>,
    /// Young's modulus E (default 73e3).
    #[arg(long, value_name = "E", allow_hyphen_values = true)]
    pub young: Option<f64>,
    /// Poisson's ratio ν, in (-1, 0.5) (default 0.34).
    #[arg(long, value_name = "NU", allow_hyphen_values = true)]
    pub poisson: Option<f64>,
    /// Plane strain or plane stress (default strain; the paper does not say).
    #[arg(long, value_enum)]
    pub plane: Option<PlaneModel>,
    /// Coulomb friction coefficient 𝓕 ≥ 0 (default 0.5; 0 is frictionless).
    #[arg(long, value_name = "F", allow_hyphen_values = true)]
    pub friction: Option<f64>,
}

impl SceneArgs {
    /// The scene with the overrides applied, validated (condition (13) included).
    pub fn resolve(&self) -> Result<Scene> {
        let mut scene = match (&self.scene, self.problem) {
            (Some(path), _) => crate::scene_file::load(path)?,
            (None, Some(n)) => Scene::paper_problem(n)?,
            (None, None) => anyhow::bail!("give --problem N or --scene FILE"),
        };
        if let Some(h) = self.h {
            scene.set_finest(h);
        }
        if let Some(e) = self.young {
            scene.material.young = e;
        }
        if let Some(nu) = self.poisson {
            scene.material.poisson = nu;
        }
        if let Some(p) = self.plane {
            scene.material.plane = p;
        }
        if let Some(f) = self.friction {
            scene.friction = f;
        }
        scene.validate()?;
        Ok(scene)
    }
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
    }
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
    Ok(())
}

/// Relative pivot threshold for the measured kernel dimension.
pub const KERNEL_PIVOT_TOL: f64 = 1e-9;
