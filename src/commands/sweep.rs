//! `contactlab sweep`: one-factor sweeps and the work-precision diagram.

use anyhow::{Result, bail};
use contactlab_solvers::Law;

use crate::cli::SweepArgs;
use crate::commands::{run_study, solver_list};
use crate::io::output::{log, print};
use crate::io::run_folder::RunFolder;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::lab::write_artifacts;
use crate::study::sweep::{STUDY, Sweep, SweepSpec, work_cap};
use crate::study::trial::TrialSpec;
use crate::study::tuning_map::{Axis, TuningMap, check_map};

pub fn run(args: &SweepArgs) -> Result<()> {
    let (scenes, base) = match &args.scene {
        Some(path) => {
            let (scene, settings) = crate::formats::scene_file::load(path)?;
            (vec![scene], settings)
        }
        None => (
            args.problems
                .iter()
                .map(|&p| Scene::paper_problem(p))
                .collect::<Result<_, _>>()?,
            Settings::default(),
        ),
    };
    let scenes = scenes
        .into_iter()
        .map(|s| args.material.apply(s, None))
        .collect::<Result<Vec<_>>>()?;
    if !args.grid.is_empty() {
        return map(args, scenes, base);
    }
    let solvers = solver_list(&args.solvers)?;
    let settings = args.settings.resolve_for(base, &solvers)?;
    let spec = SweepSpec {
        scenes,
        meshes: args.meshes.clone(),
        fine_meshes: args.fine_meshes.clone(),
        solvers,
        variations: args.vary.is_empty(),
        work_precision: !args.no_work_precision,
        quick: args.quick,
        repeats: args.repeats as usize,
        work_scale: 1.0,
    };
    let extra = varied(args, &spec, &settings)?;
    if extra.is_empty() && crate::study::sweep::plan(&spec, &settings)?.is_empty() {
        let names: Vec<&str> = spec.solvers.iter().map(|e| e.name).collect();
        bail!(
            "the sweep plans no trials: {} {} no settings to vary in the registry's sweeps and --no-work-precision skips the work-precision diagram; give --vary PATH=V1,V2,... or drop --no-work-precision",
            names.join(", "),
            if names.len() == 1 { "has" } else { "have" }
        );
    }
    let folder = RunFolder::create(&args.out)?;
    let study = Sweep {
        spec,
        extra,
        references_file: "references.csv",
    };
    let (findings, artifacts) = run_study(&study, settings)?;
    write_artifacts(folder.path(), &artifacts)?;
    let target = folder.commit()?;
    let failed = findings.iter().filter(|m| !m.trial.certified()).count();
    log(format!("{} trials, {failed} not certified", findings.len()));
    print(&format!(
        "wrote {}/sweep_summary.md (a table of every trial), sweep.csv, sweep_timing.csv, references.csv and charts\n",
        target.display()
    ))
}

/// The trials of `--vary PATH=V1,V2,...`.
fn varied(args: &SweepArgs, spec: &SweepSpec, settings: &Settings) -> Result<Vec<TrialSpec>> {
    let mut out = Vec::new();
    for v in &args.vary {
        let Some((path, values)) = v.split_once('=') else {
            bail!(
                "--vary '{v}': write it as PATH=V1,V2,..., e.g. --vary {}=V1,V2",
                crate::settings::example_path()
            );
        };
        let owner = path.split('.').next().unwrap_or("");
        let solvers: Vec<_> = spec
            .solvers
            .iter()
            .copied()
            .filter(|e| e.name == owner || owner == "coulomb" || !path.contains('.'))
            .collect();
        if solvers.is_empty() {
            bail!("--vary '{v}': '{owner}' is not among the solvers swept");
        }
        for scene in &spec.scenes {
            for &h in &spec.meshes {
                let mut scene = scene.clone();
                scene.set_finest(h);
                for &entry in &solvers {
                    for value in values.split(',') {
                        out.push(
                            TrialSpec::new(STUDY, path, &scene, entry, Law::Coulomb, settings)
                                .with_work(work_cap(entry, spec.work_scale))
                                .varying(path, value.trim())?,
                        );
                    }
                }
            }
        }
    }
    Ok(out)
}

/// `sweep --grid`: a tuning map per scene and mesh, into one folder.
fn map(args: &SweepArgs, scenes: Vec<Scene>, base: Settings) -> Result<()> {
    let axes = args
        .grid
        .iter()
        .map(|g| Axis::parse(g))
        .collect::<Result<Vec<_>>>()?;
    let owners: Vec<&str> = axes
        .iter()
        .map(|a| a.path.split('.').next().unwrap_or(""))
        .filter(|o| *o != crate::settings::COULOMB)
        .collect();
    let Some(&owner) = owners.first() else {
        bail!("--grid: name at least one setting of a solver (SOLVER.KNOB=...), e.g. relaxation.r");
    };
    let solver = crate::solve::solver_entry(owner)?;
    if !args.solvers.is_empty() && args.solvers.iter().any(|s| s != owner) {
        bail!("--grid maps {owner}, the owner of its settings; drop --solvers or name {owner}");
    }
    let law = args.law.law();
    check_map(solver, law, &axes)?;
    let mut meshes = args.meshes.clone();
    meshes.sort();
    if meshes.windows(2).any(|w| w[0] == w[1]) {
        bail!("--h: a mesh is given twice; give each once");
    }
    if args.problems.len() > 1 {
        let mut p = args.problems.clone();
        p.sort();
        if p.windows(2).any(|w| w[0] == w[1]) {
            bail!("--problem: a problem is given twice; give each once");
        }
    }
    let settings = args.settings.resolve_for(base, &[solver])?;
    let folder = RunFolder::create(&args.out)?;
    let mut lines = Vec::new();
    for scene in &scenes {
        for &h in &args.meshes {
            let mut scene = scene.clone();
            scene.set_finest(h);
            // Several scenes in one folder: each map's files carry its
            // scene's name.
            let tag = (scenes.len() > 1).then(|| file_tag(&scene.name));
            let study = TuningMap {
                scene,
                solver,
                law,
                axes: axes.clone(),
                repeats: args.repeats as usize,
                tag,
                point_seconds: args.time_limit,
            };
            eprintln!("{}", study.plan_line(&settings)?);
            let (found, artifacts) = run_study(&study, settings.clone())?;
            write_artifacts(folder.path(), &artifacts)?;
            lines.push(format!(
                "{}, h = {h}: {}",
                study.scene.name,
                crate::study::tuning_map::verdict_sentence(&axes, &found.points)?
            ));
        }
    }
    let target = folder.commit()?;
    print(&format!(
        "{}\nwrote the tuning maps (tuning_map_*.csv, their trials and charts) into {}\n",
        lines.join("\n"),
        target.display()
    ))
}

/// A scene's name as part of a file name: `problem_1`.
fn file_tag(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .take(40)
        .collect()
}
