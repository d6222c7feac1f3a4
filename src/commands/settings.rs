//! `contactlab settings [SOLVER]`: every setting, by path (as `--set`
//! and scene files spell it), its default and the paper's value, from the registry (so a new solver's
//! settings are listed without a line here).

use anyhow::Result;
use contactlab_solvers::registry;

use crate::cli::SettingsListArgs;
use crate::coulomb::fixed_point;
use crate::io::output::print;

pub fn run(args: &SettingsListArgs) -> Result<()> {
    let mut text = String::new();
    if args.solver.is_none() {
        text += &format!(
            "certificate (the check of every answer, and its error bound)\n  --certify-tol TOL  (--set certificate.tolerance=TOL)\n      the largest violation of any condition, in the problem's scales, that certifies an answer [default {:e}]\n  --set certificate.bound_max_unknowns\n      bound the error of answers of problems up to this many unknowns, in `solve` and in every study's trials (finer, the bound costs several times the fastest solve: at 1/1024 13 s beside tnnmg's 3.5 s); 0: never [default {} (h = 1/512)]\n\n",
            crate::certificate::DEFAULT_TOLERANCE,
            crate::certificate::SOLVE_BOUND_MAX_UNKNOWNS
        );
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
            text += &format!("  --set {}.{}=VALUE\n      {}\n", e.name, k.name, e.help(k));
        }
    }
    print(&text)
}
