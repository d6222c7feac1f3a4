//! The paper's scene as one algebraic problem: counts, symmetry, rigid
//! motions, the one-dimensional kernel, the patch test, loads and masses.

use contactlab::mechanics::assembly::{self, BodyMaterials, strain_matrix};
use contactlab::mechanics::discretization::{BuildError, Discretization};
use contactlab::mechanics::dofs::{DofExpansion, DofMap, PhysicalDofs};
use contactlab::mechanics::material::{Material, PlaneModel};
use contactlab::mechanics::mesh::{Body, Mesh};
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::{Scene, SceneError, Traction};
use contactlab::solvers::numerics::linalg::{SparseCholesky, kernel_dimension, max_abs, spmv};
use nalgebra_sparse::{CooMatrix, CsrMatrix};

fn h(k: u32) -> MeshSize {
    MeshSize::from_level(k).unwrap()
}

fn problem(n: u32, k: u32) -> Discretization {
    Discretization::new(&Scene::paper_problem(n).unwrap(), h(k)).unwrap()
}

/// The stiffness has one row per kind of node (the interior, edges and
/// corners of each body, Γ_K), the same at every h, so the problem keeps
/// its values once: the same few hundred numbers whatever the mesh, and
/// its prolongations likewise. An assembly that summed one element's
/// entries in another order than the next one's (other bits for the same
/// stencil) would make them grow with h, and A's memory with them. Its
/// columns likewise: the unknowns are numbered node by node, row by row,
/// so each kind of node meets its neighbours at the same distances in the
/// numbering; a numbering that broke this (or an assembly that kept the
/// columns whole) would add 4 bytes per entry at every h.
#[test]
fn the_stiffness_keeps_each_distinct_row_once_whatever_h() {
    let stored: Vec<[usize; 2]> = (4..=7)
        .map(|k| {
            let d = problem(1, k);
            let a = d.problem.a();
            assert!(a.is_shared(), "A at k = {k}");
            assert!(a.has_shared_columns(), "A's columns at k = {k}");
            for (l, p) in d.problem.prolongations().iter().enumerate() {
                assert!(p.is_shared(), "prolongation {l} at k = {k}");
            }
            [a.stored_values(), a.stored_columns()]
        })
        .collect();
    assert!(stored.iter().all(|&s| s == stored[0]), "{stored:?}");
    assert!(stored[0][0] < 1000 && stored[0][1] < 1000, "{stored:?}");
}

fn materials() -> [Material; 2] {
    [PlaneModel::Strain, PlaneModel::Stress].map(|plane| Material {
        plane,
        ..Material::default()
    })
}

#[test]
fn counts_of_nodes_elements_and_unknowns() {
    for k in [1, 3, 4, 5, 6] {
        let d = problem(1, k);
        let n = (1usize << k) + 1;
        assert_eq!(d.mesh.num_nodes(), n * n + n);
        assert_eq!(d.mesh.num_elements(), 2 * (n - 1) * (n - 1));
        // Every node has 2 components; the clamped row y = 0 (n nodes) loses
        // both, the roller x = 1, ½ < y ≤ 1 ((n − 1)/2 nodes) loses u''_1.
        assert_eq!(
            d.problem.n(),
            2 * (n * n + n) - 2 * n - (n - 1) / 2,
            "k = {k}"
        );
        assert_eq!(d.problem.contacts().len(), n);
    }
}

#[test]
fn trapezoid_weights_sum_to_the_length_of_the_contact_line() {
    let d = problem(1, 4);
    let w: Vec<f64> = d.problem.contacts().iter().map(|c| c.weight).collect();
    assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-14);
    assert_eq!(w[0], w[1] / 2.0);
    assert_eq!(w[w.len() - 1], w[1] / 2.0);
}

fn max_asymmetry(a: &CsrMatrix<f64>) -> f64 {
    a.triplet_iter()
        .map(|(i, j, v)| (v - a.get_entry(j, i).map(|e| e.into_value()).unwrap_or(0.0)).abs())
        .fold(0.0, f64::max)
}

#[test]
fn stiffness_is_symmetric() {
    for m in materials() {
        let mesh = Mesh::new(h(3));
        let a = assembly::stiffness(
            &mesh,
            &PhysicalDofs {
                num_nodes: mesh.num_nodes(),
            },
            &BodyMaterials::both(&m),
        )
        .to_nalgebra();
        let scale = max_abs(a.values());
        assert_eq!(
            max_asymmetry(&a),
            0.0,
            "assembled entries are summed in the same order"
        );
        assert!(scale > 0.0);
        let d = problem(2, 4);
        assert!(
            max_asymmetry(&d.problem.a().to_nalgebra())
                <= 1e-12 * max_abs(d.problem.a().to_nalgebra().values())
        );
    }
}

