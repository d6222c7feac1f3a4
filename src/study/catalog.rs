//! The studies as the command line, Python and `reproduce` see them. A
//! study in the catalog is a [`Study`] that also says how it
//! is called ([`Catalogued`]): its command's name and help, and its
//! parameters as one typed [`Catalogued::Spec`], from which its flags
//! (clap), its JSON form (serde: Python's keyword arguments, the
//! checkpoint of a resumed run) and its budget in a run of each length
//! come. The list of them is `study::studies`: the command line
//! makes a subcommand of each entry (`commands::study`), Python calls each
//! by name (`contactlab.study`), and `reproduce` runs each: adding a study
//! is one file plus one line there, and `tests/toy_study.rs` adds one and
//! finds it in all three. This module is the engine's part (it knows no
//! study).

use std::fmt::Debug;
use std::marker::PhantomData;

use anyhow::{Context, Result, bail};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{ArgMatches, Args, Command, FromArgMatches};
use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::coulomb::continuation::Schedule;
use crate::mechanics::material::PlaneModel;
use crate::settings::Settings;
use crate::study::lab::{Planned, RunLength};

/// A study that can be called by name: its command, its help and its
/// parameters.
pub trait Catalogued: Planned + Send + Sized + 'static {
    /// Its command (`contactlab COMMAND`) and its name for Python
    /// (`contactlab.study("COMMAND")`).
    const COMMAND: &'static str;
    /// What it measures, in a sentence: the command's help.
    const ABOUT: &'static str;
    /// Its parameters, declared once: each field's doc comment is its
    /// flag's help, its serde name its Python keyword. A field that is
    /// not a flag is `#[arg(skip)]`; a flag has no clap default (its
    /// default is the run length's, [`Catalogued::spec`]) and is not
    /// required.
    type Spec: Args + Serialize + DeserializeOwned + Clone + Debug + Send + 'static;

    /// Its parameters in a run of `length`: the default of every flag.
    fn spec(length: RunLength) -> Self::Spec;

    /// The study of `spec`, checked: a one-line error naming the field.
    fn of(spec: Self::Spec) -> Result<Self>;

    /// Whether it runs at the paper's settings (Table 1): its command's
    /// and Python's settings then change the paper's (`--stopping`
    /// defaults to `paper`, and only the paper's method's knobs are
    /// offered), not the defaults.
    const AT_PAPERS_SETTINGS: bool = false;

    /// The study as a run of several (`reproduce`) runs it, given the
    /// run's settings: itself, at the run's settings; a study at the
    /// paper's settings pins its own here.
    fn in_run(self, _run: &Settings) -> Self {
        self
    }
}

/// The longest time limit a run may be given: a week.
pub const MAX_SECONDS: f64 = 7.0 * 24.0 * 3600.0;

/// The spec of a run of `length` from a study's three budgets: the
/// smoke run's, the main job's and the long run's.
pub fn by_length<T>(length: RunLength, quick: fn() -> T, main: fn() -> T, long: fn() -> T) -> T {
    match length {
        RunLength::Quick => quick(),
        RunLength::Standard => main(),
        RunLength::Long => long(),
    }
}

/// A spec's list of the paper's problems: at least one, each 1, 2 or 3
/// (a one-line error naming the field otherwise).
pub fn check_paper_problems(problems: &[u32]) -> Result<()> {
    anyhow::ensure!(
        !problems.is_empty() && problems.iter().all(|p| (1..=3).contains(p)),
        "problems = {problems:?}: give the paper's problems, 1, 2 or 3, at least one"
    );
    Ok(())
}

/// A catalogued study with its types erased, as the list holds it.
pub trait Entry: Sync {
    /// Its command's name.
    fn command(&self) -> &'static str;
    /// Its help, one sentence.
    fn about(&self) -> &'static str;
    /// `cmd` with the spec's flags.
    fn flags(&self, cmd: Command) -> Command;
    /// The study of a run of `length`, its spec updated by the flags in
    /// `matches` that were given.
    fn planned_with_flags(
        &self,
        length: RunLength,
        matches: &ArgMatches,
    ) -> Result<Box<dyn Planned + Send>>;
    /// The study of a run of `length`, its spec updated by the fields of
    /// the JSON object `changes` (Python's keyword arguments).
    fn planned_with_json(
        &self,
        length: RunLength,
        changes: &str,
    ) -> Result<Box<dyn Planned + Send>>;
    /// Whether it runs at the paper's settings
    /// ([`Catalogued::AT_PAPERS_SETTINGS`]).
    fn at_papers_settings(&self) -> bool;
    /// The settings its command's flags and Python's `settings=` change:
    /// the defaults, or the paper's.
    fn settings_base(&self) -> Settings {
        if self.at_papers_settings() {
            Settings::paper()
        } else {
            Settings::default()
        }
    }
    /// The solvers whose settings its command and Python offer: the
    /// paper's method alone for a study at the paper's settings, else all.
    fn offered_solvers(&self) -> Vec<&'static contactlab_solvers::registry::Entry> {
        use contactlab_solvers::registry::{self, Role};
        if self.at_papers_settings() {
            registry::with_role(Role::PapersMethod)
                .into_iter()
                .collect()
        } else {
            registry::solvers()
        }
    }
    /// The study in a run of `length` at the settings `run` (`reproduce`),
    /// at its own budget for it ([`Catalogued::in_run`]).
    fn planned(&self, length: RunLength, run: &Settings) -> Result<Box<dyn Planned + Send>>;
    /// The spec of a run of `length`, as JSON (what Python shows of it).
    fn spec_json(&self, length: RunLength) -> Result<serde_json::Value>;
}

