//! Writing an instance folder (see [`super`] for its files): the matrices
//! in Matrix Market, the contact nodes as CSV, the condensed form on the
//! contact unknowns, `problem.json` and the map from unknowns to nodes.

use super::*;

/// A general matrix in Matrix Market coordinate format, with the banner
/// `%%MatrixMarket` that scipy.io.mmread requires.
fn mtx(coo: &CooMatrix<f64>) -> Vec<u8> {
    let entries: Vec<_> = coo.triplet_iter().map(|(i, j, &v)| (i, j, v)).collect();
    matrix_market::write_coordinate(coo.nrows(), coo.ncols(), entries.into_iter(), false)
        .into_bytes()
}

/// A symmetric matrix, marked so (its lower triangle written).
fn mtx_symmetric(coo: &CooMatrix<f64>) -> Vec<u8> {
    let entries: Vec<_> = coo.triplet_iter().map(|(i, j, &v)| (i, j, v)).collect();
    matrix_market::write_coordinate(coo.nrows(), coo.ncols(), entries.into_iter(), true)
        .into_bytes()
}

fn dense(rows: usize, cols: usize, at: impl Fn(usize, usize) -> f64) -> CooMatrix<f64> {
    let mut c = CooMatrix::new(rows, cols);
    for j in 0..cols {
        for i in 0..rows {
            c.push(i, j, at(i, j));
        }
    }
    c
}