/// Rigid motions of one body: two translations and the infinitesimal rotation.
fn rigid_motions(mesh: &Mesh, body: Body) -> Vec<Vec<f64>> {
    let field = |f: &dyn Fn(f64, f64) -> [f64; 2]| -> Vec<f64> {
        (0..mesh.num_nodes())
            .flat_map(|node| {
                let (b, ..) = mesh.locate(node);
                let [x, y] = mesh.coords(node);
                if b == body { f(x, y) } else { [0.0, 0.0] }
            })
            .collect()
    };
    vec![
        field(&|_, _| [1.0, 0.0]),
        field(&|_, _| [0.0, 1.0]),
        field(&|x, y| [-y, x]),
    ]
}

#[test]
fn rigid_motions_of_each_body_have_zero_energy_before_boundary_conditions() {
    for m in materials() {
        let mesh = Mesh::new(h(4));
        let a = assembly::stiffness(
            &mesh,
            &PhysicalDofs {
                num_nodes: mesh.num_nodes(),
            },
            &BodyMaterials::both(&m),
        )
        .to_nalgebra();
        let scale = max_abs(a.values());
        for body in [Body::Lower, Body::Upper] {
            for z in rigid_motions(&mesh, body) {
                let az = spmv(&a, &z);
                assert!(
                    max_abs(&az) <= 1e-11 * scale,
                    "{body:?}: |Az| = {}",
                    max_abs(&az)
                );
                let energy: f64 = z.iter().zip(&az).map(|(x, y)| x * y).sum();
                assert!(energy.abs() <= 1e-10 * scale);
            }
        }
        // And these are all: the unconstrained two-body assembly has a measured
        // kernel of dimension 2 × 3.
        assert_eq!(kernel_dimension(&a, 1e-9).unwrap(), 6);
    }
}

#[test]
fn a_deformation_has_positive_energy() {
    let mesh = Mesh::new(h(3));
    let a = assembly::stiffness(
        &mesh,
        &PhysicalDofs {
            num_nodes: mesh.num_nodes(),
        },
        &BodyMaterials::both(&Material::default()),
    )
    .to_nalgebra();
    let stretch: Vec<f64> = (0..mesh.num_nodes())
        .flat_map(|n| [mesh.coords(n)[0], 0.0])
        .collect();
    let e: f64 = stretch
        .iter()
        .zip(spmv(&a, &stretch))
        .map(|(x, y)| x * y)
        .sum();
    // Uniform strain ε11 = 1 over area 1: energy ∫ σ:ε = D11.
    let d11 = Material::default().elasticity_matrix()[0][0];
    assert!((e - d11).abs() <= 1e-9 * d11, "{e} vs {d11}");
}

/// Sparse A + z zᵀ (z dense on its support) as CSR.
fn plus_outer(a: &CsrMatrix<f64>, z: &[f64]) -> CsrMatrix<f64> {
    let n = a.nrows();
    let mut coo = CooMatrix::new(n, n);
    for (i, j, &v) in a.triplet_iter() {
        coo.push(i, j, v);
    }
    let support: Vec<usize> = (0..n).filter(|&i| z[i] != 0.0).collect();
    for &i in &support {
        for &j in &support {
            coo.push(i, j, z[i] * z[j]);
        }
    }
    CsrMatrix::from(&coo)
}

#[test]
fn kernel_after_boundary_conditions_is_the_upper_bodys_vertical_translation() {
    for k in [3, 6] {
        for m in materials() {
            let mut scene = Scene::paper_problem(1).unwrap();
            scene.material = m;
            let d = Discretization::new(&scene, h(k)).unwrap();
            let a = &d.problem.a().to_nalgebra();
            let z = d.kernel_vector();
            // In the (t, s) variables: -1 on every jump, +1 on v''_2 off Γ_K, 0 elsewhere.
            for c in d.problem.contacts() {
                assert_eq!(z[c.t], -1.0);
                assert_eq!(z[c.s], 0.0);
            }
            let scale = max_abs(a.values());
            assert!(max_abs(&spmv(a, &z)) <= 1e-11 * scale, "A z ≠ 0 at k = {k}");
            // A + z zᵀ positive definite ⇔ ker A ⊆ span z (A is PSD).
            let az = plus_outer(a, &z);
            SparseCholesky::new(&az).expect("A + z zᵀ must be positive definite");
            // Measured: one near-zero Cholesky pivot for A, none for A + z zᵀ.
            // (A plain LLᵀ of A may "succeed" on a round-off pivot, so it
            // cannot show singularity by itself.)
            assert_eq!(kernel_dimension(a, 1e-9).unwrap(), 1);
            assert_eq!(kernel_dimension(&az, 1e-9).unwrap(), 0);
        }
    }
}

