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
//! body's free corner (see `errors`). The pressure is compared at the
//! coarse contact nodes (which are reference nodes too), in the maximum
//! norm, and along Γ_K in L2 ([`pressure_l2_error`]): where the pressure
//! is unbounded (problem 3, at an end of Γ_K) its largest nodal value
//! grows as h falls, so no maximum error can converge, while the L2 error
//! does. The separated zone is compared by its start. Every solution is
//! certified. The standard study's reference is h = 1/4096 (33.6 million
//! unknowns), which only the multigrid solver reaches, in about 46 s and
//! 3.9 GiB (the speed study's row); 1/2048, the reference before, took 2 minutes
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
use serde::{Deserialize, Serialize};

use crate::coulomb::continuation::Schedule;
use crate::io::csv::fixed;
use crate::mechanics::assembly::{energy_norm_squared, l2_norm_squared};
use crate::mechanics::discretization::Discretization;
use crate::mechanics::material::Material;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::solve::{Solved, solve_scene, solver_entry};
use crate::solvers::{Friction, Law, Silent, registry};
use crate::study::bench::FastestDirect;
use crate::study::catalog::{Catalogued, by_length, check_paper_problems};
use crate::study::lab::{Artifact, Lab, Ran, RunLength, Section, Study};

mod views;
pub use views::{charts, findings};

