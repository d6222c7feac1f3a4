//! The field over both bodies for ParaView: a VTK XML unstructured grid
//! (`.vtu`, ASCII), every node of both bodies (the contact nodes of Γ_K once
//! per body) and every P1 triangle.
//!
//! - point data `displacement` (u₁, u₂, 0); `contact_state` (−1 away from
//!   Γ_K, else 0 stick, 1 slip, 2 open, on both nodes of a contact pair);
//!   `contact_pressure` and `friction_traction` (0 away from Γ_K);
//! - cell data `body` (0 lower, 1 upper); `stress` (σ₁₁, σ₂₂, σ₁₂, named
//!   sigma_11, sigma_22, sigma_12 in the file; constant
//!   per triangle, σ = D ε); `von_mises` with σ₃₃ = ν(σ₁₁ + σ₂₂) in plane
//!   strain and 0 in plane stress.

use std::fmt::Write;

use contactlab_solvers::Solution;

use crate::mechanics::assembly::BodyMaterials;
use crate::mechanics::assembly::strain_matrix;
use crate::mechanics::contact_zone::{ContactState, SEPARATION_TOL, largest_displacement};
use crate::mechanics::discretization::Discretization;
use crate::mechanics::material::{Material, PlaneModel};
use crate::mechanics::mesh::Body;

/// Stress (σ₁₁, σ₂₂, σ₁₂) of each triangle and its von Mises stress, each
/// body by its own material.
pub fn element_stresses(
    d: &Discretization,
    materials: &BodyMaterials,
    u: &[[f64; 2]],
) -> Vec<([f64; 3], f64)> {
    let of = |body| match body {
        Body::Lower => &materials.lower,
        Body::Upper => &materials.upper,
    };
    let dms = [
        materials.lower.elasticity_matrix(),
        materials.upper.elasticity_matrix(),
    ];
    d.mesh
        .triangles()
        .map(|(body, nodes)| {
            let material: &Material = of(body);
            let dm = &dms[usize::from(body == Body::Upper)];
            let p = nodes.map(|n| d.mesh.coords(n));
            let b = strain_matrix(p);
            let ue: Vec<f64> = nodes.iter().flat_map(|&n| u[n]).collect();
            let eps: Vec<f64> = b
                .iter()
                .map(|row| row.iter().zip(&ue).map(|(a, x)| a * x).sum())
                .collect();
            let sigma: [f64; 3] = std::array::from_fn(|i| (0..3).map(|j| dm[i][j] * eps[j]).sum());
            let s33 = match material.plane {
                PlaneModel::Strain => material.poisson * (sigma[0] + sigma[1]),
                PlaneModel::Stress => 0.0,
            };
            let (a, bb, c) = (sigma[0], sigma[1], s33);
            let vm = (0.5 * ((a - bb).powi(2) + (bb - c).powi(2) + (c - a).powi(2))
                + 3.0 * sigma[2].powi(2))
            .sqrt();
            (sigma, vm)
        })
        .collect()
}

fn data_array(
    out: &mut String,
    name: &str,
    kind: &str,
    components: usize,
    values: impl Iterator<Item = String>,
) {
    named_data_array(out, name, kind, components, &[], values)
}

/// A data array whose components carry names (VTK's `ComponentName<i>`
/// attributes, which ParaView shows instead of 0, 1, 2).
fn named_data_array(
    out: &mut String,
    name: &str,
    kind: &str,
    components: usize,
    component_names: &[&str],
    values: impl Iterator<Item = String>,
) {
    let names: String = component_names
        .iter()
        .enumerate()
        .map(|(i, c)| format!(" ComponentName{i}=\"{c}\""))
        .collect();
    let _ = writeln!(
        out,
        "<DataArray type=\"{kind}\" Name=\"{name}\" NumberOfComponents=\"{components}\"{names} format=\"ascii\">"
    );
    for v in values {
        let _ = writeln!(out, "{v}");
    }
    out.push_str("</DataArray>\n");
}

