//! An instance as files any scientific code reads, and back: the matrices in
//! Matrix Market (coordinate, general, every value in shortest round-trip
//! decimal, so that a reader gets the same doubles), the index sets and
//! per-node data as CSV, and `problem.json`, which states the problem, its
//! unknowns, signs, units and scales; and the condensed form on the contact
//! unknowns with its rigid-mode constraint.
//!
//! Files of an exported folder (0-based indices everywhere):
//!
//! | file | what |
//! |---|---|
//! | `A.mtx` | stiffness A (n × n, symmetric positive semidefinite) |
//! | `M.mtx` | mass matrix M (the L2 inner product of displacements) |
//! | `f.mtx` | load vector f (n × 1) |
//! | `rigid_modes.mtx` | the kernel of A (n × k; here k = 1, the upper body's vertical translation) |
//! | `contact.csv` | per contact node: `node,x,t,s,weight,g,coefficient` |
//! | `S.mtx`, `b_condensed.mtx`, `z_condensed.mtx` | the condensed problem on y = (t_0, s_0, t_1, s_1, ...): S y = b̂ − r, and its rigid mode ẑ (2m × k) |
//! | `problem.json` | the statement, conventions, units, scales and the scene |

use std::path::Path;

use anyhow::{Context, Result, bail};
use contactlab_solvers::reduction::condensed::condense;
use contactlab_solvers::{ContactNode, ContactProblem, Friction};
use nalgebra_sparse::{CooMatrix, CsrMatrix};
use serde::{Deserialize, Serialize};

use crate::io::guarded::{self, Lines};
use crate::io::matrix_market::{self, Expect, Triplets};
use crate::io::output::{json_bytes, write_atomic};
use crate::mechanics::discretization::Discretization;
use crate::mechanics::scene::Scene;

/// One row of `contact.csv`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactRow {
    pub node: usize,
    /// Position along Γ_K.
    pub x: f64,
    /// Index of the jump t_i = v'₂ − v''₂ among the unknowns.
    pub t: usize,
    /// Index of the slip s_i = v'₁ − v''₁.
    pub s: usize,
    /// Trapezoid weight w_i of Γ_K.
    pub weight: f64,
    /// Friction bound g_i of the given-friction subproblem (force/length);
    /// empty when the instance states none (the Coulomb problem's bound is
    /// 𝓕p of its own answer, unknown before it is solved).
    pub g: Option<f64>,
    /// Coulomb coefficient 𝓕_i.
    pub coefficient: f64,
}

/// `problem.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Description {
    pub format: &'static str,
    pub statement: Vec<&'static str>,
    pub unknowns: String,
    pub conventions: Vec<&'static str>,
    pub units: Vec<&'static str>,
    pub n: usize,
    pub contact_nodes: usize,
    pub rigid_modes: usize,
    pub scales: contactlab_solvers::Scales,
    pub certificate: Vec<&'static str>,
    pub files: Vec<(&'static str, &'static str)>,
    pub scene: Scene,
    pub h: String,
    pub git_commit: String,
}

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
    write_atomic(&dir.join("A.mtx"), &mtx_symmetric(&CooMatrix::from(p.a())))?;
    write_atomic(
        &dir.join("M.mtx"),
        &mtx_symmetric(&CooMatrix::from(&*p.mass())),
    )?;
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
        })
        .collect();
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in &rows {
        w.serialize(r)?;
    }
    write_atomic(&dir.join("contact.csv"), &w.into_inner()?)?;
    let c = condense(p).map_err(anyhow::Error::msg)?;
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
            "Given-friction (Tresca) subproblem, paper (10): minimize 1/2 v'A v - f'v + sum_i w_i g_i |v[s_i]| subject to v[t_i] <= 0 for every contact node i.",
            "Coulomb problem, paper (7)-(8): the same with g_i = coefficient_i * p_i, p_i the contact pressure of the solution itself.",
            "A is singular: its kernel is spanned by the columns of rigid_modes.mtx (the upper body's vertical translation); a solution exists only if the contact forces can balance the load along it, paper condition (13).",
            "Optimality (what `contactlab certify` checks): A v - f + sum_i w_i p_i e_{t_i} - sum_i w_i q_i e_{s_i} = 0; t_i <= 0, p_i >= 0, p_i t_i = 0; |q_i| <= g_i, s_i = 0 where |q_i| < g_i, q_i = -g_i sign(s_i) where s_i != 0.",
            "Condensed form: with y = (t_0, s_0, t_1, s_1, ...) the contact unknowns and r = (w_0 p_0, -w_0 q_0, ...) the nodal contact forces, S y = b_condensed - r, and z_condensed' (b_condensed - r) = 0 (S z_condensed = 0: the rigid mode).",
        ],
        unknowns: format!(
            "v, {n} values: the free displacement unknowns of both bodies after the change of variables of paper section 5 (at a contact node the lower body's displacement and the jump t = v'2 - v''2 and slip s = v'1 - v''1 are unknowns)"
        ),
        conventions: vec![
            "indices are 0-based (Matrix Market files are 1-based as the format requires)",
            "t_i <= 0: negative jump means the bodies separate",
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
                "condensed operator on the contact unknowns, 2m x 2m (dense, every entry)",
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
    super::mesh_map::write(dir, d)?;
    Ok(())
}

