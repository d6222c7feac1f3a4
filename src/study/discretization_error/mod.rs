//! The discretization error: how the discrete Coulomb solution converges as
//! h → 0, against the finest mesh as the reference.
//!
//! The meshes h = 1/2^k are nested (same diagonal direction), so a coarse
//! P1 field is also a fine P1 field: it is interpolated onto the reference
//! mesh exactly, and with e = u_h − u_ref the norms
//!
//! ```text
//! ‖e‖²_L2 = ∫ |e|²,   ‖e‖²_energy = A(e, e) = ∫ σ(e):ε(e)
//! ```
//!
//! are summed exactly, element by element over the reference mesh, of the
//! nodal fields. Not through the reference's unknowns: the coarse answer
//! does not satisfy the reference's roller condition next to the upper
//! body's free corner (see `errors`). The pressure
//! is compared at the coarse contact nodes (which are reference nodes too),
//! the separated zone by its start. Every solution is certified. The
//! standard study's reference is h = 1/4096 (33.6 million unknowns),
//! which only the multigrid solver reaches, in about 46 s and 3.9 GiB
//! (the speed study's row); 1/2048, the reference before, took 2 minutes
//! and 8.4 GB when it was chosen. `tnnmg` under the nested schedule
//! solves every mesh, the friction fixed point to its default ε = 1e-7 of
//! 𝓕P, two decades below the smallest error measured against 1/2048 (3e-5
//! in L2 at 1/512, falling as h^1.7); it agrees with the direct
//! `newton-coulomb` to about 1e-11 of P at 1/256 (the speed study's goal
//! row).
//! Without a solver of its own a spec uses a direct Coulomb solver, so that
//! no fixed-point tolerance enters (in `reproduce --quick`, the fastest of
//! the speed study).

use anyhow::{Context, Result};
use serde::Serialize;

use crate::coulomb::continuation::Schedule;
use crate::io::csv::fixed;
use crate::mechanics::assembly::{energy_norm_squared, l2_norm_squared};
use crate::mechanics::material::Material;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::solve::{Solved, solve_scene, solver_entry};
use crate::solvers::{Friction, Law, Silent, registry};
use crate::study::bench::FastestDirect;
use crate::study::lab::{Artifact, Lab, Ran, RunLength, Section, Study, chart_markdown};

mod views;
pub use views::{PAPERS_ZONE_START, charts, findings, markdown};

/// Which problems, on which meshes, against which reference mesh.
#[derive(Clone, Debug, Serialize)]
pub struct ErrorSpec {
    pub problems: Vec<u32>,
    pub meshes: Vec<MeshSize>,
    pub reference: MeshSize,
    /// The solver (None: the registry's first direct Coulomb solver).
    pub solver: Option<&'static str>,
    /// The mesh continuation it runs with (None: the settings').
    pub schedule: Option<Schedule>,
}

impl ErrorSpec {
    /// Problems 1 and 3, h = 1/16 to 1/1024 against 1/4096 (the finest
    /// mesh compared a quarter of the reference's size, as 1/512 was of
    /// 1/2048), by `tnnmg` under the nested schedule.
    pub fn standard() -> Self {
        Self {
            problems: vec![1, 3],
            meshes: (4..=10).map(level).collect(),
            reference: level(12),
            solver: Some(MULTIGRID),
            schedule: Some(Schedule::Nested),
        }
    }

    /// 1/8 and 1/16 against 1/32: for tests.
    pub fn quick() -> Self {
        Self {
            problems: vec![1, 3],
            meshes: vec![level(3), level(4)],
            reference: level(5),
            solver: None,
            schedule: None,
        }
    }
}

fn level(k: u32) -> MeshSize {
    MeshSize::from_level(k).expect("in range")
}

/// One problem on one mesh against the reference.
#[derive(Clone, Debug, Serialize)]
pub struct ErrorRow {
    pub problem: u32,
    pub h: String,
    pub reference_h: String,
    pub solver: String,
    pub status: String,
    #[serde(serialize_with = "fixed")]
    pub certificate: f64,
    /// ‖u_h − u_ref‖_L2 / ‖u_ref‖_L2.
    #[serde(serialize_with = "fixed")]
    pub l2_error: f64,
    /// ‖u_h − u_ref‖_A / ‖u_ref‖_A.
    #[serde(serialize_with = "fixed")]
    pub energy_error: f64,
    /// max over the contact nodes of |p_h − p_ref| / max p_ref.
    #[serde(serialize_with = "fixed")]
    pub pressure_error: f64,
    /// Start of the separated zone (NaN: none).
    #[serde(serialize_with = "fixed")]
    pub zone_start: f64,
    /// |zone start − the reference's|.
    #[serde(serialize_with = "fixed")]
    pub zone_start_error: f64,
    #[serde(serialize_with = "fixed")]
    pub separated_fraction: f64,
    /// Observed orders log2(e(2h)/e(h)) against the next coarser mesh
    /// (NaN on the coarsest).
    #[serde(serialize_with = "fixed")]
    pub l2_rate: f64,
    #[serde(serialize_with = "fixed")]
    pub energy_rate: f64,
    #[serde(serialize_with = "fixed")]
    pub pressure_rate: f64,
}

