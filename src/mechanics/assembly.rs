//! P1 finite elements for plane elasticity: stiffness A(u, v) = ∫ σ(u):ε(v),
//! the consistent mass matrix of the L2 product, and loads from piecewise
//! constant tractions on the top side y = 1, integrated exactly.

use std::collections::HashMap;

use nalgebra_sparse::CsrMatrix;

pub use crate::mechanics::element::{element_mass, element_stiffness, strain_matrix};

use crate::mechanics::dofs::DofExpansion;
use crate::mechanics::material::Material;
use crate::mechanics::mesh::{Body, Mesh};
use crate::mechanics::scene::Traction;

mod pattern;
use crate::solvers::Csr;
use crate::solvers::numerics::linalg::CsrBuilder;
use pattern::append;

/// The triangles of the mesh (optionally one body's), as node triples.
/// Pushed from `for_each`, which drives the mesh's nested iterator from the
/// inside: collecting it item by item was a tenth of a 1/64 assembly.
fn triangles(mesh: &Mesh, only: Option<Body>) -> Vec<[u32; 3]> {
    let mut tris = Vec::new();
    mesh.triangles().for_each(|(body, tri)| {
        if only.is_none_or(|b| b == body) {
            tris.push(tri.map(|node| node as u32));
        }
    });
    tris
}

/// `rows[i]` as a compressed list: offsets and the flattened items, in 32
/// bits (a mesh's nodes, triangles and unknowns stay below 2³²: checked by
/// [`assemble_rows`]), half the memory of the assembly's largest temporaries.
struct Lists {
    offsets: Vec<u32>,
    items: Vec<u32>,
}

impl Lists {
    /// Groups the `(row, item)` pairs that `pairs` emits (it is called twice)
    /// by row with a counting sort, keeping their order within a row:
    /// O(rows + pairs).
    fn group(rows: usize, pairs: impl Fn(&mut dyn FnMut(usize, usize))) -> Self {
        let mut offsets = vec![0u32; rows + 1];
        pairs(&mut |r, _| offsets[r + 1] += 1);
        for r in 0..rows {
            offsets[r + 1] += offsets[r];
        }
        let mut next = offsets.clone();
        let mut items = vec![0u32; offsets[rows] as usize];
        pairs(&mut |r, item| {
            items[next[r] as usize] = item as u32;
            next[r] += 1;
        });
        Self { offsets, items }
    }

    fn of(&self, row: usize) -> &[u32] {
        &self.items[self.offsets[row] as usize..self.offsets[row + 1] as usize]
    }
}

/// An element matrix of a triangle of a body from its corners, local order
/// (u1_a, u2_a, u1_b, ...): the body, because each may have its own
/// material.
pub type ElementMatrix<'a> = dyn Fn(Body, [[f64; 2]; 3]) -> [[f64; 6]; 6] + 'a;

/// Up to this many distinct shapes are found by a scan.
const SCANNED_SHAPES: usize = 8;

/// The element matrices of every triangle, computed once per shape and
/// body: an element matrix depends on the edge vectors and the body's
/// material only, and on a mesh of h = 1/2^k the edge vectors are exact, so
/// congruent triangles of a body share one matrix bit for bit (this mesh has
/// two shapes per body). Any other mesh gets one entry per distinct shape,
/// at worst one per triangle.
struct ElementTable<const K: usize> {
    shape: Vec<u32>,
    matrices: Vec<[[[f64; 6]; 6]; K]>,
}

