//! The discretization error: how the discrete Coulomb solution converges as
//! h → 0, against the finest mesh as the reference.
//!
//! The meshes h = 1/2^k are nested (same diagonal direction), so a coarse P1
//! field is also a fine P1 field: it is interpolated onto the reference mesh
//! exactly, and with e = u_h − u_ref there
//!
//! ```text
//! ‖e‖²_L2 = eᵀ M e,   ‖e‖²_energy = A(e, e) = eᵀ A e
//! ```
//!
//! exactly, with the reference's mass and stiffness matrices. The pressure
//! is compared at the coarse contact nodes (which are reference nodes too),
//! the separated zone by its start. Every solution is certified; the solver
//! solves the Coulomb law directly (in `reproduce` the fastest such solver
//! of the speed study), so that no fixed-point tolerance enters the error.

use anyhow::{Context, Result};
use serde::Serialize;

use crate::io::charts::{Chart, Series};
use crate::io::csv::fixed;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::solve::{Solved, solve_scene, solver_entry};
use crate::solvers::{Friction, Law, Silent, registry};
use crate::study::lab::{Artifact, Findings, Lab, Study};

/// Which problems, on which meshes, against which reference mesh.
#[derive(Clone, Debug, Serialize)]
pub struct ErrorSpec {
    pub problems: Vec<u32>,
    pub meshes: Vec<MeshSize>,
    pub reference: MeshSize,
    /// The direct Coulomb solver (None: the registry's first).
    pub solver: Option<&'static str>,
}

impl ErrorSpec {
    /// Problems 1 and 3, h = 1/16 to 1/512 against 1/1024 (the issue's
    /// study; about 3 minutes and 6.4 GB at 1/1024).
    pub fn standard() -> Self {
        Self {
            problems: vec![1, 3],
            meshes: (4..=9).map(level).collect(),
            reference: level(10),
            solver: None,
        }
    }

