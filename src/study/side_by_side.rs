//! Two answers of the Coulomb problem node by node along Γ_K: a solver
//! against another, against the earned reference, or against an answer
//! imported from a `profile.csv` (`contactlab solve --out`). The
//! verification a researcher does by joining two profiles, done once:
//! per contact node both answers' displacements, jump, slip, pressure and
//! friction traction, their differences in the problem's scales (U for
//! displacements, P for forces per length: the scales of the certificate,
//! `Scales` in the solvers crate), and whether the contact states match;
//! an overlay chart of p and q and a chart of the differences.

use anyhow::{Result, bail};
use contactlab_solvers::Law;
use contactlab_solvers::registry::Entry;
use serde::Serialize;

use crate::io::charts::{Chart, Series};
use crate::io::csv::fixed;
use crate::mechanics::contact_zone::{ContactState, ProfileRow, contact_profile};
use crate::mechanics::scene::Scene;
use crate::study::class::WRONG_PRESSURE;
use crate::study::lab::{Artifact, Lab, Ran, RunLength, Section, Study};
use crate::study::runner::Keep;
use crate::study::template;
use crate::study::trial::TrialSpec;

/// The study's name in trial records.
pub const STUDY: &str = "side_by_side";

/// One side of a comparison.
#[derive(Clone, Debug)]
pub enum Side {
    /// A registered solver at the run's settings.
    Solver(&'static Entry),
    /// The earned reference: the exact solvers at their tightest settings,
    /// the certified answer with the smallest certificate.
    Reference,
    /// An answer read from a profile (`name`: its folder and file, or
    /// the whole `path` where two profiles share those,
    /// [`with_distinct_names`]).
    Imported {
        name: String,
        path: String,
        rows: Vec<ImportedRow>,
    },
}

/// A node of an imported profile: the columns a comparison reads.
#[derive(Clone, Debug, serde::Deserialize)]
pub struct ImportedRow {
    pub x: f64,
    pub u1_lower: f64,
    pub u2_lower: f64,
    pub u1_upper: f64,
    pub u2_upper: f64,
    pub jump: f64,
    pub slip: f64,
    pub pressure: f64,
    pub friction_traction: f64,
    pub state: String,
}

impl Side {
    /// Its name in files and tables.
    pub fn name(&self) -> String {
        match self {
            Side::Solver(e) => e.name.to_string(),
            Side::Reference => "reference".into(),
            Side::Imported { name, .. } => name.clone(),
        }
    }
}

/// One answer along Γ_K with what it is.
struct Answer {
    /// `relaxation`, or `reference (newton-coulomb)`.
    label: String,
    status: String,
    rows: Vec<ImportedRow>,
}

fn from_profile(rows: &[ProfileRow]) -> Vec<ImportedRow> {
    rows.iter()
        .map(|r| ImportedRow {
            x: r.x,
            u1_lower: r.u1_lower,
            u2_lower: r.u2_lower,
            u1_upper: r.u1_upper,
            u2_upper: r.u2_upper,
            jump: r.jump,
            slip: r.slip,
            pressure: r.pressure,
            friction_traction: r.friction_traction,
            state: state_name(r.state).into(),
        })
        .collect()
}

/// The contact states a profile may name ([`state_name`]'s words).
pub const STATES: [&str; 3] = ["stick", "slip", "open"];

fn state_name(s: ContactState) -> &'static str {
    match s {
        ContactState::Stick => "stick",
        ContactState::Slip => "slip",
        ContactState::Open => "open",
    }
}

