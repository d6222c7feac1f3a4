//! Unknowns of the algebraic problem: the paper's boundary conditions are
//! eliminated and, at each contact node i of Γ_K, the upper body's
//! displacement is replaced by the jump and the slip (paper, section 5):
//!
//! ```text
//! t_i = v'_2 − v''_2   (replaces v''_2),     s_i = v'_1 − v''_1   (replaces v''_1),
//! ```
//!
//! so that v''_k = v'_k − (s_i, t_i)_k. Fixed values are zero (the clamp,
//! the paper's roller). A scene's `side_shift` δ on the upper body's held
//! sides is a rigid lift: u''_1 = δ + v''_1 on the whole upper body, with
//! v''_1 = 0 where it is held. The stiffness does not see a rigid
//! translation, so the load stays the applied one; the slip of the bodies
//! is s_i − δ, the problem's slip offset
//! ([`contactlab_solvers::ContactProblem::with_slip_offset`]).

use serde::{Deserialize, Serialize};

use crate::mechanics::mesh::{Body, Mesh};

/// How the upper body is held sideways (its vertical translation is always
/// free: the semicoercive mode of paper (11)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Hold {
    /// The paper's roller: u''_1 = 0 on the right side x = 1, ½ < y ≤ 1.
    #[default]
    Roller,
    /// Rollers on both sides: u''_1 = 0 on x = 0 and on x = 1, ½ < y ≤ 1.
    /// Symmetric about x = ½, where a curved body's contact is centred: the
    /// paper's roller on one side alone tilts it towards that side (Hertz's
    /// contact moved by a/43 at R = ½, which cost 4.5% of the pressure in
    /// L2). (u''_1 = 0 on the top side alone leaves the body free to turn
    /// about a point of it, a second kernel mode; a rigid platen on top,
    /// one u''_2 for the whole side, holds that but took `tnnmg` past 500
    /// iterations at h = 1/512.)
    Rollers,
    /// Free to slide: rollers on x = 0 and x = 1 that move together,
    /// u''_1 = δ on both held sides with δ one unknown. The sides keep the
    /// body from turning (nothing held at all, it keeps three rigid modes,
    /// its rotation among them), and its horizontal translation is a second
    /// rigid mode, which only friction holds: a tangential load on it must
    /// stay below what friction can carry, |Q| < 𝓕P. Cattaneo–Mindlin's
    /// force-driven form.
    Sliding,
}

impl Hold {
    pub fn as_str(self) -> &'static str {
        match self {
            Hold::Roller => "roller",
            Hold::Rollers => "rollers",
            Hold::Sliding => "sliding",
        }
    }
}

/// How one physical displacement component is expressed in the unknowns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Dof {
    /// Prescribed zero: clamped (lower body, y = 0) or roller (upper, x = 1).
    Fixed,
    /// An unknown of its own.
    Slot(usize),
    /// Upper contact node: v'' = v[base] − v[own], with `own` the slip or jump.
    Relative { base: usize, own: usize },
}

/// Up to two (unknown, coefficient) pairs expressing one physical component.
#[derive(Clone, Copy, Debug)]
pub struct Terms {
    items: [(usize, f64); 2],
    len: usize,
}

impl Terms {
    #[inline]
    pub fn as_slice(&self) -> &[(usize, f64)] {
        &self.items[..self.len]
    }
}

/// Maps physical nodal components (node, k) to linear combinations of unknowns.
pub trait DofExpansion {
    /// Number of unknowns.
    fn n(&self) -> usize;
    /// Component k (0: x, 1: y) of `node` as a combination of unknowns.
    fn terms(&self, node: usize, k: usize) -> Terms;
}

/// The unknowns of the algebraic problem: boundary conditions eliminated,
/// (t, s) at the contact nodes.
///
/// The numbering follows the mesh's nodes (row by row, the lower body
/// first), two unknowns per free node, one on the roller x = 1, and the
/// contact nodes' (s, t) last; so each node's unknowns follow from its row
/// and column ([`DofMap::dofs`]) and only the contact nodes are stored (a
/// table of every node's unknowns was 8 bytes per unknown, 270 MB at
/// h = 1/4096, beside the solver's at the peak of a solve).
#[derive(Clone, Debug)]
pub struct DofMap {
    mesh: Mesh,
    hold: Hold,
    /// The rigid lift δ of the upper body: u''_1 on its held sides (a
    /// scene's `side_shift`; 0: the paper's).
    side_shift: f64,
    n: usize,
    contacts: Vec<ContactDofs>,
}

