//! The paper's mesh (section 5): the unit square cut at y = 1/2 into the lower
//! body Ω' = [0,1]×[0,½] and the upper body Ω'' = [0,1]×[½,1], uniform right
//! isosceles triangles (each h-square cut along its diagonal from lower-left to
//! upper-right), and the contact nodes of Γ_K duplicated, one per body, so that
//! there are N = n² + n nodes with n = 1/h + 1.

use crate::mechanics::mesh_size::MeshSize;

/// Which body a node or element belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Body {
    /// Ω', clamped on y = 0.
    Lower,
    /// Ω'', on a roller on x = 1 and loaded on y = 1.
    Upper,
}

/// A structured two-body triangulation. Nodes are numbered row by row, the
/// lower body first; row 0 of the upper body and the top row of the lower body
/// both lie on Γ_K.
#[derive(Clone, Debug)]
pub struct Mesh {
    size: MeshSize,
    n: usize,
    rows: usize,
}

impl Mesh {
    pub fn new(size: MeshSize) -> Self {
        let n = size.divisions() + 1;
        Self {
            size,
            n,
            rows: size.divisions() / 2 + 1,
        }
    }

    pub fn size(&self) -> MeshSize {
        self.size
    }

    pub fn h(&self) -> f64 {
        self.size.h()
    }

    /// Nodes along a side of the unit square, n = 1/h + 1.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Node rows per body, 1/(2h) + 1.
    pub fn rows(&self) -> usize {
        self.rows
    }

    pub fn num_nodes(&self) -> usize {
        2 * self.n * self.rows
    }

    /// The unknowns of the algebraic problem on this mesh, counted without
    /// building it ([`crate::mechanics::dofs::DofMap`] numbers them): two
    /// per node off the clamped side y = 0 and off Γ_K, less one per node
    /// of the upper body's roller x = 1, plus the jump and the slip of each
    /// contact node. What a run will need is estimated from it before
    /// anything is allocated ([`crate::memory`]).
    pub fn unknowns(&self) -> usize {
        self.unknowns_with(crate::mechanics::dofs::Hold::Roller)
    }

    /// As [`Mesh::unknowns`], with the upper body held sideways as `hold`
    /// says: on the roller one fewer per row above Γ_K, on rollers on both
    /// sides two fewer.
    pub fn unknowns_with(&self, hold: crate::mechanics::dofs::Hold) -> usize {
        let (n, above) = (self.n, self.rows - 1);
        let upper = match hold {
            crate::mechanics::dofs::Hold::Roller => 2 * n * above - above,
            crate::mechanics::dofs::Hold::Rollers => (2 * n - 2) * above,
            crate::mechanics::dofs::Hold::Sliding => (2 * n - 2) * above + 1,
        };
        2 * n * above + upper + 2 * n
    }

    pub fn num_elements(&self) -> usize {
        2 * 2 * (self.n - 1) * (self.rows - 1)
    }

    /// Node at column i (x = ih) and row j of a body.
    pub fn node(&self, body: Body, i: usize, j: usize) -> usize {
        let offset = match body {
            Body::Lower => 0,
            Body::Upper => self.n * self.rows,
        };
        offset + j * self.n + i
    }

    /// (body, column, row) of a node.
    pub fn locate(&self, node: usize) -> (Body, usize, usize) {
        let per_body = self.n * self.rows;
        let (body, local) = if node < per_body {
            (Body::Lower, node)
        } else {
            (Body::Upper, node - per_body)
        };
        (body, local % self.n, local / self.n)
    }

    /// The body a node belongs to (the lower body's nodes come first).
    pub fn body_of(&self, node: usize) -> Body {
        if node < self.n * self.rows {
            Body::Lower
        } else {
            Body::Upper
        }
    }

    /// Coordinates of a node.
    pub fn coords(&self, node: usize) -> [f64; 2] {
        let (body, i, j) = self.locate(node);
        let h = self.h();
        let y0 = match body {
            Body::Lower => 0.0,
            Body::Upper => 0.5,
        };
        [i as f64 * h, y0 + j as f64 * h]
    }

    /// Row index of Γ_K within a body.
    pub fn contact_row(&self, body: Body) -> usize {
        match body {
            Body::Lower => self.rows - 1,
            Body::Upper => 0,
        }
    }

    /// Triangles (counterclockwise) with their body: each h-square
    /// (LL, LR, UR, UL) is cut into (LL, LR, UR) and (LL, UR, UL).
    pub fn triangles(&self) -> impl Iterator<Item = (Body, [usize; 3])> + '_ {
        [Body::Lower, Body::Upper]
            .into_iter()
            .flat_map(move |body| {
                (0..self.rows - 1).flat_map(move |j| {
                    (0..self.n - 1).flat_map(move |i| {
                        let ll = self.node(body, i, j);
                        let lr = self.node(body, i + 1, j);
                        let ur = self.node(body, i + 1, j + 1);
                        let ul = self.node(body, i, j + 1);
                        [(body, [ll, lr, ur]), (body, [ll, ur, ul])]
                    })
                })
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_match_the_paper() {
        for k in 1..=8 {
            let m = Mesh::new(MeshSize::from_level(k).unwrap());
            let n = m.n();
            assert_eq!(n, (1 << k) + 1);
            assert_eq!(m.num_nodes(), n * n + n, "N = n² + n at k = {k}");
            assert_eq!(m.triangles().count(), m.num_elements());
            assert_eq!(m.num_elements(), 2 * (n - 1) * (n - 1));
            let numbered = crate::mechanics::dofs::DofMap::new(&m);
            let counted = crate::mechanics::dofs::DofExpansion::n(&numbered);
            assert_eq!(m.unknowns(), counted, "unknowns at k = {k}");
        }
        // h = 1/512, as `info` prints it.
        assert_eq!(
            Mesh::new(MeshSize::from_level(9).unwrap()).unknowns(),
            526_082
        );
    }

    #[test]
    fn triangles_are_counterclockwise_and_tile_each_body() {
        let m = Mesh::new(MeshSize::from_level(3).unwrap());
        let mut area = [0.0, 0.0];
        for (body, [a, b, c]) in m.triangles() {
            let (pa, pb, pc) = (m.coords(a), m.coords(b), m.coords(c));
            let det = (pb[0] - pa[0]) * (pc[1] - pa[1]) - (pc[0] - pa[0]) * (pb[1] - pa[1]);
            assert!(det > 0.0);
            area[(body == Body::Upper) as usize] += det / 2.0;
        }
        assert!((area[0] - 0.5).abs() < 1e-14 && (area[1] - 0.5).abs() < 1e-14);
    }

    #[test]
    fn contact_rows_coincide() {
        let m = Mesh::new(MeshSize::from_level(4).unwrap());
        for i in 0..m.n() {
            let lo = m.coords(m.node(Body::Lower, i, m.contact_row(Body::Lower)));
            let up = m.coords(m.node(Body::Upper, i, m.contact_row(Body::Upper)));
            assert_eq!(lo, up);
            assert_eq!(lo[1], 0.5);
        }
    }
}
