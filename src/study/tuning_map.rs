//! Tuning as a map: one solver on a joint grid of two or three of its
//! settings (the paper's r × ε of the modified Lagrangian, section 3, or
//! a relaxation factor ω), every point timed over repeated runs and
//! certified. The one-factor sweeps ([`crate::study::sweep`]) move one
//! setting around the defaults; a map shows how the settings act together
//! and where the method fails.
//!
//! On meshes finer than [`OWN_FORM_FINEST`] a solver is mapped in its fast
//! form ([`crate::study::plans::Fine`]: the paper's method with its inner
//! minimization by multigrid), unless the user set those settings: a point
//! of the paper's own sweeps takes 127-179 s at 1/128 (measured), so a
//! grid there does not fit a run. Fine meshes carry no reference (the
//! certificate measures each answer), as in the sweep.
//!
//! Time is the median over the runs. The run's noise is the largest
//! relative spread (median less fastest run) of any certified point; a
//! point whose median is within twice that of the best median is a tie:
//! timing alone cannot rank it, and the map says so instead of naming a
//! winner by chance. Work (iterations) is exact and has a map of its own.

use anyhow::{Result, bail};
use contactlab_solvers::Law;
use contactlab_solvers::registry::Entry;
use serde::Serialize;

use crate::io::csv::{fixed, records};
use crate::io::heatmap::{Cell, HeatMap, Mark};
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::lab::{Artifact, Lab, Ran, RunLength, Section, Study};
use crate::study::plans;
use crate::study::runner::{Keep, Measured};
use crate::study::sweep::work_cap;
use crate::study::template;
use crate::study::trial::{Setting, TrialSpec};

/// The study's name in trial records.
pub const STUDY: &str = "tuning_map";

/// The finest mesh (level k of h = 1/2^k) mapped in a solver's own form.
pub const OWN_FORM_FINEST: u32 = 6;

/// Settings of a solver's fast form, (knob, value), as the command line
/// writes them.
pub type Form = Vec<(String, String)>;

/// One axis of the grid: a setting's path and its values.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    pub path: String,
    pub values: Vec<String>,
}

impl Axis {
    /// `PATH=V1,V2,...`.
    pub fn parse(text: &str) -> Result<Self> {
        let Some((path, values)) = text.split_once('=') else {
            bail!(
                "--grid '{text}': write it as PATH=V1,V2,..., e.g. --grid relaxation.r=1e3,1e5,1e7"
            );
        };
        let values: Vec<String> = values
            .split(',')
            .map(|v| v.trim().to_string())
            .filter(|v| !v.is_empty())
            .collect();
        if values.len() < 2 {
            bail!("--grid '{text}': give at least two values, PATH=V1,V2,...");
        }
        let axis = Self {
            path: path.trim().to_string(),
            values,
        };
        axis.check_values()?;
        Ok(axis)
    }

    /// The values distinct as the settings read them: a number in any
    /// spelling (1e-6, 0.000001, 1.0e-6) is one value, a word is compared
    /// without case. A value given twice would map a setting against
    /// itself and rank the two spellings.
    pub fn check_values(&self) -> Result<()> {
        if self.values.len() < 2 {
            bail!("--grid {}: give at least two values", self.path);
        }
        let key = |v: &str| match v.trim().parse::<f64>() {
            Ok(x) => format!("{:e}", x),
            Err(_) => v.trim().to_lowercase(),
        };
        for (i, a) in self.values.iter().enumerate() {
            if let Some(b) = self.values[..i].iter().find(|b| key(b) == key(a)) {
                bail!(
                    "--grid {}: {b} and {a} are one value; give each value once",
                    self.path
                );
            }
        }
        Ok(())
    }

    /// The knob's name without its owner: `r` of `relaxation.r`.
    pub fn knob(&self) -> &str {
        self.path.rsplit('.').next().unwrap_or(&self.path)
    }
}

/// The most points a map may have: a map is read cell by cell, and at
/// 1/64 each point takes one to a few seconds (times its repeats); more
/// is a grid to split, refused before any work.
pub const MAX_POINTS: usize = 400;

