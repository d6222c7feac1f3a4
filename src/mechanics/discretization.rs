//! One scene on one mesh, turned into the algebraic given-friction subproblem,
//! and the way back from its unknowns to both bodies' nodal displacements.

use contactlab_solvers::{ContactNode, ContactProblem, Csr, Mass, ProblemError};
use thiserror::Error;

use crate::mechanics::assembly;
use crate::mechanics::dofs::{ContactDofs, DofMap, Hold};
use crate::mechanics::mesh::{Body, Mesh};
use crate::mechanics::mesh_size::MeshSize;
use crate::mechanics::scene::{Scene, SceneError, Traction};

/// Building a discretization failed.
#[derive(Debug, Error)]
pub enum BuildError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(
        "material.young (--young) and loads[].p2 are too far apart in magnitude for double precision: {0}; choose units in which both are nearer 1"
    )]
    Scales(ProblemError),
    #[error(
        "material.young (--young) = {} makes the stiffness overflow: choose units in which E is smaller",
        crate::mechanics::scene::Shown::shown(young)
    )]
    Overflow { young: f64 },
    #[error("assembled problem is inconsistent: {0}")]
    Problem(ProblemError),
    #[error(transparent)]
    Memory(#[from] crate::memory::MemoryError),
}

/// The paper's scene on one mesh.
#[derive(Clone, Debug)]
pub struct Discretization {
    pub mesh: Mesh,
    pub dofs: DofMap,
    /// The contact problem (coefficient 𝓕 of the scene, bound g = 0).
    pub problem: ContactProblem,
    /// The scene's tractions on the top side ([`Discretization::forces`]
    /// gives their nodal forces: not kept, 16 bytes per node).
    pub loads: Vec<Traction>,
    /// Σ p2 · (to − from) of the scene's loads (condition (13): negative).
    pub total_load: f64,
}

impl Discretization {
    /// Validates the scene (condition (13) included) and assembles it on mesh `h`.
    pub fn new(scene: &Scene, h: MeshSize) -> Result<Self, BuildError> {
        scene.validate()?;
        Self::assemble(scene, h, true, true)
    }

    /// As [`Discretization::new`], without the mass matrix M
    /// ([`Mass::Omitted`]): for a solver that does not read it
    /// (`Entry::uses_mass`). A is the same to the bit.
    pub fn new_without_mass(scene: &Scene, h: MeshSize) -> Result<Self, BuildError> {
        scene.validate()?;
        Self::assemble(scene, h, false, true)
    }

    /// Assembles a scene without checking condition (13): only for showing
    /// what a solver does with a problem that has no solution (the stability
    /// map). Everything else should go through [`Discretization::new`].
    pub fn new_unchecked(scene: &Scene, h: MeshSize) -> Result<Self, BuildError> {
        Self::assemble(scene, h, true, false)
    }

    fn assemble(
        scene: &Scene,
        h: MeshSize,
        with_mass: bool,
        checked: bool,
    ) -> Result<Self, BuildError> {
        // Nothing large is allocated before the estimate says it fits.
        crate::memory::check(
            &format!("assembling {} at h = {h}", scene.name),
            h,
            |h| crate::memory::assembly(h, with_mass),
            |_| None,
        )?;
        let mesh = Mesh::new(h);
        let dofs = DofMap::with_hold(&mesh, scene.hold).with_side_shift(scene.side_shift);
        let (a, mass) = if with_mass {
            let (a, m) = assembly::stiffness_and_mass(&mesh, &dofs, &scene.materials());
            (a, Mass::OnStiffnessPattern(m))
        } else {
            let a = assembly::stiffness(&mesh, &dofs, &scene.materials());
            (a, Mass::Omitted)
        };
        let forces = assembly::top_traction_forces(&mesh, &scene.loads);
        let f = assembly::load_vector(&dofs, &forces);
        let contacts = contact_nodes(&mesh, dofs.contacts(), scene.friction);
        let modes = rigid_modes(&mesh, &dofs);
        let problem = if checked {
            ContactProblem::new(a, f, mass, contacts, modes)
        } else {
            ContactProblem::without_solvability_checks(a, f, mass, contacts, modes)
        };
        let gap: Vec<f64> = match &scene.gap {
            Some(g) => dofs.contacts().iter().map(|c| g.at(c.x)).collect(),
            None => Vec::new(),
        };
        let problem = problem
            .and_then(|p| {
                if gap.is_empty() {
                    Ok(p)
                } else {
                    p.with_gap(gap)
                }
            })
            .and_then(|p| {
                // A side shift is a rigid lift of the upper body: no load,
                // the slip offset σ = δ ([`DofMap::with_side_shift`]).
                if dofs.side_shift() == 0.0 {
                    Ok(p)
                } else {
                    p.with_slip_offset(dofs.slip_offset())
                }
            })
            .and_then(|p| {
                p.with_hierarchy(crate::mechanics::hierarchy::prolongations((&mesh, &dofs)))
            })
            .map_err(|e| match e {
                ProblemError::Scale { .. } => BuildError::Scales(e),
                ProblemError::NonFinite { what: "A" } => BuildError::Overflow {
                    young: scene.material.young.max(scene.materials().lower.young),
                },
                other => BuildError::Problem(other),
            })?;
        Ok(Self {
            mesh,
            dofs,
            problem,
            loads: scene.loads.clone(),
            total_load: scene.total_vertical_load(),
        })
    }

    /// Applied nodal forces (per node, x and y), before the change of
    /// variables.
    pub fn forces(&self) -> Vec<[f64; 2]> {
        assembly::top_traction_forces(&self.mesh, &self.loads)
    }

