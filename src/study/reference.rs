//! The reference a study measures differences against is earned, not
//! assumed: every registered solver that can give an exact answer (its
//! registry entry says so) solves the problem at its tightest settings, the
//! answers are certified, and the one with the smallest certificate measure
//! is the reference. The oracle is then a row like any other.
//!
//! A reference of the Coulomb problem gives the operating point g = 𝓕p of
//! the given-friction trials; the given-friction reference is earned the same
//! way on the subproblem at that g.

use std::sync::Arc;

use anyhow::Result;
use contactlab_solvers::registry::{self, Entry};
use contactlab_solvers::{Friction, Law, Silent, Status};
use serde::Serialize;
use serde_json::Value;

use crate::io::csv::fixed;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::solve::{Assembled, Caps, Outcome, Solved, TooLarge, refuse_too_large, solve};
use crate::study::parallel::map_on_cores;

/// The fixed point's relative tolerance for reference solves.
pub const REFERENCE_COULOMB_EPSILON: f64 = 1e-11;

/// Wall-clock seconds a candidate may take (a safety net: at fine meshes the
/// interior-point oracle is far slower than the Newton solver, and a
/// candidate that runs out of time simply does not compete).
pub const CANDIDATE_SECONDS: f64 = 120.0;

/// One candidate's answer.
#[derive(Clone, Debug, Serialize)]
pub struct Candidate {
    pub scene: String,
    pub h: String,
    pub law: Law,
    pub solver: String,
    pub status: Status,
    #[serde(serialize_with = "fixed")]
    pub certificate: f64,
    /// Whether it became the reference.
    pub chosen: bool,
}

/// The reference answer of the subproblem at the reference's g.
pub struct GivenFrictionReference {
    pub solver: &'static str,
    pub outcome: Outcome,
}

/// The references of one scene on one mesh.
pub struct Reference {
    pub scene: Scene,
    /// The Coulomb problem's reference and who earned it.
    pub solver: &'static str,
    pub coulomb: Solved,
    /// g = 𝓕p of the Coulomb reference: the given-friction trials' bound.
    pub g: Vec<f64>,
    pub given_friction: Option<GivenFrictionReference>,
    pub candidates: Vec<Candidate>,
}

/// Settings of a reference solve with `entry`: relative stopping, the
/// fixed point at [`REFERENCE_COULOMB_EPSILON`], the solver at its
/// reference accuracy.
pub fn reference_settings(entry: &Entry, base: &Settings) -> Result<Settings> {
    let mut s = Settings::default();
    s.certificate = base.certificate;
    s.schedule = base.schedule;
    s.set("coulomb.epsilon", Value::from(REFERENCE_COULOMB_EPSILON))
        .map_err(anyhow::Error::msg)?;
    s.set("coulomb.max_iterations", Value::from(200u64))
        .map_err(anyhow::Error::msg)?;
    s.set(
        &format!("{}.{}", entry.name, entry.accuracy.knob),
        Value::from(entry.accuracy.reference),
    )
    .map_err(anyhow::Error::msg)?;
    Ok(s)
}

/// Earns the references of `scene` (on its finest level). `None` when no
/// exact solver's answer passes the certificate (then trials carry no
/// differences, only their certificates).
pub fn earn(scene: &Scene, base: &Settings, seconds: f64) -> Result<Option<Reference>> {
    let on_cores = seconds >= CANDIDATE_SECONDS;
    earn_among(scene, base, Cap { seconds, on_cores }, None, None)
}

/// What a reference's candidates may take: `seconds` each on the clock,
/// and whether two run at once (`on_cores`).
///
/// A candidate's own clock is what two at once could change. With the
/// default cap, far above a candidate's time on a mesh that fits twice in
/// memory, they run on both cores. A study that caps them tighter and
/// reports only the reference chosen, not the candidates' statuses (bench,
/// at twice its budget: the winner, a Newton solver, takes a fraction of
/// the cap), may still run them on both cores; one that reports them runs
/// them one at a time.
#[derive(Clone, Copy, Debug)]
pub struct Cap {
    pub seconds: f64,
    pub on_cores: bool,
}

/// The exact solvers a reference is earned among, per law (see
/// [`earn_among`]).
#[derive(Clone, Debug, Default)]
pub struct Among {
    pub coulomb: Vec<&'static str>,
    pub given_friction: Vec<&'static str>,
}