/// What `problem.json` must say for the files beside it to be read.
#[derive(Debug, Deserialize)]
struct Declared {
    format: String,
    n: usize,
    contact_nodes: usize,
    rigid_modes: usize,
}

/// The format line of `problem.json` this version writes and reads.
const FORMAT: &str = "contactlab instance, version 1";

/// `problem.json` is at most this large (it holds the statement and the scene).
const MAX_DESCRIPTION_BYTES: u64 = 16 << 20;

/// The largest instance a file may declare: 1e9 unknowns (h = 1/4096 has
/// 3.4e7), so that a declared size alone never asks for terabytes.
const MAX_UNKNOWNS: usize = 1_000_000_000;

/// Reads one matrix of an exported folder, of the size `problem.json`
/// declares.
fn load(dir: &Path, name: &str, rows: usize, cols: usize, what: &'static str) -> Result<Triplets> {
    let expect = Expect {
        rows: Some(rows),
        cols: Some(cols),
        what,
    };
    Ok(matrix_market::read(&dir.join(name), expect)?)
}

/// A sparse matrix from triplets (duplicates summed).
fn csr(t: &Triplets) -> CsrMatrix<f64> {
    let mut coo = CooMatrix::new(t.rows, t.cols);
    for &(i, j, x) in &t.entries {
        coo.push(i, j, x);
    }
    CsrMatrix::from(&coo)
}