/// Which problems, on which meshes, against which reference mesh: the
/// study's parameters (its flags, and Python's keywords).
#[derive(Clone, Debug, Serialize, Deserialize, clap::Args)]
pub struct ErrorSpec {
    /// The paper's problems measured (1, 2, 3), such as 1,3.
    #[arg(long = "problem", value_delimiter = ',', value_name = "N", value_parser = clap::value_parser!(u32).range(1..=3))]
    pub problems: Vec<u32>,
    /// The meshes measured, such as 1/16,1/32,1/64: each coarser than the
    /// reference.
    #[arg(long, value_delimiter = ',', value_name = "H")]
    pub meshes: Vec<MeshSize>,
    /// The reference mesh, such as 1/2048: its answer stands in for the
    /// exact one.
    #[arg(long, value_name = "H", required = false)]
    pub reference: MeshSize,
    /// The solver [default: tnnmg under the nested schedule; --quick: the
    /// registry's first direct Coulomb solver].
    #[arg(long, value_name = "SOLVER", value_parser = crate::study::catalog::registered_solver)]
    pub solver: Option<String>,
    /// The mesh continuation it runs with (None: the settings').
    #[arg(skip)]
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
            solver: Some(MULTIGRID.into()),
            schedule: Some(Schedule::Nested),
        }
    }

    /// The main job's (`reproduce`): h = 1/16 … 1/512 against
    /// 1/2048 (a reference four times finer than the finest mesh: its own
    /// error, O(h²) in L2, is a sixteenth of the finest mesh's), about a
    /// minute; the long run's goes to 1/1024 against 1/4096 (5 min).
    pub fn main() -> Self {
        Self {
            meshes: (4..=9).map(level).collect(),
            reference: level(11),
            ..Self::standard()
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

impl ErrorSpec {
    /// The spec's own consistency: a one-line error naming the field.
    pub fn check(&self) -> Result<()> {
        check_paper_problems(&self.problems)?;
        anyhow::ensure!(
            !self.meshes.is_empty(),
            "meshes: give at least one mesh, such as 1/16,1/32"
        );
        if let Some(h) = self
            .meshes
            .iter()
            .find(|h| h.level() > self.reference.level())
        {
            anyhow::bail!(
                "meshes: {h} is finer than the reference {}: give meshes no finer than the reference, or a finer reference",
                self.reference
            );
        }
        if let Some(name) = &self.solver {
            solver_entry(name)?;
        }
        Ok(())
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
    /// ‖p_h − p_ref‖_L2(Γ_K) / ‖p_ref‖_L2(Γ_K) ([`pressure_l2_error`]).
    #[serde(serialize_with = "fixed")]
    pub pressure_l2_error: f64,
    /// The largest nodal pressure of this mesh's answer, and where on Γ_K.
    #[serde(serialize_with = "fixed")]
    pub peak_pressure: f64,
    #[serde(serialize_with = "fixed")]
    pub peak_x: f64,
    /// The reference's largest nodal pressure.
    #[serde(serialize_with = "fixed")]
    pub reference_peak_pressure: f64,
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
    #[serde(serialize_with = "fixed")]
    pub pressure_l2_rate: f64,
}

/// The solver of the standard study: the one that reaches its reference.
pub const MULTIGRID: &str = "tnnmg";

/// The solver the study uses: the spec's (the Coulomb law directly or
/// through the friction fixed point), or the registry's first direct
/// Coulomb solver.
fn solver(spec: &ErrorSpec) -> Result<&'static str> {
    if let Some(name) = spec.solver.as_deref() {
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
fn errors(problem: u32, material: &Material, coarse: &Solved, fine: &ReferenceField) -> ErrorRow {
    let (reference, uf) = (fine.solved, &fine.u);
    let (dc, df) = (&coarse.finest, &reference.finest);
    let uc = dc.displacements(&coarse.outcome.solution.v);
    let e: Vec<[f64; 2]> = (0..df.mesh.num_nodes())
        .map(|node| {
            let (body, _, _) = df.mesh.locate(node);
            let [x, y] = df.mesh.coords(node);
            let at = dc.evaluate(&uc, body, x, y);
            [at[0] - uf[node][0], at[1] - uf[node][1]]
        })
        .collect();
    let (l2, energy) = (
        l2_norm(df, &e) / fine.l2,
        energy_norm(df, material, &e) / fine.energy,
    );
    // Coarse contact node i sits at reference contact node i·ratio.
    let ratio = 1usize << (df.h().level() - dc.h().level());
    let (pc, pf) = (
        &coarse.outcome.solution.pressure,
        &reference.outcome.solution.pressure,
    );
    let p_max = pf.iter().fold(0.0f64, |m, x| m.max(*x));
    let pressure_error = pc
        .iter()
        .enumerate()
        .map(|(i, p)| (p - pf[i * ratio]).abs())
        .fold(0.0f64, f64::max)
        / p_max;
    let xc = dc.contact_x();
    let pressure_l2 = pressure_l2_error(&xc, pc, &df.contact_x(), pf);
    let (peak_pressure, peak_x) =
        pc.iter()
            .zip(&xc)
            .fold((f64::NEG_INFINITY, f64::NAN), |m, (&p, &x)| {
                if p > m.0 { (p, x) } else { m }
            });
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
        pressure_l2_error: pressure_l2,
        peak_pressure,
        peak_x,
        reference_peak_pressure: p_max,
        zone_start: start,
        zone_start_error: (start - start_ref).abs(),
        separated_fraction: coarse.separation().fraction,
        l2_rate: f64::NAN,
        energy_rate: f64::NAN,
        pressure_rate: f64::NAN,
        pressure_l2_rate: f64::NAN,
    }
}

/// The reference answer with its nodal field and both its norms, computed
/// once for every coarse mesh compared with it (on 1/4096 the norms took
/// seconds a mesh).
struct ReferenceField<'a> {
    solved: &'a Solved,
    u: Vec<[f64; 2]>,
    l2: f64,
    energy: f64,
}

impl<'a> ReferenceField<'a> {
    fn of(solved: &'a Solved, material: &Material) -> Self {
        let d = &solved.finest;
        let u = d.displacements(&solved.outcome.solution.v);
        Self {
            l2: l2_norm(d, &u),
            energy: energy_norm(d, material, &u),
            solved,
            u,
        }
    }
}

/// ‖u‖_L2 of a nodal field on `d`'s mesh.
fn l2_norm(d: &Discretization, u: &[[f64; 2]]) -> f64 {
    l2_norm_squared(&d.mesh, u).max(0.0).sqrt()
}

/// The energy norm of a nodal field on `d`'s mesh.
fn energy_norm(d: &Discretization, material: &Material, u: &[[f64; 2]]) -> f64 {
    energy_norm_squared(&d.mesh, material, u).max(0.0).sqrt()
}

/// ‖p_h − p_ref‖_L2(Γ_K) / ‖p_ref‖_L2(Γ_K) of two nodal pressures along
/// Γ_K, each taken as the P1 field of its nodes (`xc`, `xf`: their x,
/// increasing). The coarse field is interpolated at the reference's nodes,
/// exactly on nested meshes, and the square of the P1 difference is
/// integrated exactly on each reference segment of length ℓ with end values
/// a and b: ℓ(a² + ab + b²)/3. NaN with fewer than two coarse nodes.
///
/// This is the measure that converges where the pressure is unbounded:
/// problem 3's largest nodal pressure, at the right end of Γ_K, grows as h
/// falls (65.2 at h = 1/64, 114.5 at 1/1024, 178.7 at 1/4096: about
/// h^−0.3), so its maximum error against a finer reference grows with that
/// reference, while its L2 error falls (0.057 at 1/16 to 0.024 at 1/1024
/// against 1/4096).
pub fn pressure_l2_error(xc: &[f64], pc: &[f64], xf: &[f64], pf: &[f64]) -> f64 {
    if xc.len() < 2 || xc.len() != pc.len() || xf.len() != pf.len() {
        return f64::NAN;
    }
    let coarse_at = |x: f64| {
        let j = xc.partition_point(|&c| c <= x).clamp(1, xc.len() - 1);
        let t = (x - xc[j - 1]) / (xc[j] - xc[j - 1]);
        pc[j - 1] + t * (pc[j] - pc[j - 1])
    };
    let e: Vec<f64> = xf.iter().zip(pf).map(|(&x, &p)| coarse_at(x) - p).collect();
    let squared = |v: &[f64]| -> f64 {
        xf.windows(2)
            .zip(v.windows(2))
            .map(|(x, v)| (x[1] - x[0]) * (v[0] * v[0] + v[0] * v[1] + v[1] * v[1]) / 3.0)
            .sum()
    };
    (squared(&e) / squared(pf)).sqrt()
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
        let fine = ReferenceField::of(&reference, &material);
        let mut previous: Option<ErrorRow> = None;
        for &h in &spec.meshes {
            log(&format!("problem {problem}: h = {h}"));
            let coarse = solve(problem, h, solver, settings)?;
            let mut row = errors(problem, &material, &coarse, &fine);
            if let Some(prev) = &previous {
                let rate = |a: f64, b: f64| (a / b).log2();
                row.l2_rate = rate(prev.l2_error, row.l2_error);
                row.energy_rate = rate(prev.energy_error, row.energy_error);
                row.pressure_rate = rate(prev.pressure_error, row.pressure_error);
                row.pressure_l2_rate = rate(prev.pressure_l2_error, row.pressure_l2_error);
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

impl Catalogued for Errors {
    const COMMAND: &'static str = "discretization-error";
    const ABOUT: &'static str = "How the discrete solution converges as h → 0 on the paper's problems: the errors of \
        the displacement (L2, energy), of the pressure and of the separated zone's start on each mesh against a finer \
        reference mesh, with the observed orders. Writes discretization_error.csv and charts into --out.";
    type Spec = ErrorSpec;

    fn spec(length: RunLength) -> ErrorSpec {
        by_length(
            length,
            ErrorSpec::quick,
            ErrorSpec::main,
            ErrorSpec::standard,
        )
    }

    fn of(spec: ErrorSpec) -> Result<Self> {
        spec.check()?;
        Ok(Self { spec })
    }
}

impl Study for Errors {
    /// One row per mesh.
    type Findings = Vec<ErrorRow>;

    fn name(&self) -> &'static str {
        "discretization_error"
    }

    fn estimated_seconds(&self, length: RunLength) -> f64 {
        match (length, self.spec.reference.level()) {
            (RunLength::Quick, _) => 1.4,
            // Two references at 1/2048, about 10 s each, and each mesh
            // compared on the reference's mesh, 2 s each.
            (_, k) if k <= 11 => 50.0,
            // Two references at 1/4096, about 70 s each, and 9 s a mesh.
            _ => 280.0,
        }
    }

    fn section(&self, errors: &Vec<ErrorRow>, _: &Lab, charts: &[String]) -> Result<Section> {
        Ok(Section {
            markdown: views::section(errors, &self.spec.reference.to_string(), charts)?,
        })
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
                .and_then(|f| f.at_or_finest(&spec.reference.to_string()))
                .map(String::from);
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

#[cfg(test)]
mod tests {
    use super::pressure_l2_error;

    /// Exact for P1 data: a linear pressure on the coarse nodes is the same
    /// field as on the fine ones (no error); and x² on nodes 0, ½, 1 against
    /// its coarse interpolant x on nodes 0, 1: the difference is 0, ¼, 0 at
    /// the fine nodes, ∫e² = 2·½·(¼)²/3 = 1/48 and ∫p² = ½·(¼)²/3 +
    /// ½·((¼)² + ¼ + 1)/3 = 11/48, so the error is √(1/11). A coarse value
    /// read at the wrong fine node, or a segment integrated by its ends
    /// alone, gives another number.
    #[test]
    fn the_pressure_l2_error_is_exact_on_p1_fields() {
        let linear = |x: f64| 3.0 + 2.0 * x;
        let (xc, xf) = (vec![0.0, 0.5, 1.0], vec![0.0, 0.25, 0.5, 0.75, 1.0]);
        let pc: Vec<f64> = xc.iter().map(|&x| linear(x)).collect();
        let pf: Vec<f64> = xf.iter().map(|&x| linear(x)).collect();
        assert!(pressure_l2_error(&xc, &pc, &xf, &pf) <= 1e-15);
        let e = pressure_l2_error(
            &[0.0, 1.0],
            &[0.0, 1.0],
            &[0.0, 0.5, 1.0],
            &[0.0, 0.25, 1.0],
        );
        assert!((e - (1.0f64 / 11.0).sqrt()).abs() <= 1e-15, "{e}");
        assert!(pressure_l2_error(&[0.0], &[1.0], &xf, &pf).is_nan());
    }
}
