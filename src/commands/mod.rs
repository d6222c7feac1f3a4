//! The commands of the command line: each reads its arguments, runs a study
//! or a solve, writes its output folder whole, and only then prints.

pub mod bench;
pub mod benchmark;
pub mod certify;
pub mod compare;
pub mod export;
pub mod info;
pub mod reproduce;
pub mod settings;
pub mod solve;
pub mod study;
pub mod sweep;

use anyhow::Result;
use contactlab_solvers::registry::{self, Entry};
use contactlab_solvers::{Control, Observer, Progress};

use crate::coulomb::fixed_point;
use crate::io::output::log;
use crate::settings::Settings;
use crate::study::lab::{Artifact, Lab, Study, Tracker};
use crate::study::trial::TrialSpec;

/// Logs the friction loop to stderr, each iteration with an estimate of
/// what is left: the fixed point contracts linearly (paper, section 3), so
/// from the last two changes' ratio ρ the iterations left to the tolerance
/// are ln(tol/Δ)/ln ρ, at the pace of the last iteration. Before two
/// iterations, or while the change does not fall, it says so rather than
/// guess.
pub struct LogObserver {
    /// The fixed point's threshold on max|Δg| (None: not known).
    tolerance: Option<f64>,
    /// The last iteration's change and the seconds at its end.
    last: Option<(f64, f64)>,
}

impl LogObserver {
    /// An observer that estimates the iterations left to `tolerance`.
    pub fn toward(tolerance: Option<f64>) -> Self {
        Self {
            tolerance,
            last: None,
        }
    }

    /// What is left after a change `change` at `seconds`: iterations and
    /// seconds, when the change falls and the tolerance is known.
    pub fn estimate(&self, change: f64, seconds: f64) -> Option<(usize, f64)> {
        let tol = self.tolerance?;
        let (previous, at) = self.last?;
        if change <= tol {
            return Some((0, 0.0));
        }
        let ratio = change / previous;
        if !(ratio > 0.0 && ratio < 1.0 && change.is_finite()) {
            return None;
        }
        // Less a hair: ln(1e-4)/ln(0.1) is 4 only up to rounding.
        let left = ((tol / change).ln() / ratio.ln() - 1e-9).ceil().max(1.0);
        (left < 1e6).then(|| (left as usize, left * (seconds - at).max(0.0)))
    }
}

impl Observer for LogObserver {
    fn observe(&mut self, p: &Progress) -> Control {
        if p.stage == fixed_point::STAGE {
            // A new fixed point (the nested schedule's next level) starts
            // its own count.
            if p.iteration <= 1 {
                self.last = None;
            }
            let left = match self.estimate(p.residual, p.seconds) {
                Some((0, _)) => String::new(),
                Some((n, s)) => format!(", about {n} more at this rate (about {s:.0} s)"),
                None if self.last.is_some() => ", not contracting yet: no estimate".into(),
                None => String::new(),
            };
            log(format!(
                "friction iteration {:>3}: max|Δg| = {:.3e}  ({:.2} s){left}",
                p.iteration, p.residual, p.seconds
            ));
            self.last = Some((p.residual, p.seconds));
        }
        Control::Continue
    }

    fn wants(&self, stage: &str) -> bool {
        stage == fixed_point::STAGE
    }
}

/// Progress of a study on stderr: a bar with an ETA when stderr is a
/// terminal (redrawn every second, so a long trial shows time passing), and
/// otherwise a log line with the count, the elapsed time and the estimate
/// at most every ten seconds, so that a run under a scheduler or with its
/// stderr in a file is never silent for long.
pub struct StudyProgress {
    bar: indicatif::ProgressBar,
    what: String,
    start: std::time::Instant,
    last_line: std::cell::Cell<std::time::Instant>,
    done: std::cell::Cell<u64>,
    total: u64,
    terminal: bool,
    /// Expected relative cost of each unit, in the order they are done, and
    /// the seconds one unit can take at most (see [`StudyProgress::with_costs`]).
    costs: Option<(Vec<f64>, f64)>,
}

