//! The catalogued studies as commands (`crate::study::catalog`): one
//! subcommand per entry, `contactlab COMMAND [--quick | --long] --out DIR`,
//! the settings' flags and the study's own (its spec's fields), made here
//! from the catalog rather than written per study. Each runs its study at
//! the run length's budget with the flags given, writes its folder whole,
//! and prints its README section.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Arg, ArgAction, ArgMatches, Command, FromArgMatches, Subcommand};

use crate::cli::{AllSolvers, PapersMethod, SettingsArgs, SolverSet};
use crate::commands::in_lab;
use crate::io::output::print;
use crate::io::run_folder::RunFolder;
use crate::settings::Settings;
use crate::study::catalog::Entry;
use crate::study::lab::{RunLength, write_artifacts};
use crate::study::studies::{by_command, catalog};

/// A catalogued study's command, as parsed: its entry and its arguments.
#[derive(Clone)]
pub struct StudyCommand {
    pub entry: &'static dyn Entry,
    pub matches: ArgMatches,
}

impl std::fmt::Debug for StudyCommand {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "StudyCommand({})", self.entry.command())
    }
}

/// The command of `entry`: its help, the run lengths, the output folder,
/// the settings and the spec's flags.
fn command_of(entry: &'static dyn Entry) -> Command {
    let cmd = Command::new(entry.command())
        .arg(
            Arg::new("quick")
                .long("quick")
                .action(ArgAction::SetTrue)
                .conflicts_with("long")
                .help("A small run for tests (seconds): the study's quick budget"),
        )
        .arg(
            Arg::new("long")
                .long("long")
                .action(ArgAction::SetTrue)
                .help("The long run's budget (what `reproduce --long` runs)"),
        )
        .arg(
            Arg::new("out")
                .long("out")
                .value_name("DIR")
                .required(true)
                .value_parser(clap::value_parser!(PathBuf))
                .help("Output folder (replaced whole)"),
        );
    let cmd = if entry.at_papers_settings() {
        <SettingsArgs<PapersMethod> as clap::Args>::augment_args(cmd)
    } else {
        <SettingsArgs as clap::Args>::augment_args(cmd)
    };
    // The spec's own doc comment would be the command's help: the entry's
    // is, after it.
    entry
        .flags(cmd)
        .about(entry.about())
        .long_about(None::<&str>)
}

impl FromArgMatches for StudyCommand {
    fn from_arg_matches(matches: &ArgMatches) -> Result<Self, clap::Error> {
        let Some((name, sub)) = matches.subcommand() else {
            return Err(clap::Error::new(clap::error::ErrorKind::MissingSubcommand));
        };
        let entry = by_command(name).ok_or_else(|| {
            clap::Error::raw(
                clap::error::ErrorKind::InvalidSubcommand,
                format!("no study called {name:?}"),
            )
        })?;
        Ok(Self {
            entry,
            matches: sub.clone(),
        })
    }

    fn update_from_arg_matches(&mut self, matches: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(matches)?;
        Ok(())
    }
}

impl Subcommand for StudyCommand {
    fn augment_subcommands(cmd: Command) -> Command {
        catalog()
            .into_iter()
            .fold(cmd, |cmd, e| cmd.subcommand(command_of(e)))
    }

    fn augment_subcommands_for_update(cmd: Command) -> Command {
        Self::augment_subcommands(cmd)
    }

    fn has_subcommand(name: &str) -> bool {
        by_command(name).is_some()
    }
}

impl StudyCommand {
    /// The run length asked for.
    fn length(&self) -> RunLength {
        if self.matches.get_flag("quick") {
            RunLength::Quick
        } else if self.matches.get_flag("long") {
            RunLength::Long
        } else {
            RunLength::Standard
        }
    }
}

/// The settings flags of `matches` (those a command offering `S`'s
/// solvers has) applied to `base`.
fn settings_of<S: SolverSet>(matches: &ArgMatches, base: Settings) -> Result<Settings> {
    SettingsArgs::<S>::from_arg_matches(matches)
        .map_err(|e| anyhow::anyhow!("{}", e.to_string().trim()))?
        .resolve_on(base)
}

/// Runs the study: its folder written whole, then its section printed.
pub fn run(c: &StudyCommand) -> Result<()> {
    let base = c.entry.settings_base();
    let settings = if c.entry.at_papers_settings() {
        settings_of::<PapersMethod>(&c.matches, base)?
    } else {
        settings_of::<AllSolvers>(&c.matches, base)?
    };
    let study = c.entry.planned_with_flags(c.length(), &c.matches)?;
    let out: &PathBuf = c
        .matches
        .get_one("out")
        .ok_or_else(|| anyhow::anyhow!("--out DIR: give the output folder"))?;
    let folder = RunFolder::create(out)?;
    let (artifacts, section) = in_lab(study.name(), settings, |lab| study.run_for_report(lab))?;
    let files = write_artifacts(folder.path(), &artifacts)?;
    let target = folder.commit()?;
    let count = |prefix: &str| files.iter().filter(|f| f.starts_with(prefix)).count();
    let shown: Vec<&str> = files
        .iter()
        .map(String::as_str)
        .filter(|f| !f.starts_with("profiles/") && !f.starts_with("charts/"))
        .collect();
    let mut wrote = shown.join(", ");
    for (n, what) in [
        (count("charts/"), "charts"),
        (count("profiles/"), "profiles"),
    ] {
        if n > 0 {
            wrote += &format!(", {n} {what}");
        }
    }
    print(&format!(
        "{}\nwrote {wrote} into {}\n",
        section.markdown,
        target.display()
    ))
}