/// Reads an exported folder back into the algebraic problem. `problem.json`
/// is read first and every file is held to what it declares: n unknowns
/// (A, M n × n, f n × 1), k rigid modes (n × k), m contact nodes (exactly m
/// rows of `contact.csv`, node i on row i), before anything is allocated.
pub fn import(dir: &Path) -> Result<Instance> {
    let shown = dir.display();
    let json_path = dir.join("problem.json");
    if !json_path.is_file() {
        bail!("{shown}: no problem.json; give a folder written by `contactlab export`");
    }
    let text = guarded::read_small_text(&json_path, MAX_DESCRIPTION_BYTES)
        .map_err(|reason| anyhow::anyhow!("cannot read {}: {reason}", json_path.display()))?;
    let declared: Declared = serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: it does not state format, n, contact_nodes and rigid_modes",
            json_path.display()
        )
    })?;
    if declared.format != FORMAT {
        bail!(
            "{}: format '{}' is not '{FORMAT}'; export the problem again with this version",
            json_path.display(),
            declared.format
        );
    }
    let (n, m, k) = (declared.n, declared.contact_nodes, declared.rigid_modes);
    if n > MAX_UNKNOWNS || 2 * m > n || k > n {
        bail!(
            "{}: n = {n}, contact_nodes = {m}, rigid_modes = {k} cannot describe a problem (n at most {MAX_UNKNOWNS:e}, 2·contact_nodes and rigid_modes at most n)",
            json_path.display()
        );
    }
    let a = csr(&load(dir, "A.mtx", n, n, "A (the stiffness, n × n)")?);
    let mass = csr(&load(dir, "M.mtx", n, n, "M (the mass matrix, n × n)")?);
    let f = load(dir, "f.mtx", n, 1, "f (the load, n × 1)")?.column(0);
    let modes = load(
        dir,
        "rigid_modes.mtx",
        n,
        k,
        "the rigid modes (n × rigid_modes)",
    )?;
    let modes: Vec<Vec<f64>> = (0..k).map(|j| modes.column(j)).collect();
    let (contacts, g) = read_contacts(&dir.join("contact.csv"), m)?;
    let problem = ContactProblem::new(a, f, mass, contacts, modes)
        .with_context(|| format!("{shown}: the files do not form a contact problem"))?;
    let g = match g.iter().filter(|g| g.is_some()).count() {
        0 => None,
        given if given == g.len() => Some(g.into_iter().flatten().collect::<Vec<f64>>()),
        given => bail!(
            "{shown}: contact.csv's column g gives a bound for {given} of {} nodes; give it for every node or for none",
            g.len()
        ),
    };
    if let Some(g) = &g {
        Friction::Given(g)
            .check(&problem)
            .map_err(|e| anyhow::anyhow!("{shown}: contact.csv's column g: {e}"))?;
    }
    Ok(Instance { problem, g })
}

/// An exported problem read back: the problem, and the friction bound g of
/// its given-friction subproblem (`contact.csv`'s column g; None if empty).
pub struct Instance {
    pub problem: ContactProblem,
    pub g: Option<Vec<f64>>,
}

/// Reads exactly `m` rows of `contact.csv`, node i on row i.
fn read_contacts(path: &Path, m: usize) -> Result<(Vec<ContactNode>, Vec<Option<f64>>)> {
    let (file, _) = guarded::open(path)
        .map_err(|reason| anyhow::anyhow!("cannot read {}: {reason}", path.display()))?;
    contacts_from(file, m, &path.display().to_string())
}

/// The rows of a `contact.csv` read from `source` (named `shown` in
/// messages): exactly `m`, node i on row i; the contact nodes and the
/// friction bound g.
pub fn contacts_from(
    source: impl std::io::Read,
    m: usize,
    shown: &str,
) -> Result<(Vec<ContactNode>, Vec<Option<f64>>)> {
    let mut contacts = Vec::with_capacity(m);
    let mut g = Vec::with_capacity(m);
    for (i, rec) in guarded::csv_reader(source)
        .deserialize::<ContactRow>()
        .enumerate()
    {
        let c = rec.with_context(|| format!("{shown}: row {} does not parse", i + 1))?;
        if i >= m {
            bail!("{shown}: more than the {m} rows problem.json declares");
        }
        if c.node != i {
            bail!(
                "{shown}: row {} is node {}, expected node {i} (rows in node order)",
                i + 1,
                c.node
            );
        }
        contacts.push(ContactNode {
            t: c.t,
            s: c.s,
            weight: c.weight,
            coefficient: c.coefficient,
        });
        g.push(c.g);
    }
    if contacts.len() != m {
        bail!(
            "{shown}: {} rows, but problem.json declares {m} contact nodes",
            contacts.len()
        );
    }
    Ok((contacts, g))
}

