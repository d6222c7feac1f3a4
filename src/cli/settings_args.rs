//! Settings on the command line: the harness's own flags, one flag
//! `--SOLVER-KNOB` for every knob of every registered solver (generated from
//! the registry, with its help), and `--set PATH=VALUE` for any setting.

use anyhow::{Result, bail};
use clap::{Arg, ArgAction, ArgMatches, Command};
use contactlab_solvers::Stopping;
use contactlab_solvers::registry::{self, Knob};
use serde_json::Value;

use crate::coulomb::continuation::Schedule;
use crate::coulomb::fixed_point;
use crate::settings::Settings;

/// Which solvers' knobs a command offers as flags.
pub trait SolverSet: Clone + std::fmt::Debug + Default + Send + Sync + 'static {
    fn solvers() -> Vec<&'static registry::Entry>;
    /// Whether the command offers --schedule (a command with its own
    /// schedule flag does not).
    const SCHEDULE: bool = true;
    /// The stopping mode the command uses when --stopping is not given.
    const STOPPING_DEFAULT: &'static str = "relative";
}

/// Every registered solver.
#[derive(Clone, Debug, Default)]
pub struct AllSolvers;

impl SolverSet for AllSolvers {
    fn solvers() -> Vec<&'static registry::Entry> {
        registry::solvers()
    }
}

/// The paper's method alone (Table 1).
#[derive(Clone, Debug, Default)]
pub struct PapersMethod;

impl SolverSet for PapersMethod {
    fn solvers() -> Vec<&'static registry::Entry> {
        registry::with_role(registry::Role::PapersMethod)
            .into_iter()
            .collect()
    }
    const SCHEDULE: bool = false;
    const STOPPING_DEFAULT: &'static str = "paper";
}

/// Changes to the settings given on the command line; the knobs offered are
/// those of the solvers in `S`.
#[derive(Debug, Clone, Default)]
pub struct SettingsArgs<S: SolverSet = AllSolvers> {
    pub solvers: std::marker::PhantomData<S>,
    pub stopping: Option<Stopping>,
    pub epsilon: Option<f64>,
    pub max_friction_iterations: Option<String>,
    pub schedule: Option<Schedule>,
    pub certificate_tolerance: Option<f64>,
    /// (path, value as written, the flag that gave it), in order.
    pub assignments: Vec<(String, String, String)>,
}

const STOPPING: &str = "stopping";
const EPSILON: &str = "epsilon";
const MAX_FRICTION: &str = "max-friction-iterations";
const SCHEDULE: &str = "schedule";
const CERTIFY_TOL: &str = "certify-tol";
const SET: &str = "set";

/// The default of the fixed point's setting `name`, as help shows it.
fn coulomb_default(name: &str) -> String {
    fixed_point::KNOBS
        .iter()
        .find(|k| k.name == name)
        .map(|k| k.default_text(fixed_point::default_tree))
        .unwrap_or_default()
}

/// The flag of a solver's knob: `--relaxation-r`, `--clarabel-max-iter`.
pub fn knob_flag(solver: &str, knob: &Knob) -> String {
    format!("{solver}-{}", knob.name.replace('_', "-"))
}

fn knob_id(solver: &str, knob: &Knob) -> String {
    format!("knob:{solver}.{}", knob.name)
}

fn number<T: std::str::FromStr>(
    flag: &'static str,
    hint: &'static str,
) -> impl Fn(&str) -> Result<T, String> + Clone {
    move |text: &str| {
        text.trim()
            .parse::<T>()
            .map_err(|_| format!("--{flag} = '{text}' is invalid: {hint}"))
    }
}

