//! `contactlab solve`: one scene's Coulomb problem with one solver,
//! certified. The output folder (if any) is written whole before anything is
//! printed; an answer that is not certified is a non-zero exit.

use anyhow::{Context, Result, bail};
use contactlab_solvers::registry::{self, Role};
use contactlab_solvers::{Friction, Status};

use crate::cli::SolveArgs;
use crate::commands::LogObserver;
use crate::io::csv::to_csv;
use crate::io::manifest::git_commit;
use crate::io::output::{json_bytes, log, print, write_atomic};
use crate::io::run_folder::RunFolder;
use crate::mechanics::contact_zone::PROFILE_COLUMNS;
use crate::solve::summary::{Summary, answer_bound};
use crate::solve::{Assembled, Caps, solve, solver_entry};

pub fn run(args: &SolveArgs) -> Result<()> {
    let (scene, base) = args.scene.load()?;
    let solver = match &args.solver {
        Some(name) => solver_entry(name)?,
        None => registry::with_role(Role::Oracle).context("no oracle is registered")?,
    };
    let settings = args.settings.resolve_for(base, &[solver])?;
    let folder = args.out.as_deref().map(RunFolder::create).transpose()?;
    let continuation = if solver.warm_starts && scene.levels.len() > 1 {
        format!(" ({} schedule)", settings.schedule_of(solver))
    } else {
        String::new()
    };
    log(format!(
        "solving {} at h = {} with {}{continuation}",
        scene.name,
        scene.finest(),
        solver.name
    ));
    let problem = Assembled::for_solver(&scene, solver)?;
    let tolerance = settings
        .coulomb()
        .ok()
        .map(|c| c.tolerance(&problem.finest().problem));
    let caps = Caps {
        work: None,
        seconds: args.time_limit,
    };
    let solved = solve(
        problem,
        Friction::Coulomb,
        solver,
        &settings,
        caps,
        &mut LogObserver::toward(tolerance),
    )?;
    let bound = answer_bound(&solved, &settings.certificate);
    let summary = Summary::of(&solved, &scene, &settings, bound, git_commit());
    let mut report = summary_text(&summary);
    if let Some(folder) = folder {
        let dir = folder.path().to_path_buf();
        write_atomic(
            &dir.join("profile.csv"),
            &to_csv(&solved.profile(), &PROFILE_COLUMNS)?,
        )?;
        write_atomic(&dir.join("summary.json"), &json_bytes(&summary)?)?;
        // The answer itself, in the unknowns and node order of `export`, so
        // that `certify --displacements` or `--forces` can check any run.
        let answer = &solved.outcome.solution;
        let v = &answer.v;
        write_atomic(
            &dir.join("displacements.mtx"),
            crate::io::matrix_market::write_coordinate(
                v.len(),
                1,
                v.iter().enumerate().map(|(i, &x)| (i, 0, x)),
                false,
            )
            .as_bytes(),
        )?;
        let mut forces = csv::Writer::from_writer(Vec::new());
        forces.write_record(["pressure", "friction_traction"])?;
        for (p, q) in answer.pressure.iter().zip(&answer.friction_traction) {
            forces.write_record([format!("{p:e}"), format!("{q:e}")])?;
        }
        write_atomic(&dir.join("forces.csv"), &forces.into_inner()?)?;
        if args.vtu {
            let text = crate::formats::vtu::vtu(
                &solved.finest,
                &scene.materials(),
                &solved.outcome.solution,
            );
            write_atomic(&dir.join("field.vtu"), text.as_bytes())?;
        }
        let target = folder.commit()?;
        report += &format!(
            "wrote {}, displacements.mtx, forces.csv and {}{}\n",
            target.join("profile.csv").display(),
            target.join("summary.json").display(),
            if args.vtu { " and field.vtu" } else { "" }
        );
    }
    print(&report)?;
    let o = &solved.outcome;
    if o.status == Status::Inaccurate {
        bail!(
            "the answer is inaccurate: {} claims convergence but the certificate {}",
            solver.name,
            o.certificate.summary()
        );
    }
    if o.status == Status::TimeLimit {
        bail!(
            "the solve stopped at --time-limit {} s: {} ({}); what it had is written and certified above",
            args.time_limit.unwrap_or(f64::NAN),
            o.status,
            o.detail
        );
    }
    if !o.status.is_converged() {
        bail!("the solve did not converge: {} ({})", o.status, o.detail);
    }
    Ok(())
}

fn summary_text(s: &Summary) -> String {
    let intervals: Vec<String> = s
        .separated_intervals
        .iter()
        .map(|[a, b]| format!("[{a:.4}, {b:.4}]"))
        .collect();
    format!(
        "{}, h = {}, solver {}, plane {}, friction coefficient {}\n\
         status              {} (solver's claim: {}; {})\n\
         certificate         {}\n\
         error bound         {}\n\
         friction iterations {}\n\
         separated           {} = {:.2}% of Γ_K (jump < -{:.1e})\n\
         max pressure        {:.6}\n\
         contact force       {:.10} (applied load {})\n\
         objective           {:.10e}\n\
         iterations          {} outer, {} inner\n\
         time                {:.3} s (set-up {:.3} s)\n",
        s.problem,
        s.h,
        s.solver,
        s.plane,
        s.friction_coefficient,
        s.status,
        s.solver_status,
        s.detail,
        s.certificate_summary,
        s.error_bound.line(),
        s.friction_iterations,
        if intervals.is_empty() {
            "none".to_string()
        } else {
            intervals.join(" ∪ ")
        },
        100.0 * s.separated_fraction,
        s.separation_tolerance,
        s.max_pressure,
        s.total_contact_force,
        s.total_applied_load,
        s.objective,
        s.iterations_outer,
        s.iterations_inner,
        s.seconds,
        s.seconds_setup
    )
}