/// Checks a map's inputs before any work: two or three axes, their paths
/// distinct, their values distinct ([`Axis::check_values`]), each a setting
/// the solver reads at `law` (its own `SOLVER.KNOB`, or the fixed point's
/// `coulomb.*` only where the fixed point runs: the Coulomb law by a
/// given-friction solver), the law one the solver can be run at, and at
/// most [`MAX_POINTS`] points.
pub fn check_map(solver: &Entry, law: Law, axes: &[Axis]) -> Result<()> {
    if !(2..=3).contains(&axes.len()) {
        bail!(
            "--grid: a tuning map takes two or three settings, got {}; for one, use --vary",
            axes.len()
        );
    }
    for (i, a) in axes.iter().enumerate() {
        if axes[..i].iter().any(|b| b.path == a.path) {
            bail!(
                "--grid {}: the setting is given twice; give each axis once, with all its values",
                a.path
            );
        }
        a.check_values()?;
    }
    if law == Law::GivenFriction && !solver.solves(law) {
        bail!(
            "--law given-friction: {} solves the Coulomb law only; map it at --law coulomb",
            solver.name
        );
    }
    let fixed_point = law == Law::Coulomb && !solver.solves(Law::Coulomb);
    for a in axes {
        let owner = a.path.split('.').next().unwrap_or("");
        if owner == crate::settings::COULOMB && !fixed_point {
            bail!(
                "--grid {}: {} at the {} law runs no friction fixed point and never reads coulomb.*; map its own settings ({} settings lists them)",
                a.path,
                solver.name,
                law.as_str().replace('_', "-"),
                solver.name
            );
        }
        if owner != crate::settings::COULOMB && owner != solver.name {
            bail!(
                "--grid {}: a tuning map is of one solver, {}; name its settings ({}.KNOB) or the fixed point's (coulomb.KNOB)",
                a.path,
                solver.name,
                solver.name
            );
        }
    }
    let points = axes
        .iter()
        .map(|a| a.values.len())
        .fold(1usize, |p, k| p.saturating_mul(k));
    if points > MAX_POINTS {
        bail!(
            "--grid: {} points ({}) is more than a map of {MAX_POINTS}; give fewer values, or split the grid",
            points,
            axes.iter()
                .map(|a| a.values.len().to_string())
                .collect::<Vec<_>>()
                .join(" × ")
        );
    }
    Ok(())
}

/// A map of `solver` on `scene` over `axes` (two or three).
pub struct TuningMap {
    pub scene: Scene,
    pub solver: &'static Entry,
    pub law: Law,
    pub axes: Vec<Axis>,
    /// Timed runs of each point after the first.
    pub repeats: usize,
    /// Added to the file names when one run maps several scenes
    /// (`sweep --grid --problem 1,2`), so that no map overwrites another.
    pub tag: Option<String>,
    /// Each point's solve stops after this many seconds (`--time-limit`).
    pub point_seconds: Option<f64>,
}

/// One point of the map, measured and ranked.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    /// The values of the axes, in order.
    pub values: Vec<String>,
    pub status: String,
    pub certified: bool,
    #[serde(serialize_with = "fixed")]
    pub seconds_median: f64,
    #[serde(serialize_with = "fixed")]
    pub seconds_min: f64,
    pub runs: usize,
    pub work: usize,
    #[serde(serialize_with = "fixed")]
    pub certificate: f64,
    #[serde(serialize_with = "fixed")]
    pub pressure_error: f64,
    /// `best`, `tie` (within the noise of the best) or empty.
    pub mark: String,
}

/// A point as a typed record of the map's table: each axis's value under
/// its path (a number when it is one, as the setting reads it), then the
/// point's own fields, in the file's column order.
struct MapRow<'a> {
    axes: &'a [Axis],
    point: &'a Point,
}

impl Serialize for MapRow<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let p = self.point;
        let mut m = s.serialize_map(None)?;
        for (axis, value) in self.axes.iter().zip(&p.values) {
            match value.parse::<f64>() {
                Ok(x) if x.is_finite() => m.serialize_entry(&axis.path, &x)?,
                _ => m.serialize_entry(&axis.path, value)?,
            }
        }
        m.serialize_entry("status", &p.status)?;
        m.serialize_entry("certified", &p.certified)?;
        let number = |x: f64| x.is_finite().then_some(x);
        m.serialize_entry("seconds_median", &number(p.seconds_median))?;
        m.serialize_entry("seconds_min", &number(p.seconds_min))?;
        m.serialize_entry("runs", &p.runs)?;
        m.serialize_entry("work", &p.work)?;
        m.serialize_entry("certificate", &number(p.certificate))?;
        m.serialize_entry("pressure_error", &number(p.pressure_error))?;
        m.serialize_entry("mark", &p.mark)?;
        m.end()
    }
}

impl Point {
    fn noise(&self) -> f64 {
        (self.seconds_median - self.seconds_min).max(0.0)
    }
}

/// What a map found: its points, ranked, and the trials behind them.
pub struct MapFindings {
    pub points: Vec<Point>,
    pub measured: Vec<Measured>,
    /// The settings of the form mapped (`inner = multigrid`), if not the
    /// solver's own.
    pub form: Form,
}