impl<const K: usize> ElementTable<K> {
    fn new(mesh: &Mesh, tris: &[[u32; 3]], elements: [&ElementMatrix<'_>; K]) -> Self {
        // Each node's coordinates once: a triangle's corners are then three
        // loads, not three divisions to locate each node.
        let coords: Vec<[f64; 2]> = (0..mesh.num_nodes()).map(|v| mesh.coords(v)).collect();
        // Shapes seen so far; looked up by scanning while they are few (this
        // mesh has two), by hashing beyond.
        let mut keys: Vec<[u64; 5]> = Vec::new();
        let mut index: HashMap<[u64; 5], u32> = HashMap::new();
        let mut matrices = Vec::new();
        let shape = tris
            .iter()
            .map(|tri| {
                let p = tri.map(|node| coords[node as usize]);
                let body = mesh.body_of(tri[0] as usize);
                let edges = [
                    p[1][0] - p[0][0],
                    p[1][1] - p[0][1],
                    p[2][0] - p[0][0],
                    p[2][1] - p[0][1],
                ]
                .map(f64::to_bits);
                let key = [edges[0], edges[1], edges[2], edges[3], body as u64];
                let known = if keys.len() <= SCANNED_SHAPES {
                    keys.iter().position(|k| *k == key).map(|i| i as u32)
                } else {
                    index.get(&key).copied()
                };
                known.unwrap_or_else(|| {
                    let i = matrices.len() as u32;
                    matrices.push(elements.map(|element| element(body, p)));
                    keys.push(key);
                    if keys.len() == SCANNED_SHAPES + 1 {
                        index.extend(keys.iter().enumerate().map(|(i, k)| (*k, i as u32)));
                    } else if keys.len() > SCANNED_SHAPES + 1 {
                        index.insert(key, i);
                    }
                    i
                })
            })
            .collect();
        Self { shape, matrices }
    }
}

/// The rows of one block (one unknown, or two whose components lie on the
/// same nodes) on one of its components' nodes: row r takes the node's
/// component k[r] with coefficient ci[r]; a single row repeats its k with
/// ci = 0.
#[derive(Clone, Copy)]
struct BlockRows {
    k: [usize; 2],
    ci: [f64; 2],
}

/// Sums one block's rows from the triangles around its nodes: what every
/// block reads, and the scratch it reuses.
struct BlockSums<'a, D, const K: usize> {
    dofs: &'a D,
    tris: &'a [[u32; 3]],
    table: &'a ElementTable<K>,
    node_triangles: &'a Lists,
    /// marker[j] = (stamp, slot), for the sums by unknowns: column j was
    /// met in the block with this stamp (the block's first unknown), and its
    /// sums are found[slot].
    marker: Vec<(u32, u32)>,
    /// The block's columns, sorted, and per column both rows' sums (a single
    /// row leaves the second at zero). A short list, so it stays in cache.
    found: Vec<(usize, [[f64; K]; 2])>,
    /// By nodes: the nodes around, each with its 2 × 2 block per matrix,
    /// `near[s].1[kc][r][m]` for the node's component kc and row r.
    near: Vec<(usize, [[[f64; K]; 2]; 2])>,
}

