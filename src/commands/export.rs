//! `contactlab export`: a scene's finest-level problem as files any
//! scientific code reads ([`crate::formats::instance`]).

use anyhow::Result;

use crate::cli::ExportArgs;
use crate::formats::instance::export;
use crate::io::manifest::git_commit;
use crate::io::output::print;
use crate::io::run_folder::RunFolder;
use crate::mechanics::discretization::Discretization;

pub fn run(args: &ExportArgs) -> Result<()> {
    let scene = args.scene.resolve()?;
    let h = scene.finest();
    // The condensed form is one sparse factorization of A: the largest
    // part of an export, checked before anything is assembled.
    crate::memory::check(
        &format!(
            "exporting {} at h = {h} (with its condensed form)",
            scene.name
        ),
        h,
        |h| crate::memory::condensation(crate::memory::unknowns(h)),
        |_| None,
    )?;
    let folder = RunFolder::create(&args.out)?;
    let d = Discretization::new(&scene, scene.finest())?;
    export(
        folder.path(),
        &scene,
        &d,
        args.friction_bound,
        &git_commit(),
    )?;
    let target = folder.commit()?;
    print(&format!(
        "wrote {} at h = {} ({} unknowns, {} contact nodes) into {}: A.mtx, M.mtx, f.mtx, rigid_modes.mtx, contact.csv, S.mtx, b_condensed.mtx, z_condensed.mtx, nodes.csv, triangles.csv, problem.json\n",
        scene.name,
        d.h(),
        d.problem.n(),
        d.problem.contacts().len(),
        target.display()
    ))
}