/// [`earn`], or with `named` the reference the user named: that solver
/// alone, at its tightest settings, and only if certified. (The
/// given-friction reference is earned among the exact solvers as usual
/// when the named one does not solve that law.) With `among`, per law the
/// exact solvers of those names only: a study that already knows the
/// others cannot finish within the cap there (`bench` stops a solver
/// whose times predict more than its budget) does not run them to their
/// cap.
pub fn earn_among(
    scene: &Scene,
    base: &Settings,
    cap: Cap,
    named: Option<&'static Entry>,
    among: Option<&Among>,
) -> Result<Option<Reference>> {
    let exact = |names: Option<&Vec<&'static str>>| -> Vec<&'static Entry> {
        registry::solvers()
            .into_iter()
            .filter(|e| e.accuracy.exact)
            .filter(|e| names.is_none_or(|n| n.contains(&e.name)))
            .collect()
    };
    let coulomb_candidates: Vec<&'static Entry> =
        named.map_or_else(|| exact(among.map(|a| &a.coulomb)), |e| vec![e]);
    let friction_candidates: Vec<&'static Entry> = match named {
        Some(e) if e.solves(Law::GivenFriction) => vec![e],
        _ => exact(among.map(|a| &a.given_friction)),
    };
    let caps = Caps {
        work: None,
        seconds: Some(cap.seconds),
    };
    let on_cores = cap.on_cores;
    let need = coulomb_candidates
        .iter()
        .chain(&friction_candidates)
        .map(|e| crate::memory::solve(scene.finest(), e))
        .fold(0.0, f64::max);
    let mut candidates = Vec::new();
    let mut best: Option<(&'static Entry, Solved)> = None;
    for (&entry, solved) in coulomb_candidates.iter().zip(run_candidates(
        scene,
        base,
        caps,
        &coulomb_candidates,
        Friction::Coulomb,
        on_cores.then_some(need),
    )?) {
        let solved = match solved {
            Ok(solved) => solved,
            Err(refused) => {
                candidates.push(refused);
                continue;
            }
        };
        let outcome = &solved.outcome;
        candidates.push(candidate(scene, Law::Coulomb, entry, outcome));
        let better = best
            .as_ref()
            .is_none_or(|(_, b)| outcome.certificate.residual() < b.outcome.certificate.residual());
        if outcome.status == Status::Converged && better {
            best = Some((entry, solved));
        }
    }
    let Some((entry, coulomb)) = best else {
        return Ok(None);
    };
    mark_chosen(&mut candidates, Law::Coulomb, entry.name);
    let g = coulomb.outcome.bound.clone();
    let given: Vec<&'static Entry> = friction_candidates
        .iter()
        .copied()
        .filter(|e| e.solves(Law::GivenFriction))
        .collect();
    let mut gf_best: Option<GivenFrictionReference> = None;
    for (&e, solved) in given.iter().zip(run_candidates(
        scene,
        base,
        caps,
        &given,
        Friction::Given(&g),
        on_cores.then_some(need),
    )?) {
        let outcome = match solved {
            Ok(solved) => solved.outcome,
            Err(refused) => {
                candidates.push(refused);
                continue;
            }
        };
        candidates.push(candidate(scene, Law::GivenFriction, e, &outcome));
        let better = gf_best
            .as_ref()
            .is_none_or(|b| outcome.certificate.residual() < b.outcome.certificate.residual());
        if outcome.status == Status::Converged && better {
            gf_best = Some(GivenFrictionReference {
                solver: e.name,
                outcome,
            });
        }
    }
    if let Some(b) = &gf_best {
        mark_chosen(&mut candidates, Law::GivenFriction, b.solver);
    }
    Ok(Some(Reference {
        scene: scene.clone(),
        solver: entry.name,
        coulomb,
        g,
        given_friction: gf_best,
        candidates,
    }))
}

/// Each of `entries` solving `scene` under `friction` as a candidate (its
/// answer, or why it could not run there), in the entries' order: on the
/// machine's cores with `on_cores` (each needing that many bytes), else
/// one at a time.
fn run_candidates(
    scene: &Scene,
    base: &Settings,
    caps: Caps,
    entries: &[&'static Entry],
    friction: Friction<'_>,
    on_cores: Option<f64>,
) -> Result<Vec<Result<Solved, Candidate>>> {
    let run = |&entry: &&'static Entry| -> Result<Result<Solved, Candidate>> {
        // A candidate that cannot run on this mesh does not compete.
        if let Err(e) = refuse_too_large(scene, entry) {
            return Ok(Err(refused(scene, friction.law(), entry, &e)));
        }
        let settings = reference_settings(entry, base)?;
        let problem = Assembled::for_solver(scene, entry)?;
        Ok(Ok(solve(
            problem,
            friction,
            entry,
            &settings,
            caps,
            &mut Silent,
        )?))
    };
    match on_cores {
        Some(need) => map_on_cores(entries, need, run),
        None => entries.iter().map(run).collect(),
    }
}

fn candidate(scene: &Scene, law: Law, entry: &Entry, outcome: &Outcome) -> Candidate {
    Candidate {
        scene: scene.name.clone(),
        h: scene.finest().to_string(),
        law,
        solver: entry.name.into(),
        status: outcome.status,
        certificate: outcome.certificate.residual(),
        chosen: false,
    }
}

