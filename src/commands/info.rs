//! `contactlab info`: the sizes and scales of a discretized scene.

use anyhow::{Context, Result};

use crate::cli::InfoArgs;
use crate::io::output::print;
use crate::mechanics::discretization::Discretization;

/// Relative pivot threshold for the measured kernel dimension.
pub const KERNEL_PIVOT_TOL: f64 = 1e-9;

pub fn run(args: &InfoArgs) -> Result<()> {
    let scene = args.scene.resolve()?;
    let h = scene.finest();
    let d = Discretization::new(&scene, h).context("building the discretization")?;
    let p = &d.problem;
    let kernel =
        crate::solvers::numerics::linalg::kernel_dimension(&p.a().to_nalgebra(), KERNEL_PIVOT_TOL)
            .context("measuring the kernel of A")?;
    let applied: f64 = d.forces.iter().map(|f| f[1]).sum();
    let sc = p.scales();
    let m = &scene.material;
    let text = format!(
        "scene              {} (plane {}, E = {}, ν = {}, 𝓕 = {})\n\
         h                  {h}\n\
         nodes              {} (n = {}, N = n² + n)\n\
         elements           {}\n\
         free unknowns      {}\n\
         nonzeros of A      {}\n\
         contact nodes      {}\n\
         applied load       {applied:.12} (vertical, on the upper body; scene total {:.12})\n\
         dim ker A          {kernel} (measured: Cholesky pivots below {KERNEL_PIVOT_TOL:e}·max diag)\n\
         scales             load F = {:.6e}, length L = {:.6e}, stiffness K = {:.6e}, pressure P = {:.6e}, displacement U = {:.6e}\n",
        scene.name,
        m.plane,
        m.young,
        m.poisson,
        scene.friction,
        d.mesh.num_nodes(),
        d.mesh.n(),
        d.mesh.num_elements(),
        p.n(),
        p.a().nnz(),
        p.contacts().len(),
        d.total_load,
        sc.force,
        sc.length,
        sc.stiffness,
        sc.pressure,
        sc.displacement
    );
    print(&text)
}