impl TuningMap {
    /// The settings every point shares, and the fast form's settings when
    /// the mesh is finer than [`OWN_FORM_FINEST`].
    fn base(&self, shared: &Settings) -> Result<(Settings, Form)> {
        let mut settings = shared.clone();
        let mut form = Vec::new();
        if self.scene.finest().level() > OWN_FORM_FINEST
            && let Some(fine) = plans::plan(self.solver).fine
        {
            for (knob, value) in fine.settings {
                let path = format!("{}.{knob}", self.solver.name);
                if !settings.overrides().contains_key(&path) {
                    settings
                        .set_text(&path, value)
                        .map_err(anyhow::Error::msg)?;
                    form.push((knob.to_string(), value.to_string()));
                }
            }
        }
        Ok((settings, form))
    }

    /// Every combination of the axes' values, the first axis fastest.
    pub fn grid(&self) -> Vec<Vec<String>> {
        let mut out: Vec<Vec<String>> = vec![Vec::new()];
        for axis in &self.axes {
            out = axis
                .values
                .iter()
                .flat_map(|v| {
                    out.iter().map(move |p| {
                        let mut p = p.clone();
                        p.push(v.clone());
                        p
                    })
                })
                .collect();
        }
        out
    }

    /// The form the map shows, named on its charts whatever the mesh: the
    /// value of each setting that chooses the solver's form at fine h
    /// (`inner = sweeps`, the paper's, or `inner = multigrid`), as the
    /// points run it; empty for a solver with one form.
    fn shown_form(&self, shared: &Settings) -> Result<Form> {
        let (settings, _) = self.base(shared)?;
        let Some(fine) = plans::plan(self.solver).fine else {
            return Ok(Vec::new());
        };
        Ok(fine
            .settings
            .iter()
            .filter_map(|(knob, _)| {
                let path = format!("{}.{knob}", self.solver.name);
                // An axis of the map varies it: each point names its value.
                if self.axes.iter().any(|a| a.path == path) {
                    return None;
                }
                let value = settings.get(&path)?;
                let text = value
                    .as_str()
                    .map_or_else(|| value.to_string(), String::from);
                Some((knob.to_string(), text))
            })
            .collect())
    }

    /// The trials: one per point of the grid.
    pub fn plan(&self, lab: &Lab) -> Result<(Vec<TrialSpec>, Form)> {
        if !(2..=3).contains(&self.axes.len()) {
            bail!(
                "a tuning map takes two or three settings (--grid PATH=V1,V2,... two or three times), got {}",
                self.axes.len()
            );
        }
        let (base, form) = self.base(&lab.settings)?;
        let fine = self.scene.finest().level() > OWN_FORM_FINEST;
        let paths: Vec<&str> = self.axes.iter().map(|a| a.path.as_str()).collect();
        let mut out = Vec::new();
        for values in self.grid() {
            let mut settings = base.clone();
            for (path, value) in paths.iter().zip(&values) {
                settings
                    .set_text(path, value)
                    .map_err(|e| anyhow::anyhow!("--grid {path}={value}: {e}"))?;
            }
            let mut t = TrialSpec::new(
                STUDY,
                self.group(),
                &self.scene,
                self.solver,
                self.law,
                &settings,
            )
            .with_work(work_cap(self.solver, 1.0))
            .with_seconds(self.point_seconds)
            .with_repeats(self.repeats)
            // A map of speed over settings: none of its views reads an
            // error bound, which at h = 1/256 took longer than the point
            // it bounded (about 2 s against 1.2 s).
            .unbounded();
            t.setting = Some(Setting::new(&paths.join(" × "), &values.join(" × ")));
            if fine && self.law == Law::Coulomb {
                t = t.without_reference();
            }
            out.push(t);
        }
        Ok((out, form))
    }

    /// The solves the map runs: each point once and `repeats` times more.
    fn solves(&self) -> usize {
        let points: usize = self.axes.iter().map(|a| a.values.len()).product();
        points * (1 + self.repeats)
    }

    /// What one solve of a point takes, from a few seconds to many (the
    /// work varies with the settings mapped), measured on problem 1 on the
    /// 2-core machine and scaled with the mesh: the paper's form (`inner =
    /// sweeps`) at ε = 1e-4 and 1e-6, 8 and 140 s a Coulomb solve at
    /// 1/128, 0.34 and 1.6 s a given-friction one at 1/64, growing as
    /// (1/h)³ (sweeps of n unknowns, their count growing as 1/h); the
    /// multigrid form 0.6 to 1.6 s a Coulomb solve at 1/256, as (1/h)²;
    /// another solver 1 to 3 s at 1/64, as (1/h)².
    fn solve_seconds(&self, shared: &Settings) -> (f64, f64) {
        let n = self.scene.finest().divisions() as f64;
        let form = self.shown_form(shared).unwrap_or_default();
        let inner = form
            .iter()
            .find(|(k, _)| k == "inner")
            .map(|(_, v)| v.as_str());
        let (low, high, at, power) = match (inner, self.law) {
            (Some("sweeps"), Law::Coulomb) => (8.0, 140.0, 128.0, 3),
            (Some("sweeps"), Law::GivenFriction) => (0.34, 1.6, 64.0, 3),
            (Some(_), _) => (0.6, 1.6, 256.0, 2),
            (None, _) => (1.0, 3.0, 64.0, 2),
        };
        let scale = (n / at).powi(power);
        (low * scale, high * scale)
    }

