//! The list of solvers the harness knows: adding a solver is its own file
//! (which defines its [`Entry`], see [`crate::entry`]) plus one line in
//! [`SOLVERS`], or a call to [`register`] at run time.

use std::sync::RwLock;

pub use crate::entry::*;
#[cfg(test)]
use crate::settings::Stopping;

/// The registry.
pub const SOLVERS: &[&Entry] = &[
    &crate::conic::ENTRY,
    &crate::relaxation::ENTRY,
    &crate::newton::tresca::ENTRY,
    &crate::conic::ENTRY_QP,
    &crate::conic::ENTRY_FAER,
    &crate::conic::ENTRY_CONDENSED,
    &crate::splitting::nsgs::ENTRY,
    &crate::splitting::apgd::ENTRY,
    &crate::splitting::admm::ENTRY,
    &crate::newton::coulomb::ENTRY,
    &crate::multigrid::ENTRY,
];

/// Solvers registered at run time (by a program that embeds contactlab, or
/// a test), after the built-in ones.
static REGISTERED: RwLock<Vec<&'static Entry>> = RwLock::new(Vec::new());

/// Registers a solver at run time; every command and study sees it from
/// then on. Names must be unique.
pub fn register(entry: &'static Entry) -> Result<(), String> {
    if by_name(entry.name).is_some() {
        return Err(format!(
            "a solver named '{}' is registered already",
            entry.name
        ));
    }
    REGISTERED
        .write()
        .map_err(|_| "the registry lock is poisoned".to_string())?
        .push(entry);
    Ok(())
}

/// Every registered solver: the built-in ones, then those registered at run time.
pub fn solvers() -> Vec<&'static Entry> {
    let mut all: Vec<&'static Entry> = SOLVERS.to_vec();
    if let Ok(extra) = REGISTERED.read() {
        all.extend(extra.iter().copied());
    }
    all
}

/// The solver with a role (the paper's method, the oracle), if registered.
pub fn with_role(role: Role) -> Option<&'static Entry> {
    solvers().into_iter().find(|e| e.role == role)
}

/// The oracle and its registered variants: the entries with the oracle's
/// laws and knobs (the same program with other defaults: another
/// formulation, linear solver or condensation). Empty without an oracle.
pub fn oracle_family() -> Vec<&'static Entry> {
    let Some(oracle) = with_role(Role::Oracle) else {
        return Vec::new();
    };
    let knobs = |e: &Entry| e.knobs.iter().map(|k| k.name).collect::<Vec<_>>();
    solvers()
        .into_iter()
        .filter(|e| e.laws == oracle.laws && knobs(e) == knobs(oracle))
        .collect()
}

/// Looks a solver up by name.
pub fn by_name(name: &str) -> Option<&'static Entry> {
    solvers().into_iter().find(|e| e.name == name)
}

/// The registered names, for messages.
pub fn names() -> Vec<&'static str> {
    solvers().iter().map(|e| e.name).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_entry_is_consistent() {
        for e in SOLVERS {
            assert!(e.stage(e.work_stage).is_some(), "{}: work stage", e.name);
            for stopping in [Stopping::Relative, Stopping::Paper] {
                let tree = (e.defaults)(stopping);
                e.build
                    .call(&tree)
                    .unwrap_or_else(|m| panic!("{}: defaults: {m}", e.name));
                for k in e.knobs {
                    for f in k.fields {
                        assert!(tree.get(f).is_some(), "{}.{}: no field {f}", e.name, k.name);
                    }
                }
            }
            assert!(
                e.knob(e.accuracy.knob).is_some(),
                "{}: accuracy knob",
                e.name
            );
        }
        let mut names = names();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), SOLVERS.len(), "names are unique");
        for role in [Role::PapersMethod, Role::Oracle] {
            let n = SOLVERS.iter().filter(|e| e.role == role).count();
            assert!(n <= 1, "at most one solver has role {role:?}");
        }
    }

    #[test]
    fn the_oracle_family_is_the_oracle_and_its_variants_only() {
        let family: Vec<&str> = oracle_family().iter().map(|e| e.name).collect();
        let oracle = with_role(Role::Oracle).expect("registered");
        let paper = with_role(Role::PapersMethod).expect("registered");
        assert!(family.contains(&oracle.name), "{family:?}");
        assert!(!family.contains(&paper.name), "{family:?}");
        for name in &family {
            let e = by_name(name).expect("registered");
            assert_eq!(e.laws, oracle.laws, "{name} solves other laws");
        }
    }
}