/// A row of `side_by_side_<a>_<b>.csv`: one contact node.
#[derive(Clone, Debug, Serialize)]
pub struct NodeRow {
    #[serde(serialize_with = "fixed")]
    pub x: f64,
    #[serde(serialize_with = "fixed")]
    pub u2_upper_a: f64,
    #[serde(serialize_with = "fixed")]
    pub u2_upper_b: f64,
    #[serde(serialize_with = "fixed")]
    pub jump_a: f64,
    #[serde(serialize_with = "fixed")]
    pub jump_b: f64,
    #[serde(serialize_with = "fixed")]
    pub slip_a: f64,
    #[serde(serialize_with = "fixed")]
    pub slip_b: f64,
    #[serde(serialize_with = "fixed")]
    pub pressure_a: f64,
    #[serde(serialize_with = "fixed")]
    pub pressure_b: f64,
    #[serde(serialize_with = "fixed")]
    pub friction_traction_a: f64,
    #[serde(serialize_with = "fixed")]
    pub friction_traction_b: f64,
    pub state_a: String,
    pub state_b: String,
    /// max over both bodies and both components of |u_a − u_b| / U.
    #[serde(serialize_with = "fixed")]
    pub du_over_u: f64,
    #[serde(serialize_with = "fixed")]
    pub djump_over_u: f64,
    #[serde(serialize_with = "fixed")]
    pub dslip_over_u: f64,
    #[serde(serialize_with = "fixed")]
    pub dp_over_p: f64,
    #[serde(serialize_with = "fixed")]
    pub dq_over_p: f64,
    pub states_match: bool,
}

/// The largest differences of a pair, in the problem's scales.
#[derive(Clone, Debug, Serialize)]
pub struct PairSummary {
    pub scene: String,
    pub h: String,
    pub a: String,
    pub b: String,
    pub status_a: String,
    pub status_b: String,
    pub nodes: usize,
    #[serde(serialize_with = "fixed")]
    pub max_du_over_u: f64,
    #[serde(serialize_with = "fixed")]
    pub max_djump_over_u: f64,
    #[serde(serialize_with = "fixed")]
    pub max_dslip_over_u: f64,
    #[serde(serialize_with = "fixed")]
    pub max_dp_over_p: f64,
    #[serde(serialize_with = "fixed")]
    pub max_dq_over_p: f64,
    /// Where (x) each largest difference sits.
    #[serde(serialize_with = "fixed")]
    pub x_max_du: f64,
    #[serde(serialize_with = "fixed")]
    pub x_max_djump: f64,
    #[serde(serialize_with = "fixed")]
    pub x_max_dslip: f64,
    #[serde(serialize_with = "fixed")]
    pub x_max_dp: f64,
    #[serde(serialize_with = "fixed")]
    pub x_max_dq: f64,
    /// Nodes whose contact states differ, and where (x).
    pub states_differ: usize,
    pub differing_at: String,
    /// The threshold each largest difference is held to, in the problem's
    /// scales ([`AGREEMENT`]), and the verdict: `agree`, or `disagree`
    /// with the quantities past it (`u`, `jump`, `slip`, `p`, `q`,
    /// `states`).
    #[serde(serialize_with = "fixed")]
    pub threshold: f64,
    pub verdict: String,
    /// The scales: U = F/K and P = N/L of the problem.
    #[serde(serialize_with = "fixed")]
    pub scale_u: f64,
    #[serde(serialize_with = "fixed")]
    pub scale_p: f64,
}

/// One pair, compared.
#[derive(Clone, Debug)]
pub struct Pair {
    pub summary: PairSummary,
    pub nodes: Vec<NodeRow>,
}

