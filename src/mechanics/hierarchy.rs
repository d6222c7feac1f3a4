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

use crate::mechanics::dofs::{Dof, DofExpansion, DofMap};
use crate::mechanics::mesh::{Body, Mesh};
use crate::mechanics::mesh_size::{MIN_LEVEL, MeshSize};
use crate::solvers::Csr;
use crate::solvers::numerics::linalg::CsrBuilder;

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
/// level finer), as an n_fine × n_coarse sparse matrix, built row by row
/// (no triplets: at h = 1/4096 those and their sorting took 1.4 GB beside
/// the assembled problem).
pub fn prolongation(coarse: (&Mesh, &DofMap), fine: (&Mesh, &DofMap)) -> Csr {
    let (cmesh, cdofs) = coarse;
    let (fmesh, fdofs) = fine;
    // Component k of fine node `node` as (coarse unknown, weight) terms,
    // with `sign`.
    let physical = |node: usize, k: usize, sign: f64, out: &mut Vec<(u32, f64)>| {
        let (body, i, j) = fmesh.locate(node);
        for (parent, w) in parents(cmesh, body, i, j) {
            if w != 0.0 {
                for &(unknown, c) in cdofs.terms(parent, k).as_slice() {
                    out.push((unknown as u32, sign * w * c));
                }
            }
        }
    };
    // Each fine unknown's source: 2·node + k for a node's own component,
    // CONTACT + 2·c + k for the slip (k = 0) or jump (k = 1) of contact c.
    const CONTACT: u64 = 1 << 63;
    let mut source = vec![u64::MAX; fdofs.n()];
    for node in 0..fmesh.num_nodes() {
        for k in 0..2 {
            if let Dof::Slot(row) = fdofs.dof(node, k) {
                source[row] = (2 * node + k) as u64;
            }
        }
    }
    for (c, dofs) in fdofs.contacts().iter().enumerate() {
        for (k, row) in [(0, dofs.s), (1, dofs.t)] {
            source[row] = CONTACT | (2 * c + k) as u64;
        }
    }
    let mut out = CsrBuilder::<1>::new(fdofs.n(), cdofs.n());
    let (mut terms, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    for &from in &source {
        assert!(
            from != u64::MAX,
            "every fine unknown is a node's or a contact's"
        );
        terms.clear();
        if from & CONTACT == 0 {
            let from = from as usize;
            physical(from / 2, from % 2, 1.0, &mut terms);
        } else {
            let from = (from & !CONTACT) as usize;
            let (c, k) = (&fdofs.contacts()[from / 2], from % 2);
            // s = u'_1 − u''_1, t = u'_2 − u''_2.
            physical(c.lower_node, k, 1.0, &mut terms);
            physical(c.upper_node, k, -1.0, &mut terms);
        }
        // Duplicates (a coarse unknown reached twice) are summed in the
        // order met; exact zeros (u' − u'' of a shared lower unknown) are
        // dropped.
        terms.sort_by_key(|&(col, _)| col);
        cols.clear();
        vals.clear();
        for &(col, w) in &terms {
            if cols.last() == Some(&col) {
                *vals.last_mut().expect("one per column") += w;
            } else {
                cols.push(col);
                vals.push(w);
            }
        }
        let mut kept = 0;
        for q in 0..cols.len() {
            if vals[q] != 0.0 {
                (cols[kept], vals[kept]) = (cols[q], vals[q]);
                kept += 1;
            }
        }
        out.push_row(&cols[..kept], [&vals[..kept]]);
    }
    let [p] = out
        .finish()
        .expect("a prolongation's rows are sorted, distinct and in range");
    p
}

/// The prolongations of the nested meshes 1/2, 1/4, …, down to the mesh
/// of `finest` (its unknowns given), coarse to fine (empty at h = 1/2).
pub fn prolongations(finest: (&Mesh, &DofMap)) -> Vec<Csr> {
    let level = finest.0.size().level();
    let meshes: Vec<Mesh> = (MIN_LEVEL..level)
        .map(|k| Mesh::new(MeshSize::from_level(k).expect("between the bounds")))
        .collect();
    let hold = finest.1.hold();
    let dofs: Vec<DofMap> = meshes.iter().map(|m| DofMap::with_hold(m, hold)).collect();
    let level_of = |l: usize| {
        if l < meshes.len() {
            (&meshes[l], &dofs[l])
        } else {
            finest
        }
    };
    (1..=meshes.len())
        .map(|l| prolongation(level_of(l - 1), level_of(l)))
        .collect()
}