/// The two nodes of contact node i of Γ_K and their unknowns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactDofs {
    pub x: f64,
    pub lower_node: usize,
    pub upper_node: usize,
    /// Unknown holding the jump t_i.
    pub t: usize,
    /// Unknown holding the slip s_i.
    pub s: usize,
}

impl DofMap {
    /// Lower body clamped on y = 0; upper body on a roller (u''_1 = 0) on
    /// x = 1, ½ < y ≤ 1; the upper contact node at (1, ½) is free.
    pub fn new(mesh: &Mesh) -> Self {
        Self::with_hold(mesh, Hold::Roller)
    }

    /// As [`DofMap::new`], with the upper body held sideways as `hold` says.
    pub fn with_hold(mesh: &Mesh, hold: Hold) -> Self {
        let n = mesh.unknowns_with(hold);
        // Contact node i: (s, t) follow every other unknown, in increasing x.
        let first = n - 2 * mesh.n();
        let contacts = (0..mesh.n())
            .map(|i| {
                let lower_node = mesh.node(Body::Lower, i, mesh.contact_row(Body::Lower));
                let upper_node = mesh.node(Body::Upper, i, mesh.contact_row(Body::Upper));
                ContactDofs {
                    x: mesh.coords(lower_node)[0],
                    lower_node,
                    upper_node,
                    s: first + 2 * i,
                    t: first + 2 * i + 1,
                }
            })
            .collect();
        Self {
            mesh: mesh.clone(),
            hold,
            side_shift: 0.0,
            n,
            contacts,
        }
    }

    /// The same unknowns, with u''_1 = `shift` on the held sides instead
    /// of 0, as a rigid lift: every u''_1 is `shift` plus its unknown part
    /// ([`DofMap::to_physical`] adds it), the held parts are zero, and the
    /// slip the friction sees is s_i − `shift` ([`DofMap::slip_offset`]).
    pub fn with_side_shift(mut self, shift: f64) -> Self {
        self.side_shift = shift;
        self
    }

    /// u''_1 prescribed on the held sides.
    pub fn side_shift(&self) -> f64 {
        self.side_shift
    }

    /// The slip offset σ_i of each contact node: the rigid lift δ, since
    /// u'_1 − u''_1 = (v'_1 − v''_1) − δ = s_i − δ.
    pub fn slip_offset(&self) -> Vec<f64> {
        vec![self.side_shift; self.contacts.len()]
    }

    /// The rigid lift's part of component k of a node of `body`: δ on the
    /// upper body's u''_1, 0 elsewhere.
    fn lift(&self, body: Body, k: usize) -> f64 {
        match body {
            Body::Upper if k == 0 => self.side_shift,
            _ => 0.0,
        }
    }

    /// How the upper body is held sideways.
    pub fn hold(&self) -> Hold {
        self.hold
    }

