//! The mesh beside an exported instance: node coordinates, the map from
//! the problem's unknowns to nodal displacements, and the triangles, so
//! that an answer computed elsewhere can be plotted or post-processed
//! (`export`'s `nodes.csv` and `triangles.csv`).
//!
//! The unknowns are the free nodal components, except at the upper body's
//! contact nodes, whose components are replaced by the jump and the slip
//! (paper, section 5): v''_k = v'_k − (s_i, t_i)_k. So each displacement
//! component is u = v[plus] − v[minus], either index possibly absent
//! (absent both: a fixed zero of the boundary conditions).

use std::path::Path;

use anyhow::Result;
use serde::Serialize;

use crate::io::output::write_atomic;
use crate::mechanics::discretization::Discretization;
use crate::mechanics::dofs::Dof;
use crate::mechanics::mesh::Body;

/// One row of `nodes.csv`: a mesh node and its displacement in unknowns.
#[derive(Debug, Serialize, PartialEq)]
pub struct NodeRow {
    pub node: usize,
    /// `lower` (Ω', clamped on y = 0) or `upper` (Ω'', on the roller x = 1).
    pub body: &'static str,
    pub x: f64,
    pub y: f64,
    /// u₁ = v[u1_plus] − v[u1_minus] (0-based; empty: that term is absent).
    pub u1_plus: Option<usize>,
    pub u1_minus: Option<usize>,
    /// u₂ = v[u2_plus] − v[u2_minus].
    pub u2_plus: Option<usize>,
    pub u2_minus: Option<usize>,
}

/// One row of `triangles.csv`: a P1 element, counterclockwise.
#[derive(Debug, Serialize)]
struct TriangleRow {
    body: &'static str,
    n0: usize,
    n1: usize,
    n2: usize,
}

fn body_name(body: Body) -> &'static str {
    match body {
        Body::Lower => "lower",
        Body::Upper => "upper",
    }
}

fn split(dof: Dof) -> (Option<usize>, Option<usize>) {
    match dof {
        Dof::Fixed => (None, None),
        Dof::Slot(k) => (Some(k), None),
        Dof::Relative { base, own } => (Some(base), Some(own)),
    }
}

/// The rows of `nodes.csv` for `d`, one per mesh node in node order.
pub fn node_rows(d: &Discretization) -> Vec<NodeRow> {
    (0..d.mesh.num_nodes())
        .map(|node| {
            let (body, _, _) = d.mesh.locate(node);
            let [x, y] = d.mesh.coords(node);
            let (u1_plus, u1_minus) = split(d.dofs.dof(node, 0));
            let (u2_plus, u2_minus) = split(d.dofs.dof(node, 1));
            NodeRow {
                node,
                body: body_name(body),
                x,
                y,
                u1_plus,
                u1_minus,
                u2_plus,
                u2_minus,
            }
        })
        .collect()
}

/// Writes `nodes.csv` and `triangles.csv` of `d` into `dir`.
pub fn write(dir: &Path, d: &Discretization) -> Result<()> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for row in node_rows(d) {
        w.serialize(row)?;
    }
    write_atomic(&dir.join("nodes.csv"), &w.into_inner()?)?;
    let mut w = csv::Writer::from_writer(Vec::new());
    for (body, [n0, n1, n2]) in d.mesh.triangles() {
        w.serialize(TriangleRow {
            body: body_name(body),
            n0,
            n1,
            n2,
        })?;
    }
    write_atomic(&dir.join("triangles.csv"), &w.into_inner()?)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::mesh_size::MeshSize;
    use crate::mechanics::scene::Scene;

    /// The map reproduces the discretization's own nodal displacements
    /// from any vector of unknowns, node for node: u = v[plus] − v[minus].
    #[test]
    fn the_map_gives_the_nodal_displacements() {
        let scene = Scene::paper_problem(1).unwrap();
        let d = Discretization::new(&scene, MeshSize::from_level(3).unwrap()).unwrap();
        let v: Vec<f64> = (0..d.problem.n()).map(|k| (k as f64).sin()).collect();
        let u = d.displacements(&v);
        let term = |plus: Option<usize>, minus: Option<usize>| {
            plus.map_or(0.0, |k| v[k]) - minus.map_or(0.0, |k| v[k])
        };
        let rows = node_rows(&d);
        assert_eq!(rows.len(), u.len());
        let mut relative = 0;
        for (r, ui) in rows.iter().zip(&u) {
            assert_eq!(term(r.u1_plus, r.u1_minus), ui[0], "node {}", r.node);
            assert_eq!(term(r.u2_plus, r.u2_minus), ui[1], "node {}", r.node);
            relative += usize::from(r.u2_minus.is_some());
            // Clamped lower edge, roller on the upper body's x = 1.
            if r.body == "lower" && r.y == 0.0 {
                assert_eq!((r.u1_plus, r.u2_plus), (None, None));
            }
            // (the corner on Γ_K keeps its slip unknown: a contact node.)
            if r.body == "upper" && r.x == 1.0 && r.u2_minus.is_none() {
                assert_eq!(r.u1_plus, None);
            }
        }
        assert_eq!(relative, d.problem.contacts().len(), "one per contact node");
    }
}