/// Affine field u = (a0 + a1 x + a2 y, b0 + b1 x + b2 y).
fn affine(x: f64, y: f64) -> [f64; 2] {
    [1e-3 + 2e-4 * x - 3e-4 * y, -2e-3 + 5e-4 * x + 1e-4 * y]
}

#[test]
fn patch_test_affine_field_gives_constant_stress_and_no_interior_forces() {
    let exact_strain = [2e-4, 1e-4, -3e-4 + 5e-4];
    for m in materials() {
        let d = m.elasticity_matrix();
        let mesh = Mesh::new(h(3));
        // Exact constant strain (hence stress D ε) in every element.
        for (_, tri) in mesh.triangles() {
            let p = tri.map(|n| mesh.coords(n));
            let ue: Vec<f64> = p.iter().flat_map(|q| affine(q[0], q[1])).collect();
            let b = strain_matrix(p);
            for r in 0..3 {
                let eps: f64 = (0..6).map(|c| b[r][c] * ue[c]).sum();
                assert!((eps - exact_strain[r]).abs() < 1e-15, "strain {r}: {eps}");
            }
        }
        // Zero nodal forces at interior nodes of each body.
        let a = assembly::stiffness(
            &mesh,
            &PhysicalDofs {
                num_nodes: mesh.num_nodes(),
            },
            &BodyMaterials::both(&m),
        )
        .to_nalgebra();
        let u: Vec<f64> = (0..mesh.num_nodes())
            .flat_map(|n| {
                let [x, y] = mesh.coords(n);
                affine(x, y)
            })
            .collect();
        let forces = spmv(&a, &u);
        let scale = d[0][0] * 5e-4;
        for node in 0..mesh.num_nodes() {
            let (_, i, j) = mesh.locate(node);
            let interior = i > 0 && i < mesh.n() - 1 && j > 0 && j < mesh.rows() - 1;
            if interior {
                for k in 0..2 {
                    assert!(
                        forces[2 * node + k].abs() < 1e-12 * scale,
                        "node {node}: {}",
                        forces[2 * node + k]
                    );
                }
            }
        }
        // Boundary forces equal the exact traction σ n integrated: on the
        // lower body's right side x = 1 (n = e1) the x-force is σ11 × length.
        let sigma11: f64 = (0..3).map(|c| d[0][c] * exact_strain[c]).sum();
        let right: f64 = (0..mesh.rows())
            .map(|j| forces[2 * mesh.node(Body::Lower, mesh.n() - 1, j)])
            .sum();
        assert!(
            (right - sigma11 * 0.5).abs() < 1e-10 * scale,
            "{right} vs {}",
            sigma11 * 0.5
        );
    }
}

#[test]
fn load_totals_match_the_applied_force_for_every_h() {
    for (n, total) in [(1, -20.0), (2, -40.0), (3, -60.0)] {
        for k in 1..=8 {
            let d = problem(n, k);
            let fy: f64 = d.forces().iter().map(|f| f[1]).sum();
            let fx: f64 = d.forces().iter().map(|f| f[0]).sum();
            assert!(
                (fy - total).abs() < 1e-12 * total.abs(),
                "problem {n}, k = {k}: {fy}"
            );
            assert_eq!(fx, 0.0);
            // f · z = total vertical load on the upper body (condition (13)).
            let z = d.kernel_vector();
            let fz: f64 = d.problem.f().iter().zip(&z).map(|(a, b)| a * b).sum();
            assert!((fz - total).abs() < 1e-12 * total.abs());
        }
    }
}

#[test]
fn load_ending_inside_an_edge_is_split_exactly() {
    // 1/3 is never a node: the edge holding it gets the exact hat integrals.
    let d = problem(1, 3);
    let hh = 1.0 / 8.0;
    let top = d.mesh.rows() - 1;
    let fy = |i| d.forces()[d.mesh.node(Body::Upper, i, top)][1];
    // Nodes 0, 1, 2 (x = 0, 1/8, 1/4) and 3 (x = 3/8) share the edge [1/4, 3/8]
    // cut at 1/3: on [1/4, 1/3] ∫ φ_2 = (1/12)(1 − (7/24 − 1/4)/h) and so on.
    let len = 1.0 / 3.0 - 0.25;
    let mid = (0.25 + 1.0 / 3.0) / 2.0;
    let phi3 = (mid - 0.25) / hh;
    assert!((fy(3) - (-60.0 * len * phi3)).abs() < 1e-13);
    assert!((fy(2) - (-60.0 * (hh / 2.0 + len * (1.0 - phi3)))).abs() < 1e-13);
    assert!((fy(0) - (-60.0 * hh / 2.0)).abs() < 1e-13);
    assert_eq!(fy(4), 0.0);
}