/// The node-by-node comparison of `a` and `b` (same nodes, in order) in
/// the scales `u` and `p`.
fn pair(a: &Answer, b: &Answer, u: f64, p: f64) -> Result<Vec<NodeRow>> {
    if a.rows.len() != b.rows.len() {
        bail!(
            "{} has {} contact nodes and {} has {}: not the same mesh",
            a.label,
            a.rows.len(),
            b.label,
            b.rows.len()
        );
    }
    let mut out = Vec::with_capacity(a.rows.len());
    for (ra, rb) in a.rows.iter().zip(&b.rows) {
        if (ra.x - rb.x).abs() > 1e-9 * (1.0 + ra.x.abs()) {
            bail!(
                "contact node at x = {} in {} is at x = {} in {}: not the same mesh",
                ra.x,
                a.label,
                rb.x,
                b.label
            );
        }
        let du = [
            ra.u1_lower - rb.u1_lower,
            ra.u2_lower - rb.u2_lower,
            ra.u1_upper - rb.u1_upper,
            ra.u2_upper - rb.u2_upper,
        ]
        .iter()
        .fold(0.0f64, |m, d| m.max(d.abs()));
        out.push(NodeRow {
            x: ra.x,
            u2_upper_a: ra.u2_upper,
            u2_upper_b: rb.u2_upper,
            jump_a: ra.jump,
            jump_b: rb.jump,
            slip_a: ra.slip,
            slip_b: rb.slip,
            pressure_a: ra.pressure,
            pressure_b: rb.pressure,
            friction_traction_a: ra.friction_traction,
            friction_traction_b: rb.friction_traction,
            state_a: ra.state.clone(),
            state_b: rb.state.clone(),
            du_over_u: du / u,
            djump_over_u: (ra.jump - rb.jump).abs() / u,
            dslip_over_u: (ra.slip - rb.slip).abs() / u,
            dp_over_p: (ra.pressure - rb.pressure).abs() / p,
            dq_over_p: (ra.friction_traction - rb.friction_traction).abs() / p,
            states_match: ra.state == rb.state,
        });
    }
    Ok(out)
}

/// The threshold of a side-by-side's verdict: two answers agree when
/// every largest difference is within it, displacements over U and
/// forces over P, and their contact states match at every node. It is the
/// threshold of "wrong" of the comparison and the stability map
/// ([`WRONG_PRESSURE`], about what moves the separation zone by a node at
/// h = 1/64), here in the problem's scales.
pub const AGREEMENT: f64 = WRONG_PRESSURE;

/// The quantities past [`AGREEMENT`], by name, and whether the states
/// differ: empty when the two answers agree.
fn past_threshold(x: &PairSummary) -> Vec<&'static str> {
    let mut out: Vec<&'static str> = [
        ("u", x.max_du_over_u),
        ("jump", x.max_djump_over_u),
        ("slip", x.max_dslip_over_u),
        ("p", x.max_dp_over_p),
        ("q", x.max_dq_over_p),
    ]
    .into_iter()
    // A NaN difference is no agreement.
    .filter(|(_, d)| d.is_nan() || *d > x.threshold)
    .map(|(name, _)| name)
    .collect();
    if x.states_differ > 0 {
        out.push("states");
    }
    out
}

/// The largest of `f` over the nodes and where it sits (the first node
/// of the largest; a NaN wins, so that it is seen).
fn largest(nodes: &[NodeRow], f: fn(&NodeRow) -> f64) -> (f64, f64) {
    let mut best = (0.0f64, nodes.first().map_or(f64::NAN, |n| n.x));
    for n in nodes {
        let d = f(n);
        if d.is_nan() {
            return (d, n.x);
        }
        if d > best.0 {
            best = (d, n.x);
        }
    }
    best
}

fn summary(
    scene: &Scene,
    a: &Answer,
    b: &Answer,
    nodes: &[NodeRow],
    u: f64,
    p: f64,
) -> PairSummary {
    let (du, x_du) = largest(nodes, |n| n.du_over_u);
    let (djump, x_djump) = largest(nodes, |n| n.djump_over_u);
    let (dslip, x_dslip) = largest(nodes, |n| n.dslip_over_u);
    let (dp, x_dp) = largest(nodes, |n| n.dp_over_p);
    let (dq, x_dq) = largest(nodes, |n| n.dq_over_p);
    let differing: Vec<String> = nodes
        .iter()
        .filter(|n| !n.states_match)
        .map(|n| format!("{:.4}", n.x))
        .collect();
    let mut out = PairSummary {
        scene: scene.name.clone(),
        h: scene.finest().to_string(),
        a: a.label.clone(),
        b: b.label.clone(),
        status_a: a.status.clone(),
        status_b: b.status.clone(),
        nodes: nodes.len(),
        max_du_over_u: du,
        max_djump_over_u: djump,
        max_dslip_over_u: dslip,
        max_dp_over_p: dp,
        max_dq_over_p: dq,
        x_max_du: x_du,
        x_max_djump: x_djump,
        x_max_dslip: x_dslip,
        x_max_dp: x_dp,
        x_max_dq: x_dq,
        states_differ: differing.len(),
        differing_at: differing.join(" "),
        threshold: AGREEMENT,
        verdict: String::new(),
        scale_u: u,
        scale_p: p,
    };
    let past = past_threshold(&out);
    out.verdict = if past.is_empty() {
        "agree".into()
    } else {
        format!("disagree ({})", past.join(", "))
    };
    out
}

