//! The paper's Table 1: iteration counts of its method (the registry's
//! [`Role::PapersMethod`]) with mesh continuation, ours beside the paper's.
//! Its trials run at the paper's settings: its command and Python change
//! the paper's (not the defaults), `reproduce` runs it at the paper's with
//! the run's certificate. A catalogued study (`study::studies`).

use anyhow::{Context, Result};
use contactlab_solvers::Law;
use contactlab_solvers::registry::{self, Role};
use serde::{Deserialize, Serialize};

use crate::coulomb::continuation::Schedule;
use crate::io::csv::fixed;
use crate::io::latex::{ClaimMarks, Tabular, math, number, text};
use crate::mechanics::material::PlaneModel;
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::catalog::{Catalogued, by_length, check_paper_problems};
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

/// Table 1's parameters: its flags, and Python's keywords.
#[derive(Clone, Debug, Serialize, Deserialize, clap::Args)]
pub struct Table1Spec {
    /// Finest mesh (continuation runs 1/8, ..., h) [default: 1/64; --quick: 1/16].
    #[arg(long, value_name = "1/2^k", required = false)]
    pub h: MeshSize,
    /// The paper's problems to run, `1,3` (or `1 3`) [default: 1,2,3].
    #[arg(long = "problem", value_name = "N", value_delimiter = ',', num_args = 1.., value_parser = clap::value_parser!(u32).range(1..=3))]
    pub problems: Vec<u32>,
    /// Continuation schedules to run (`revisit finest-only` or with commas) [default: both].
    #[arg(long, value_parser = crate::study::catalog::schedule_choice(), value_delimiter = ',', num_args = 1..)]
    pub schedules: Vec<Schedule>,
    /// Plane strain or plane stress [default: strain].
    #[arg(long, value_parser = crate::study::catalog::plane_choice(), required = false)]
    pub plane: PlaneModel,
}

impl Table1Spec {
    /// The paper's table: its three problems, both schedules, plane
    /// strain, continuation to `h`.
    fn to(h: u32) -> Self {
        Self {
            h: MeshSize::from_level(h).expect("in range"),
            problems: vec![1, 2, 3],
            schedules: vec![Schedule::Revisit, Schedule::FinestOnly],
            plane: PlaneModel::Strain,
        }
    }

    /// The main job's and the long run's: to the paper's finest mesh, 1/64.
    pub fn standard() -> Self {
        Self::to(6)
    }

    /// A smoke run's: to 1/16.
    pub fn quick() -> Self {
        Self::to(4)
    }
}

/// Table 1 as a study: table1.csv, table1.tex and table1_trials.csv.
pub struct Table1 {
    pub spec: Table1Spec,
    /// The settings of its trials; none: the lab's (which its command and
    /// Python resolve on the paper's, [`Catalogued::AT_PAPERS_SETTINGS`]).
    /// In a run of several studies, the paper's with the run's
    /// certificate ([`Catalogued::in_run`]).
    pub settings: Option<Settings>,
}

impl Catalogued for Table1 {
    const COMMAND: &'static str = "table1";
    const ABOUT: &'static str = "The paper's Table 1: its method with mesh continuation on problems 1-3 at the \
        paper's settings (--stopping paper unless told otherwise), our iteration counts beside the paper's. Prints \
        the section; writes table1.csv, table1.tex and table1_trials.csv into --out.";
    type Spec = Table1Spec;
    const AT_PAPERS_SETTINGS: bool = true;

    fn spec(length: RunLength) -> Table1Spec {
        by_length(
            length,
            Table1Spec::quick,
            Table1Spec::standard,
            Table1Spec::standard,
        )
    }

    fn of(spec: Table1Spec) -> Result<Self> {
        check_paper_problems(&spec.problems)?;
        anyhow::ensure!(
            !spec.schedules.is_empty(),
            "schedules: give at least one, such as revisit"
        );
        Ok(Self {
            spec,
            settings: None,
        })
    }

    fn in_run(mut self, run: &Settings) -> Self {
        let mut paper = Settings::paper();
        paper.certificate = run.certificate;
        self.settings = Some(paper);
        self
    }
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
        let spec = &self.spec;
        lab.log(&format!(
            "Table 1 at h = {} (schedules: {})",
            spec.h,
            spec.schedules
                .iter()
                .map(|s| s.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ));
        let settings = self.settings.as_ref().unwrap_or(&lab.settings).clone();
        let specs = plan(
            &spec.problems,
            &spec.schedules,
            &settings,
            spec.h,
            spec.plane,
        )?;
        let measured = lab.measure_alone(&specs, Keep::default())?;
        let rows = rows(&measured, &specs, &spec.problems);
        let trials: Vec<_> = measured.iter().map(|m| m.trial.row()).collect();
        let artifacts = vec![
            Artifact::csv("table1.csv", &rows, &[])?,
            Artifact::text("table1.tex", &latex(&rows)?),
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
/// (the smaller sum of |ln(ours / paper's)| over its rows); none unless
/// both ran on the same problems (a schedule with no rows would score 0).
fn closer_schedule(rows: &[Table1Row]) -> Option<Schedule> {
    let problems = |schedule: Schedule| -> Vec<u32> {
        rows.iter()
            .filter(|r| r.schedule == schedule)
            .map(|r| r.problem)
            .collect()
    };
    let (revisit, finest_only) = (problems(Schedule::Revisit), problems(Schedule::FinestOnly));
    if revisit.is_empty() || revisit != finest_only {
        return None;
    }
    let score = |schedule: Schedule| -> f64 {
        rows.iter()
            .filter(|r| r.schedule == schedule)
            .map(|r| {
                (r.mpp as f64 / r.paper_mpp.max(1) as f64).ln().abs()
                    + (r.mu as f64 / r.paper_mu.max(1) as f64).ln().abs()
            })
            .sum()
    };
    Some(if score(Schedule::Revisit) <= score(Schedule::FinestOnly) {
        Schedule::Revisit
    } else {
        Schedule::FinestOnly
    })
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
pub fn latex(rows: &[Table1Row]) -> Result<String> {
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
    let caption = template::render(
        "table1_caption",
        include_str!("templates/table1_caption.tex"),
        template::facts! { claims => claims.caption() },
    )?;
    let mut t = Tabular::new(&caption, "table1", header);
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
    Ok(t.render())
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

    /// The closer schedule is named only when both ran on the same
    /// problems: one alone scored the other's empty rows 0 and named the
    /// schedule that never ran.
    #[test]
    fn the_closer_schedule_needs_both() {
        let revisit = vec![row(1, Schedule::Revisit)];
        assert_eq!(closer_schedule(&revisit), None);
        let mut both = revisit.clone();
        let mut far = row(1, Schedule::FinestOnly);
        far.mpp = 40;
        both.push(far);
        assert_eq!(closer_schedule(&both), Some(Schedule::Revisit));
        both[0].mu = 4000;
        assert_eq!(closer_schedule(&both), Some(Schedule::FinestOnly));
        let text = markdown(&revisit).unwrap();
        assert!(!text.contains("closer match"), "{text}");
        assert!(
            markdown(&both)
                .unwrap()
                .contains("The `finest-only` schedule is the closer match")
        );
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
        let tex = latex(&rows).unwrap();
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
        let tex = latex(&refused).unwrap();
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
