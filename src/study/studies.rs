//! The catalog of studies: every catalogued study ([`crate::study::catalog::Catalogued`]), the
//! one list the command line's study commands, Python's `study` calls and
//! `reproduce` are made from. A new study is one line in [`library`].

use anyhow::{Result, bail};

use crate::study::bench::goals::Bench;
use crate::study::catalog::{Entry, Of};
use crate::study::discretization_error::Errors;
use crate::study::error_bound::ErrorBoundStudy;
use crate::study::oracle::Oracle;
use crate::study::stability::Stability;
use crate::study::table1::Table1;
use crate::study::verify::VerifyStudy;

/// Every catalogued study, in the order `reproduce` runs them: the
/// library's, then those a program added ([`register`]). A new study is
/// one line here.
pub fn catalog() -> Vec<&'static dyn Entry> {
    let mut out = library();
    out.extend(ADDED.read().unwrap_or_else(|e| e.into_inner()).iter());
    out
}

/// The library's own studies.
fn library() -> Vec<&'static dyn Entry> {
    vec![
        &Of::<Table1>::ENTRY,
        &Of::<Stability>::ENTRY,
        &Of::<Bench>::ENTRY,
        &Of::<Errors>::ENTRY,
        &Of::<Oracle>::ENTRY,
        &Of::<ErrorBoundStudy>::ENTRY,
        &Of::<VerifyStudy>::ENTRY,
    ]
}

/// Studies a program added to the catalog ([`register`]).
static ADDED: std::sync::RwLock<Vec<&'static dyn Entry>> = std::sync::RwLock::new(Vec::new());

/// Adds the study of `entry` to the catalog of this process, after the
/// library's: its command, its Python call and its place in `reproduce`
/// (what a program built on the library, or a test, does). A command
/// already there is an error.
pub fn register(entry: &'static dyn Entry) -> Result<()> {
    let mut added = ADDED.write().unwrap_or_else(|e| e.into_inner());
    if library()
        .iter()
        .chain(added.iter())
        .any(|e| e.command() == entry.command())
    {
        bail!(
            "a study called {:?} is already in the catalog",
            entry.command()
        );
    }
    added.push(entry);
    Ok(())
}

/// The catalogued study called `command`.
pub fn by_command(command: &str) -> Option<&'static dyn Entry> {
    catalog().into_iter().find(|e| e.command() == command)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::lab::RunLength;

    /// Every library study's own spec, at every run length, is one its
    /// check accepts, reads back from its JSON form to the same, and
    /// names a command no other study has.
    #[test]
    fn every_catalogued_spec_is_valid_and_round_trips() {
        let mut commands: Vec<&str> = Vec::new();
        for e in library() {
            assert!(!commands.contains(&e.command()), "{} twice", e.command());
            commands.push(e.command());
            for length in [RunLength::Quick, RunLength::Standard, RunLength::Long] {
                e.planned(length, &crate::settings::Settings::default())
                    .unwrap();
                let json = e.spec_json(length).unwrap();
                let again = e.planned_with_json(length, &json.to_string()).unwrap();
                assert_eq!(
                    again.name(),
                    e.planned(length, &crate::settings::Settings::default())
                        .unwrap()
                        .name()
                );
            }
        }
    }

    /// A field the spec does not have, or a value of the wrong type, is a
    /// one-line error naming it.
    #[test]
    fn a_wrong_parameter_is_named() {
        let e = by_command("discretization-error").unwrap();
        let unknown = e.planned_with_json(RunLength::Quick, r#"{"mesh": ["1/8"]}"#);
        let m = format!("{:#}", unknown.err().unwrap());
        assert!(m.contains("\"mesh\"") && m.contains("meshes"), "{m}");
        let wrong = e.planned_with_json(RunLength::Quick, r#"{"meshes": ["1/3"]}"#);
        let m = format!("{:#}", wrong.err().unwrap());
        assert!(m.contains("power-of-two"), "{m}");
        let finer = e.planned_with_json(
            RunLength::Quick,
            r#"{"meshes": ["1/64"], "reference": "1/32"}"#,
        );
        let m = format!("{:#}", finer.err().unwrap());
        assert!(m.contains("finer than the reference"), "{m}");
        assert!(!m.contains('\n'), "{m}");
    }
}
