//! P1 finite elements for plane elasticity: stiffness A(u, v) = ∫ σ(u):ε(v),
//! the consistent mass matrix of the L2 product, and loads from piecewise
//! constant tractions on the top side y = 1, integrated exactly.

use nalgebra_sparse::{CooMatrix, CsrMatrix};

use crate::mechanics::dofs::DofExpansion;
use crate::mechanics::material::Material;
use crate::mechanics::mesh::{Body, Mesh};
use crate::mechanics::scene::Traction;

/// Twice the signed area of a triangle.
fn twice_area(p: &[[f64; 2]; 3]) -> f64 {
    (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1])
}

/// The constant strain matrix B of a linear triangle: ε = B u_e with
/// ε = (ε11, ε22, 2ε12) and u_e = (u1_a, u2_a, u1_b, ...).
pub fn strain_matrix(p: [[f64; 2]; 3]) -> [[f64; 6]; 3] {
    let area2 = twice_area(&p);
    let mut b = [[0.0; 6]; 3];
    for a in 0..3 {
        let (q, r) = (p[(a + 1) % 3], p[(a + 2) % 3]);
        let dx = (q[1] - r[1]) / area2; // ∂φ_a/∂x
        let dy = (r[0] - q[0]) / area2; // ∂φ_a/∂y
        b[0][2 * a] = dx;
        b[1][2 * a + 1] = dy;
        b[2][2 * a] = dy;
        b[2][2 * a + 1] = dx;
    }
    b
}

/// Element stiffness of a linear triangle, local order (u1_a, u2_a, u1_b, ...):
/// K = area · BᵀDB.
pub fn element_stiffness(p: [[f64; 2]; 3], d: &[[f64; 3]; 3]) -> [[f64; 6]; 6] {
    let b = strain_matrix(p);
    let area = twice_area(&p) / 2.0;
    let mut k = [[0.0; 6]; 6];
    for (i, ki) in k.iter_mut().enumerate() {
        for (j, kij) in ki.iter_mut().enumerate() {
            let mut sum = 0.0;
            for r in 0..3 {
                for c in 0..3 {
                    sum += b[r][i] * d[r][c] * b[c][j];
                }
            }
            *kij = area * sum;
        }
    }
    k
}

/// Consistent P1 mass matrix of a triangle, per component: area/12·(1 + δ_ab).
/// Consistent rather than lumped because the proximal term of paper (15) is
/// the exact L2 norm, and on this mesh it has the sparsity of the stiffness,
/// so the relaxation sweep over A + M costs the same either way.
pub fn element_mass(p: [[f64; 2]; 3]) -> [[f64; 6]; 6] {
    let area = twice_area(&p) / 2.0;
    let mut m = [[0.0; 6]; 6];
    for a in 0..3 {
        for b in 0..3 {
            let value = area / 12.0 * if a == b { 2.0 } else { 1.0 };
            m[2 * a][2 * b] = value;
            m[2 * a + 1][2 * b + 1] = value;
        }
    }
    m
}

/// Assembles an element matrix over every triangle (optionally one body) into
/// the unknowns of `dofs` (eliminated components drop out, relative ones
/// expand into their two terms).
pub fn assemble(
    mesh: &Mesh,
    dofs: &impl DofExpansion,
    only: Option<Body>,
    element: impl Fn([[f64; 2]; 3]) -> [[f64; 6]; 6],
) -> CsrMatrix<f64> {
    let n = dofs.n();
    let mut coo = CooMatrix::new(n, n);
    for (body, tri) in mesh.triangles() {
        if only.is_some_and(|b| b != body) {
            continue;
        }
        let p = tri.map(|node| mesh.coords(node));
        let ke = element(p);
        let terms: Vec<_> = (0..6).map(|l| dofs.terms(tri[l / 2], l % 2)).collect();
        for (a, ta) in terms.iter().enumerate() {
            for (b, tb) in terms.iter().enumerate() {
                for &(i, ci) in ta.as_slice() {
                    for &(j, cj) in tb.as_slice() {
                        coo.push(i, j, ci * cj * ke[a][b]);
                    }
                }
            }
        }
    }
    CsrMatrix::from(&coo)
}

/// Stiffness matrix of both bodies.
pub fn stiffness(mesh: &Mesh, dofs: &impl DofExpansion, material: &Material) -> CsrMatrix<f64> {
    let d = material.elasticity_matrix();
    assemble(mesh, dofs, None, |p| element_stiffness(p, &d))
}

/// Mass matrix of both bodies (L2 product of displacement fields).
pub fn mass(mesh: &Mesh, dofs: &impl DofExpansion) -> CsrMatrix<f64> {
    assemble(mesh, dofs, None, element_mass)
}

/// Physical nodal forces (per node, x and y) of tractions (P''_1, P''_2) on
/// the top side y = 1 of the upper body. Each traction is constant on its
/// segment, so ∫ P φ_i over the part of an edge it covers is exact: the length
/// of that part times φ_i at its midpoint. Segment ends need not be nodes.
pub fn top_traction_forces(mesh: &Mesh, loads: &[Traction]) -> Vec<[f64; 2]> {
    let mut forces = vec![[0.0; 2]; mesh.num_nodes()];
    let h = mesh.h();
    let top = mesh.rows() - 1;
    for load in loads {
        for e in 0..mesh.n() - 1 {
            let (xa, xb) = (e as f64 * h, (e + 1) as f64 * h);
            let (lo, hi) = (load.from.max(xa), load.to.min(xb));
            if hi <= lo {
                continue;
            }
            let mid = 0.5 * (lo + hi);
            let len = hi - lo;
            let phi_b = (mid - xa) / h;
            for (k, p) in [(0, load.p1), (1, load.p2)] {
                forces[mesh.node(Body::Upper, e, top)][k] += p * len * (1.0 - phi_b);
                forces[mesh.node(Body::Upper, e + 1, top)][k] += p * len * phi_b;
            }
        }
    }
    forces
}

/// The load vector in the unknowns of `dofs`: f = Tᵀ F for the change of variables T.
pub fn load_vector(dofs: &impl DofExpansion, forces: &[[f64; 2]]) -> Vec<f64> {
    let mut f = vec![0.0; dofs.n()];
    for (node, force) in forces.iter().enumerate() {
        for (k, &value) in force.iter().enumerate() {
            for &(i, c) in dofs.terms(node, k).as_slice() {
                f[i] += c * value;
            }
        }
    }
    f
}