/// The entry of the study type `S`.
pub struct Of<S>(PhantomData<fn() -> S>);

impl<S> Of<S> {
    /// The entry, as a constant: `&Of::<MyStudy>::ENTRY` is a
    /// `&'static dyn Entry`, the one line of a study in the catalog.
    pub const ENTRY: Self = Self(PhantomData);
}

impl<S: Catalogued> Entry for Of<S> {
    fn command(&self) -> &'static str {
        S::COMMAND
    }

    fn about(&self) -> &'static str {
        S::ABOUT
    }

    fn flags(&self, cmd: Command) -> Command {
        S::Spec::augment_args(cmd)
    }

    fn planned_with_flags(
        &self,
        length: RunLength,
        matches: &ArgMatches,
    ) -> Result<Box<dyn Planned + Send>> {
        let mut spec = S::spec(length);
        spec.update_from_arg_matches(matches)
            .map_err(|e| anyhow::anyhow!("{}", e.to_string().trim()))?;
        Ok(Box::new(S::of(spec)?))
    }

    fn planned_with_json(
        &self,
        length: RunLength,
        changes: &str,
    ) -> Result<Box<dyn Planned + Send>> {
        let spec = merged::<S::Spec>(&S::spec(length), changes, S::COMMAND)?;
        Ok(Box::new(S::of(spec)?))
    }

    fn at_papers_settings(&self) -> bool {
        S::AT_PAPERS_SETTINGS
    }

    fn planned(&self, length: RunLength, run: &Settings) -> Result<Box<dyn Planned + Send>> {
        Ok(Box::new(S::of(S::spec(length))?.in_run(run)))
    }

    fn spec_json(&self, length: RunLength) -> Result<serde_json::Value> {
        Ok(serde_json::to_value(S::spec(length))?)
    }
}

/// `base` with the fields of the JSON object `changes` replaced: a field
/// the spec does not have, or a value of the wrong type, is an error
/// naming it (and the fields there are).
fn merged<T: Serialize + DeserializeOwned>(base: &T, changes: &str, study: &str) -> Result<T> {
    let mut tree = serde_json::to_value(base)?;
    let changes: serde_json::Value =
        serde_json::from_str(changes).context("the study's parameters are not a JSON object")?;
    let (Some(fields), Some(changes)) = (tree.as_object_mut(), changes.as_object()) else {
        bail!("the study's parameters are not a JSON object");
    };
    for (key, value) in changes {
        let Some(field) = fields.get_mut(key) else {
            let known: Vec<&str> = fields.keys().map(String::as_str).collect();
            bail!(
                "{study}: no parameter {key:?}; its parameters are {}",
                known.join(", ")
            );
        };
        *field = value.clone();
    }
    serde_json::from_value(tree).map_err(|e| anyhow::anyhow!("{study}: {e}"))
}

/// A flag's value among a domain enum's `all`, by the names it carries
/// itself (`name`; the domain types know nothing of clap).
fn named_choice<T, const N: usize>(
    all: [T; N],
    name: fn(T) -> &'static str,
) -> impl TypedValueParser<Value = T>
where
    T: Copy + Send + Sync + 'static,
{
    PossibleValuesParser::new(all.map(name)).map(move |s| {
        all.into_iter()
            .find(|&t| name(t) == s)
            .expect("one of the names offered")
    })
}

/// A flag's `strain|stress` ([`PlaneModel`]).
pub fn plane_choice() -> impl TypedValueParser<Value = PlaneModel> {
    named_choice(PlaneModel::ALL, PlaneModel::name)
}

/// A flag's continuation schedule, `revisit,finest-only` ([`Schedule`]).
pub fn schedule_choice() -> impl TypedValueParser<Value = Schedule> {
    named_choice(Schedule::ALL, Schedule::name)
}

/// A flag's value that names a solver: the solver's name if it is
/// registered (a Python solver among them), else the names there are.
pub fn registered_solver(name: &str) -> Result<String, String> {
    crate::solve::solver_entry(name)
        .map(|e| e.name.to_string())
        .map_err(|e| format!("{e:#}"))
}