impl StudyProgress {
    /// `len` units of work; 0: unknown (a count and the elapsed time, no
    /// estimate).
    pub fn new(len: u64, what: &str) -> Self {
        use std::io::IsTerminal;
        let terminal = std::io::stderr().is_terminal();
        let bar = match (terminal, len) {
            (false, _) => indicatif::ProgressBar::hidden(),
            (true, 0) => indicatif::ProgressBar::new_spinner(),
            (true, _) => indicatif::ProgressBar::new(len),
        };
        let template = if len == 0 {
            "{prefix} {spinner} {pos} done {msg} (elapsed {elapsed})"
        } else {
            "{prefix} [{bar:30}] {pos}/{len} {msg} (elapsed {elapsed}, eta {eta})"
        };
        bar.set_style(style(template));
        bar.set_prefix(what.to_string());
        if terminal {
            bar.enable_steady_tick(std::time::Duration::from_secs(1));
        }
        let now = std::time::Instant::now();
        Self {
            bar,
            what: what.to_string(),
            start: now,
            last_line: std::cell::Cell::new(now),
            done: std::cell::Cell::new(0),
            total: len,
            terminal,
            costs: None,
        }
    }

    /// Estimates the time left from each unit's expected relative cost
    /// (`costs`, one per unit in the order they are done) instead of
    /// assuming all units alike: seconds per unit of cost are measured on
    /// the units done, and each unit left is predicted at that rate, capped
    /// at `cap` seconds (a time limit per run). A plan whose finest meshes
    /// come last is then not predicted at the pace of its coarse ones.
    pub fn with_costs(mut self, costs: Vec<f64>, cap: f64) -> Self {
        if costs.len() as u64 == self.total && costs.iter().all(|c| c.is_finite() && *c > 0.0) {
            self.costs = Some((costs, cap));
            // indicatif's own estimate assumes units alike: the message
            // carries this one instead.
            self.bar.set_style(style(
                "{prefix} [{bar:30}] {pos}/{len} {msg} (elapsed {elapsed})",
            ));
        }
        self
    }

    /// Seconds left after `done` units in `elapsed` seconds.
    fn left(&self, done: u64, elapsed: f64) -> f64 {
        let done = done as usize;
        match &self.costs {
            Some((costs, cap)) => {
                let spent: f64 = costs[..done.min(costs.len())].iter().sum();
                let rate = elapsed / spent;
                // + 0.0: an empty sum is −0.0, which would print as "-0".
                costs[done.min(costs.len())..]
                    .iter()
                    .map(|c| (rate * c).min(*cap))
                    .sum::<f64>()
                    + 0.0
            }
            None => elapsed / done as f64 * self.total.saturating_sub(done as u64) as f64,
        }
    }

    /// A trial is done.
    pub fn tick(&self, t: &TrialSpec) {
        let knob = t
            .setting
            .as_ref()
            .map(|s| format!(", {} = {}", s.path, s.value))
            .unwrap_or_default();
        let msg = format!("{} {}{knob}", t.solver.name, t.law.as_str());
        self.step(&msg);
    }

