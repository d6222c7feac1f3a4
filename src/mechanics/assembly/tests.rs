use super::*;

/// Row offsets and column indices.
type Pattern = (Vec<u32>, Vec<u32>);
use crate::mechanics::dofs::{DofMap, PhysicalDofs, Terms};
use crate::mechanics::mesh_size::MeshSize;

/// Both sums, as pattern and values' bits.
fn both_sums(
    mesh: &Mesh,
    dofs: &impl DofExpansion,
    only: Option<Body>,
) -> [(Pattern, Vec<Vec<u64>>); 2] {
    let d = Material::default().elasticity_matrix();
    let elements: [&ElementMatrix<'_>; 2] =
        [&|_, p| element_stiffness(p, &d), &|_, p| element_mass(p)];
    [Sum::ByNodesWherePossible, Sum::ByUnknowns].map(|sum| {
        let matrices = assemble_rows(mesh, dofs, only, elements, sum);
        let pattern = (
            matrices[0].row_offsets().to_vec(),
            matrices[0].whole_col_indices().into_owned(),
        );
        let bits = matrices.iter().map(|m| {
            m.values()
                .iter(m.row_offsets())
                .map(|x| x.to_bits())
                .collect()
        });
        (pattern, bits.collect())
    })
}

/// Every component of node `b` is node `a`'s unknown: the nodes next to
/// both meet that unknown through two nodes.
struct Tied {
    physical: PhysicalDofs,
    a: usize,
    b: usize,
}

impl DofExpansion for Tied {
    fn n(&self) -> usize {
        self.physical.n()
    }

    fn terms(&self, node: usize, k: usize) -> Terms {
        let node = if node == self.b { self.a } else { node };
        self.physical.terms(node, k)
    }
}

/// A block whose nodes around meet one unknown through two nodes goes
/// back to the sums by unknowns: kept by nodes, its rows would hold that
/// column twice and the patterns would differ.
#[test]
fn an_unknown_met_through_two_nodes_is_summed_by_unknowns() {
    let mesh = Mesh::new(MeshSize::from_level(2).unwrap());
    let dofs = Tied {
        physical: PhysicalDofs {
            num_nodes: mesh.num_nodes(),
        },
        a: mesh.node(Body::Lower, 1, 1),
        b: mesh.node(Body::Lower, 2, 1),
    };
    let [(p1, v1), (p2, v2)] = both_sums(&mesh, &dofs, None);
    assert_eq!(p1, p2);
    assert_eq!(v1, v2);
}

/// Summing one-node blocks by nodes gives the sums by unknowns bit for
/// bit (the sign of zero included) on the paper's meshes, both bodies
/// and each alone: a wrong corner, component or coefficient in the
/// 2 × 2 blocks, a lost contact term, or a duplicate unknown not sent
/// back to the sums by unknowns would show here.
#[test]
fn sums_by_nodes_are_the_sums_by_unknowns_bit_for_bit() {
    for k in 1..=5 {
        let mesh = Mesh::new(MeshSize::from_level(k).unwrap());
        let dofs = DofMap::new(&mesh);
        for only in [None, Some(Body::Lower), Some(Body::Upper)] {
            let [(p1, v1), (p2, v2)] = both_sums(&mesh, &dofs, only);
            assert_eq!(p1, p2, "k = {k}, {only:?}");
            assert_eq!(v1, v2, "k = {k}, {only:?}");
        }
    }
}

/// The matrix-free energy is vᵀ A v with the assembled A, in the problem's
/// own unknowns (the change of variables on Γ_K and the boundary
/// conditions included): a wrong element matrix, or the field read in the
/// wrong order, fails it.
#[test]
fn energy_without_a_is_the_stiffness_form() {
    let mesh = Mesh::new(MeshSize::from_level(3).unwrap());
    let dofs = DofMap::new(&mesh);
    let material = Material::default();
    let a = stiffness(&mesh, &dofs, &BodyMaterials::both(&material));
    let v: Vec<f64> = (0..dofs.n())
        .map(|i| ((i * 29 % 23) as f64 - 11.0) / 7.0)
        .collect();
    let av = contactlab_solvers::numerics::linalg::spmv(&a, &v);
    let expected: f64 = v.iter().zip(&av).map(|(a, b)| a * b).sum();
    let got = energy_norm_squared(&mesh, &material, &dofs.to_physical(&v));
    assert!(
        (got - expected).abs() <= 1e-12 * expected,
        "{got} vs {expected}"
    );
}

/// The matrix-free L2 norm is vᵀ M v with the assembled M, in the problem's
/// own unknowns (the change of variables on Γ_K included).
#[test]
fn l2_norm_without_m_is_the_mass_matrix_form() {
    let mesh = Mesh::new(MeshSize::from_level(3).unwrap());
    let dofs = DofMap::new(&mesh);
    let m = mass(&mesh, &dofs);
    let v: Vec<f64> = (0..dofs.n())
        .map(|i| ((i * 29 % 23) as f64 - 11.0) / 7.0)
        .collect();
    let mv = contactlab_solvers::numerics::linalg::spmv(&m, &v);
    let expected: f64 = v.iter().zip(&mv).map(|(a, b)| a * b).sum();
    let got = l2_norm_squared(&mesh, &dofs.to_physical(&v));
    assert!(
        (got - expected).abs() <= 1e-12 * expected,
        "{got} vs {expected}"
    );
}

/// Each body is assembled with its own material: with the lower body
/// twice as stiff, vᵀ A v grows by exactly the lower body's energy (the
/// upper's unchanged), for a v that strains both. Assembling either body
/// with the other's material, or the element cache sharing one matrix
/// across bodies, fails it.
#[test]
fn each_body_is_assembled_with_its_own_material() {
    let mesh = Mesh::new(MeshSize::from_level(3).unwrap());
    let dofs = DofMap::new(&mesh);
    let upper = Material::default();
    let lower = Material {
        young: 2.0 * upper.young,
        ..upper
    };
    let v: Vec<f64> = (0..dofs.n())
        .map(|i| ((i * 29 % 23) as f64 - 11.0) / 7.0)
        .collect();
    let energy = |a: &Csr| {
        let av = contactlab_solvers::numerics::linalg::spmv(a, &v);
        v.iter().zip(&av).map(|(a, b)| a * b).sum::<f64>()
    };
    let one = energy(&stiffness(&mesh, &dofs, &BodyMaterials::both(&upper)));
    let two = energy(&stiffness(&mesh, &dofs, &BodyMaterials { lower, upper }));
    let d = upper.elasticity_matrix();
    let lower_only = assemble(&mesh, &dofs, Some(Body::Lower), |p| {
        element_stiffness(p, &d)
    });
    let lower_energy: f64 = lower_only
        .triplet_iter()
        .map(|(i, j, x)| v[i] * x * v[j])
        .sum();
    assert!(
        lower_energy > 0.1 * one && lower_energy < 0.9 * one,
        "{lower_energy} of {one}"
    );
    assert!(
        (two - (one + lower_energy)).abs() <= 1e-12 * two,
        "{two} vs {one} + {lower_energy}"
    );
    // With the mass on the same pattern, the stiffness is the same.
    let (a, _) = stiffness_and_mass(&mesh, &dofs, &BodyMaterials { lower, upper });
    assert!((energy(&a) - two).abs() <= 1e-12 * two);
}