/// Writes the instance `d` (the finest level of `scene`) into `dir`.
/// `bound`: the uniform friction bound g of a given-friction subproblem to
/// state in `contact.csv` (None: its column g stays empty).
pub fn export(
    dir: &Path,
    scene: &Scene,
    d: &Discretization,
    bound: Option<f64>,
    git_commit: &str,
) -> Result<()> {
    let p = &d.problem;
    let n = p.n();
    write_atomic(
        &dir.join("A.mtx"),
        &mtx_symmetric(&CooMatrix::from(&p.a().to_nalgebra())),
    )?;
    // A level built without M (the Python package's problem) has it
    // assembled from its mesh here, rather than the whole level again.
    let mass = match p.mass() {
        Some(m) => m,
        None => std::borrow::Cow::Owned(d.assemble_mass()?.to_nalgebra()),
    };
    write_atomic(&dir.join("M.mtx"), &mtx_symmetric(&CooMatrix::from(&*mass)))?;
    // Freed once written: the condensation below needs the room.
    drop(mass);
    write_atomic(&dir.join("f.mtx"), &mtx(&dense(n, 1, |i, _| p.f()[i])))?;
    let modes = p.rigid_modes();
    write_atomic(
        &dir.join("rigid_modes.mtx"),
        &mtx(&dense(n, modes.len(), |i, j| modes[j][i])),
    )?;
    let x = d.contact_x();
    let rows: Vec<ContactRow> = p
        .contacts()
        .iter()
        .enumerate()
        .map(|(i, c)| ContactRow {
            node: i,
            x: x[i],
            t: c.t,
            s: c.s,
            weight: c.weight,
            g: bound,
            coefficient: c.coefficient,
            gap: p.gap()[i],
            slip_offset: p.slip_offset()[i],
        })
        .collect();
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in &rows {
        w.serialize(r)?;
    }
    write_atomic(&dir.join("contact.csv"), &w.into_inner()?)?;
    let c = condense(p).map_err(|e| anyhow::Error::msg(e.detail))?;
    let m2 = c.b.len();
    write_atomic(
        &dir.join("S.mtx"),
        &mtx_symmetric(&dense(m2, m2, |i, j| c.s[(i, j)])),
    )?;
    write_atomic(
        &dir.join("b_condensed.mtx"),
        &mtx(&dense(m2, 1, |i, _| c.b[i])),
    )?;
    let on_contacts = |z: &[f64], k: usize| {
        let node = &p.contacts()[k / 2];
        if k.is_multiple_of(2) {
            z[node.t]
        } else {
            z[node.s]
        }
    };
    write_atomic(
        &dir.join("z_condensed.mtx"),
        &mtx(&dense(m2, modes.len(), |i, j| on_contacts(&modes[j], i))),
    )?;
    let description = Description {
        format: FORMAT,
        statement: vec![
            "Given-friction (Tresca) subproblem, paper (10): minimize 1/2 v'A v - f'v + sum_i w_i g_i |v[s_i] - slip_offset_i| subject to v[t_i] <= gap_i for every contact node i (gap: contact.csv's column, the initial distance between the bodies; slip_offset: its column, the slip of a body moved sideways by a rigid lift; both 0 in the paper's scene).",
            "Coulomb problem, paper (7)-(8): the same with g_i = coefficient_i * p_i, p_i the contact pressure of the solution itself.",
            "A is singular: its kernel is spanned by the columns of rigid_modes.mtx (the upper body's vertical translation); a solution exists only if the contact forces can balance the load along it, paper condition (13).",
            "Optimality (what `contactlab certify` checks): A v - f + sum_i w_i p_i e_{t_i} - sum_i w_i q_i e_{s_i} = 0; t_i <= gap_i, p_i >= 0, p_i (gap_i - t_i) = 0; |q_i| <= g_i, and with the slip s_i - slip_offset_i: it is 0 where |q_i| < g_i, q_i = -g_i sign(it) where it is not 0.",
            "Condensed form: with y = (t_0, s_0, t_1, s_1, ...) the contact unknowns and r = (w_0 p_0, -w_0 q_0, ...) the nodal contact forces, S y = b_condensed - r, and z_condensed' (b_condensed - r) = 0 (S z_condensed = 0: the rigid mode).",
        ],
        unknowns: format!(
            "v, {n} values: the free displacement unknowns of both bodies after the change of variables of paper section 5 (at a contact node the lower body's displacement and the jump t = v'2 - v''2 and slip s = v'1 - v''1 are unknowns)"
        ),
        conventions: vec![
            "indices are 0-based (Matrix Market files are 1-based as the format requires)",
            "t_i <= gap_i: a jump below the gap means the bodies separate (the lower body is primed, the normal of Gamma_K is vertical: t = u2_lower - u2_upper)",
            "p_i >= 0: contact pressure (the multiplier l = -sigma_n), force per length of Gamma_K",
            "q_i: tangential (x) traction on the lower body, |q_i| <= g_i, opposing the slip",
        ],
        units: vec![
            "those of the scene: lengths in its length unit, Young's modulus and tractions in force per length (plane problem, unit thickness)",
            "the paper gives none; its values: E = 73e3, loads -60 or -120 on parts of the top side of length 1/3 or 1",
        ],
        n,
        contact_nodes: p.contacts().len(),
        rigid_modes: modes.len(),
        scales: *p.scales(),
        certificate: vec![
            "each condition's violation in the problem's scales: jumps and slips over displacement U, pressures and tractions over pressure P, nodal force residuals over P * max w_i, the balance over |z'f|",
            "an answer is certified if every violation is at most the tolerance (default 1e-5)",
        ],
        files: vec![
            ("A.mtx", "stiffness A, n x n"),
            ("M.mtx", "mass matrix M, n x n"),
            ("f.mtx", "load f, n x 1"),
            ("rigid_modes.mtx", "kernel of A, n x k"),
            (
                "contact.csv",
                "node,x,t,s,weight,g,coefficient per contact node (g, the bound of a given-friction subproblem, empty unless export was given --friction-bound)",
            ),
            (
                "S.mtx",
                "condensed operator on the contact unknowns, 2m x 2m, dense and symmetric (its lower triangle written, header 'symmetric', as A.mtx and M.mtx)",
            ),
            ("b_condensed.mtx", "condensed load, 2m x 1"),
            (
                "z_condensed.mtx",
                "rigid mode on the contact unknowns, 2m x k",
            ),
            (
                "nodes.csv",
                "node,body,x,y,u1_plus,u1_minus,u2_plus,u2_minus per mesh node: u_k = v[uk_plus] - v[uk_minus], 0-based, an empty index absent (both: fixed zero)",
            ),
            (
                "triangles.csv",
                "body,n0,n1,n2 per P1 triangle (counterclockwise), nodes as in nodes.csv",
            ),
        ],
        scene: scene.clone(),
        h: d.h().to_string(),
        git_commit: git_commit.to_string(),
    };
    write_atomic(&dir.join("problem.json"), &json_bytes(&description)?)?;
    write_atomic(&dir.join("README.md"), readme(&description).as_bytes())?;
    crate::formats::mesh_map::write(dir, d)?;
    Ok(())
}

