//! The paper's Table 1: iteration counts of its method (the registry's
//! [`Role::PapersMethod`]) with mesh continuation, ours beside the paper's.
//! Its trials run with whatever settings they are given; the `table1`
//! command and `reproduce` give the paper's absolute stopping rules.

use anyhow::{Context, Result};
use contactlab_solvers::Law;
use contactlab_solvers::registry::{self, Role};
use serde::Serialize;

use crate::coulomb::continuation::Schedule;
use crate::io::csv::fixed;
use crate::io::latex::{ClaimMarks, Tabular, math, number, text};
use crate::mechanics::material::PlaneModel;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::lab::{Artifact, Lab, Ran, RunLength, Section, Study};
use crate::study::runner::{Keep, Measured};
use crate::study::template;
use crate::study::trial::{Trial, TrialSpec};

/// The study's name in trial records.
pub const STUDY: &str = "table1";

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
    /// Certified status, and the solver's claim.
    pub status: String,
    pub solver_status: String,
    /// Friction iterations (MPP).
    pub mpp: usize,
    /// Uzawa iterations over all levels and friction iterations (MU).
    pub mu: usize,
    /// Relaxation sweeps in total (MPR) and at h = 1/32 and 1/64 (none
    /// where that level was never run: an empty cell, "not run", never 0).
    pub mpr: usize,
    pub mpr_1_32: Option<usize>,
    pub mpr_1_64: Option<usize>,
    #[serde(serialize_with = "fixed")]
    pub separated_fraction: f64,
    #[serde(serialize_with = "fixed")]
    pub certificate: f64,
    pub paper_mpp: usize,
    pub paper_mu: usize,
    pub paper_mpr: usize,
    pub paper_mpr_1_32: usize,
    pub paper_mpr_1_64: usize,
}

/// The trials: the paper's method on each problem for each schedule.
pub fn plan(
    problems: &[u32],
    schedules: &[Schedule],
    settings: &Settings,
    finest: MeshSize,
    plane: PlaneModel,
) -> Result<Vec<TrialSpec>> {
    let entry = registry::with_role(Role::PapersMethod)
        .context("no registered solver has the role of the paper's method")?;
    let mut out = Vec::new();
    for &schedule in schedules {
        for &problem in problems {
            let mut scene = Scene::paper_problem_to(problem, finest)?;
            scene.material.plane = plane;
            let mut s = settings.clone();
            s.schedule = Some(schedule);
            out.push(
                TrialSpec::new(STUDY, schedule.to_string(), &scene, entry, Law::Coulomb, &s)
                    .with_work(Some(crate::study::plans::plan(entry).work * 20)),
            );
        }
    }
    Ok(out)
}

/// Table 1 as a study: table1.csv, table1.tex and table1_trials.csv.
pub struct Table1 {
    pub problems: Vec<u32>,
    pub schedules: Vec<Schedule>,
    pub h: MeshSize,
    pub plane: PlaneModel,
    /// The settings of its trials (the paper's, by default: not the lab's).
    pub settings: Settings,
}

impl Study for Table1 {
    /// Its rows, ours beside the paper's.
    type Findings = Vec<Table1Row>;