    pub fn h(&self) -> MeshSize {
        self.mesh.size()
    }

    /// The mass matrix M of the proximal term, paper (15), assembled from
    /// the mesh on A's pattern: for a level built without it
    /// ([`Discretization::new_without_mass`]), to read or export, without
    /// keeping it. Refused up front, as an assembly is, if it would not
    /// fit beside what the process holds.
    pub fn assemble_mass(&self) -> Result<Csr, BuildError> {
        let h = self.h();
        crate::memory::check(
            &format!("assembling the mass matrix M at h = {h}"),
            h,
            crate::memory::mass,
            |_| None,
        )?;
        Ok(assembly::mass_rows(&self.mesh, &self.dofs))
    }

    /// x of each contact node, increasing.
    pub fn contact_x(&self) -> Vec<f64> {
        self.dofs.contacts().iter().map(|c| c.x).collect()
    }

    /// The rigid vertical translation of the upper body (paper (11)).
    pub fn kernel_vector(&self) -> Vec<f64> {
        rigid_modes(&self.mesh, &self.dofs).swap_remove(0)
    }

    /// Nodal displacements of both bodies (per node, x and y).
    pub fn displacements(&self, v: &[f64]) -> Vec<[f64; 2]> {
        self.dofs.to_physical(v)
    }

    /// Evaluates this mesh's P1 field `u` (per node) of `body` at a point of it.
    pub fn evaluate(&self, u: &[[f64; 2]], body: Body, x: f64, y: f64) -> [f64; 2] {
        let h = self.mesh.h();
        let y0 = match body {
            Body::Lower => 0.0,
            Body::Upper => 0.5,
        };
        let (fx, fy) = (x / h, (y - y0) / h);
        let i = (fx.floor() as usize).min(self.mesh.n() - 2);
        let j = (fy.floor() as usize).min(self.mesh.rows() - 2);
        let (xi, eta) = (fx - i as f64, fy - j as f64);
        let node = |di, dj| u[self.mesh.node(body, i + di, j + dj)];
        // Lower-right triangle (LL, LR, UR) where ξ ≥ η, else (LL, UR, UL).
        let (corners, weights) = if xi >= eta {
            (
                [node(0, 0), node(1, 0), node(1, 1)],
                [1.0 - xi, xi - eta, eta],
            )
        } else {
            (
                [node(0, 0), node(1, 1), node(0, 1)],
                [1.0 - eta, xi, eta - xi],
            )
        };
        let mut out = [0.0; 2];
        for (c, w) in corners.iter().zip(weights) {
            out[0] += w * c[0];
            out[1] += w * c[1];
        }
        out
    }

    /// Unknowns of this mesh interpolating (linearly, per body) the unknowns
    /// `v` of another discretization of the same scene: prolongation from a
    /// coarse level, or injection from a fine one (nested meshes).
    pub fn transfer_from(&self, other: &Discretization, v: &[f64]) -> Vec<f64> {
        let u_other = other.displacements(v);
        let u: Vec<[f64; 2]> = (0..self.mesh.num_nodes())
            .map(|node| {
                let (body, ..) = self.mesh.locate(node);
                let [x, y] = self.mesh.coords(node);
                other.evaluate(&u_other, body, x, y)
            })
            .collect();
        self.dofs.from_physical(&u)
    }

    /// A quantity given per contact node of another discretization, linearly
    /// interpolated along Γ_K to this one's contact nodes.
    pub fn transfer_contact(&self, other: &Discretization, values: &[f64]) -> Vec<f64> {
        let h = other.mesh.h();
        let last = values.len() - 1;
        self.contact_x()
            .iter()
            .map(|&x| {
                let i = ((x / h).floor() as usize).min(last.saturating_sub(1));
                let w = (x / h - i as f64).clamp(0.0, 1.0);
                if last == 0 {
                    values[0]
                } else {
                    (1.0 - w) * values[i] + w * values[i + 1]
                }
            })
            .collect()
    }
}

/// The kernel of A: the rigid vertical translation of the upper body,
/// z'' = (0, 1), in the unknowns +1 on v''_2 away from Γ_K and −1 on every
/// jump t_i (paper (11)); and for a body free to slide ([`Hold::Sliding`])
/// its horizontal translation (1, 0), +1 on v''_1 and −1 on every slip s_i.
fn rigid_modes(mesh: &Mesh, dofs: &DofMap) -> Vec<Vec<f64>> {
    let translation = |e: [f64; 2]| {
        let u: Vec<[f64; 2]> = (0..mesh.num_nodes())
            .map(|node| match mesh.locate(node).0 {
                Body::Lower => [0.0, 0.0],
                Body::Upper => e,
            })
            .collect();
        dofs.from_direction(&u)
    };
    let mut modes = vec![translation([0.0, 1.0])];
    if dofs.hold() == Hold::Sliding {
        modes.push(translation([1.0, 0.0]));
    }
    modes
}

fn contact_nodes(mesh: &Mesh, contacts: &[ContactDofs], coefficient: f64) -> Vec<ContactNode> {
    let h = mesh.h();
    let last = contacts.len() - 1;
    contacts
        .iter()
        .enumerate()
        .map(|(i, c)| ContactNode {
            t: c.t,
            s: c.s,
            // Trapezoid rule on Γ_K: h inside, h/2 at both ends.
            weight: if i == 0 || i == last { h / 2.0 } else { h },
            coefficient,
        })
        .collect()
}