/// The file stem of a pair: `side_by_side_relaxation_clarabel` (each
/// side's name cleaned and cut to 60 characters; [`unique_stems`] makes
/// the stems of a run distinct).
pub fn stem(a: &str, b: &str) -> String {
    let clean = |s: &str| {
        let s: String = s
            .chars()
            .rev()
            .take(60)
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect();
        s.chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' {
                    c
                } else {
                    '_'
                }
            })
            .collect::<String>()
    };
    format!("{STUDY}_{}_{}", clean(a), clean(b))
}

/// The stems of a run's pairs, made distinct: a stem that an earlier pair
/// has (two names that clean to one, `a/b` and `a_b`) gets `_2`, `_3`, …,
/// so that no pair's files overwrite another's. A pair given twice is
/// refused.
pub fn unique_stems(pairs: &[(Side, Side)]) -> Result<Vec<String>> {
    let mut names: Vec<(String, String)> = Vec::new();
    let mut out: Vec<String> = Vec::new();
    for (a, b) in pairs {
        let key = (a.name(), b.name());
        if names.contains(&key) {
            bail!(
                "--side-by-side: the pair {},{} is given twice: give each pair once",
                key.0,
                key.1
            );
        }
        let base = stem(&key.0, &key.1);
        let mut candidate = base.clone();
        let mut k = 2;
        while out.contains(&candidate) {
            candidate = format!("{base}_{k}");
            k += 1;
        }
        names.push(key);
        out.push(candidate);
    }
    Ok(out)
}

/// The overlay: p and q of both answers along Γ_K.
fn overlay(scene: &Scene, a: &Answer, b: &Answer) -> Chart {
    let along = |rows: &[ImportedRow], f: fn(&ImportedRow) -> f64| {
        rows.iter().map(|r| (r.x, f(r))).collect::<Vec<_>>()
    };
    let series = vec![
        Series::line(format!("p, {}", a.label), along(&a.rows, |r| r.pressure)).colored(0),
        Series::line(format!("p, {}", b.label), along(&b.rows, |r| r.pressure))
            .colored(1)
            .dashed(),
        Series::line(
            format!("q, {}", a.label),
            along(&a.rows, |r| r.friction_traction),
        )
        .colored(2),
        Series::line(
            format!("q, {}", b.label),
            along(&b.rows, |r| r.friction_traction),
        )
        .colored(3)
        .dashed(),
    ];
    Chart::new(
        format!(
            "{} against {}: {}, h = {}",
            a.label,
            b.label,
            scene.name,
            scene.finest()
        ),
        "x along the contact boundary",
        "pressure p and friction traction q",
        false,
        false,
        series,
    )
}

/// The differences along Γ_K in the problem's scales (log axis; exact
/// agreement at a node is drawn at the axis' floor, 1e-16).
fn differences(scene: &Scene, a: &Answer, b: &Answer, nodes: &[NodeRow]) -> Chart {
    let floor = 1e-16;
    let along = |f: fn(&NodeRow) -> f64| {
        nodes
            .iter()
            .map(|n| (n.x, f(n).max(floor)))
            .collect::<Vec<_>>()
    };
    let series = vec![
        Series::line("|Δu| / U", along(|n| n.du_over_u)).colored(0),
        Series::line("|Δjump| / U", along(|n| n.djump_over_u)).colored(4),
        Series::line("|Δp| / P", along(|n| n.dp_over_p)).colored(1),
        Series::line("|Δq| / P", along(|n| n.dq_over_p)).colored(2),
    ];
    Chart::new(
        format!(
            "{} minus {}: {}, h = {}",
            a.label,
            b.label,
            scene.name,
            scene.finest()
        ),
        "x along the contact boundary",
        "difference in the problem's scales",
        false,
        true,
        series,
    )
}