    fn name(&self) -> &'static str {
        STUDY
    }

    fn estimated_seconds(&self, length: RunLength) -> f64 {
        match length {
            RunLength::Quick => 0.1,
            _ => 10.0,
        }
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<Vec<Table1Row>>> {
        lab.log(&format!(
            "Table 1 at h = {} (schedules: {})",
            self.h,
            self.schedules
                .iter()
                .map(|s| s.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ));
        let specs = plan(
            &self.problems,
            &self.schedules,
            &self.settings,
            self.h,
            self.plane,
        )?;
        let measured = lab.measure_alone(&specs, Keep::default())?;
        let rows = rows(&measured, &specs, &self.problems);
        let trials: Vec<_> = measured.iter().map(|m| m.trial.row()).collect();
        let artifacts = vec![
            Artifact::csv("table1.csv", &rows, &[])?,
            Artifact::text("table1.tex", &latex(&rows)),
            Artifact::csv("table1_trials.csv", &trials, &[])?,
        ];
        Ok(Ran {
            findings: rows,
            artifacts,
        })
    }

    fn section(&self, rows: &Vec<Table1Row>, _: &Lab, _: &[String]) -> Result<Section> {
        Ok(Section {
            markdown: markdown(rows)?,
        })
    }
}

/// Which schedule matches the paper's friction and Uzawa counts better
/// (the smaller sum of |ln(ours / paper's)| over its rows).
fn closer_schedule(rows: &[Table1Row]) -> Schedule {
    let score = |schedule: Schedule| -> f64 {
        rows.iter()
            .filter(|r| r.schedule == schedule)
            .map(|r| {
                (r.mpp as f64 / r.paper_mpp.max(1) as f64).ln().abs()
                    + (r.mu as f64 / r.paper_mu.max(1) as f64).ln().abs()
            })
            .sum()
    };
    if score(Schedule::Revisit) <= score(Schedule::FinestOnly) {
        Schedule::Revisit
    } else {
        Schedule::FinestOnly
    }
}

/// The rows of measured Table 1 trials.
fn rows(measured: &[Measured], specs: &[TrialSpec], problems: &[u32]) -> Vec<Table1Row> {
    measured
        .iter()
        .zip(specs)
        .zip(problems.iter().cycle())
        .map(|((m, spec), &problem)| row(m, spec.settings.schedule_of(spec.solver), problem))
        .collect()
}

fn row(m: &Measured, schedule: Schedule, problem: u32) -> Table1Row {
    let at = |h: &str| {
        m.levels()
            .iter()
            .find(|l| l.h.to_string() == h)
            .map(|l| l.sweeps)
    };
    let paper = PAPER_TABLE_1
        .iter()
        .find(|p| p.0 == problem)
        .copied()
        .unwrap_or((problem, 0, 0, 0, 0, 0));
    let t: &Trial = &m.trial;
    Table1Row {
        problem,
        schedule,
        status: t.status.to_string(),
        solver_status: t.solver_status.to_string(),
        mpp: t.friction_iterations,
        mu: t.outer_iterations,
        mpr: t.inner_iterations,
        mpr_1_32: at("1/32"),
        mpr_1_64: at("1/64"),
        separated_fraction: t.separated_fraction,
        certificate: t.residual(),
        paper_mpp: paper.1,
        paper_mu: paper.2,
        paper_mpr: paper.3,
        paper_mpr_1_32: paper.4,
        paper_mpr_1_64: paper.5,
    }
}

/// The README section (`templates/table1.md`): the table in Markdown,
/// ours / paper in each cell, its key, and which schedule the counts match.
pub fn markdown(rows: &[Table1Row]) -> Result<String> {
    template::render(
        "table1",
        include_str!("templates/table1.md"),
        template::facts! {
            rows,
            closer => closer_schedule(rows),
            fewer_sweeps => rows.iter().filter(|r| r.mpr < r.paper_mpr).count(),
        },
    )
}

/// Table 1 for a paper: a group row per problem, the paper's counts in
/// its first row and each schedule's below, one count a cell; a claim of
/// the solver's that differs from the certified status is a letter on it,
/// named in the caption (eight columns, to fit a page's width).
pub fn latex(rows: &[Table1Row]) -> String {
    let header = vec![
        "schedule".into(),
        "status".into(),
        "certificate".into(),
        "MPP".into(),
        "MU".into(),
        "MPR".into(),
        math("\\mathrm{MPR}_{1/32}"),
        math("\\mathrm{MPR}_{1/64}"),
    ];
    let claims = ClaimMarks::of(
        rows.iter()
            .map(|r| (r.status.as_str(), r.solver_status.as_str())),
    );
    let mut t = Tabular::new(
        &format!(
            "Table 1 of Zhiltsov & Namm (2019) beside ours: iteration counts of the paper's method, the paper's in each \
             problem's first row. MPP: friction iterations; MU: Uzawa iterations; MPR: relaxation sweeps (in all, at \
             h = 1/32, at 1/64); status: certified{}; certificate: the largest violation of the Coulomb law's conditions \
             in the problem's scales (contactlab reproduce).",
            claims.caption()
        ),
        "table1",
        header,
    );
    let ran = |n: Option<usize>| n.map_or("not run".to_string(), |n| n.to_string());
    let mut problems: Vec<_> = rows.iter().map(|r| r.problem).collect();
    problems.sort_unstable();
    problems.dedup();
    for problem in problems {
        let ours: Vec<&Table1Row> = rows.iter().filter(|r| r.problem == problem).collect();
        t.group(format!("Problem {problem}"));
        let p = ours[0];
        t.row(vec![
            "paper".into(),
            "--".into(),
            "--".into(),
            p.paper_mpp.to_string(),
            p.paper_mu.to_string(),
            p.paper_mpr.to_string(),
            p.paper_mpr_1_32.to_string(),
            p.paper_mpr_1_64.to_string(),
        ]);
        for r in ours {
            t.row(vec![
                text(&r.schedule.to_string()),
                claims.status(&r.status, &r.solver_status),
                number(r.certificate),
                r.mpp.to_string(),
                r.mu.to_string(),
                r.mpr.to_string(),
                ran(r.mpr_1_32),
                ran(r.mpr_1_64),
            ]);
        }
    }
    t.render()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(problem: u32, schedule: Schedule) -> Table1Row {
        Table1Row {
            problem,
            schedule,
            status: "converged".into(),
            solver_status: "converged".into(),
            mpp: 3,
            mu: 40,
            mpr: 900,
            mpr_1_32: Some(700),
            mpr_1_64: None,
            separated_fraction: 0.2,
            certificate: 1e-7,
            paper_mpp: 4,
            paper_mu: 47,
            paper_mpr: 27550,
            paper_mpr_1_32: 5478,
            paper_mpr_1_64: 21440,
        }
    }

    /// Rows come schedule by schedule; the table groups them by problem,
    /// once each, the paper's counts first (the committed table once
    /// repeated a group row above every data row).
    #[test]
    fn the_latex_table_has_one_group_per_problem_and_the_papers_row() {
        let rows: Vec<Table1Row> = [Schedule::Revisit, Schedule::FinestOnly]
            .into_iter()
            .flat_map(|s| (1..=3).map(move |p| row(p, s)))
            .collect();
        let tex = latex(&rows);
        for p in 1..=3 {
            assert_eq!(tex.matches(&format!("{{Problem {p}}}")).count(), 1, "{tex}");
        }
        assert_eq!(tex.matches("\\midrule").count(), 3, "{tex}");
        assert_eq!(
            tex.matches("paper & -- & -- & 4 & 47 & 27550 & 5478 & 21440")
                .count(),
            3,
            "{tex}"
        );
        assert_eq!(tex.matches(" & not run \\\\").count(), 6, "{tex}");
        // A claim that the certificate refused is a letter, named once.
        let mut refused = rows.clone();
        refused[0].status = "inaccurate".into();
        refused[1].status = "inaccurate".into();
        let tex = latex(&refused);
        assert_eq!(
            tex.matches("revisit & inaccurate$^a$ &").count(),
            2,
            "{tex}"
        );
        assert_eq!(tex.matches("the solver claimed").count(), 1, "{tex}");
        assert!(
            tex.contains("status: certified (a: the solver claimed converged)"),
            "{tex}"
        );
    }

    #[test]
    fn a_level_never_run_reads_not_run_not_zero() {
        let row = row(1, Schedule::Revisit);
        let table = markdown(&[row]).unwrap();
        assert!(
            table.contains("| 700 / 5478 | not run / 21440 |"),
            "{table}"
        );
        assert!(!table.contains("| 0 / "), "{table}");
    }
}