/// The solver of the standard study: the one that reaches its reference.
pub const MULTIGRID: &str = "tnnmg";

/// What the report says of the study's solver (after its name).
pub fn solver_note(solver: &str) -> &'static str {
    if solver == MULTIGRID {
        ", under the nested schedule, the one solver that reaches the reference mesh here; its friction fixed point ends at the default ε = 1e-7 of 𝓕P, far below the smallest error measured, and it agrees with `newton-coulomb` to about 1e-11 of P (the speed study's goal row)"
    } else {
        ", the fastest direct Coulomb solver of the speed study, so that no fixed-point tolerance enters"
    }
}

/// The solver the study uses: the spec's (the Coulomb law directly or
/// through the friction fixed point), or the registry's first direct
/// Coulomb solver.
fn solver(spec: &ErrorSpec) -> Result<&'static str> {
    if let Some(name) = spec.solver {
        let e = registry::by_name(name).context("unknown solver")?;
        anyhow::ensure!(
            e.solves(Law::Coulomb) || e.solves(Law::GivenFriction),
            "{name} solves neither the Coulomb law nor the given-friction problem"
        );
        return Ok(e.name);
    }
    registry::solvers()
        .into_iter()
        .find(|e| e.solves(Law::Coulomb))
        .map(|e| e.name)
        .context("no registered solver solves the Coulomb law directly")
}

fn solve(problem: u32, h: MeshSize, solver: &str, settings: &Settings) -> Result<Solved> {
    let scene = Scene::paper_problem_to(problem, h)?;
    solve_scene(
        &scene,
        Friction::Coulomb,
        solver_entry(solver)?,
        settings,
        &mut Silent,
    )
}

fn zone_start(run: &Solved) -> f64 {
    run.separation()
        .intervals
        .first()
        .map_or(f64::NAN, |iv| iv[0])
}

/// The errors of `coarse` against `reference` for `problem` (whose bodies
/// are of `material`), without rates.
///
/// Both norms are summed element by element over the reference mesh, of
/// the nodal fields, not through the reference's unknowns: the coarse
/// answer is not in the reference's space. The roller Γ''_u = {x = 1,
/// ½ < y ≤ 1} leaves the upper body's corner (1, ½) free, so the coarse
/// u_x falls to 0 along one coarse edge of x = 1, where the reference's
/// falls along one fine edge. Mapped to the reference's unknowns, the
/// coarse field lost its u_x on the fine roller nodes of that edge, and
/// the energy of that layer grew as h_coarse/h_ref: the energy error of
/// problem 3 at h = 1/16 read 0.43 against 1/2048 and 0.61 against 1/4096.
fn errors(problem: u32, material: &Material, coarse: &Solved, reference: &Solved) -> ErrorRow {
    let (dc, df) = (&coarse.finest, &reference.finest);
    let uc = dc.displacements(&coarse.outcome.solution.v);
    let uf = df.displacements(&reference.outcome.solution.v);
    let e: Vec<[f64; 2]> = (0..df.mesh.num_nodes())
        .map(|node| {
            let (body, _, _) = df.mesh.locate(node);
            let [x, y] = df.mesh.coords(node);
            let at = dc.evaluate(&uc, body, x, y);
            [at[0] - uf[node][0], at[1] - uf[node][1]]
        })
        .collect();
    let l2_norm = |u: &[[f64; 2]]| l2_norm_squared(&df.mesh, u).max(0.0).sqrt();
    let energy_norm = |u: &[[f64; 2]]| energy_norm_squared(&df.mesh, material, u).max(0.0).sqrt();
    let (l2, energy) = (
        l2_norm(&e) / l2_norm(&uf),
        energy_norm(&e) / energy_norm(&uf),
    );
    // Coarse contact node i sits at reference contact node i·ratio.
    let ratio = 1usize << (df.h().level() - dc.h().level());
    let pf: Vec<f64> = reference.outcome.solution.pressure.clone();
    let p_max = pf.iter().fold(0.0f64, |m, x| m.max(*x));
    let pressure_error = coarse
        .outcome
        .solution
        .pressure
        .iter()
        .enumerate()
        .map(|(i, p)| (p - pf[i * ratio]).abs())
        .fold(0.0f64, f64::max)
        / p_max;
    let (start, start_ref) = (zone_start(coarse), zone_start(reference));
    ErrorRow {
        problem,
        h: dc.h().to_string(),
        reference_h: df.h().to_string(),
        solver: coarse.outcome.solver.name.to_string(),
        status: coarse.outcome.status.as_str().to_string(),
        certificate: coarse.outcome.certificate.residual(),
        l2_error: l2,
        energy_error: energy,
        pressure_error,
        zone_start: start,
        zone_start_error: (start - start_ref).abs(),
        separated_fraction: coarse.separation().fraction,
        l2_rate: f64::NAN,
        energy_rate: f64::NAN,
        pressure_rate: f64::NAN,
    }
}

