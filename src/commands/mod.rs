//! The commands of the command line: each reads its arguments, runs a study
//! or a solve, writes its output folder whole, and only then prints.

pub mod bench;
pub mod compare;
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

/// A progress bar with an ETA on stderr (hidden when stderr is not a terminal).
pub fn progress_bar(len: u64, what: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{prefix} [{bar:30}] {pos}/{len} {msg} (elapsed {elapsed}, eta {eta})",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    bar.set_prefix(what.to_string());
    bar
}

/// A study's tick: advances `bar` and names the trial just done.
pub fn ticker(bar: &indicatif::ProgressBar) -> impl Fn(&TrialSpec) + '_ {
    move |t: &TrialSpec| {
        let knob = t
            .knob
            .as_ref()
            .map(|(k, v)| format!(", {k} = {v}"))
            .unwrap_or_default();
        bar.set_message(format!("{} {}{knob}", t.solver.name, t.law.as_str()));
        bar.inc(1);
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
