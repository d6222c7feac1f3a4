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
//! | `contact.csv` | per contact node: `node,x,t,s,weight,g,coefficient,gap,slip_offset` |
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

mod export;
pub use export::export;

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
    /// Initial gap d_i ≥ 0 between the bodies (t_i ≤ d_i); a file without
    /// the column has none.
    #[serde(default)]
    pub gap: f64,
    /// Slip offset σ_i: friction acts on s_i − σ_i (a body moved sideways
    /// by a rigid lift); a file without the column has none.
    #[serde(default)]
    pub slip_offset: f64,
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
    import_for(dir, |_| 0.0)
}

/// As [`import`], for a run that needs `also(n)` bytes beside the instance
/// (`certify` completing an answer given as forces): the whole checked
/// once, before the first file is read, and admitted
/// ([`crate::memory::admit`]).
pub fn import_for(dir: &Path, also: impl Fn(usize) -> f64) -> Result<Instance> {
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
    let need = crate::memory::instance(n) + also(n);
    crate::memory::check_need(
        &format!("reading the instance {shown}"),
        need,
        n,
        Vec::new(),
    )?;
    crate::memory::admit(need);
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
    let Contacts {
        nodes,
        g,
        gap,
        slip_offset,
    } = read_contacts(&dir.join("contact.csv"), m)?;
    let problem = ContactProblem::new(a, f, mass, nodes, modes)
        .and_then(|p| p.with_gap(gap))
        .and_then(|p| p.with_slip_offset(slip_offset))
        .with_context(|| format!("{shown}: the files do not form a contact problem"))?;
    let definiteness = crate::certificate::problem_checks::check_definite(
        &problem,
        crate::certificate::bound_room(),
    )
    .map_err(|e| anyhow::anyhow!("{shown}: the files do not form a contact problem: {e}"))?;
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
    Ok(Instance {
        problem,
        g,
        definiteness,
    })
}

/// An exported problem read back: the problem, the friction bound g of its
/// given-friction subproblem (`contact.csv`'s column g; None if empty), and
/// what was checked of A beyond `ContactProblem::new`.
pub struct Instance {
    pub problem: ContactProblem,
    pub g: Option<Vec<f64>>,
    /// How far A was checked to be positive semidefinite with exactly the
    /// declared rigid modes ([`crate::certificate::problem_checks`]).
    pub definiteness: crate::certificate::problem_checks::Definiteness,
}

/// Reads exactly `m` rows of `contact.csv`, node i on row i.
fn read_contacts(path: &Path, m: usize) -> Result<Contacts> {
    let (file, _) = guarded::open(path)
        .map_err(|reason| anyhow::anyhow!("cannot read {}: {reason}", path.display()))?;
    contacts_from(file, m, &path.display().to_string())
}

/// The columns of a `contact.csv`, one entry per contact node.
#[derive(Debug)]
pub struct Contacts {
    pub nodes: Vec<ContactNode>,
    /// The friction bound g (None where the column is empty).
    pub g: Vec<Option<f64>>,
    /// The initial gap d.
    pub gap: Vec<f64>,
    /// The slip offset σ.
    pub slip_offset: Vec<f64>,
}

/// The rows of a `contact.csv` read from `source` (named `shown` in
/// messages): exactly `m`, node i on row i.
pub fn contacts_from(source: impl std::io::Read, m: usize, shown: &str) -> Result<Contacts> {
    let mut contacts = Vec::with_capacity(m);
    let mut g = Vec::with_capacity(m);
    let mut gap = Vec::with_capacity(m);
    let mut slip_offset = Vec::with_capacity(m);
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
        gap.push(c.gap);
        slip_offset.push(c.slip_offset);
    }
    if contacts.len() != m {
        bail!(
            "{shown}: {} rows, but problem.json declares {m} contact nodes",
            contacts.len()
        );
    }
    Ok(Contacts {
        nodes: contacts,
        g,
        gap,
        slip_offset,
    })
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
            let (p, q) = crate::certificate::implied_forces(problem, &v);
            (v, p, q)
        }
        (None, Some((p, q))) => {
            let n = problem.n();
            crate::memory::check_need(
                "the displacements of an answer given as forces (a condensation onto the contact unknowns)",
                crate::memory::forces_completion(n),
                n,
                vec!["give the displacements too".into()],
            )?;
            let v = contactlab_solvers::reduction::dual::displacements_from_forces(problem, &p, &q)
                .map_err(anyhow::Error::msg)?;
            (v, p, q)
        }
        (None, None) => {
            anyhow::bail!("no answer given: give the displacements and/or the contact forces")
        }
    })
}
