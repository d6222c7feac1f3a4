//! Settings on the command line: the harness's own flags (those a user
//! types daily: --stopping, --epsilon, --max-friction-iterations,
//! --certify-tol, --schedule) and `--set PATH=VALUE` for any setting, the
//! one spelling of a solver's knob (`contactlab settings SOLVER` lists
//! them, with their help, from the registry). The flags once generated per
//! knob (`--relaxation-r 1e8`) are refused with the `--set` they stand for
//! ([`old_spelling`]).

use anyhow::{Result, bail};
use clap::{Arg, ArgAction, ArgMatches, Command};
use contactlab_solvers::registry::{self, Knob};

use crate::coulomb::continuation::Schedule;
use crate::coulomb::fixed_point;
use crate::settings::changes::Refusal;
use crate::settings::changes::Spelling;
use crate::settings::{Change, Changes, Settings};

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

/// Changes to the settings given on the command line, in the order given
/// ([`Changes`]: the later change of a setting wins, whichever flag gave
/// it); the knobs offered are those of the solvers in `S`.
#[derive(Debug, Clone, Default)]
pub struct SettingsArgs<S: SolverSet = AllSolvers> {
    pub solvers: std::marker::PhantomData<S>,
    pub changes: Changes,
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

/// The flag a solver's knob once had (`relaxation-r`, `clarabel-max-iter`):
/// the old spelling [`old_spelling`] recognizes.
fn knob_flag(solver: &str, knob: &Knob) -> String {
    format!("{solver}-{}", knob.name.replace('_', "-"))
}

/// The one spelling of a solver's knob: `--set relaxation.r=`.
pub fn knob_set(solver: &str, knob: &Knob) -> String {
    format!("--set {solver}.{}=", knob.name)
}

/// Flags that had another spelling once, with the one they have now.
const RENAMED: [(&str, &str); 4] = [
    ("problems", "--problem"),
    ("repeats", "--runs"),
    ("budget", "--time-limit"),
    ("tolerance", "--certify-tol"),
];

/// A one-line hint for an argument in an old spelling: a knob's old flag
/// (`--relaxation-r 1e8`, `--relaxation-r=1e8`: the `--set` to write
/// instead) or a renamed flag (`--repeats`: `--runs`). None for any other
/// argument (clap then says what it says).
pub fn old_spelling(args: &[String]) -> Option<String> {
    for (i, arg) in args.iter().enumerate() {
        let Some(flag) = arg.strip_prefix("--") else {
            continue;
        };
        let (flag, inline) = match flag.split_once('=') {
            Some((f, v)) => (f, Some(v.to_string())),
            None => (flag, None),
        };
        if let Some((_, now)) = RENAMED.iter().find(|(old, _)| *old == flag) {
            return Some(format!("--{flag} is no longer a flag: write {now}"));
        }
        for e in registry::solvers() {
            if let Some(k) = e.knobs.iter().find(|k| knob_flag(e.name, k) == flag) {
                let value = inline
                    .or_else(|| args.get(i + 1).cloned())
                    .unwrap_or_else(|| "VALUE".into());
                return Some(format!(
                    "--{flag} is no longer a flag: write {}{value} (every solver setting is set by --set; `contactlab settings {}` lists them)",
                    knob_set(e.name, k),
                    e.name
                ));
            }
        }
    }
    None
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
                        "Any setting by path, e.g. --set coulomb.stall_window=8 or --set {}=VALUE (repeatable): the one spelling of a solver's settings (--set relaxation.r=1e8); `contactlab settings [SOLVER]` lists them all. All settings flags apply in the order given: when two set the same setting (--set stopping=paper --stopping relative), the later one wins. --set certificate.bound_max_unknowns=N bounds the error of answers up to N unknowns (default {}, h = 1/512; 0: none)",
                        crate::settings::example_path(),
                        crate::certificate::SOLVE_BOUND_MAX_UNKNOWNS
                    )),
            );
        if S::SCHEDULE {
            cmd = cmd            .arg(
                Arg::new(SCHEDULE)
                    .long(SCHEDULE)
                    .value_name("SCHEDULE")
                    .value_parser(Schedule::ALL.map(Schedule::name))
                    .help("Mesh continuation for solvers that warm-start: revisit the coarse levels in every friction iteration, or only in the first, or nested: the whole Coulomb problem on each level in turn, each started from the level below and the coarse ones solved to coulomb.coarse_epsilon [default: each solver's fastest, nested for tnnmg, revisit (the paper's) for relaxation with its sweeps, nested for relaxation.inner = multigrid]"),
            );
        }
        cmd
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