    /// Both components of `node` as unknowns: numbered in node order, the
    /// lower body's rows above y = 0 two per node, then the upper body's
    /// rows above Γ_K two per node but one (v''_2) on the roller, then
    /// (s, t) of each contact node; an upper contact node is its lower
    /// partner less (s, t).
    #[inline]
    fn dofs(&self, node: usize) -> [Dof; 2] {
        let per_row = self.mesh.n();
        let (body, i, j) = self.mesh.locate(node);
        match body {
            Body::Lower if j == 0 => [Dof::Fixed, Dof::Fixed],
            Body::Lower => {
                let s = 2 * ((j - 1) * per_row + i);
                [Dof::Slot(s), Dof::Slot(s + 1)]
            }
            Body::Upper if j == 0 => {
                let c = &self.contacts[i];
                match self.dofs(c.lower_node) {
                    [Dof::Slot(x), Dof::Slot(y)] => [
                        Dof::Relative { base: x, own: c.s },
                        Dof::Relative { base: y, own: c.t },
                    ],
                    _ => unreachable!("lower contact nodes are free"),
                }
            }
            Body::Upper => {
                let lower = 2 * per_row * (self.mesh.rows() - 1);
                match self.hold {
                    Hold::Roller => {
                        let s = lower + (j - 1) * (2 * per_row - 1) + 2 * i;
                        if i == per_row - 1 {
                            [Dof::Fixed, Dof::Slot(s)]
                        } else {
                            [Dof::Slot(s), Dof::Slot(s + 1)]
                        }
                    }
                    Hold::Rollers | Hold::Sliding => {
                        let row = lower + (j - 1) * (2 * per_row - 2);
                        // Sliding: the sides' shared u''_1 follows the
                        // bodies' other unknowns, before the contacts'.
                        let side = match self.hold {
                            Hold::Sliding => {
                                Dof::Slot(lower + (self.mesh.rows() - 1) * (2 * per_row - 2))
                            }
                            _ => Dof::Fixed,
                        };
                        if i == 0 {
                            [side, Dof::Slot(row)]
                        } else if i == per_row - 1 {
                            [side, Dof::Slot(row + 2 * per_row - 3)]
                        } else {
                            [Dof::Slot(row + 2 * i - 1), Dof::Slot(row + 2 * i)]
                        }
                    }
                }
            }
        }
    }

    pub fn dof(&self, node: usize, k: usize) -> Dof {
        self.dofs(node)[k]
    }

    /// Contact nodes of Γ_K in increasing x.
    pub fn contacts(&self) -> &[ContactDofs] {
        &self.contacts
    }

    /// Physical nodal displacements (per node, x and y) from the unknowns.
    pub fn to_physical(&self, v: &[f64]) -> Vec<[f64; 2]> {
        (0..self.mesh.num_nodes())
            .map(|node| {
                let body = self.mesh.locate(node).0;
                let dofs = self.dofs(node);
                std::array::from_fn(|k| {
                    self.lift(body, k)
                        + match dofs[k] {
                            Dof::Fixed => 0.0,
                            Dof::Slot(s) => v[s],
                            Dof::Relative { base, own } => v[base] - v[own],
                        }
                })
            })
            .collect()
    }

    /// The unknowns representing a physical displacement field, the rigid
    /// lift taken off. Components on fixed boundaries are ignored (the
    /// field is assumed to satisfy them).
    pub fn from_physical(&self, u: &[[f64; 2]]) -> Vec<f64> {
        self.unknowns_of(u, true)
    }

    /// The unknowns of a change of displacement (a direction, such as a
    /// rigid mode): linear, without the rigid lift.
    pub fn from_direction(&self, u: &[[f64; 2]]) -> Vec<f64> {
        self.unknowns_of(u, false)
    }

    fn unknowns_of(&self, u: &[[f64; 2]], lifted: bool) -> Vec<f64> {
        let mut v = vec![0.0; self.n];
        let unlifted = |node: usize, k: usize| {
            u[node][k]
                - if lifted {
                    self.lift(self.mesh.locate(node).0, k)
                } else {
                    0.0
                }
        };
        for node in 0..u.len().min(self.mesh.num_nodes()) {
            for (k, dof) in self.dofs(node).into_iter().enumerate() {
                if let Dof::Slot(s) = dof {
                    v[s] = unlifted(node, k);
                }
            }
        }
        for c in &self.contacts {
            for (k, own) in [(0, c.s), (1, c.t)] {
                v[own] = unlifted(c.lower_node, k) - unlifted(c.upper_node, k);
            }
        }
        v
    }
}

impl DofExpansion for DofMap {
    fn n(&self) -> usize {
        self.n
    }

    #[inline]
    fn terms(&self, node: usize, k: usize) -> Terms {
        match self.dofs(node)[k] {
            Dof::Fixed => Terms {
                items: [(0, 0.0); 2],
                len: 0,
            },
            Dof::Slot(s) => Terms {
                items: [(s, 1.0), (0, 0.0)],
                len: 1,
            },
            Dof::Relative { base, own } => Terms {
                items: [(base, 1.0), (own, -1.0)],
                len: 2,
            },
        }
    }
}