#[test]
fn mass_matrix_integrates_a_constant_to_each_bodys_area() {
    let mesh = Mesh::new(h(4));
    let dofs = PhysicalDofs {
        num_nodes: mesh.num_nodes(),
    };
    for body in [Body::Lower, Body::Upper] {
        let m = assembly::assemble(&mesh, &dofs, Some(body), assembly::element_mass);
        for k in 0..2 {
            let one: Vec<f64> = (0..mesh.num_nodes())
                .flat_map(|n| {
                    let on = mesh.locate(n).0 == body;
                    let mut v = [0.0; 2];
                    v[k] = if on { 1.0 } else { 0.0 };
                    v
                })
                .collect();
            let integral: f64 = one.iter().zip(spmv(&m, &one)).map(|(a, b)| a * b).sum();
            assert!(
                (integral - 0.5).abs() < 1e-14,
                "{body:?} component {k}: {integral}"
            );
        }
    }
    // In the (t, s) unknowns the mass matrix still measures ‖u‖²: the upper
    // body's unit vertical translation has L2 norm² equal to its area.
    let d = problem(1, 4);
    let z = d.kernel_vector();
    let zz: f64 = z
        .iter()
        .zip(spmv(&*d.problem.mass().unwrap(), &z))
        .map(|(a, b)| a * b)
        .sum();
    assert!((zz - 0.5).abs() < 1e-14);
}

/// A level built without M (what the Python problem holds) gives, on
/// demand, the M a full assembly holds: the same pattern and the same
/// values to the bit, with the upper body's area as the rigid mode's
/// norm². An M on a pattern of its own, summed in another order or in the
/// physical unknowns instead of (t, s), fails it.
#[test]
fn the_mass_matrix_assembled_on_demand_is_the_one_a_full_assembly_holds() {
    let scene = Scene::paper_problem(2).unwrap();
    for k in [3, 5] {
        let full = Discretization::new(&scene, h(k)).unwrap();
        let lean = Discretization::new_without_mass(&scene, h(k)).unwrap();
        assert!(!lean.problem.has_mass());
        let m = lean.assemble_mass().unwrap().to_nalgebra();
        assert_eq!(m, *full.problem.mass().unwrap(), "h = {}", h(k));
        let z = lean.kernel_vector();
        let zz: f64 = z.iter().zip(spmv(&m, &z)).map(|(a, b)| a * b).sum();
        assert!((zz - 0.5).abs() < 1e-14, "{zz}");
    }
}

#[test]
fn upward_or_zero_total_load_is_rejected_with_the_typed_error() {
    for p2 in [60.0, 0.0] {
        let mut scene = Scene::paper_problem(1).unwrap();
        scene.loads = vec![Traction {
            from: 0.0,
            to: 1.0 / 3.0,
            p2,
            p1: 0.0,
        }];
        match Discretization::new(&scene, h(3)) {
            Err(BuildError::Scene(SceneError::NoSolution { total })) => assert!(total >= 0.0),
            other => panic!("expected the condition (13) error, got {other:?}"),
        }
    }
}