/// The folder's README: what each file holds (its shape, units and signs),
/// what the condensed form and the rigid mode mean for a solver of one's
/// own, and how to hand an answer back to `certify`, with a worked example
/// in Python. Written from the same description as `problem.json`.
fn readme(d: &Description) -> String {
    let mut s = format!(
        "# {} at h = {}: the algebraic contact problem\n\n\
         Written by `contactlab export` (commit {}). `problem.json` says the same in JSON; \
         `contactlab certify` reads this folder back.\n\n\
         n = {} unknowns, m = {} contact nodes, {} rigid mode(s).\n\n## The problem\n\n",
        d.scene.name, d.h, d.git_commit, d.n, d.contact_nodes, d.rigid_modes
    );
    for line in &d.statement {
        s += &format!("- {line}\n");
    }
    s += &format!(
        "\n**Unknowns.** {}\n\n## Conventions and units\n\n",
        d.unknowns
    );
    for line in d.conventions.iter().chain(&d.units) {
        s += &format!("- {line}\n");
    }
    let sc = &d.scales;
    s += &format!(
        "\n**The problem's scales** (the certificate measures in them): force F = {:e}, length of Γ_K L = {:e}, \
         stiffness K = {:e}, pressure P = F/L = {:e}, displacement U = F/K = {:e}.\n\n## Files\n\n\
         | file | what |\n|---|---|\n",
        sc.force, sc.length, sc.stiffness, sc.pressure, sc.displacement
    );
    for (file, what) in &d.files {
        s += &format!("| `{file}` | {what} |\n");
    }
    s += "| `problem.json` | this description, for programs |\n| `README.md` | this file |\n";
    s += "\n## For a solver of your own\n\n\
          - **A is singular.** The rigid mode z (`rigid_modes.mtx`) is the upper body's vertical translation: \
          A z = 0. A solver must not invert A: the contact forces fix the translation, and a solution exists only \
          if they can balance the load along z (paper condition (13)).\n\
          - **The condensed form** eliminates every unknown but the contact ones (y = t_0, s_0, t_1, s_1, …): \
          S y = b_condensed − r with r the nodal contact forces, S z_condensed = 0, and z_condensed'(b_condensed − r) \
          = 0. A local (node-by-node) solver works on S and b_condensed alone.\n\
          - **A multigrid solver** needs the mesh: `nodes.csv` and `triangles.csv` map the unknowns to the P1 mesh.\n\
          \n## Handing an answer to `certify`\n\n\
          Write the displacements v (n values), or the contact forces (pressure p and friction traction q, m values \
          each), or both; the missing half follows (forces from stationarity at the contact rows, displacements from \
          the elastic response). Files are Matrix Market columns (n × 1 or m × 1) or one number per line:\n\n\
          ```\ncontactlab certify --instance THIS_FOLDER --displacements v.mtx\n\
          contactlab certify --instance THIS_FOLDER --forces forces.csv   # header pressure,friction_traction, one row per contact node\n```\n\n\
          In Python (scipy reads every file here):\n\n```python\n\
          import numpy as np, scipy.io, scipy.sparse.linalg as sla\n\
          A = scipy.io.mmread(\"A.mtx\").tocsr()            # symmetric: scipy fills the upper triangle\n\
          f = scipy.io.mmread(\"f.mtx\").toarray().ravel()\n\
          # ... your solver gives v ...\n\
          scipy.io.mmwrite(\"v.mtx\", v.reshape(-1, 1))\n\
          # then: contactlab certify --instance . --displacements v.mtx\n\
          # or, with the Python package: cl.certify(cl.Problem.from_instance(\".\"), displacements=v)\n```\n\n\
          The certificate checks nonpenetration, pressure ≥ 0, complementarity, the friction bound (g = 𝓕p for the \
          Coulomb law), no slip below it, the slip opposite to the traction, stationarity and the force balance, each \
          relative to the scales above.\n";
    for line in &d.certificate {
        s += &format!("- {line}\n");
    }
    s
}
