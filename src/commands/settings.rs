//! `contactlab settings [SOLVER]`: every setting, by path, with its flag,
//! its default and the paper's value, from the registry (so a new solver's
//! settings are listed without a line here).

use anyhow::Result;
use contactlab_solvers::registry;

use crate::cli::SettingsListArgs;
use crate::cli::settings_args::knob_flag;
use crate::coulomb::fixed_point;
use crate::io::output::print;

pub fn run(args: &SettingsListArgs) -> Result<()> {
    let mut text = String::new();
    if args.solver.is_none() {
        text += "coulomb (the friction fixed point of paper (9), every solver that is not a Coulomb solver)\n";
        for k in fixed_point::KNOBS {
            text += &format!(
                "  --set coulomb.{}\n      {}\n",
                k.name,
                k.help_with_default(fixed_point::default_tree)
            );
        }
    }
    for e in registry::solvers()
        .into_iter()
        .filter(|e| args.solver.as_deref().is_none_or(|s| s == e.name))
    {
        text += &format!("\n{} ({})\n", e.name, e.about);
        for k in e.knobs {
            text += &format!(
                "  --{} VALUE  (--set {}.{}=VALUE)\n      {}\n",
                knob_flag(e.name, k),
                e.name,
                k.name,
                e.help(k)
            );
        }
    }
    print(&text)
}