impl<S: SolverSet> clap::Args for SettingsArgs<S> {
    fn augment_args(cmd: Command) -> Command {
        let mut cmd = cmd
            .arg(
                Arg::new(STOPPING)
                    .long(STOPPING)
                    .value_name("MODE")
                    .value_parser(["relative", "paper"])
                    .help(format!("How tolerances and scale-dependent settings are read: `relative` to the problem's own scales (load, stiffness, length of Γ_K), so that the units do not matter, or `paper`: the paper's absolute values, for its Table 1 [default: {}]", S::STOPPING_DEFAULT)),
            )
            .arg(
                Arg::new(EPSILON)
                    .long(EPSILON)
                    .value_name("EPS")
                    .allow_hyphen_values(true)
                    .value_parser(number::<f64>(EPSILON, "give a positive number"))
                    .help(format!(
                        "The paper's ε for every loop that uses one: the friction fixed point (coulomb.epsilon [default {}]) and every solver setting named epsilon",
                        coulomb_default("epsilon")
                    )),
            )
            .arg(
                Arg::new(MAX_FRICTION)
                    .long(MAX_FRICTION)
                    .value_name("N")
                    .allow_hyphen_values(true)
                    .help(format!(
                        "Cap on friction iterations, coulomb.max_iterations [default {}]",
                        coulomb_default("max_iterations")
                    )),
            )
            .arg(
                Arg::new(CERTIFY_TOL)
                    .long(CERTIFY_TOL)
                    .value_name("TOL")
                    .allow_hyphen_values(true)
                    .value_parser(number::<f64>(CERTIFY_TOL, "give a positive number"))
                    .help(format!(
                        "The certificate's tolerance: the largest violation of any condition, in the problem's scales, that certifies an answer [default: {:e}]",
                        crate::certificate::DEFAULT_TOLERANCE
                    )),
            )
            .arg(
                Arg::new(SET)
                    .long(SET)
                    .value_name("PATH=VALUE")
                    .action(ArgAction::Append)
                    .allow_hyphen_values(true)
                    .help(format!(
                        "Any setting by path, e.g. --set coulomb.stall_window=8 or --set {}=VALUE (repeatable). Each solver's settings are also flags (--relaxation-r 1e8); `contactlab settings [SOLVER]` lists them all",
                        crate::settings::example_path()
                    )),
            );
        if S::SCHEDULE {
            cmd = cmd            .arg(
                Arg::new(SCHEDULE)
                    .long(SCHEDULE)
                    .value_name("SCHEDULE")
                    .value_parser(Schedule::ALL.map(Schedule::name))
                    .help("Mesh continuation for solvers that warm-start: revisit the coarse levels in every friction iteration, or only in the first, or nested: the whole Coulomb problem on each level in turn, each started from the level below and the coarse ones solved to coulomb.coarse_epsilon [default: revisit]"),
            );
        }
        for e in S::solvers() {
            for k in e.knobs {
                cmd = cmd.arg(
                    Arg::new(knob_id(e.name, k))
                        .long(knob_flag(e.name, k))
                        .value_name("VALUE")
                        .allow_hyphen_values(true)
                        // Listed by `contactlab settings`, not in every
                        // command's help (which they made 150 lines long).
                        .hide(true)
                        .help(e.help(k)),
                );
            }
        }
        cmd
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

impl<S: SolverSet> clap::FromArgMatches for SettingsArgs<S> {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let text = |id: &str| m.try_get_one::<String>(id).ok().flatten().cloned();
        let mut out = SettingsArgs {
            solvers: std::marker::PhantomData,
            stopping: text(STOPPING).map(|s| match s.as_str() {
                "paper" => Stopping::Paper,
                _ => Stopping::Relative,
            }),
            epsilon: m.try_get_one::<f64>(EPSILON).ok().flatten().copied(),
            max_friction_iterations: text(MAX_FRICTION),
            schedule: text(SCHEDULE).and_then(|s| Schedule::from_name(&s)),
            certificate_tolerance: m.try_get_one::<f64>(CERTIFY_TOL).ok().flatten().copied(),
            assignments: Vec::new(),
        };
        for e in S::solvers() {
            for k in e.knobs {
                if let Some(value) = text(&knob_id(e.name, k)) {
                    out.assignments.push((
                        format!("{}.{}", e.name, k.name),
                        value,
                        format!("--{}", knob_flag(e.name, k)),
                    ));
                }
            }
        }
        if let Ok(Some(sets)) = m.try_get_many::<String>(SET) {
            for s in sets {
                let (path, value) = s.split_once('=').unwrap_or((s.as_str(), ""));
                out.assignments
                    .push((path.trim().to_string(), value.to_string(), "--set".into()));
            }
        }
        Ok(out)
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl<S: SolverSet> SettingsArgs<S> {
    /// Default settings with these flags applied, validated.
    pub fn resolve(&self) -> Result<Settings> {
        self.resolve_on(Settings::default())
    }

    /// `base` (e.g. a scene file's settings) with these flags applied, validated.
    pub fn resolve_on(&self, mut settings: Settings) -> Result<Settings> {
        if let Some(s) = self.stopping {
            settings.stopping = s;
        }
        if let Some(s) = self.schedule {
            settings.schedule = s;
        }
        if let Some(t) = self.certificate_tolerance {
            settings.certificate.tolerance = t;
        }
        if let Some(e) = self.epsilon {
            settings
                .set_epsilon(e)
                .map_err(|m| anyhow::anyhow!("--epsilon: {m}"))?;
        }
        if let Some(n) = &self.max_friction_iterations {
            let value = n.trim().parse::<u64>().map_err(|_| {
                anyhow::anyhow!(
                    "--max-friction-iterations = '{n}' is invalid: give a whole number of iterations ≥ 1"
                )
            })?;
            settings
                .set("coulomb.max_iterations", Value::from(value))
                .map_err(|m| anyhow::anyhow!(with_flag(m)))?;
        }
        let offered: Vec<&str> = S::solvers().iter().map(|e| e.name).collect();
        for (path, text, flag) in &self.assignments {
            if flag == "--set" && !text_has_value(path, text) {
                bail!(
                    "--set '{path}': write it as PATH=VALUE, e.g. --set {}=VALUE",
                    crate::settings::example_path()
                );
            }
            if let Some(owner) = other_solver(path, &offered) {
                let owner = owner.name;
                bail!(
                    "--set '{path}': this command runs only {}; settings of {owner} would be ignored",
                    offered.join(", ")
                );
            }
            settings.set_text(path, text).map_err(|m| {
                let m = with_flag(m);
                if m.contains(flag.as_str()) {
                    anyhow::anyhow!(m)
                } else {
                    anyhow::anyhow!("{flag}: {m}")
                }
            })?;
        }
        if let Err(m) = settings.validate() {
            bail!(with_flag(m));
        }
        Ok(settings)
    }

    /// Refuses settings of a registered solver that this run does not use
    /// (`running`): they would be ignored without a word, e.g.
    /// `--clarabel-tol` with `--solver clarabel-faer`, whose flags are
    /// `--clarabel-faer-*`. The error names the flag for the solver run.
    pub fn check_used_by(&self, running: &[&'static registry::Entry]) -> Result<()> {
        let names: Vec<&str> = running.iter().map(|r| r.name).collect();
        for (path, _, flag) in &self.assignments {
            let Some(owner) = other_solver(path, &names) else {
                continue;
            };
            let owner = owner.name;
            let knob = path.split_once('.').map_or("", |(_, k)| k);
            let instead: Vec<String> = running
                .iter()
                .filter_map(|r| r.knob(knob).map(|k| format!("--{}", knob_flag(r.name, k))))
                .collect();
            let hint = if instead.is_empty() {
                String::new()
            } else {
                format!(": use {} instead", instead.join(" or "))
            };
            let given = if flag == "--set" {
                format!("--set {path}")
            } else {
                flag.clone()
            };
            bail!(
                "{given} sets a setting of {owner}, but this run uses {}; it would be ignored{hint}",
                names.join(", ")
            );
        }
        Ok(())
    }
}

/// The registered solver that owns setting `path`, if it is not one of
/// `names` (its settings would be ignored by a run of those).
fn other_solver(path: &str, names: &[&str]) -> Option<&'static registry::Entry> {
    let owner = path.split('.').next().unwrap_or("");
    registry::by_name(owner).filter(|e| !names.contains(&e.name))
}

fn text_has_value(path: &str, text: &str) -> bool {
    !path.is_empty() && !text.trim().is_empty()
}

/// Adds the command-line flag to a message that starts with a settings path.
pub fn with_flag(message: String) -> String {
    let Some((path, rest)) = message.split_once(' ') else {
        return message;
    };
    let flag = match path.split_once('.') {
        Some(("coulomb", "epsilon")) => Some("--epsilon".to_string()),
        Some(("coulomb", "max_iterations")) => Some("--max-friction-iterations".to_string()),
        Some(("certificate", "tolerance")) => Some("--certify-tol".to_string()),
        Some(("coulomb", field)) => Some(format!("--set coulomb.{field}=")),
        Some((owner, field)) => registry::by_name(owner).and_then(|e| {
            e.knobs
                .iter()
                .find(|k| k.fields.contains(&field))
                .map(|k| format!("--{}", knob_flag(e.name, k)))
        }),
        None => None,
    };
    match flag {
        Some(f) => format!("{path} ({f}) {rest}"),
        None => message,
    }
}