    /// What the map will run and may take, stated before it starts: the
    /// solver and the form mapped, the solves, the estimate's range and,
    /// with a time limit per solve, the most it can take.
    pub fn plan_line(&self, shared: &Settings) -> Result<String> {
        let form = self.shown_form(shared)?;
        let form = if form.is_empty() {
            String::new()
        } else {
            let named: Vec<String> = form.iter().map(|(k, v)| format!("{k} = {v}")).collect();
            format!(" ({})", named.join(", "))
        };
        let (low, high) = self.solve_seconds(shared);
        let solves = self.solves() as f64;
        let mut line = format!(
            "mapping {}{form} on the {} problem of {} at h = {}: {} solves, about {} to {} (estimated from measured solves of this form; the settings mapped move it)",
            self.solver.name,
            self.law.as_str(),
            self.scene.name,
            self.scene.finest(),
            self.solves(),
            crate::io::duration(low * solves),
            crate::io::duration(high * solves),
        );
        match self.point_seconds {
            Some(limit) => {
                line += &format!(
                    "; at most {} with --time-limit {limit} s a solve",
                    crate::io::duration(limit * solves)
                )
            }
            None if high * solves > 600.0 => {
                line += "; --time-limit SECONDS caps each solve";
            }
            None => {}
        }
        Ok(line)
    }

    /// The trials' group: `relaxation.r × relaxation.epsilon`.
    fn group(&self) -> String {
        let paths: Vec<&str> = self.axes.iter().map(|a| a.path.as_str()).collect();
        paths.join(" × ")
    }

    /// The file stem: `tuning_map_relaxation_coulomb_h256`.
    pub fn stem(&self) -> String {
        let stem = format!(
            "{STUDY}_{}_{}_h{}",
            self.solver.name,
            self.law.as_str(),
            self.scene.finest().divisions()
        );
        match &self.tag {
            Some(tag) => format!("{stem}_{tag}"),
            None => stem,
        }
    }
}

/// The run's timing noise: the largest relative spread (median less the
/// fastest run, over the median) of any certified point. Noise is the
/// machine's, not a point's: a point timed twice can happen to agree with
/// itself, so the map takes the largest spread it saw.
pub fn noise(points: &[Point]) -> f64 {
    points
        .iter()
        .filter(|p| p.certified && p.seconds_median > 0.0)
        .map(|p| p.noise() / p.seconds_median)
        .fold(0.0f64, f64::max)
}

/// Work within this fraction of another point's is equal work: the same
/// iterations to the count's resolution (the committed 1/64 map's
/// r = 1e5 … 1e11 did 23,840-23,842 sweeps), where only time can rank
/// and time is noise.
pub const EQUAL_WORK: f64 = 0.01;

/// Ranks `points` in place by what is not noise: the certified points of
/// least work (within [`EQUAL_WORK`] of the least) are the candidates; of
/// them the least median time is `best`, and another whose median is
/// within twice the run's relative [`noise`] of it is a `tie`; a
/// candidate beyond the noise is `equal work`. Work is exact, so a point
/// of more work is never ranked by its time against the best.
pub fn rank(points: &mut [Point]) {
    let least = points.iter().filter(|p| p.certified).map(|p| p.work).min();
    let Some(least) = least else { return };
    let equal = |p: &Point| p.certified && p.work as f64 <= least as f64 * (1.0 + EQUAL_WORK);
    let best = points
        .iter()
        .enumerate()
        .filter(|(_, p)| equal(p))
        .min_by(|a, b| a.1.seconds_median.total_cmp(&b.1.seconds_median))
        .map(|(k, _)| k);
    let Some(b) = best else { return };
    let timed = points[b].runs >= 2;
    let limit = points[b].seconds_median * (1.0 + 2.0 * noise(points));
    let marks: Vec<&str> = points
        .iter()
        .enumerate()
        .map(|(k, p)| {
            if k == b {
                "best"
            } else if equal(p) && timed && p.seconds_median <= limit {
                "tie"
            } else if equal(p) {
                "equal work"
            } else {
                ""
            }
        })
        .collect();
    for (p, mark) in points.iter_mut().zip(marks) {
        p.mark = mark.into();
    }
}

