//! `contactlab info`: the sizes and scales of a discretized scene, the
//! measured kernel of A, and what a solve by each solver would need.

use anyhow::{Context, Result};
use contactlab_solvers::registry;

use crate::cli::InfoArgs;
use crate::io::output::print;
use crate::mechanics::discretization::Discretization;
use crate::mechanics::mesh_size::MeshSize;
use crate::memory::{self, Bytes};

/// Relative pivot threshold for the measured kernel dimension.
pub const KERNEL_PIVOT_TOL: f64 = 1e-9;

/// The finest mesh on which the kernel's dimension is measured (a sparse
/// Cholesky factorization, whose memory grows faster than the problem:
/// 60 MB here, 4 GB at 1/1024). On a finer mesh it is measured here and the
/// rigid mode is checked on the mesh itself: the meshes are nested, so the
/// finer space holds every rigid motion of the coarser, and a P1 field of
/// zero energy is a rigid motion of each body, whatever the mesh.
const KERNEL_MEASURED_UP_TO: u32 = 7;

pub fn run(args: &InfoArgs) -> Result<()> {
    let scene = args.scene.resolve()?;
    let h = scene.finest();
    // One estimate for the run, checked once before anything is assembled:
    // the problem and, finer than the kernel is measured on, the coarser
    // problem measured beside it (checked alone after the first was
    // assembled, it was refused where the whole had been admitted).
    let mut need = memory::assembly(h, false);
    if h.level() > KERNEL_MEASURED_UP_TO {
        need += 2.0
            * memory::assembly(
                MeshSize::from_level(KERNEL_MEASURED_UP_TO).expect("in range"),
                false,
            );
    }
    memory::check_need(
        &format!("info on {} at h = {h}", scene.name),
        need,
        memory::unknowns(h),
        Vec::new(),
    )?;
    memory::admit(need);
    // M is not shown: `info` assembles the problem without it.
    let d = Discretization::new_without_mass(&scene, h).context("building the discretization")?;
    let p = &d.problem;
    let kernel = kernel_line(&scene, &d)?;
    let applied: f64 = d.forces().iter().map(|f| f[1]).sum();
    let sc = p.scales();
    let m = &scene.material;
    let room = memory::room();
    let estimates: Vec<String> = registry::solvers()
        .iter()
        .map(|e| {
            let n = memory::unknowns(h);
            match e.max_unknowns.filter(|&cap| n > cap) {
                Some(_) => format!("{} refused (factors A)", e.name),
                None => format!("{} {}", e.name, Bytes(memory::solve(h, e))),
            }
        })
        .collect();
    let held = format!(
        "{}{}",
        match scene.hold {
            crate::mechanics::dofs::Hold::Roller => "on a roller on x = 1 (the paper's)",
            crate::mechanics::dofs::Hold::Rollers => "on rollers on x = 0 and x = 1",
            crate::mechanics::dofs::Hold::Sliding => {
                "on rollers on x = 0 and x = 1 that slide together (its horizontal translation a second rigid mode, held by friction alone)"
            }
        },
        if scene.side_shift == 0.0 {
            String::new()
        } else {
            format!(
                ", shifted to u''_1 = {:e} there (a rigid lift of the whole body: the slip offset σ = {:e}, no load)",
                scene.side_shift, scene.side_shift
            )
        }
    );
    let text = format!(
        "scene              {} (plane {}, E = {}, ν = {}{}, 𝓕 = {})\n\
         h                  {h}\n\
         nodes              {} (n = {}, N = n² + n)\n\
         elements           {}\n\
         free unknowns      {}\n\
         nonzeros of A      {}\n\
         contact nodes      {}\n\
         upper body held    {}\n\
         initial gap        {}\n\
         applied load       {applied:.12} (vertical, on the upper body; scene total {:.12})\n\
         dim ker A          {kernel}\n\
         scales             load F = {:.6e}, length L = {:.6e}, stiffness K = {:.6e}, pressure P = {:.6e}, displacement U = {:.6e}\n\
         memory of a solve  {} (estimates); this process may use {}\n",
        scene.name,
        m.plane,
        m.young,
        m.poisson,
        match &scene.lower_material {
            Some(l) => format!(
                " (the upper body); the lower body E = {}, ν = {}",
                l.young, l.poisson
            ),
            None => String::new(),
        },
        scene.friction,
        d.mesh.num_nodes(),
        d.mesh.n(),
        d.mesh.num_elements(),
        p.n(),
        p.a().nnz(),
        p.contacts().len(),
        held,
        if p.has_gap() {
            let gap = p.gap();
            format!(
                "from {:.6e} to {:.6e} along Γ_K (t ≤ d)",
                gap.iter().copied().fold(f64::INFINITY, f64::min),
                gap.iter().copied().fold(0.0, f64::max)
            )
        } else {
            "none (the bodies touch all along Γ_K)".to_string()
        },
        d.total_load,
        sc.force,
        sc.length,
        sc.stiffness,
        sc.pressure,
        sc.displacement,
        estimates.join(", "),
        room.map_or("an amount this system does not tell".to_string(), |r| {
            Bytes(r.bytes).to_string()
        }),
    );
    print(&text)
}

/// The kernel's dimension, measured by Cholesky pivots on this mesh or, on
/// a finer one than [`KERNEL_MEASURED_UP_TO`], on that mesh, with the rigid
/// mode checked here (‖A z‖ against the stiffness, in memory of the
/// problem's size).
fn kernel_line(scene: &crate::mechanics::scene::Scene, d: &Discretization) -> Result<String> {
    let measure = |d: &Discretization| {
        crate::solvers::numerics::linalg::kernel_dimension(
            &d.problem.a().to_nalgebra(),
            KERNEL_PIVOT_TOL,
        )
        .context("measuring the kernel of A")
    };
    let how = format!("Cholesky pivots below {KERNEL_PIVOT_TOL:e}·max diag");
    let h = d.h();
    if h.level() <= KERNEL_MEASURED_UP_TO {
        return Ok(format!("{} (measured: {how})", measure(d)?));
    }
    let coarse = MeshSize::from_level(KERNEL_MEASURED_UP_TO).expect("in range");
    let dim = measure(&Discretization::new_without_mass(scene, coarse)?)?;
    let p = &d.problem;
    let worst = p
        .rigid_modes()
        .iter()
        .map(|z| {
            let az = crate::solvers::numerics::linalg::spmv(p.a(), z);
            let size = z.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            az.iter().fold(0.0f64, |m, x| m.max(x.abs())) / (p.scales().stiffness * size)
        })
        .fold(0.0f64, f64::max);
    Ok(format!(
        "{dim} (measured at h = {coarse}: {how}; the meshes are nested and a P1 field of zero energy is rigid, so it is the same here, where the rigid mode z gives max|A z| = {worst:.1e}·K·max|z|)"
    ))
}