/// Reads the displacements of an `n`-unknown problem: a Matrix Market file
/// (`.mtx`, n × 1, coordinate or array), or plain text with one number per
/// line (blank lines and lines starting with `#` or `%` skipped).
pub fn read_vector(path: &Path, n: usize) -> Result<Vec<f64>> {
    if path.extension().is_some_and(|e| e == "mtx") {
        let expect = Expect {
            rows: Some(n),
            cols: Some(1),
            what: "--displacements (one value per unknown)",
        };
        return Ok(matrix_market::read(path, expect)?.column(0));
    }
    let shown = path.display();
    let (mut lines, _) =
        Lines::open(path).map_err(|reason| anyhow::anyhow!("cannot read {shown}: {reason}"))?;
    let mut v = Vec::new();
    while let Some((number, line)) = lines
        .next_numbered()
        .map_err(|r| anyhow::anyhow!("{shown}: {r}"))?
    {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') || l.starts_with('%') {
            continue;
        }
        let x = l
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .with_context(|| {
                format!(
                    "{shown}: line {number} is not a finite number: '{}'",
                    l.chars()
                        .take(40)
                        .filter(|c| !c.is_control())
                        .collect::<String>()
                )
            })?;
        if v.len() == n {
            bail!("--displacements {shown}: more than the problem's {n} values (line {number})");
        }
        v.push(x);
    }
    if v.len() != n {
        bail!(
            "--displacements {shown}: {} values, the problem has {n} unknowns",
            v.len()
        );
    }
    Ok(v)
}

/// One row of a contact-forces file.
#[derive(Clone, Debug, Deserialize)]
pub struct ForceRow {
    pub pressure: f64,
    pub friction_traction: f64,
}

/// Reads pressures and friction tractions of `m` contact nodes (CSV with
/// columns `pressure,friction_traction`, others ignored, one row per node
/// in the order of `contact.csv`).
pub fn read_forces(path: &Path, m: usize) -> Result<(Vec<f64>, Vec<f64>)> {
    let shown = format!("--forces {}", path.display());
    let (file, _) =
        guarded::open(path).map_err(|reason| anyhow::anyhow!("cannot read {shown}: {reason}"))?;
    forces_from(file, m, &shown)
}

/// The forces of `m` contact nodes read from `source` (named `shown` in
/// messages).
pub fn forces_from(
    source: impl std::io::Read,
    m: usize,
    shown: &str,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let mut p = Vec::new();
    let mut q = Vec::new();
    for (i, rec) in guarded::csv_reader(source)
        .deserialize::<ForceRow>()
        .enumerate()
    {
        let row = rec.with_context(|| {
            format!(
                "{shown}: row {} needs numbers in columns pressure and friction_traction",
                i + 1
            )
        })?;
        if i >= m {
            bail!("{shown}: more than the problem's {m} contact nodes");
        }
        p.push(row.pressure);
        q.push(row.friction_traction);
    }
    if p.len() != m {
        bail!(
            "{shown}: {} rows, the problem has {m} contact nodes",
            p.len()
        );
    }
    Ok((p, q))
}

/// An answer made whole for the certificate: displacements v, pressures p
/// and friction tractions q. Given v alone, the forces follow from
/// stationarity at the contact rows, A v − f + Σ w p e_t − Σ w q e_s = 0;
/// given the forces alone, v follows from the elastic response to them
/// ([`displacements_from_forces`]). `certify` and the Python package's
/// `certify` both complete an answer here.
pub fn complete_answer(
    problem: &ContactProblem,
    v: Option<Vec<f64>>,
    forces: Option<(Vec<f64>, Vec<f64>)>,
) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    Ok(match (v, forces) {
        (Some(v), Some((p, q))) => (v, p, q),
        (Some(v), None) => {
            let (offsets, cols, vals) = problem.a().csr_data();
            let row = |i: usize| -> f64 {
                (offsets[i]..offsets[i + 1])
                    .map(|k| vals[k] * v[cols[k]])
                    .sum::<f64>()
                    - problem.f()[i]
            };
            let p = problem
                .contacts()
                .iter()
                .map(|c| -row(c.t) / c.weight)
                .collect();
            let q = problem
                .contacts()
                .iter()
                .map(|c| row(c.s) / c.weight)
                .collect();
            (v, p, q)
        }
        (None, Some((p, q))) => {
            let v = contactlab_solvers::reduction::dual::displacements_from_forces(problem, &p, &q)
                .map_err(anyhow::Error::msg)?;
            (v, p, q)
        }
        (None, None) => {
            anyhow::bail!("no answer given: give the displacements and/or the contact forces")
        }
    })
}