/// How much an axis moves the work: over every slice of the grid with the
/// other axes fixed, the largest ratio of most to least work among its
/// certified points (None when no slice has two certified points).
pub fn work_effect(axis: usize, points: &[Point]) -> Option<f64> {
    // Per slice (the other axes' values): least and most work, and how
    // many certified points it has.
    let mut slices: Vec<(Vec<&str>, usize, usize, usize)> = Vec::new();
    for p in points.iter().filter(|p| p.certified) {
        let others: Vec<&str> = p
            .values
            .iter()
            .enumerate()
            .filter(|(k, _)| *k != axis)
            .map(|(_, v)| v.as_str())
            .collect();
        match slices.iter_mut().find(|(o, ..)| *o == others) {
            Some((_, lo, hi, n)) => {
                *lo = (*lo).min(p.work);
                *hi = (*hi).max(p.work);
                *n += 1;
            }
            None => slices.push((others, p.work, p.work, 1)),
        }
    }
    slices
        .iter()
        .filter(|(.., n)| *n >= 2)
        .map(|(_, lo, hi, _)| *hi as f64 / (*lo).max(1) as f64)
        .fold(None, |m: Option<f64>, r| Some(m.map_or(r, |m| m.max(r))))
}

/// A point of the grid as the verdict names it.
#[derive(Clone, Debug, Serialize)]
pub struct Named {
    /// Its settings: `r = 1e5, epsilon = 1e-4`.
    pub setting: String,
    pub work: usize,
    /// Median and fastest time, over `runs` timed runs.
    pub seconds: f64,
    pub seconds_min: f64,
    pub runs: usize,
}

/// What an axis does to the work ([`work_effect`]).
#[derive(Clone, Debug, Serialize)]
pub struct Effect {
    pub knob: String,
    /// The largest ratio of most to least work along it (none: no two
    /// certified points along it), and whether that is more than
    /// [`EQUAL_WORK`].
    pub ratio: Option<f64>,
    pub moves: bool,
}

/// The next least work after the best and its equals.
#[derive(Clone, Debug, Serialize)]
pub struct Next {
    #[serde(flatten)]
    pub point: Named,
    /// Its work over the best's, less one, in percent.
    pub more_percent: f64,
}

/// The map's verdict as facts: the best setting by work, what moves the
/// work along each axis, the points of equal work ranked by time (ties
/// within the noise), the next least work, and the failures.
#[derive(Clone, Debug, Serialize)]
pub struct Verdict {
    /// None when no point was certified.
    pub best: Option<Named>,
    pub effects: Vec<Effect>,
    pub equal_work_percent: f64,
    /// Points of equal work other than the best, and those of them within
    /// twice the run's timing noise (in percent) of it.
    pub equal: usize,
    pub ties: Vec<Named>,
    pub noise_percent: f64,
    pub next: Option<Next>,
    pub failed: usize,
    pub points: usize,
}

/// The verdict of a map: by work, with what moves the work along each
/// axis, then by time among the points of equal work.
pub fn verdict(axes: &[Axis], points: &[Point]) -> Verdict {
    let named = |p: &Point| Named {
        setting: axes
            .iter()
            .zip(&p.values)
            .map(|(a, v)| format!("{} = {v}", a.knob()))
            .collect::<Vec<_>>()
            .join(", "),
        work: p.work,
        seconds: p.seconds_median,
        seconds_min: p.seconds_min,
        runs: p.runs,
    };
    let best = points.iter().find(|p| p.mark == "best");
    let effects = axes
        .iter()
        .enumerate()
        .map(|(k, a)| {
            let ratio = work_effect(k, points);
            Effect {
                knob: a.knob().to_string(),
                ratio,
                moves: ratio.is_some_and(|r| r > 1.0 + EQUAL_WORK),
            }
        })
        .collect();
    let next = best.and_then(|b| {
        points
            .iter()
            .filter(|p| p.certified && p.mark.is_empty())
            .min_by_key(|p| p.work)
            .map(|n| Next {
                point: named(n),
                more_percent: 100.0 * (n.work as f64 / b.work.max(1) as f64 - 1.0),
            })
    });
    Verdict {
        best: best.map(named),
        effects,
        equal_work_percent: 100.0 * EQUAL_WORK,
        equal: points
            .iter()
            .filter(|p| p.mark == "tie" || p.mark == "equal work")
            .count(),
        ties: points
            .iter()
            .filter(|p| p.mark == "tie")
            .map(named)
            .collect(),
        noise_percent: 100.0 * noise(points),
        next,
        failed: points.iter().filter(|p| !p.certified).count(),
        points: points.len(),
    }
}

/// The verdict as a sentence (`templates/tuning_verdict.md`), for the
/// section and for `sweep --grid`'s report.
pub fn verdict_sentence(axes: &[Axis], points: &[Point]) -> Result<String> {
    let text = template::render(
        "tuning_verdict",
        include_str!("templates/tuning_verdict.md"),
        verdict(axes, points),
    )?;
    Ok(text.trim_end().to_string())
}

