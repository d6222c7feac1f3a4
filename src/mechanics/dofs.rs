//! Unknowns of the algebraic problem: the paper's boundary conditions are
//! eliminated and, at each contact node i of Γ_K, the upper body's
//! displacement is replaced by the jump and the slip (paper, section 5):
//!
//! ```text
//! t_i = v'_2 − v''_2   (replaces v''_2),     s_i = v'_1 − v''_1   (replaces v''_1),
//! ```
//!
//! so that v''_k = v'_k − (s_i, t_i)_k. Fixed values are zero, so elimination
//! simply drops them.

use crate::mechanics::mesh::{Body, Mesh};

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

/// A [`Dof`] as the map keeps it: two 32-bit unknowns, [`Packed::NONE`]
/// where there is none (8 bytes, not the enum's 24: at h = 1/4096 the map
/// took 0.8 GB beside the problem).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Packed([u32; 2]);

impl Packed {
    const NONE: u32 = u32::MAX;
    const FIXED: Packed = Packed([Self::NONE; 2]);

    fn of(dof: Dof) -> Self {
        let index = |i: usize| {
            u32::try_from(i)
                .ok()
                .filter(|&i| i != Self::NONE)
                .expect("unknowns are numbered below 2³² − 1")
        };
        match dof {
            Dof::Fixed => Self::FIXED,
            Dof::Slot(s) => Packed([index(s), Self::NONE]),
            Dof::Relative { base, own } => Packed([index(base), index(own)]),
        }
    }

    #[inline(always)]
    fn dof(self) -> Dof {
        match self.0 {
            [Self::NONE, _] => Dof::Fixed,
            [s, Self::NONE] => Dof::Slot(s as usize),
            [base, own] => Dof::Relative {
                base: base as usize,
                own: own as usize,
            },
        }
    }
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
#[derive(Clone, Debug)]
pub struct DofMap {
    map: Vec<[Packed; 2]>,
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
        let num_nodes = mesh.num_nodes();
        let mut map = vec![[Packed::FIXED; 2]; num_nodes];
        let mut n = 0;
        let mut next = || {
            n += 1;
            n - 1
        };
        let last = mesh.n() - 1;
        for (node, dofs) in map.iter_mut().enumerate() {
            let (body, i, j) = mesh.locate(node);
            let these = match body {
                Body::Lower if j == 0 => [Dof::Fixed, Dof::Fixed],
                Body::Lower => [Dof::Slot(next()), Dof::Slot(next())],
                Body::Upper if j == 0 => [Dof::Fixed, Dof::Fixed], // filled below
                Body::Upper if i == last => [Dof::Fixed, Dof::Slot(next())],
                Body::Upper => [Dof::Slot(next()), Dof::Slot(next())],
            };
            *dofs = these.map(Packed::of);
        }
        // Contact nodes: the lower partner's unknowns exist, add (s, t) as the
        // upper node's own unknowns.
        let mut contacts = Vec::with_capacity(mesh.n());
        for i in 0..mesh.n() {
            let lower_node = mesh.node(Body::Lower, i, mesh.contact_row(Body::Lower));
            let upper_node = mesh.node(Body::Upper, i, mesh.contact_row(Body::Upper));
            let slot = |d: Dof| match d {
                Dof::Slot(s) => s,
                _ => unreachable!("lower contact nodes are free"),
            };
            let s = next();
            let t = next();
            map[upper_node] = [
                Dof::Relative {
                    base: slot(map[lower_node][0].dof()),
                    own: s,
                },
                Dof::Relative {
                    base: slot(map[lower_node][1].dof()),
                    own: t,
                },
            ]
            .map(Packed::of);
            contacts.push(ContactDofs {
                x: mesh.coords(lower_node)[0],
                lower_node,
                upper_node,
                t,
                s,
            });
        }
        Self { map, n, contacts }
    }

    pub fn dof(&self, node: usize, k: usize) -> Dof {
        self.map[node][k].dof()
    }

    /// Contact nodes of Γ_K in increasing x.
    pub fn contacts(&self) -> &[ContactDofs] {
        &self.contacts
    }

    /// Physical nodal displacements (per node, x and y) from the unknowns.
    pub fn to_physical(&self, v: &[f64]) -> Vec<[f64; 2]> {
        self.map
            .iter()
            .map(|dofs| {
                dofs.map(|d| match d.dof() {
                    Dof::Fixed => 0.0,
                    Dof::Slot(s) => v[s],
                    Dof::Relative { base, own } => v[base] - v[own],
                })
            })
            .collect()
    }

    /// The unknowns representing a physical displacement field. Components on
    /// fixed boundaries are ignored (the field is assumed to satisfy them).
    pub fn from_physical(&self, u: &[[f64; 2]]) -> Vec<f64> {
        let mut v = vec![0.0; self.n];
        for (node, dofs) in self.map.iter().enumerate() {
            for k in 0..2 {
                if let Dof::Slot(s) = dofs[k].dof() {
                    v[s] = u[node][k];
                }
            }
        }
        for c in &self.contacts {
            for (k, own) in [(0, c.s), (1, c.t)] {
                v[own] = u[c.lower_node][k] - u[c.upper_node][k];
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
        match self.map[node][k].dof() {
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