/// The settings path each of the harness's own flags sets.
const FLAG_PATHS: [(&str, &str); 5] = [
    (STOPPING, "stopping"),
    (SCHEDULE, "schedule"),
    (CERTIFY_TOL, "certificate.tolerance"),
    (EPSILON, "epsilon"),
    (MAX_FRICTION, "coulomb.max_iterations"),
];

impl<S: SolverSet> clap::FromArgMatches for SettingsArgs<S> {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        // Every change with its position on the command line.
        let mut given: Vec<(usize, Change)> = Vec::new();
        let mut add = |id: &str, path: &str, flag: String| {
            // An id this command does not declare (table1 has its own
            // --schedules) is asked for only through try_get_raw:
            // indices_of panics on it in a debug build.
            let Ok(Some(values)) = m.try_get_raw(id) else {
                return;
            };
            let Some(at) = m.indices_of(id).map(|i| i.collect::<Vec<_>>()) else {
                return;
            };
            for (value, index) in values.zip(at) {
                let value = value.to_string_lossy().into_owned();
                let (path, value) = if id == SET {
                    let (p, v) = value.split_once('=').unwrap_or((value.as_str(), ""));
                    (p.trim().to_string(), v.to_string())
                } else {
                    (path.to_string(), value)
                };
                given.push((
                    index,
                    Change {
                        path,
                        value,
                        given_as: flag.clone(),
                    },
                ));
            }
        };
        for (id, path) in FLAG_PATHS {
            add(id, path, format!("--{id}"));
        }
        add(SET, "", "--set".into());
        given.sort_by_key(|(index, _)| *index);
        Ok(SettingsArgs {
            solvers: std::marker::PhantomData,
            changes: Changes(given.into_iter().map(|(_, c)| c).collect()),
        })
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

    /// `base` (e.g. a scene file's settings) with these flags applied in
    /// the order given, validated, for a run of the solvers `running`: the
    /// library's one resolution ([`Changes::resolve`]), its messages
    /// naming flags.
    pub fn resolve_for(
        &self,
        base: Settings,
        running: &[&'static registry::Entry],
    ) -> Result<Settings> {
        self.resolved(base, running, "")
    }

    /// `base` (e.g. a scene file's settings) with these flags applied in
    /// the order given, validated, for a command that runs the solvers it
    /// offers flags for (all, or only the paper's method).
    pub fn resolve_on(&self, base: Settings) -> Result<Settings> {
        let offered = S::solvers();
        let note = if offered.len() < registry::solvers().len() {
            let names: Vec<&str> = offered.iter().map(|e| e.name).collect();
            format!(" (this command runs only {})", names.join(", "))
        } else {
            String::new()
        };
        self.resolved(base, &offered, &note)
    }

    fn resolved(
        &self,
        base: Settings,
        running: &[&'static registry::Entry],
        note: &str,
    ) -> Result<Settings> {
        self.check_spelling()?;
        self.changes
            .resolve(base, running, &AS_FLAGS)
            .map_err(|r| match r {
                Refusal::Value(m) => anyhow::anyhow!(with_flag(m)),
                Refusal::Unused(m) => anyhow::anyhow!("{m}{note}"),
            })
    }

    /// `--set` written as PATH=VALUE.
    fn check_spelling(&self) -> Result<()> {
        for c in &self.changes.0 {
            if c.given_as == "--set" && (c.path.is_empty() || c.value.trim().is_empty()) {
                bail!(
                    "--set '{}': write it as PATH=VALUE, e.g. --set {}=VALUE",
                    c.path,
                    crate::settings::example_path()
                );
            }
        }
        Ok(())
    }
}

/// Settings named as they are set (`use --set tnnmg.tolerance= instead`).
const AS_FLAGS: Spelling = Spelling {
    verb: "use",
    name: |e, k| knob_set(e.name, k),
};

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
        // A solver's setting is spelt by its path (`--set relaxation.r=`):
        // the message names it already.
        Some(_) | None => None,
    };
    match flag {
        Some(f) => format!("{path} ({f}) {rest}"),
        None => message,
    }
}