/// The VTU text of a solution on `d` (its finest level).
pub fn vtu(d: &Discretization, materials: &BodyMaterials, s: &Solution) -> String {
    let mesh = &d.mesh;
    let u = d.displacements(&s.v);
    let n = mesh.num_nodes();
    let tol = SEPARATION_TOL * largest_displacement(d, s);
    let mut state = vec![-1i32; n];
    let mut pressure = vec![0.0; n];
    let mut traction = vec![0.0; n];
    for (i, c) in d.dofs.contacts().iter().enumerate() {
        let p = &d.problem;
        let st = ContactState::of(p.jump(&s.v, i), p.slip(&s.v, i), tol) as i32;
        for node in [c.lower_node, c.upper_node] {
            state[node] = st;
            pressure[node] = s.pressure[i];
            traction[node] = s.friction_traction[i];
        }
    }
    let triangles: Vec<(Body, [usize; 3])> = mesh.triangles().collect();
    let stresses = element_stresses(d, materials, &u);
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n");
    let _ = writeln!(
        out,
        "<Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{}\">",
        triangles.len()
    );
    out.push_str("<Points>\n");
    data_array(
        &mut out,
        "coordinates",
        "Float64",
        3,
        (0..n).map(|k| {
            let [x, y] = mesh.coords(k);
            format!("{x:e} {y:e} 0")
        }),
    );
    out.push_str("</Points>\n<Cells>\n");
    data_array(
        &mut out,
        "connectivity",
        "Int64",
        1,
        triangles
            .iter()
            .map(|(_, t)| format!("{} {} {}", t[0], t[1], t[2])),
    );
    data_array(
        &mut out,
        "offsets",
        "Int64",
        1,
        (1..=triangles.len()).map(|k| (3 * k).to_string()),
    );
    data_array(
        &mut out,
        "types",
        "UInt8",
        1,
        triangles.iter().map(|_| "5".to_string()),
    );
    out.push_str("</Cells>\n<PointData Vectors=\"displacement\">\n");
    data_array(
        &mut out,
        "displacement",
        "Float64",
        3,
        u.iter().map(|[a, b]| format!("{a:e} {b:e} 0")),
    );
    data_array(
        &mut out,
        "contact_state",
        "Int32",
        1,
        state.iter().map(|x| x.to_string()),
    );
    data_array(
        &mut out,
        "contact_pressure",
        "Float64",
        1,
        pressure.iter().map(|x| format!("{x:e}")),
    );
    data_array(
        &mut out,
        "friction_traction",
        "Float64",
        1,
        traction.iter().map(|x| format!("{x:e}")),
    );
    out.push_str("</PointData>\n<CellData Scalars=\"von_mises\">\n");
    data_array(
        &mut out,
        "body",
        "Int32",
        1,
        triangles
            .iter()
            .map(|(b, _)| (*b == Body::Upper) as i32)
            .map(|x| x.to_string()),
    );
    named_data_array(
        &mut out,
        "stress",
        "Float64",
        3,
        &["sigma_11", "sigma_22", "sigma_12"],
        stresses
            .iter()
            .map(|(s, _)| format!("{:e} {:e} {:e}", s[0], s[1], s[2])),
    );
    data_array(
        &mut out,
        "von_mises",
        "Float64",
        1,
        stresses.iter().map(|(_, v)| format!("{v:e}")),
    );
    out.push_str("</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_uniform_strain_gives_the_stress_of_hookes_law() {
        // u = (a x, 0): ε11 = a; plane strain: σ11 = c(1−ν)a, σ22 = cνa.
        let scene = crate::mechanics::scene::Scene::paper_problem(1).unwrap();
        let d = Discretization::new(
            &scene,
            crate::mechanics::mesh_size::MeshSize::from_level(3).unwrap(),
        )
        .unwrap();
        let m = Material::default();
        let a = 1e-3;
        let u: Vec<[f64; 2]> = (0..d.mesh.num_nodes())
            .map(|k| [a * d.mesh.coords(k)[0], 0.0])
            .collect();
        let (e, nu) = (m.young, m.poisson);
        let c = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
        for (s, _) in element_stresses(&d, &BodyMaterials::both(&m), &u) {
            assert!((s[0] - c * (1.0 - nu) * a).abs() < 1e-9 * e * a);
            assert!((s[1] - c * nu * a).abs() < 1e-9 * e * a);
            assert!(s[2].abs() < 1e-9 * e * a);
        }
    }
}