/// Solves every problem on every mesh and on the reference mesh, and
/// measures the errors. `log` receives a line per solve.
pub fn run(spec: &ErrorSpec, settings: &Settings, log: &dyn Fn(&str)) -> Result<Vec<ErrorRow>> {
    let mut rows = Vec::new();
    let solver = solver(spec)?;
    let mut settings = settings.clone();
    if let Some(schedule) = spec.schedule {
        settings.schedule = Some(schedule);
    }
    let settings = &settings;
    for &problem in &spec.problems {
        log(&format!(
            "problem {problem}: reference at h = {}",
            spec.reference
        ));
        let material = Scene::paper_problem(problem)?.material;
        let reference = solve(problem, spec.reference, solver, settings)?;
        anyhow::ensure!(
            reference.outcome.certificate.passed(),
            "the reference of problem {problem} at h = {} is not certified: {}",
            spec.reference,
            reference.outcome.certificate.summary()
        );
        let mut previous: Option<ErrorRow> = None;
        for &h in &spec.meshes {
            log(&format!("problem {problem}: h = {h}"));
            let coarse = solve(problem, h, solver, settings)?;
            let mut row = errors(problem, &material, &coarse, &reference);
            if let Some(prev) = &previous {
                let rate = |a: f64, b: f64| (a / b).log2();
                row.l2_rate = rate(prev.l2_error, row.l2_error);
                row.energy_rate = rate(prev.energy_error, row.energy_error);
                row.pressure_rate = rate(prev.pressure_error, row.pressure_error);
            }
            previous = Some(row.clone());
            rows.push(row);
        }
    }
    Ok(rows)
}

/// The discretization error as a study: discretization_error.csv and its
/// charts. Its solver is the spec's, else the direct one certified on the
/// reference mesh in the speed study run before it, else the fastest
/// certified on that study's finest mesh.
pub struct Errors {
    pub spec: ErrorSpec,
}

impl Study for Errors {
    /// One row per mesh.
    type Findings = Vec<ErrorRow>;

    fn name(&self) -> &'static str {
        "discretization_error"
    }

    fn estimated_seconds(&self, length: RunLength) -> f64 {
        match length {
            RunLength::Quick => 1.4,
            // Two references at 1/4096, about 46 s each.
            _ => 150.0,
        }
    }

    fn section(&self, errors: &Vec<ErrorRow>, _: &Lab, charts: &[String]) -> Result<Section> {
        let solver = errors.first().map_or("", |r| r.solver.as_str());
        let mut s = format!(
            "## Discretization error\n\nHow the discrete solution converges as h → 0, against h = {} as the \
             reference (`discretization_error.csv`), with `{solver}`{}: errors of the displacement in L2 and in the \
             energy norm (both exact on these nested meshes, relative to the reference's norms), of the pressure at \
             the contact nodes (relative to its maximum) and of the start of the separated zone, with the observed \
             orders log₂(e(2h)/e(h)).\n\n{}{}\n",
            self.spec.reference,
            solver_note(solver),
            markdown(errors),
            findings(errors)
        );
        for c in charts {
            s += &chart_markdown(
                c,
                "How fast each error falls as h → 0 against the finest mesh: on log–log axes the slope is the observed order.",
            );
        }
        Ok(Section { markdown: s })
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<Vec<ErrorRow>>> {
        lab.log(&format!(
            "discretization error against h = {}",
            self.spec.reference
        ));
        let mut spec = self.spec.clone();
        if spec.solver.is_none() {
            spec.solver = lab
                .handoff
                .get::<FastestDirect>()
                .and_then(|f| f.at_or_finest(&spec.reference.to_string()));
        }
        let log = lab.logger();
        let errors = run(&spec, &lab.settings, &|l| {
            log(&format!("discretization error: {l}"))
        })?;
        let mut artifacts = vec![Artifact::csv("discretization_error.csv", &errors, &[])?];
        artifacts.extend(Artifact::charts(charts(&errors)));
        Ok(Ran {
            findings: errors,
            artifacts,
        })
    }
}