/// The sentence stating the best setting: by work, with what moves the
/// work along each axis, then by time among the points of equal work.
/// The heat maps of a two-axis slice (`third`: the value of a third axis
/// fixed in this slice).
fn heat_maps(
    map: &TuningMap,
    points: &[&Point],
    third: Option<&str>,
    form: &[(String, String)],
) -> (HeatMap, HeatMap) {
    let (ax, ay) = (&map.axes[0], &map.axes[1]);
    // The best framed on both maps; ties (equal work, time within the
    // noise) marked on the time map, where they are ties.
    let cell = |i: usize, j: usize, value: &dyn Fn(&Point) -> f64, ties: bool| {
        let p = points
            .iter()
            .find(|p| p.values[0] == ax.values[i] && p.values[1] == ay.values[j])
            .expect("every grid point was measured");
        if p.certified {
            Cell::Value {
                value: value(p),
                mark: match (p.mark.as_str(), ties) {
                    ("best", _) => Mark::Best,
                    ("tie", true) => Mark::Tie,
                    _ => Mark::None,
                },
            }
        } else {
            Cell::Failed(p.status.clone())
        }
    };
    let grid = |value: &dyn Fn(&Point) -> f64, ties: bool| {
        (0..ay.values.len())
            .map(|j| {
                (0..ax.values.len())
                    .map(|i| cell(i, j, value, ties))
                    .collect()
            })
            .collect()
    };
    let form = if form.is_empty() {
        String::new()
    } else {
        let f: Vec<String> = form.iter().map(|(k, v)| format!("{k} = {v}")).collect();
        format!(", {}", f.join(", "))
    };
    let third = third
        .map(|v| format!(", {} = {v}", map.axes[2].knob()))
        .unwrap_or_default();
    let title = |what: &str| {
        format!(
            "{what}: {}{form}{third}, {} law, {}, h = {}",
            map.solver.name,
            map.law.as_str().replace('_', "-"),
            map.scene.name,
            map.scene.finest()
        )
    };
    let runs = points.first().map_or(1, |p| p.runs);
    let time = HeatMap {
        title: title("Time to a certified answer"),
        x_label: ax.path.clone(),
        y_label: ay.path.clone(),
        x_values: ax.values.clone(),
        y_values: ay.values.clone(),
        cells: grid(&|p| p.seconds_median, true),
        value_label: format!("seconds, median of {runs}"),
    };
    let work = HeatMap {
        title: title("Work"),
        cells: grid(&|p| p.work as f64, false),
        value_label: format!("work ({})", map.solver.work_stage),
        ..time.clone()
    };
    (time, work)
}

impl Study for TuningMap {
    type Findings = MapFindings;

    fn name(&self) -> &'static str {
        STUDY
    }

    fn estimated_seconds(&self, length: RunLength) -> f64 {
        let (low, high) = self.solve_seconds(&Settings::default());
        let s = (low * high).sqrt() * self.solves() as f64;
        if length == RunLength::Quick {
            s / 10.0
        } else {
            s
        }
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<MapFindings>> {
        let (specs, form) = self.plan(lab)?;
        let shown = self.shown_form(&lab.settings)?;
        let measured = lab.measure(&specs, Keep::default())?;
        let mut points: Vec<Point> = measured
            .iter()
            .map(|m| {
                let values = m
                    .trial
                    .setting
                    .as_ref()
                    .map(|s| s.value.split(" × ").map(String::from).collect())
                    .unwrap_or_default();
                Point {
                    values,
                    status: m.trial.status.as_str().into(),
                    certified: m.trial.certified(),
                    seconds_median: m.timing.seconds_median,
                    seconds_min: m.timing.seconds_min,
                    runs: m.timing.runs,
                    work: m.trial.work,
                    certificate: m.trial.residual(),
                    pressure_error: m.trial.pressure_error().unwrap_or(f64::NAN),
                    mark: String::new(),
                }
            })
            .collect();
        rank(&mut points);
        let stem = self.stem();
        let mut artifacts = Artifact::trials(&format!("{stem}_trials"), &measured)?;
        let mut header: Vec<String> = self.axes.iter().map(|a| a.path.clone()).collect();
        header.extend(
            [
                "status",
                "certified",
                "seconds_median",
                "seconds_min",
                "runs",
                "work",
                "certificate",
                "pressure_error",
                "mark",
            ]
            .map(String::from),
        );
        let mut table = csv::Writer::from_writer(Vec::new());
        table.write_record(&header)?;
        for p in &points {
            let mut row = p.values.clone();
            row.extend([
                p.status.clone(),
                p.certified.to_string(),
                format!("{:.9e}", p.seconds_median),
                format!("{:.9e}", p.seconds_min),
                p.runs.to_string(),
                p.work.to_string(),
                format!("{:.9e}", p.certificate),
                format!("{:.9e}", p.pressure_error),
                p.mark.clone(),
            ]);
            table.write_record(&row)?;
        }
        let rows: Vec<MapRow> = points
            .iter()
            .map(|point| MapRow {
                axes: &self.axes,
                point,
            })
            .collect();
        artifacts.push(
            Artifact::bytes(
                &format!("{stem}.csv"),
                table.into_inner().map_err(|e| anyhow::anyhow!("{e}"))?,
            )
            .with_records(records(&rows)?),
        );
        let slices: Vec<Option<&str>> = match self.axes.get(2) {
            Some(a) => a.values.iter().map(|v| Some(v.as_str())).collect(),
            None => vec![None],
        };
        for third in slices {
            let slice: Vec<&Point> = points
                .iter()
                .filter(|p| third.is_none_or(|v| p.values.get(2).map(String::as_str) == Some(v)))
                .collect();
            let (time, work) = heat_maps(self, &slice, third, &shown);
            let tail = third
                .map(|v| format!("_{}{v}", self.axes[2].knob()))
                .unwrap_or_default();
            artifacts.push(Artifact::heat_map(&format!("{stem}{tail}_time"), time));
            artifacts.push(Artifact::heat_map(&format!("{stem}{tail}_work"), work));
        }
        Ok(Ran {
            findings: MapFindings {
                points,
                measured,
                form,
            },
            artifacts,
        })
    }

    fn section(&self, found: &MapFindings, _: &Lab, charts: &[String]) -> Result<Section> {
        let axes: Vec<_> = self
            .axes
            .iter()
            .map(|a| template::facts! { path => a.path, values => a.values })
            .collect();
        let verdict = verdict_sentence(&self.axes, &found.points)?;
        let markdown = template::render(
            "tuning_map",
            include_str!("templates/tuning_map.md"),
            template::facts! {
                group => self.group(),
                scene => self.scene.name,
                h => self.scene.finest().to_string(),
                law => self.law.as_str().replace('_', "-"),
                solver => self.solver.name,
                form => found.form,
                axes,
                stem => self.stem(),
                repeats => self.repeats,
                verdict,
                charts,
            },
        )?;
        Ok(Section { markdown })
    }
}

