//! The mesh hierarchy of the continuation as plain matrices: for the nested
//! uniform meshes 1/2, 1/4, …, h, the prolongation between consecutive
//! levels in the problem's own unknowns, so that multigrid solvers use the
//! hierarchy without seeing a mesh (Kornhuber & Krause 2001, section 3:
//! nested P1 spaces on both bodies; Gräser & Sander 2019, section 4).
//!
//! A fine unknown is read off the fine P1 field that interpolates the
//! coarse one: v_f = R_f I E_c v_c, with E_c the coarse unknowns' expansion
//! into nodal displacements (boundary conditions eliminated, u'' = u' − (s, t)
//! at contact nodes), I the P1 interpolation of nested meshes (a fine node is
//! a coarse node or the midpoint of a coarse edge; the diagonals run from
//! lower left to upper right on both meshes) and R_f the fine unknowns of a
//! nodal field (the jump t = u'_2 − u''_2 and slip s = u'_1 − u''_1 at the
//! contact nodes). Both bodies' P1 fields are interpolated separately, so
//! the jump and slip along Γ_K are interpolated linearly; the rigid mode of
//! the coarse problem is prolongated to the fine one exactly.

use nalgebra_sparse::{CooMatrix, CsrMatrix};

use crate::mechanics::dofs::{DofExpansion, DofMap};
use crate::mechanics::mesh::{Body, Mesh};
use crate::mechanics::mesh_size::{MIN_LEVEL, MeshSize};

/// The coarse nodes (with weights) whose P1 interpolation gives fine node
/// `(body, i, j)` of a mesh nested in `coarse` (one level finer).
fn parents(coarse: &Mesh, body: Body, i: usize, j: usize) -> [(usize, f64); 2] {
    let node = |a: usize, b: usize| coarse.node(body, a, b);
    match (i % 2, j % 2) {
        (0, 0) => [(node(i / 2, j / 2), 1.0), (node(i / 2, j / 2), 0.0)],
        (1, 0) => [(node(i / 2, j / 2), 0.5), (node(i / 2 + 1, j / 2), 0.5)],
        (0, 1) => [(node(i / 2, j / 2), 0.5), (node(i / 2, j / 2 + 1), 0.5)],
        // The midpoint of a diagonal (lower left to upper right).
        _ => [(node(i / 2, j / 2), 0.5), (node(i / 2 + 1, j / 2 + 1), 0.5)],
    }
}

/// The prolongation from the unknowns of `coarse` to those of `fine` (one
/// level finer), as an n_fine × n_coarse sparse matrix.
pub fn prolongation(coarse: (&Mesh, &DofMap), fine: (&Mesh, &DofMap)) -> CsrMatrix<f64> {
    let (cmesh, cdofs) = coarse;
    let (fmesh, fdofs) = fine;
    // Component k of fine node `node` as (coarse unknown, weight) terms.
    let physical = |node: usize, k: usize, out: &mut Vec<(usize, f64)>| {
        let (body, i, j) = fmesh.locate(node);
        for (parent, w) in parents(cmesh, body, i, j) {
            if w != 0.0 {
                for &(unknown, c) in cdofs.terms(parent, k).as_slice() {
                    out.push((unknown, w * c));
                }
            }
        }
    };
    let mut coo = CooMatrix::new(fdofs.n(), cdofs.n());
    let mut terms = Vec::with_capacity(8);
    for node in 0..fmesh.num_nodes() {
        for k in 0..2 {
            if let crate::mechanics::dofs::Dof::Slot(row) = fdofs.dof(node, k) {
                terms.clear();
                physical(node, k, &mut terms);
                for &(col, w) in &terms {
                    coo.push(row, col, w);
                }
            }
        }
    }
    for c in fdofs.contacts() {
        for (k, row) in [(0, c.s), (1, c.t)] {
            terms.clear();
            physical(c.lower_node, k, &mut terms);
            let lower = terms.len();
            physical(c.upper_node, k, &mut terms);
            for (n, &(col, w)) in terms.iter().enumerate() {
                coo.push(row, col, if n < lower { w } else { -w });
            }
        }
    }
    // Duplicates (a coarse unknown reached twice) are summed; exact zeros
    // (u' − u'' of a shared lower unknown) are dropped.
    CsrMatrix::from(&coo).filter(|_, _, &v| v != 0.0)
}

/// The prolongations of the nested meshes 1/2, 1/4, …, `h`, coarse to fine
/// (empty at h = 1/2).
pub fn prolongations(h: MeshSize) -> Vec<CsrMatrix<f64>> {
    let meshes: Vec<Mesh> = (MIN_LEVEL..=h.level())
        .map(|k| Mesh::new(MeshSize::from_level(k).expect("between the bounds")))
        .collect();
    let dofs: Vec<DofMap> = meshes.iter().map(DofMap::new).collect();
    (1..meshes.len())
        .map(|l| prolongation((&meshes[l - 1], &dofs[l - 1]), (&meshes[l], &dofs[l])))
        .collect()
}