/// Pairs of answers on one scene, node by node.
pub struct SideBySide {
    pub scene: Scene,
    pub pairs: Vec<(Side, Side)>,
}

impl SideBySide {
    /// The study of `pairs` on `scene`, its inputs checked before any
    /// work: imported sides named distinctly ([`with_distinct_names`]), no
    /// pair given twice and one set of files per pair ([`unique_stems`]).
    pub fn new(scene: Scene, pairs: Vec<(Side, Side)>) -> Result<Self> {
        let pairs = with_distinct_names(pairs);
        unique_stems(&pairs)?;
        Ok(Self { scene, pairs })
    }
}

/// The solvers that `pairs` run (their settings are resolved for them).
pub fn solvers_of(pairs: &[(Side, Side)]) -> Vec<&'static Entry> {
    pairs
        .iter()
        .flat_map(|(a, b)| [a, b])
        .filter_map(|s| match s {
            Side::Solver(e) => Some(*e),
            _ => None,
        })
        .collect()
}

/// What it found: each pair compared.
pub type Pairs = Vec<Pair>;

impl SideBySide {
    /// The answer of `side` on the scene: solvers measured once each.
    fn answer(&self, side: &Side, lab: &mut Lab, solved: &mut Vec<(String, Answer)>) -> Result<()> {
        let name = side.name();
        if solved.iter().any(|(n, _)| *n == name) {
            return Ok(());
        }
        let answer = match side {
            Side::Solver(entry) => {
                let spec = TrialSpec::new(
                    STUDY,
                    entry.name,
                    &self.scene,
                    entry,
                    Law::Coulomb,
                    &lab.settings,
                )
                .without_reference();
                let keep = Keep {
                    history: false,
                    solution: true,
                };
                let m = lab.measure(&[spec], keep)?.remove(0);
                let status = m.trial.status;
                let rows = match m.solution() {
                    Some((d, s, g)) => from_profile(&contact_profile(d, s, g, status)),
                    None => bail!("{} gave no answer: {}", entry.name, m.trial.detail),
                };
                Answer {
                    label: entry.name.to_string(),
                    status: status.as_str().into(),
                    rows,
                }
            }
            Side::Reference => {
                let settings = lab.settings.clone();
                let Some(r) = lab.reference(&self.scene, &settings)? else {
                    bail!(
                        "no exact solver certified {} at h = {}: there is no reference to compare with",
                        self.scene.name,
                        self.scene.finest()
                    );
                };
                Answer {
                    label: format!("reference ({})", r.solver),
                    status: r.coulomb.outcome.status.as_str().into(),
                    rows: from_profile(&r.coulomb.profile()),
                }
            }
            Side::Imported { name, rows, .. } => Answer {
                label: name.clone(),
                status: "imported".into(),
                rows: rows.clone(),
            },
        };
        solved.push((name, answer));
        Ok(())
    }

    /// The problem's scales U and P on the scene's finest mesh, and the
    /// positions of its contact nodes.
    fn mesh(&self) -> Result<(f64, f64, Vec<f64>)> {
        let d = crate::solve::level_for(
            &self.scene,
            self.scene.finest(),
            crate::solve::solver_entry("newton-coulomb")?,
        )?;
        let s = d.problem.scales();
        let xs = d.dofs.contacts().iter().map(|c| c.x).collect();
        Ok((s.displacement, s.pressure, xs))
    }
}

impl Study for SideBySide {
    type Findings = Pairs;