    /// One unit of work is done, described by `msg`.
    pub fn step(&self, msg: &str) {
        self.done.set(self.done.get() + 1);
        if self.costs.is_some() {
            let elapsed = self.start.elapsed().as_secs_f64();
            let left = self.left(self.done.get(), elapsed);
            self.bar
                .set_message(format!("{msg}, about {} left", clock(left)));
        } else {
            self.bar.set_message(msg.to_string());
        }
        self.bar.inc(1);
        let now = std::time::Instant::now();
        let last = self.done.get() == self.total;
        if !self.terminal
            && (now - self.last_line.get() >= std::time::Duration::from_secs(10) || last)
        {
            self.last_line.set(now);
            let elapsed = (now - self.start).as_secs_f64();
            let done = self.done.get();
            if self.total == 0 {
                // Unknown length: the count and the time only.
                log(format!(
                    "{}: {done} done (last: {msg}), {elapsed:.0} s elapsed",
                    self.what
                ));
            } else {
                let left = self.left(done, elapsed);
                log(format!(
                    "{}: {done}/{} done (last: {msg}), {elapsed:.0} s elapsed, about {left:.0} s left",
                    self.what, self.total
                ));
            }
        }
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// The bar's look with one of the templates above.
fn style(template: &str) -> indicatif::ProgressStyle {
    indicatif::ProgressStyle::with_template(template)
        .expect("valid template")
        .progress_chars("=> ")
}

/// Seconds as h:mm:ss.
fn clock(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

/// The commands' [`Tracker`]: a progress bar (a line every 10 s off a
/// terminal) for each stretch of trials a study starts; ticks outside a
/// stretch go to a counter of unknown length.
pub struct Bars {
    what: String,
    current: std::cell::RefCell<Option<StudyProgress>>,
}

impl Bars {
    pub fn new(what: &str) -> Self {
        Self {
            what: what.to_string(),
            current: std::cell::RefCell::new(None),
        }
    }
}

impl Tracker for Bars {
    fn start(&self, what: &str, costs: Vec<f64>, cap: f64) {
        self.finish();
        let what = if what.is_empty() { &self.what } else { what };
        *self.current.borrow_mut() =
            Some(StudyProgress::new(costs.len() as u64, what).with_costs(costs, cap));
    }

    fn tick(&self, trial: &TrialSpec) {
        self.current
            .borrow_mut()
            .get_or_insert_with(|| StudyProgress::new(0, &self.what))
            .tick(trial);
    }

    fn finish(&self) {
        if let Some(p) = self.current.borrow_mut().take() {
            p.finish();
        }
    }
}

/// Runs one study in a lab of its own at `settings`, with progress on
/// stderr: its findings and its artifacts.
pub fn run_study<S: Study>(study: &S, settings: Settings) -> Result<(S::Findings, Vec<Artifact>)> {
    in_lab(study.name(), settings, |lab| {
        let ran = lab.run(study)?;
        Ok((ran.findings, ran.artifacts))
    })
}

/// `f` in a lab of its own for the study `name` at `settings`, with its
/// progress bars and log lines on stderr.
pub fn in_lab<T>(
    name: &'static str,
    settings: Settings,
    f: impl FnOnce(&mut Lab) -> Result<T>,
) -> Result<T> {
    let bars = Bars::new(name);
    let log_line = move |l: &str| log(format!("{name}: {l}"));
    let mut lab = Lab::new(settings, &log_line, &bars);
    let out = f(&mut lab)?;
    bars.finish();
    Ok(out)
}

/// The solvers named (all registered ones if none).
pub fn solver_list(names: &[String]) -> Result<Vec<&'static Entry>> {
    if names.is_empty() {
        return Ok(registry::solvers());
    }
    names
        .iter()
        .map(|n| crate::solve::solver_entry(n))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{LogObserver, StudyProgress};
    use contactlab_solvers::{Observer, Progress};

    fn friction(o: &mut LogObserver, iteration: usize, change: f64, seconds: f64) {
        o.observe(&Progress {
            stage: crate::coulomb::fixed_point::STAGE,
            iteration,
            residual: change,
            seconds,
        });
    }

    /// A change falling tenfold an iteration from 1e-2 reaches 1e-6 in 4
    /// more, at the last iteration's 10 s each; no estimate before two
    /// iterations, none while the change grows, and a new fixed point
    /// (iteration 1 again) forgets the last one's pace.
    #[test]
    fn the_friction_estimate_follows_the_contraction() {
        let mut o = LogObserver::toward(Some(1e-6));
        friction(&mut o, 1, 1e-1, 10.0);
        assert_eq!(o.estimate(1e-2, 20.0), Some((4, 40.0)));
        assert_eq!(o.estimate(2e-1, 20.0), None);
        friction(&mut o, 2, 1e-2, 20.0);
        friction(&mut o, 1, 1e-1, 25.0);
        assert_eq!(o.estimate(1e-3, 27.0), Some((2, 4.0)));
        assert!(LogObserver::toward(None).estimate(1e-3, 1.0).is_none());
    }

    /// Two cheap units done in 2 s, two eight times dearer left: 16 s at the
    /// measured rate, not the 2 s a count of units predicts; a cap per unit
    /// bounds each prediction.
    #[test]
    fn the_estimate_left_weighs_units_by_their_expected_cost() {
        let alike = StudyProgress::new(4, "test");
        assert_eq!(alike.left(2, 2.0), 2.0);
        let weighted = StudyProgress::new(4, "test").with_costs(vec![1.0, 1.0, 8.0, 8.0], 100.0);
        assert_eq!(weighted.left(2, 2.0), 16.0);
        let capped = StudyProgress::new(4, "test").with_costs(vec![1.0, 1.0, 8.0, 8.0], 5.0);
        assert_eq!(capped.left(2, 2.0), 10.0);
        assert_eq!(capped.left(4, 30.0), 0.0);
        // Costs that do not match the plan are ignored, not misread.
        let ignored = StudyProgress::new(4, "test").with_costs(vec![1.0, 8.0], 100.0);
        assert_eq!(ignored.left(2, 2.0), 2.0);
    }
}