/// Several maps as one study (a run's studies have distinct names: the
/// checkpoint and the manifest record them by name): `reproduce`'s maps.
pub struct TuningMaps {
    pub maps: Vec<TuningMap>,
}

impl Study for TuningMaps {
    type Findings = Vec<MapFindings>;

    fn name(&self) -> &'static str {
        STUDY
    }

    fn estimated_seconds(&self, length: RunLength) -> f64 {
        self.maps.iter().map(|m| m.estimated_seconds(length)).sum()
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<Vec<MapFindings>>> {
        let mut findings = Vec::new();
        let mut artifacts = Vec::new();
        for map in &self.maps {
            let ran = map.run(lab)?;
            findings.push(ran.findings);
            artifacts.extend(ran.artifacts);
        }
        Ok(Ran {
            findings,
            artifacts,
        })
    }

    fn section(&self, found: &Vec<MapFindings>, lab: &Lab, charts: &[String]) -> Result<Section> {
        let mut markdown = String::new();
        for (map, f) in self.maps.iter().zip(found) {
            let stem = map.stem();
            let mine: Vec<String> = charts
                .iter()
                .filter(|c| c.starts_with(&format!("{stem}_")))
                .cloned()
                .collect();
            markdown += &map.section(f, lab, &mine)?.markdown;
        }
        Ok(Section { markdown })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(values: &[&str], certified: bool, median: f64, min: f64) -> Point {
        Point {
            values: values.iter().map(|v| v.to_string()).collect(),
            status: if certified {
                "converged"
            } else {
                "max_iterations"
            }
            .into(),
            certified,
            seconds_median: median,
            seconds_min: min,
            runs: 3,
            work: 10,
            certificate: 1e-7,
            pressure_error: f64::NAN,
            mark: String::new(),
        }
    }

    fn worked(values: &[&str], work: usize, median: f64, min: f64) -> Point {
        Point {
            work,
            ..point(values, true, median, min)
        }
    }

    /// Among points of equal work the least median is the best; a point
    /// within twice the run's noise of it ties (a failed point's spread
    /// does not count); a faster failed point is no best.
    #[test]
    fn the_best_is_certified_and_ties_are_within_the_noise() {
        // The largest spread: 5% (1e5); ties within 10% of the best.
        let mut points = vec![
            point(&["1e3", "1e-4"], false, 0.5, 0.3),
            point(&["1e5", "1e-4"], true, 1.00, 0.95),
            point(&["1e7", "1e-4"], true, 1.09, 1.08),
            point(&["1e3", "1e-6"], true, 1.20, 1.18),
        ];
        rank(&mut points);
        let marks: Vec<&str> = points.iter().map(|p| p.mark.as_str()).collect();
        assert_eq!(marks, ["", "best", "tie", "equal work"]);
        let axes = [
            Axis::parse("relaxation.r=1e3,1e5,1e7").unwrap(),
            Axis::parse("relaxation.epsilon=1e-4,1e-6").unwrap(),
        ];
        let v = verdict_sentence(&axes, &points).unwrap();
        assert!(
            v.starts_with("Least work, certified: r = 1e5, epsilon = 1e-4 with 10 work in 1.000 s"),
            "{v}"
        );
        assert!(
            v.contains("2 other settings, ranked by time only among these: 1 within twice the run's timing noise (5.0%) of the best, a tie (r = 1e7, epsilon = 1e-4, 1.090 s)"),
            "{v}"
        );
        assert!(v.contains("r has no effect on work (within 1%)"), "{v}");
        assert!(v.contains("1 of 4 points not certified"), "{v}");
    }

    /// Work ranks before time: the committed 1/128 map called a point of
    /// 58 work the best where one of 38 was slower by noise. Here the
    /// faster point does more work and is not the best; the verdict says
    /// that ε moves the work 3× and r not at all.
    #[test]
    fn work_ranks_before_time_and_the_verdict_names_what_moves_it() {
        let mut points = vec![
            worked(&["1e5", "1e-4"], 38, 1.30, 1.2),
            worked(&["1e7", "1e-4"], 38, 1.25, 1.2),
            worked(&["1e5", "1e-6"], 114, 1.00, 0.9),
            worked(&["1e7", "1e-6"], 115, 1.10, 1.0),
        ];
        rank(&mut points);
        let marks: Vec<&str> = points.iter().map(|p| p.mark.as_str()).collect();
        // 1e7, 1e-4: least time among the equal-work pair.
        assert_eq!(marks, ["tie", "best", "", ""]);
        assert_eq!(work_effect(0, &points), Some(115.0 / 114.0));
        assert_eq!(work_effect(1, &points), Some(115.0 / 38.0));
        let axes = [
            Axis::parse("relaxation.r=1e5,1e7").unwrap(),
            Axis::parse("relaxation.epsilon=1e-4,1e-6").unwrap(),
        ];
        let v = verdict_sentence(&axes, &points).unwrap();
        assert!(
            v.starts_with("Least work, certified: r = 1e7, epsilon = 1e-4 with 38 work"),
            "{v}"
        );
        assert!(
            v.contains("r has no effect on work (within 1%); epsilon changes it up to 3.03×"),
            "{v}"
        );
        assert!(
            v.contains("The next least work: r = 1e5, epsilon = 1e-6 with 114 work (200% more)"),
            "{v}"
        );
        // One run a point: no tie can be told; the equal-work point says so.
        for p in &mut points {
            p.runs = 1;
            p.seconds_min = p.seconds_median;
        }
        rank(&mut points);
        assert_eq!(points[0].mark, "equal work");
        let v = verdict_sentence(&axes, &points).unwrap();
        assert!(v.contains("no time can be told from noise"), "{v}");
        assert!(v.contains("in 1.250 s (one timed run)"), "{v}");
    }

    /// No certified point: the verdict says so and names no best; one
    /// certified point an axis: its effect is not measured.
    #[test]
    fn a_grid_without_two_certified_points_says_what_it_cannot_tell() {
        let axes = [
            Axis::parse("relaxation.r=1e5,1e7").unwrap(),
            Axis::parse("relaxation.epsilon=1e-4,1e-6").unwrap(),
        ];
        let mut points = vec![
            point(&["1e5", "1e-4"], false, 1.0, 1.0),
            point(&["1e7", "1e-6"], false, 1.0, 1.0),
        ];
        rank(&mut points);
        assert!(verdict(&axes, &points).best.is_none());
        let v = verdict_sentence(&axes, &points).unwrap();
        assert_eq!(v, "No point of the grid was certified.");
        points[0].certified = true;
        rank(&mut points);
        let facts = verdict(&axes, &points);
        assert!(facts.effects.iter().all(|e| e.ratio.is_none() && !e.moves));
        let v = verdict_sentence(&axes, &points).unwrap();
        assert!(
            v.contains("r: not measured (no two certified points along it); epsilon: not measured"),
            "{v}"
        );
        assert!(v.ends_with(" 1 of 2 points not certified."), "{v}");
    }

    #[test]
    fn an_axis_needs_a_path_and_two_values() {
        assert!(Axis::parse("relaxation.r").is_err());
        assert!(Axis::parse("relaxation.r=1e3").is_err());
        let a = Axis::parse("relaxation.r = 1e3, 1e5").unwrap();
        assert_eq!(a.path, "relaxation.r");
        assert_eq!(a.values, ["1e3", "1e5"]);
        assert_eq!(a.knob(), "r");
    }
}