impl<'a, D: DofExpansion, const K: usize> BlockSums<'a, D, K> {
    /// The triangles around `node`, each with the node's corner in it and
    /// its element matrices (decoding `node_triangles`' 3·e + corner).
    fn around(
        &self,
        node: usize,
    ) -> impl Iterator<Item = ([usize; 3], usize, &'a [[[f64; 6]; 6]; K])> + use<'a, D, K> {
        let (tris, table, lists) = (self.tris, self.table, self.node_triangles);
        lists.of(node).iter().map(move |&around| {
            let (e, corner) = (around as usize / 3, around as usize % 3);
            let tri = tris[e].map(|node| node as usize);
            (tri, corner, &table.matrices[table.shape[e] as usize])
        })
    }

    /// The block's sums by nodes, for a block on one node: each triangle
    /// around it adds a 2 × 2 block per matrix to each of its three nodes,
    /// found among the few nodes met so far, and only then are the nodes'
    /// components expanded into unknowns: per triangle three short searches
    /// instead of a marker per unknown, at about 0.8 × the time at 1/64.
    ///
    /// Returns false when some unknown is met through two nodes (it then
    /// appears twice in the sorted list, so no marker is needed): its sum
    /// would then be grouped otherwise than by unknowns, so the caller sums
    /// the block by unknowns instead. Otherwise, with coefficients ±1 (all
    /// of this program's), the sums are those of [`BlockSums::by_unknowns`]
    /// bit for bit.
    fn by_nodes(&mut self, node: usize, rows: BlockRows) -> bool {
        let BlockRows { k, ci } = rows;
        self.near.clear();
        for (tri, corner, ke) in self.around(node) {
            let rows = k.map(|k| 2 * corner + k);
            for (q, &other) in tri.iter().enumerate() {
                let slot = match self.near.iter().position(|(m, _)| *m == other) {
                    Some(slot) => slot,
                    None => {
                        self.near.push((other, [[[0.0; K]; 2]; 2]));
                        self.near.len() - 1
                    }
                };
                for (kc, acc) in self.near[slot].1.iter_mut().enumerate() {
                    for r in 0..2 {
                        for (a, m) in acc[r].iter_mut().zip(ke) {
                            *a += ci[r] * m[rows[r]][2 * q + kc];
                        }
                    }
                }
            }
        }
        self.found.clear();
        for (other, acc) in &self.near {
            for (kc, acc) in acc.iter().enumerate() {
                for &(j, cj) in self.dofs.terms(*other, kc).as_slice() {
                    // + 0.0: an empty sum is +0, as summing by unknowns gives.
                    self.found
                        .push((j, acc.map(|row| row.map(|a| cj * a + 0.0))));
                }
            }
        }
        self.found.sort_unstable_by_key(|(j, _)| *j);
        self.found.windows(2).all(|w| w[0].0 != w[1].0)
    }

    /// The block's sums by unknowns: for each of its components, the
    /// triangles around the component's node add their element rows into
    /// the unknowns of each corner's components, found through the marker;
    /// `stamp` is the block's first unknown.
    fn by_unknowns(&mut self, stamp: usize, parts: &[(usize, BlockRows)]) {
        self.found.clear();
        for &(node, BlockRows { k, ci }) in parts {
            for (tri, corner, ke) in self.around(node) {
                let rows = k.map(|k| 2 * corner + k);
                for b in 0..6 {
                    for &(j, cj) in self.dofs.terms(tri[b / 2], b % 2).as_slice() {
                        let (seen, slot) = &mut self.marker[j];
                        if *seen != stamp as u32 {
                            *seen = stamp as u32;
                            *slot = self.found.len() as u32;
                            self.found.push((j, [[0.0; K]; 2]));
                        }
                        let sums = &mut self.found[*slot as usize].1;
                        for r in 0..2 {
                            let weight = ci[r] * cj;
                            for (acc, m) in sums[r].iter_mut().zip(ke) {
                                *acc += weight * m[rows[r]][b];
                            }
                        }
                    }
                }
            }
        }
        self.found.sort_unstable_by_key(|(j, _)| *j);
    }
}

/// Assembles element matrices over every triangle (optionally one body) into
/// the unknowns of `dofs`, one matrix per element function, all on one
/// pattern, returned once with each matrix's values in its order:
/// eliminated components drop out, relative ones expand into their two
/// terms, and (i, j) is stored when a triangle couples a component involving
/// unknown i with one involving j (explicit zeros included, so the stiffness
/// and the mass share the pattern).
///
/// Row by row, Gustavson's way: for unknown i, the triangles around each node
/// whose components involve i add their element row into an accumulator, a
/// marker array finds each column's place in it, and the row's columns are
/// then sorted. Linear in the mesh, no triplet list, no search; each element
/// matrix is computed once per shape ([`ElementTable`]).
///
/// Rows come in node blocks: two consecutive unknowns whose components lie
/// on the same nodes (the x and y unknowns of a node, or the slip and jump
/// of a contact node) have the same columns, so one visit of the triangles
/// around those nodes fills both rows and their columns are found and
/// sorted once. A block on one node is summed node by node first
/// ([`BlockSums::by_nodes`]), with the same sums.
pub fn assemble_all<const K: usize>(
    mesh: &Mesh,
    dofs: &impl DofExpansion,
    only: Option<Body>,
    elements: [&ElementMatrix<'_>; K],
) -> [Csr; K] {
    assemble_rows(mesh, dofs, only, elements, Sum::ByNodesWherePossible)
}

/// How [`assemble_rows`] sums the blocks' rows.
#[derive(Clone, Copy, PartialEq)]
enum Sum {
    /// [`BlockSums::by_nodes`] on one-node blocks, by unknowns elsewhere.
    ByNodesWherePossible,
    /// [`BlockSums::by_unknowns`] everywhere (for the test that both agree).
    #[cfg(test)]
    ByUnknowns,
}

/// [`assemble_all`], with the choice of how the rows are summed.
fn assemble_rows<const K: usize>(
    mesh: &Mesh,
    dofs: &impl DofExpansion,
    only: Option<Body>,
    elements: [&ElementMatrix<'_>; K],
    sum: Sum,
) -> [Csr; K] {
    let n = dofs.n();
    assert!(
        n < u32::MAX as usize && 6 * mesh.num_nodes() < u32::MAX as usize,
        "{n} unknowns: more than 32-bit indices hold (the mesh sizes stop far below)"
    );
    let tris = triangles(mesh, only);
    let table = ElementTable::new(mesh, &tris, elements);
    // Around each node, its triangles as 3·e + (the node's corner in e).
    let node_triangles = Lists::group(mesh.num_nodes(), |emit| {
        for (e, tri) in tris.iter().enumerate() {
            for (corner, &node) in tri.iter().enumerate() {
                emit(node as usize, 3 * e + corner);
            }
        }
    });
    // Each unknown's physical components, as 2·node + k.
    let components = Lists::group(n, |emit| {
        for c in 0..2 * mesh.num_nodes() {
            for &(i, _) in dofs.terms(c / 2, c % 2).as_slice() {
                emit(i, c);
            }
        }
    });
    // The coefficient of unknown i in component c.
    let coefficient = |i: usize, c: usize| {
        dofs.terms(c / 2, c % 2)
            .as_slice()
            .iter()
            .find(|(unknown, _)| *unknown == i)
            .map_or(0.0, |(_, coefficient)| *coefficient)
    };
    // Each row goes to the matrices as it is summed, its stencil and values
    // kept once each (a uniform mesh has a few dozen): the whole arrays,
    // 16 bytes per entry, are never held.
    let mut out = CsrBuilder::<K>::new(n, n);
    let mut columns: Vec<u32> = Vec::with_capacity(32);
    let mut values: [Vec<f64>; K] = [(); K].map(|_| Vec::with_capacity(32));
    let mut block = BlockSums {
        dofs,
        tris: &tris,
        table: &table,
        node_triangles: &node_triangles,
        marker: vec![(u32::MAX, 0); n],
        found: Vec::with_capacity(32),
        near: Vec::with_capacity(16),
    };
    let mut parts: Vec<(usize, BlockRows)> = Vec::with_capacity(4);
    let mut i = 0;
    while i < n {
        let first = components.of(i);
        let paired = i + 1 < n && {
            let second = components.of(i + 1);
            second.len() == first.len() && first.iter().zip(second).all(|(c, d)| c / 2 == d / 2)
        };
        parts.clear();
        parts.extend(first.iter().enumerate().map(|(p, &c)| {
            let c = c as usize;
            let rows = if paired {
                let d = components.of(i + 1)[p] as usize;
                BlockRows {
                    k: [c % 2, d % 2],
                    ci: [coefficient(i, c), coefficient(i + 1, d)],
                }
            } else {
                BlockRows {
                    k: [c % 2; 2],
                    ci: [coefficient(i, c), 0.0],
                }
            };
            (c / 2, rows)
        }));
        let by_nodes = matches!(parts[..], [(node, rows)]
            if sum == Sum::ByNodesWherePossible && block.by_nodes(node, rows));
        if !by_nodes {
            block.by_unknowns(i, &parts);
        }
        // Each output array written in a loop of its own: one reservation
        // per row, not a capacity check and a length store per entry.
        for r in 0..1 + usize::from(paired) {
            columns.clear();
            append(&mut columns, &block.found, |(j, _)| *j as u32);
            for (m, v) in values.iter_mut().enumerate() {
                v.clear();
                append(v, &block.found, |(_, sums)| sums[r][m]);
            }
            out.push_row(&columns, std::array::from_fn(|m| &values[m][..]));
        }
        i += 1 + usize::from(paired);
    }
    // Each row's columns are unknowns (< n), sorted and distinct (by the
    // marker, or checked after the sums by nodes): `finish` checks them
    // again in one pass.
    out.finish()
        .expect("an assembly's rows are sorted, distinct, in range, one value each")
}

/// Assembles one element matrix over every triangle (optionally one body);
/// see [`assemble_all`].
pub fn assemble(
    mesh: &Mesh,
    dofs: &impl DofExpansion,
    only: Option<Body>,
    element: impl Fn([[f64; 2]; 3]) -> [[f64; 6]; 6],
) -> CsrMatrix<f64> {
    let element = |_: Body, p| element(p);
    let [a] = assemble_all(mesh, dofs, only, [&element]);
    a.to_nalgebra()
}

/// The materials of the two bodies, lower (primed) and upper
/// (double-primed): one D per body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyMaterials {
    pub lower: Material,
    pub upper: Material,
}

impl BodyMaterials {
    /// One material for both bodies.
    pub fn both(material: &Material) -> Self {
        Self {
            lower: *material,
            upper: *material,
        }
    }

    /// The elasticity matrix D of each body, as [`ElementMatrix`] reads it.
    fn elasticity(&self) -> [[[f64; 3]; 3]; 2] {
        [
            self.lower.elasticity_matrix(),
            self.upper.elasticity_matrix(),
        ]
    }
}

fn body_index(body: Body) -> usize {
    match body {
        Body::Lower => 0,
        Body::Upper => 1,
    }
}

/// Stiffness matrix of both bodies, with 32-bit column indices (the
/// problem's A), each body with its own material.
pub fn stiffness(mesh: &Mesh, dofs: &impl DofExpansion, materials: &BodyMaterials) -> Csr {
    let d = materials.elasticity();
    let element = |b, p| element_stiffness(p, &d[body_index(b)]);
    let [a] = assemble_all(mesh, dofs, None, [&element]);
    a
}

/// Mass matrix of both bodies (L2 product of displacement fields).
pub fn mass(mesh: &Mesh, dofs: &impl DofExpansion) -> CsrMatrix<f64> {
    mass_rows(mesh, dofs).to_nalgebra()
}

/// The mass matrix of both bodies stored as the problem's A is (32-bit
/// columns, each row's stencil and values kept once): on A's pattern,
/// since the pattern comes from the mesh and the unknowns alone.
pub fn mass_rows(mesh: &Mesh, dofs: &impl DofExpansion) -> Csr {
    let [m] = assemble_all(mesh, dofs, None, [&|_, p| element_mass(p)]);
    m
}

/// ‖u‖²_L2 = ∫ |u|² over both bodies for a P1 field `u` (per node, x and
/// y): Σ over the triangles of u_eᵀ M_e u_e with the element mass matrix,
/// so vᵀ M v for u = T v without M assembled (at h = 1/2048 M would take
/// 1.9 GB beside a solve that did not need it).
pub fn l2_norm_squared(mesh: &Mesh, u: &[[f64; 2]]) -> f64 {
    element_form(mesh, u, element_mass)
}

/// A(u, u) = ∫ σ(u):ε(u) over both bodies for a P1 field `u` (per node, x
/// and y): Σ over the triangles of u_eᵀ K_e u_e, so vᵀ A v for u = T v.
/// It also measures a field outside this mesh's space of admissible
/// displacements, such as a coarser mesh's answer interpolated here (the
/// discretization study): no boundary condition is applied to `u`.
pub fn energy_norm_squared(mesh: &Mesh, material: &Material, u: &[[f64; 2]]) -> f64 {
    let d = material.elasticity_matrix();
    element_form(mesh, u, |p| element_stiffness(p, &d))
}

/// Σ over the triangles of u_eᵀ E_e u_e, E_e = `element` at its corners.
fn element_form(
    mesh: &Mesh,
    u: &[[f64; 2]],
    element: impl Fn([[f64; 2]; 3]) -> [[f64; 6]; 6],
) -> f64 {
    let mut sum = 0.0;
    mesh.triangles().for_each(|(_, tri)| {
        let m = element(tri.map(|node| mesh.coords(node)));
        let ue: [f64; 6] = std::array::from_fn(|q| u[tri[q / 2]][q % 2]);
        for (row, ui) in m.iter().zip(&ue) {
            sum += ui * row.iter().zip(&ue).map(|(mij, uj)| mij * uj).sum::<f64>();
        }
    });
    sum
}

/// Stiffness and mass of both bodies in one pass on one pattern: A, and M's
/// values in the order of A's stored entries (one pattern, not two copies).
pub fn stiffness_and_mass(
    mesh: &Mesh,
    dofs: &impl DofExpansion,
    materials: &BodyMaterials,
) -> (Csr, Vec<f64>) {
    let d = materials.elasticity();
    let [a, m] = assemble_all(
        mesh,
        dofs,
        None,
        [&|b, p| element_stiffness(p, &d[body_index(b)]), &|_, p| {
            element_mass(p)
        }],
    );
    let m = m.values().to_vec(m.row_offsets());
    (a, m)
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

#[cfg(test)]
mod tests;