    fn name(&self) -> &'static str {
        STUDY
    }

    fn estimated_seconds(&self, length: RunLength) -> f64 {
        // Each side solved once: about 80 s a side at 1/128 on this
        // machine (the paper's method 160 s, the oracle 40 s, the
        // reference's candidates about a minute), cubic in 1/h.
        let mut sides: Vec<String> = Vec::new();
        for s in self.pairs.iter().flat_map(|(a, b)| [a, b]) {
            if !matches!(s, Side::Imported { .. }) && !sides.contains(&s.name()) {
                sides.push(s.name());
            }
        }
        let n = self.scene.finest().divisions() as f64;
        let s = 80.0 * sides.len() as f64 * (n / 128.0).powi(3);
        if length == RunLength::Quick {
            s / 10.0
        } else {
            s
        }
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<Pairs>> {
        // The scales, and an imported answer checked against the mesh
        // before anything is solved.
        let stems = unique_stems(&self.pairs)?;
        let (u, p, xs) = self.mesh()?;
        for side in self.pairs.iter().flat_map(|(a, b)| [a, b]) {
            if let Side::Imported { name, rows, .. } = side {
                let fits = rows.len() == xs.len()
                    && rows
                        .iter()
                        .zip(&xs)
                        .all(|(r, x)| (r.x - x).abs() <= 1e-9 * (1.0 + x.abs()));
                if !fits {
                    bail!(
                        "side-by-side: {name} has {} contact nodes, {} at h = {} has {}: not the same mesh (solve it at --h {})",
                        rows.len(),
                        self.scene.name,
                        self.scene.finest(),
                        xs.len(),
                        self.scene.finest()
                    );
                }
            }
        }
        let mut solved: Vec<(String, Answer)> = Vec::new();
        for (a, b) in &self.pairs {
            self.answer(a, lab, &mut solved)?;
            self.answer(b, lab, &mut solved)?;
        }
        let find = |s: &Side| {
            let name = s.name();
            solved
                .iter()
                .find(|(n, _)| *n == name)
                .map(|(_, a)| a)
                .expect("every side was solved above")
        };
        let mut pairs = Vec::new();
        let mut artifacts = Vec::new();
        for ((sa, sb), stem) in self.pairs.iter().zip(stems) {
            let (a, b) = (find(sa), find(sb));
            let nodes = pair(a, b, u, p)?;
            artifacts.push(Artifact::csv(&format!("{stem}.csv"), &nodes, &[])?);
            artifacts.push(Artifact::chart(
                &format!("{stem}_overlay"),
                overlay(&self.scene, a, b),
            ));
            artifacts.push(Artifact::chart(
                &format!("{stem}_difference"),
                differences(&self.scene, a, b, &nodes),
            ));
            pairs.push(Pair {
                summary: summary(&self.scene, a, b, &nodes, u, p),
                nodes,
            });
        }
        let summaries: Vec<&PairSummary> = pairs.iter().map(|p| &p.summary).collect();
        artifacts.push(Artifact::csv("side_by_side.csv", &summaries, &[])?);
        Ok(Ran {
            findings: pairs,
            artifacts,
        })
    }

    fn section(&self, pairs: &Pairs, _: &Lab, charts: &[String]) -> Result<Section> {
        Ok(Section {
            markdown: markdown(&self.scene, pairs, charts)?,
        })
    }
}

/// The section (`templates/side_by_side.md`): a table of the largest
/// differences per pair, then the charts.
pub fn markdown(scene: &Scene, pairs: &Pairs, charts: &[String]) -> Result<String> {
    let pairs: Vec<&PairSummary> = pairs.iter().map(|p| &p.summary).collect();
    template::render(
        "side_by_side",
        include_str!("templates/side_by_side.md"),
        template::facts! {
            scene => scene.name,
            h => scene.finest().to_string(),
            agreement => AGREEMENT,
            pairs,
            charts,
        },
    )
}

/// The largest profile read: 64 MB, some 400 000 contact nodes.
pub const MAX_PROFILE_BYTES: u64 = 64 << 20;

