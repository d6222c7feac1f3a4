//! The paper's Table 1: iteration counts of the relaxation solver with mesh
//! continuation, ours beside the paper's.

use anyhow::Result;
use contactlab_solvers::Observer;
use serde::Serialize;

use crate::coulomb::continuation::Schedule;
use crate::coulomb::driver::solve_scene;
use crate::io::output::csv_bytes;
use crate::mechanics::material::PlaneModel;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;

/// Table 1 of the paper: problem, MPP, MU, MPR total, MPR at h = 1/32, at 1/64.
pub const PAPER_TABLE_1: [(u32, usize, usize, usize, usize, usize); 3] = [
    (1, 6, 48, 87539, 27550, 46586),
    (2, 6, 54, 109089, 31480, 62812),
    (3, 7, 62, 91629, 25104, 52765),
];

/// One row: our counts and the paper's.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table1Row {
    pub problem: u32,
    pub schedule: Schedule,
    pub status: String,
    /// Friction iterations (MPP).
    pub mpp: usize,
    /// Uzawa iterations over all levels and friction iterations (MU).
    pub mu: usize,
    /// Relaxation sweeps in total (MPR) and at h = 1/32 and 1/64.
    pub mpr: usize,
    pub mpr_1_32: usize,
    pub mpr_1_64: usize,
    pub separated_fraction: f64,
    pub paper_mpp: usize,
    pub paper_mu: usize,
    pub paper_mpr: usize,
    pub paper_mpr_1_32: usize,
    pub paper_mpr_1_64: usize,
    /// Wall-clock seconds (not written to table1.csv, which is deterministic).
    #[serde(skip)]
    pub seconds: f64,
}

/// Runs the relaxation solver with the paper's settings (adjusted by
/// `settings`) on `problems` for each schedule.
pub fn table1(
    problems: &[u32],
    schedules: &[Schedule],
    settings: &Settings,
    finest: MeshSize,
    plane: PlaneModel,
    mut observer_for: impl FnMut(u32, Schedule) -> Box<dyn Observer>,
) -> Result<Vec<Table1Row>> {
    let mut rows = Vec::new();
    for &schedule in schedules {
        for &problem in problems {
            let mut scene = Scene::paper_problem(problem)?;
            scene.set_finest(finest);
            scene.material.plane = plane;
            let mut s = settings.clone();
            s.schedule = schedule;
            let mut observer = observer_for(problem, schedule);
            let run = solve_scene(&scene, &s, "relaxation", observer.as_mut())?;
            let at = |h: &str| {
                run.levels
                    .iter()
                    .find(|l| l.h.to_string() == h)
                    .map(|l| l.sweeps)
                    .unwrap_or(0)
            };
            let paper = PAPER_TABLE_1
                .iter()
                .find(|p| p.0 == problem)
                .copied()
                .unwrap_or((problem, 0, 0, 0, 0, 0));
            let total = run.coulomb.total_iterations();
            rows.push(Table1Row {
                problem,
                schedule,
                status: run.coulomb.status.to_string(),
                mpp: run.coulomb.history.len(),
                mu: total.outer,
                mpr: total.inner,
                mpr_1_32: at("1/32"),
                mpr_1_64: at("1/64"),
                separated_fraction: run.separation.fraction,
                paper_mpp: paper.1,
                paper_mu: paper.2,
                paper_mpr: paper.3,
                paper_mpr_1_32: paper.4,
                paper_mpr_1_64: paper.5,
                seconds: run.coulomb.seconds,
            });
        }
    }
    Ok(rows)
}

/// `table1.csv`: one row per problem and schedule.
pub fn table1_csv(rows: &[Table1Row]) -> Result<Vec<u8>> {
    let header = [
        "problem",
        "schedule",
        "status",
        "mpp",
        "mu",
        "mpr",
        "mpr_1_32",
        "mpr_1_64",
        "separated_fraction",
        "paper_mpp",
        "paper_mu",
        "paper_mpr",
        "paper_mpr_1_32",
        "paper_mpr_1_64",
    ];
    csv_bytes(
        &header,
        rows.iter().map(|r| {
            vec![
                r.problem.to_string(),
                r.schedule.to_string(),
                r.status.clone(),
                r.mpp.to_string(),
                r.mu.to_string(),
                r.mpr.to_string(),
                r.mpr_1_32.to_string(),
                r.mpr_1_64.to_string(),
                format!("{:.6}", r.separated_fraction),
                r.paper_mpp.to_string(),
                r.paper_mu.to_string(),
                r.paper_mpr.to_string(),
                r.paper_mpr_1_32.to_string(),
                r.paper_mpr_1_64.to_string(),
            ]
        }),
    )
}

/// The table in Markdown, ours / paper in each cell.
pub fn table1_markdown(rows: &[Table1Row]) -> String {
    let mut out = String::from(
        "| problem | schedule | status | MPP | MU | MPR total | MPR at 1/32 | MPR at 1/64 |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        out += &format!(
            "| {} | {} | {} | {} / {} | {} / {} | {} / {} | {} / {} | {} / {} |\n",
            r.problem,
            r.schedule,
            r.status,
            r.mpp,
            r.paper_mpp,
            r.mu,
            r.paper_mu,
            r.mpr,
            r.paper_mpr,
            r.mpr_1_32,
            r.paper_mpr_1_32,
            r.mpr_1_64,
            r.paper_mpr_1_64
        );
    }
    out + "\nEach cell: ours / the paper's (Table 1). MPP: friction iterations; MU: Uzawa iterations; MPR: relaxation sweeps.\n"
}