    /// 1/8 and 1/16 against 1/32: for tests.
    pub fn quick() -> Self {
        Self {
            problems: vec![1, 3],
            meshes: vec![level(3), level(4)],
            reference: level(5),
            solver: None,
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

/// The direct Coulomb solver the study uses: the spec's, or the registry's
/// first.
fn solver(spec: &ErrorSpec) -> Result<&'static str> {
    if let Some(name) = spec.solver {
        let e = registry::by_name(name).context("unknown solver")?;
        anyhow::ensure!(
            e.solves(Law::Coulomb),
            "{name} does not solve the Coulomb law directly"
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

/// The errors of `coarse` against `reference` for `problem`, without rates.
fn errors(problem: u32, coarse: &Solved, reference: &Solved) -> ErrorRow {
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
    let ev = df.dofs.from_physical(&e);
    let vf = &reference.outcome.solution.v;
    let p = &df.problem;
    let norm = |m, v: &[f64]| {
        let mv = crate::solvers::numerics::linalg::spmv(m, v);
        v.iter()
            .zip(&mv)
            .map(|(a, b)| a * b)
            .sum::<f64>()
            .max(0.0)
            .sqrt()
    };
    let mass = p.mass();
    let (l2, energy) = (
        norm(&mass, &ev) / norm(&mass, vf),
        norm(p.a(), &ev) / norm(p.a(), vf),
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
    for &problem in &spec.problems {
        log(&format!(
            "problem {problem}: reference at h = {}",
            spec.reference
        ));
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
            let mut row = errors(problem, &coarse, &reference);
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
/// charts. Its direct solver is the spec's, else the one certified on the
/// reference mesh in the speed study run before it, else the fastest
/// certified on that study's finest mesh.
pub struct Errors {
    pub spec: ErrorSpec,
}

impl Study for Errors {
    fn name(&self) -> &'static str {
        "discretization_error"
    }

    fn run(&self, lab: &mut Lab, findings: &mut Findings) -> Result<Vec<Artifact>> {
        lab.log(&format!(
            "discretization error against h = {}",
            self.spec.reference
        ));
        let mut spec = self.spec.clone();
        if let (None, Some(bench)) = (spec.solver, &findings.bench) {
            let finest = bench
                .meshes
                .last()
                .map(|h| h.to_string())
                .unwrap_or_default();
            spec.solver =
                crate::study::bench::certified_direct(&bench.rows, &spec.reference.to_string())
                    .or_else(|| crate::study::bench::certified_direct(&bench.rows, &finest));
        }
        let log = lab.logger();
        let errors = run(&spec, &lab.settings, &|l| {
            log(&format!("discretization error: {l}"))
        })?;
        let mut artifacts = vec![Artifact::csv("discretization_error.csv", &errors, &[])?];
        artifacts.extend(Artifact::charts(charts(&errors)));
        findings.errors = errors;
        Ok(artifacts)
    }
}

/// Errors against h on log–log axes, one chart per problem.
pub fn charts(rows: &[ErrorRow]) -> Vec<(String, Chart)> {
    let mut problems: Vec<u32> = rows.iter().map(|r| r.problem).collect();
    problems.dedup();
    problems
        .into_iter()
        .map(|problem| {
            let of = |f: &dyn Fn(&ErrorRow) -> f64| -> Vec<(f64, f64)> {
                rows.iter()
                    .filter(|r| r.problem == problem)
                    .filter_map(|r| {
                        let h = r.h.parse::<MeshSize>().ok()?.h();
                        let y = f(r);
                        (y.is_finite() && y > 0.0).then_some((h, y))
                    })
                    .collect()
            };
            let reference = rows
                .iter()
                .find(|r| r.problem == problem)
                .map_or(String::new(), |r| r.reference_h.clone());
            let (l2, energy) = (of(&|r| r.l2_error), of(&|r| r.energy_error));
            let mut series = vec![
                Series::line("displacement, L2", l2.clone()).with_markers(),
                Series::line("displacement, energy norm", energy.clone()).with_markers(),
                Series::line("pressure, max on Γ_K", of(&|r| r.pressure_error)).with_markers(),
                Series::line("start of the separated zone", of(&|r| r.zone_start_error))
                    .with_markers(),
            ];
            // Reference slopes through the coarsest point of the error each
            // order is expected of (P1 elements on a smooth solution: O(h) in
            // the energy norm, O(h²) in L2; contact may lower both).
            series.extend(guide("O(h) reference slope", &energy, 1).map(|s| s.black()));
            series.extend(guide("O(h²) reference slope", &l2, 2).map(|s| s.colored(7)));
            let mut meshes: Vec<(f64, String)> = rows
                .iter()
                .filter(|r| r.problem == problem)
                .filter_map(|r| Some((r.h.parse::<MeshSize>().ok()?.h(), r.h.clone())))
                .collect();
            meshes.dedup_by(|a, b| a.1 == b.1);
            (
                format!("discretization_error_p{problem}"),
                Chart::new(
                    format!("Discretization error, problem {problem}, against h = {reference}"),
                    "h (a tick at each mesh)",
                    "relative error (zone start: absolute)",
                    true,
                    true,
                    series,
                )
                .with_x_ticks(meshes),
            )
        })
        .collect()
}

/// A dashed line of slope `order` on log–log axes through the point of
/// `points` at the largest h, over their range of h; none without points.
fn guide(name: &str, points: &[(f64, f64)], order: i32) -> Option<Series> {
    let &(h0, e0) = points.iter().max_by(|a, b| a.0.total_cmp(&b.0))?;
    let h1 = points.iter().map(|p| p.0).fold(h0, f64::min);
    let at = |h: f64| (h, e0 * (h / h0).powi(order));
    Some(Series::line(name, vec![at(h1), at(h0)]).dashed())
}

/// A Markdown table of the rows.
pub fn markdown(rows: &[ErrorRow]) -> String {
    let num = |x: f64| {
        if x.is_finite() {
            format!("{x:.2e}")
        } else {
            "–".into()
        }
    };
    let rate = |x: f64| {
        if x.is_finite() {
            format!("{x:.2}")
        } else {
            "–".into()
        }
    };
    let mut out = String::from(
        "| problem | h | L2 error | rate | energy error | rate | pressure error | rate | zone start | its error | separated | certificate |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        out.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2}% | {} |\n",
            r.problem,
            r.h,
            num(r.l2_error),
            rate(r.l2_rate),
            num(r.energy_error),
            rate(r.energy_rate),
            num(r.pressure_error),
            rate(r.pressure_rate),
            if r.zone_start.is_finite() {
                format!("{:.4}", r.zone_start)
            } else {
                "none".into()
            },
            num(r.zone_start_error),
            100.0 * r.separated_fraction,
            num(r.certificate),
        ));
    }
    out
}

/// Where the paper's problem 1 separates at h = 1/64 (paper, section 5).
pub const PAPERS_ZONE_START: f64 = 0.81;

/// The study's findings as sentences computed from the rows: the observed
/// orders on the finest pair of meshes, and where problem 1's zone starts at
/// the paper's h = 1/64 against the reference (the paper reports 0.81, 19 %).
pub fn findings(rows: &[ErrorRow]) -> String {
    let papers_h = level(6);
    let mut lines = Vec::new();
    let mut problems: Vec<u32> = rows.iter().map(|r| r.problem).collect();
    problems.dedup();
    for problem in problems {
        let of: Vec<&ErrorRow> = rows.iter().filter(|r| r.problem == problem).collect();
        if let Some(last) = of.last().filter(|r| r.l2_rate.is_finite()) {
            lines.push(format!(
                "- Problem {problem}, from h = {} to {}: observed orders {:.2} (L2), {:.2} (energy), {:.2} (pressure); at h = {} the errors are {:.1e}, {:.1e} and {:.1e}.",
                of[of.len() - 2].h,
                last.h,
                last.l2_rate,
                last.energy_rate,
                last.pressure_rate,
                last.h,
                last.l2_error,
                last.energy_error,
                last.pressure_error
            ));
        }
        let at = of.iter().find(|r| r.h == papers_h.to_string());
        if let Some(r) = at.filter(|r| r.zone_start.is_finite() && problem == 1) {
            let gap = (r.zone_start - PAPERS_ZONE_START).abs();
            let verdict = if r.zone_start_error < gap {
                "smaller than its distance from the paper's start: the mesh does not explain the difference"
            } else {
                "as large as its distance from the paper's start: the mesh can explain the difference"
            };
            lines.push(format!(
                "- Problem 1 at the paper's h = {}: the separated zone starts at {:.4} ({:.1}% of Γ_K; the paper: {PAPERS_ZONE_START}, 19%). Its distance from the reference mesh's start, {:.1e}, is {verdict} ({gap:.1e}).",
                r.h,
                r.zone_start,
                100.0 * r.separated_fraction,
                r.zone_start_error
            ));
        }
    }
    lines.join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(h: &str, e: f64) -> ErrorRow {
        ErrorRow {
            problem: 1,
            h: h.into(),
            reference_h: "1/256".into(),
            solver: "newton-coulomb".into(),
            status: "converged".into(),
            certificate: 1e-9,
            l2_error: e * e,
            energy_error: e,
            pressure_error: e,
            zone_start: 0.8,
            zone_start_error: e,
            separated_fraction: 0.2,
            l2_rate: 2.0,
            energy_rate: 1.0,
            pressure_rate: 1.0,
        }
    }

    #[test]
    fn the_chart_has_reference_slopes_and_a_tick_at_each_mesh() {
        let rows = [row("1/16", 0.1), row("1/32", 0.05), row("1/64", 0.025)];
        let (name, chart) = charts(&rows).remove(0);
        assert_eq!(name, "discretization_error_p1");
        let slope = |label: &str| {
            let s = chart.series.iter().find(|s| s.name == label).unwrap();
            let (a, b) = (s.points[0], s.points[1]);
            (b.1 / a.1).ln() / (b.0 / a.0).ln()
        };
        assert!((slope("O(h) reference slope") - 1.0).abs() < 1e-12);
        assert!((slope("O(h²) reference slope") - 2.0).abs() < 1e-12);
        // Through the coarsest point of the error it is compared with.
        let o2 = chart
            .series
            .iter()
            .find(|s| s.name.starts_with("O(h²)"))
            .unwrap();
        assert!(o2.points.contains(&(1.0 / 16.0, 0.1 * 0.1)));
        let ticks: Vec<String> = chart
            .x_ticks
            .clone()
            .unwrap()
            .into_iter()
            .map(|t| t.1)
            .collect();
        assert_eq!(ticks, ["1/16", "1/32", "1/64"]);
        let svg = chart.to_svg().unwrap();
        for t in &ticks {
            assert!(svg.contains(&format!("\n{t}\n")), "no tick label {t}");
        }
    }
}
