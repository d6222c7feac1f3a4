//! The P1 triangle of plane elasticity: its strain matrix, element
//! stiffness ∫ σ(u):ε(v) (σ = D ε, engineering shear) and consistent mass
//! ∫ u·v, each exact for linear shape functions.

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