#[test]
fn transfer_between_levels_interpolates_linearly_and_injects_back() {
    let coarse = problem(1, 3);
    let fine = problem(1, 4);
    // Any coarse nodal field (here nonlinear, with a jump and a slip on Γ_K).
    let u: Vec<[f64; 2]> = (0..coarse.mesh.num_nodes())
        .map(|node| {
            let (body, ..) = coarse.mesh.locate(node);
            let [x, y] = coarse.mesh.coords(node);
            let s = if body == Body::Upper { 1.0 } else { 0.0 };
            [
                (3.0 * x).sin() * y + 0.1 * s,
                (x * x - y).exp() * 1e-3 - 0.2 * s,
            ]
        })
        .collect();
    let v = coarse.dofs.from_physical(&u);
    let vf = fine.transfer_from(&coarse, &v);
    // Injection back recovers the coarse unknowns exactly.
    for (a, b) in v.iter().zip(coarse.transfer_from(&fine, &vf)) {
        assert!((a - b).abs() < 1e-15);
    }
    // A fine node halfway along a coarse edge gets the mean of its ends; the
    // coarse diagonals run from lower-left to upper-right.
    // (Boundary conditions zero the field on y = 0 and the roller.)
    let uc = coarse.displacements(&v);
    let uf = fine.displacements(&vf);
    let mut worst = 0.0f64;
    for body in [Body::Lower, Body::Upper] {
        for j in 0..coarse.mesh.rows() - 1 {
            for i in 0..coarse.mesh.n() - 1 {
                let c = |di, dj| uc[coarse.mesh.node(body, i + di, j + dj)];
                let f = |di, dj| uf[fine.mesh.node(body, 2 * i + di, 2 * j + dj)];
                for (mid, a, b) in [
                    (f(1, 0), c(0, 0), c(1, 0)),
                    (f(0, 1), c(0, 0), c(0, 1)),
                    (f(1, 1), c(0, 0), c(1, 1)),
                ] {
                    for k in 0..2 {
                        let err = (mid[k] - 0.5 * (a[k] + b[k])).abs();
                        worst = worst.max(err);
                    }
                }
            }
        }
    }
    assert!(worst < 1e-15, "worst midpoint error {worst:e}");
    // An affine field on each body that meets the boundary conditions
    // (zero on y = 0, u''_1 = 0 on x = 1) is reproduced exactly.
    let affine_on = |body: Body, x: f64, y: f64| match body {
        Body::Lower => [-0.1 * y, 0.3 * y],
        Body::Upper => [0.05 * (1.0 - x), -0.1 + 0.4 * y + 0.01 * x],
    };
    let field = |d: &Discretization| -> Vec<[f64; 2]> {
        (0..d.mesh.num_nodes())
            .map(|n| {
                let [x, y] = d.mesh.coords(n);
                affine_on(d.mesh.locate(n).0, x, y)
            })
            .collect()
    };
    let vf = fine.transfer_from(&coarse, &coarse.dofs.from_physical(&field(&coarse)));
    let exact = fine.dofs.from_physical(&field(&fine));
    for (a, b) in vf.iter().zip(&exact) {
        assert!((a - b).abs() < 1e-15, "{a} vs {b}");
    }
}

/// The assembly by triplets that contactlab used before the row-wise one:
/// every element entry pushed, duplicates summed by the COO → CSR
/// conversion.
fn assemble_by_triplets(
    mesh: &Mesh,
    dofs: &DofMap,
    element: impl Fn([[f64; 2]; 3]) -> [[f64; 6]; 6],
) -> CsrMatrix<f64> {
    let mut coo = CooMatrix::new(dofs.n(), dofs.n());
    for (_, tri) in mesh.triangles() {
        let ke = element(tri.map(|node| mesh.coords(node)));
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

/// The row-wise assembly (element matrices shared between congruent
/// triangles, rows filled in node blocks) stores the same entries as the
/// triplet assembly, explicit zeros included, with the same values up to the
/// order of summation: a wrong place, a lost contact-expansion term, a
/// missing triangle, a wrong shape shared, or a block's second row taking
/// the first's component (the roller nodes have single rows, the contact
/// nodes pairs over two nodes) would show here.
#[test]
fn row_wise_assembly_equals_the_triplet_assembly_entry_by_entry() {
    for k in 1..=5 {
        let mesh = Mesh::new(h(k));
        let dofs = DofMap::new(&mesh);
        for material in materials() {
            let d = material.elasticity_matrix();
            let (a, m) =
                assembly::stiffness_and_mass(&mesh, &dofs, &BodyMaterials::both(&material));
            let m = a.nalgebra_with_values(m);
            let a = a.to_nalgebra();
            let pairs = [
                (
                    a,
                    assemble_by_triplets(&mesh, &dofs, |p| assembly::element_stiffness(p, &d)),
                ),
                (
                    m,
                    assemble_by_triplets(&mesh, &dofs, assembly::element_mass),
                ),
            ];
            for (new, old) in pairs {
                assert_eq!(new.row_offsets(), old.row_offsets(), "k = {k}");
                assert_eq!(new.col_indices(), old.col_indices(), "k = {k}");
                let scale = max_abs(old.values());
                for (x, y) in new.values().iter().zip(old.values()) {
                    assert!(
                        (x - y).abs() <= 4.0 * f64::EPSILON * scale,
                        "k = {k}: {x} against {y}"
                    );
                }
            }
        }
    }
}