/// All physical components, unconstrained: 2 unknowns per node.
pub struct PhysicalDofs {
    pub num_nodes: usize,
}

impl DofExpansion for PhysicalDofs {
    fn n(&self) -> usize {
        2 * self.num_nodes
    }

    fn terms(&self, node: usize, k: usize) -> Terms {
        Terms {
            items: [(2 * node + k, 1.0), (0, 0.0)],
            len: 1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::mesh_size::MeshSize;

    /// The numbering by enumeration, as it was built before the map became
    /// a formula: every node in order, a new unknown for each free
    /// component, then (s, t) of each contact node in increasing x.
    fn enumerated(mesh: &Mesh, hold: Hold) -> (Vec<[Dof; 2]>, usize) {
        let mut map = vec![[Dof::Fixed; 2]; mesh.num_nodes()];
        let mut n = 0;
        let mut next = || {
            n += 1;
            n - 1
        };
        let last = mesh.n() - 1;
        for (node, dofs) in map.iter_mut().enumerate() {
            let (body, i, j) = mesh.locate(node);
            *dofs = match body {
                Body::Lower if j == 0 => [Dof::Fixed, Dof::Fixed],
                Body::Lower => [Dof::Slot(next()), Dof::Slot(next())],
                Body::Upper if j == 0 => [Dof::Fixed, Dof::Fixed],
                Body::Upper if hold == Hold::Roller && i == last => [Dof::Fixed, Dof::Slot(next())],
                Body::Upper if hold == Hold::Rollers && (i == 0 || i == last) => {
                    [Dof::Fixed, Dof::Slot(next())]
                }
                Body::Upper => [Dof::Slot(next()), Dof::Slot(next())],
            };
        }
        for i in 0..mesh.n() {
            let lower = mesh.node(Body::Lower, i, mesh.contact_row(Body::Lower));
            let upper = mesh.node(Body::Upper, i, mesh.contact_row(Body::Upper));
            let slot = |d: Dof| match d {
                Dof::Slot(s) => s,
                _ => unreachable!("lower contact nodes are free"),
            };
            let (s, t) = (next(), next());
            map[upper] = [
                Dof::Relative {
                    base: slot(map[lower][0]),
                    own: s,
                },
                Dof::Relative {
                    base: slot(map[lower][1]),
                    own: t,
                },
            ];
        }
        (map, n)
    }

    /// The formula gives every node the unknowns the enumeration gives it,
    /// the same count, and each unknown once: a wrong row length, body
    /// offset or roller column would move some node's unknowns.
    #[test]
    fn the_numbering_is_the_enumeration() {
        for (level, hold) in (1..=6).flat_map(|l| [(l, Hold::Roller), (l, Hold::Rollers)]) {
            let mesh = Mesh::new(MeshSize::from_level(level).unwrap());
            let map = DofMap::with_hold(&mesh, hold);
            let (table, n) = enumerated(&mesh, hold);
            assert_eq!(map.n(), n, "level {level}");
            for (node, dofs) in table.iter().enumerate() {
                assert_eq!(map.dofs(node), *dofs, "level {level}, node {node}");
            }
            for c in map.contacts() {
                assert_eq!(
                    map.dof(c.upper_node, 1),
                    Dof::Relative {
                        base: match map.dof(c.lower_node, 1) {
                            Dof::Slot(s) => s,
                            other => panic!("lower contact node {other:?}"),
                        },
                        own: c.t
                    }
                );
            }
            let mut seen = vec![0; n];
            for node in 0..mesh.num_nodes() {
                for d in map.dofs(node) {
                    match d {
                        Dof::Slot(s) => seen[s] += 1,
                        Dof::Relative { own, .. } => seen[own] += 1,
                        Dof::Fixed => {}
                    }
                }
            }
            assert!(seen.iter().all(|&k| k == 1), "level {level}");
        }
    }
}