/// A candidate that could not run on this mesh (too many unknowns for it,
/// or not enough memory): it does not compete.
fn refused(scene: &Scene, law: Law, entry: &Entry, why: &TooLarge) -> Candidate {
    Candidate {
        scene: scene.name.clone(),
        h: scene.finest().to_string(),
        law,
        solver: entry.name.into(),
        status: why.status(),
        certificate: f64::INFINITY,
        chosen: false,
    }
}

fn mark_chosen(candidates: &mut [Candidate], law: Law, solver: &str) {
    for c in candidates.iter_mut() {
        if c.law == law && c.solver == solver {
            c.chosen = true;
        }
    }
}

/// References keyed by the whole scene (its material, friction, loads and
/// levels, not only its name), earned once per study.
pub struct References {
    /// Shared, so that trials measured on both cores can hold theirs
    /// ([`References::shared`]).
    earned: Vec<(String, Option<Arc<Reference>>)>,
    /// False for studies that measure counts, not differences (Table 1).
    enabled: bool,
    /// Wall-clock seconds a candidate may take.
    pub candidate_seconds: f64,
    /// Whether a scene's candidates run two at once (see [`Cap`]); by
    /// default when their cap is [`CANDIDATE_SECONDS`] or more.
    pub candidates_on_cores: Option<bool>,
    /// The reference the user named (None: earned among the exact
    /// solvers).
    pub named: Option<&'static Entry>,
    /// The exact solvers a reference is earned among (None: all of them;
    /// see [`earn_among`]).
    pub among: Option<Among>,
}

impl Default for References {
    fn default() -> Self {
        Self {
            earned: Vec::new(),
            enabled: true,
            candidate_seconds: CANDIDATE_SECONDS,
            candidates_on_cores: None,
            named: None,
            among: None,
        }
    }
}

impl References {
    /// References that are never earned: trials carry no differences.
    pub fn none() -> Self {
        Self {
            enabled: false,
            ..Self::default()
        }
    }

    /// The reference of `scene` on its finest level, earned on first use.
    pub fn get(&mut self, scene: &Scene, base: &Settings) -> Result<Option<&Reference>> {
        Ok(self.slot(scene, base)?.and_then(Option::as_deref))
    }

    /// The same reference, held: for work that measures on several
    /// threads while the references stay in one place.
    pub fn shared(&mut self, scene: &Scene, base: &Settings) -> Result<Option<Arc<Reference>>> {
        Ok(self.slot(scene, base)?.and_then(Clone::clone))
    }

    /// The earned entry of `scene` (earned now if it was not), None when
    /// references are never earned.
    fn slot(&mut self, scene: &Scene, base: &Settings) -> Result<Option<&Option<Arc<Reference>>>> {
        if !self.enabled {
            return Ok(None);
        }
        let key = Self::key(scene)?;
        let index = match self.earned.iter().position(|(k, _)| *k == key) {
            Some(i) => i,
            None => {
                let cap = Cap {
                    seconds: self.candidate_seconds,
                    on_cores: self
                        .candidates_on_cores
                        .unwrap_or(self.candidate_seconds >= CANDIDATE_SECONDS),
                };
                let r = earn_among(scene, base, cap, self.named, self.among.as_ref())?;
                self.earned.push((key, r.map(Arc::new)));
                self.earned.len() - 1
            }
        };
        Ok(Some(&self.earned[index].1))
    }

    /// The key of a scene's references: the whole scene (material,
    /// friction, loads, levels), not only its name.
    pub fn key(scene: &Scene) -> Result<String> {
        Ok(serde_json::to_string(scene)?)
    }

    /// The candidates of the references of the scenes with these keys, in
    /// the order of the keys.
    pub fn candidates_for(&self, keys: &[String]) -> Vec<Candidate> {
        keys.iter()
            .filter_map(|k| self.earned.iter().find(|(key, _)| key == k))
            .filter_map(|(_, r)| r.as_deref())
            .flat_map(|r| r.candidates.clone())
            .collect()
    }

    /// Every candidate of every reference earned, for `references.csv`.
    pub fn candidates(&self) -> Vec<Candidate> {
        self.earned
            .iter()
            .filter_map(|(_, r)| r.as_deref())
            .flat_map(|r| r.candidates.clone())
            .collect()
    }

    /// The references of the scenes with these keys, in the order of the
    /// keys.
    pub fn of<'a>(&'a self, keys: &'a [String]) -> impl Iterator<Item = &'a Reference> {
        keys.iter()
            .filter_map(|k| self.earned.iter().find(|(key, _)| key == k))
            .filter_map(|(_, r)| r.as_deref())
    }

    /// The references earned, in order.
    pub fn all(&self) -> impl Iterator<Item = &Reference> {
        self.earned.iter().filter_map(|(_, r)| r.as_deref())
    }
}