/// A side named on the command line or in Python: `reference`, a
/// registered solver, or the path of a `profile.csv`.
pub fn parse_side(word: &str) -> Result<Side> {
    let word = word.trim();
    if word == "reference" {
        return Ok(Side::Reference);
    }
    if let Some(e) = contactlab_solvers::registry::by_name(word) {
        return Ok(Side::Solver(e));
    }
    let path = std::path::Path::new(word);
    if !path.exists() {
        bail!(
            "side-by-side: `{word}` is neither `reference`, a solver ({}) nor a profile.csv file",
            contactlab_solvers::registry::names().join(", ")
        );
    }
    let text = crate::io::guarded::read_small_text(path, MAX_PROFILE_BYTES)
        .map_err(|e| anyhow::anyhow!("side-by-side: {}: {e}", path.display()))?;
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let mut rows = Vec::new();
    for (k, r) in reader.deserialize::<ImportedRow>().enumerate() {
        let r = r.map_err(|e| {
            anyhow::anyhow!(
                "side-by-side: {} row {}: {e} (a profile.csv of `contactlab solve --out` has the columns x, u1_lower, …, state)",
                path.display(),
                k + 1
            )
        })?;
        let values = [
            r.x,
            r.u1_lower,
            r.u2_lower,
            r.u1_upper,
            r.u2_upper,
            r.jump,
            r.slip,
            r.pressure,
            r.friction_traction,
        ];
        if values.iter().any(|v| !v.is_finite()) {
            bail!(
                "side-by-side: {} row {}: a value is not finite",
                path.display(),
                k + 1
            );
        }
        if !STATES.contains(&r.state.as_str()) {
            bail!(
                "side-by-side: {} row {}: state `{}` is not a contact state: give one of {}",
                path.display(),
                k + 1,
                r.state.chars().take(40).collect::<String>(),
                STATES.join(", ")
            );
        }
        rows.push(r);
    }
    if rows.is_empty() {
        bail!("side-by-side: {} has no contact nodes", path.display());
    }
    // A profile's rows in any order are the same answer: sorted by x, and
    // two rows at one x refused.
    rows.sort_by(|a, b| a.x.total_cmp(&b.x));
    if let Some(w) = rows.windows(2).find(|w| w[0].x == w[1].x) {
        bail!(
            "side-by-side: {}: two rows at x = {}: give one row per contact node",
            path.display(),
            w[0].x
        );
    }
    let name = path
        .parent()
        .and_then(|p| p.file_name())
        .map(|d| {
            format!(
                "{}/{}",
                d.to_string_lossy(),
                path.file_name().unwrap_or_default().to_string_lossy()
            )
        })
        .unwrap_or_else(|| word.to_string());
    Ok(Side::Imported {
        name,
        path: word.to_string(),
        rows,
    })
}

/// The pairs with every imported side's name naming one file: two
/// profiles of one folder and file name (`A1/run/profile.csv` and
/// `A2/run/profile.csv`, both `run/profile.csv`, of which the second was
/// taken to be the first) are named by their whole paths.
pub fn with_distinct_names(mut pairs: Vec<(Side, Side)>) -> Vec<(Side, Side)> {
    let mut seen: Vec<(String, String)> = Vec::new();
    for side in pairs.iter().flat_map(|(a, b)| [a, b]) {
        if let Side::Imported { name, path, .. } = side {
            seen.push((name.clone(), path.clone()));
        }
    }
    let shared = |name: &str, path: &str| seen.iter().any(|(n, p)| n == name && p != path);
    for side in pairs.iter_mut().flat_map(|(a, b)| [a, b]) {
        if let Side::Imported { name, path, .. } = side
            && shared(name, path)
        {
            *name = path.clone();
        }
    }
    pairs
}

/// A pair `A,B` of sides.
pub fn parse_pair(words: &str) -> Result<(Side, Side)> {
    match words.split_once(',') {
        Some((a, b)) if !b.contains(',') => Ok((parse_side(a)?, parse_side(b)?)),
        _ => bail!(
            "--side-by-side takes two answers, `A,B` (e.g. relaxation,clarabel or relaxation,reference), got `{words}`"
        ),
    }
}
