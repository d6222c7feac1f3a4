//! The commands of the command line: each reads its arguments, runs a study
//! or a solve, writes its output folder whole, and only then prints.

pub mod bench;
pub mod benchmark;
pub mod certify;
pub mod compare;
pub mod export;
pub mod info;
pub mod reproduce;
pub mod solve;
pub mod stability;
pub mod sweep;
pub mod table1;

use anyhow::Result;
use contactlab_solvers::registry::{self, Entry};
use contactlab_solvers::{Control, Observer, Progress};

use crate::coulomb::fixed_point;
use crate::io::output::log;
use crate::study::trial::TrialSpec;

/// Logs the friction loop to stderr.
pub struct LogObserver;

impl Observer for LogObserver {
    fn observe(&mut self, p: &Progress) -> Control {
        if p.stage == fixed_point::STAGE {
            log(format!(
                "friction iteration {:>3}: max|Δg| = {:.3e}  ({:.2} s)",
                p.iteration, p.residual, p.seconds
            ));
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
        bar.set_style(
            indicatif::ProgressStyle::with_template(template)
                .expect("valid template")
                .progress_chars("=> "),
        );
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
        }
    }

    /// A trial is done.
    pub fn tick(&self, t: &TrialSpec) {
        let knob = t
            .knob
            .as_ref()
            .map(|(k, v)| format!(", {k} = {v}"))
            .unwrap_or_default();
        let msg = format!("{} {}{knob}", t.solver.name, t.law.as_str());
        self.step(&msg);
    }

    /// One unit of work is done, described by `msg`.
    pub fn step(&self, msg: &str) {
        self.done.set(self.done.get() + 1);
        self.bar.set_message(msg.to_string());
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
                let left = elapsed / done as f64 * self.total.saturating_sub(done) as f64;
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

/// The solvers named (all registered ones if none).
pub fn solver_list(names: &[String]) -> Result<Vec<&'static Entry>> {
    if names.is_empty() {
        return Ok(registry::solvers());
    }
    names
        .iter()
        .map(|n| crate::coulomb::driver::solver_entry(n))
        .collect()
}
