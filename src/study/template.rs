//! Prose in templates: a study's README section is a minijinja template
//! (`src/study/templates/NAME.md`, compiled in) filled with typed facts the
//! study computes from its findings. The sentences are read and edited as
//! text beside the paper; every number in them comes from the trials
//! (issue 76). This module is the engine's part: it knows no study.
//!
//! The environment is strict (a name the facts do not have is an error,
//! not an empty string), keeps a template's trailing newline, and drops
//! the newline after a block tag, so that `{% for %}` lines leave no blank
//! lines in a table. Filters format numbers as the tables always have:
//! `x|sci(d)` is Rust's `{:.de}` (`5.6e-7`), `x|fixed(d)` is `{:.d}`,
//! `x|exp` is `{:e}` (`1e-6`), `x|plain` is `{}` (`10`), `x|percent(d)` is `{:.d} %` of 100 x; a
//! number that is not finite (NaN), or none (an `Option` not measured),
//! reads `–`. Facts go in as a `Serialize` value or through [`facts!`]
//! (`minijinja::context!` with rows serialized as typed values,
//! [`crate::io::csv::typed`], so that a row whose floats a CSV file holds
//! as text gives the template its numbers), never through
//! `serde_json::Value`, which turns NaN into null.

use anyhow::{Context, Result};
use minijinja::{Environment, UndefinedBehavior, Value};
use serde::Serialize;

/// The facts of a template: `minijinja::context!`, its values serialized
/// as typed values (a [`crate::io::csv::fixed`] field is its number, none
/// if not finite), as [`render`] serializes a `Serialize` value.
macro_rules! facts {
    ($($tt:tt)*) => {
        $crate::io::csv::typed(|| minijinja::context! { $($tt)* })
    };
}
pub(crate) use facts;

/// A filter's argument as a number, `None` for none (not measured); a
/// name the facts lack (undefined) or a value that is not a number is an
/// error, so that a misspelt fact does not read `–`.
fn number(x: &Value) -> Result<Option<f64>, minijinja::Error> {
    if x.is_undefined() {
        return Err(minijinja::Error::from(minijinja::ErrorKind::UndefinedError));
    }
    if x.is_none() {
        return Ok(None);
    }
    f64::try_from(x.clone()).map(Some)
}

/// `x` written by `format`, or `–` when it is none or not finite: every
/// filter's rule for what was not measured.
fn shown(x: &Value, format: impl Fn(f64) -> String) -> Result<String, minijinja::Error> {
    Ok(number(x)?
        .filter(|x| x.is_finite())
        .map_or_else(|| "–".into(), format))
}

/// The environment every section is rendered in, with its filters:
/// `sci(d)` is `{:.de}`, `fixed(d)` is `{:.d}` (d = 1 when not given),
/// `exp` is `{:e}` (its shortest exact form, a setting as the user wrote
/// it), `plain` is `{}` (`10` where the template's own printing would
/// write `10.0`), `percent(d)` is `{:.d} %` of 100 x (d = 0).
fn environment() -> Environment<'static> {
    let mut env = Environment::new();
    env.set_undefined_behavior(UndefinedBehavior::Strict);
    env.set_keep_trailing_newline(true);
    env.set_trim_blocks(true);
    env.add_filter("sci", |x: Value, d: Option<usize>| {
        let d = d.unwrap_or(1);
        shown(&x, |x| format!("{x:.d$e}"))
    });
    env.add_filter("fixed", |x: Value, d: Option<usize>| {
        let d = d.unwrap_or(1);
        shown(&x, |x| format!("{x:.d$}"))
    });
    env.add_filter("exp", |x: Value| shown(&x, |x| format!("{x:e}")));
    env.add_filter("plain", |x: Value| shown(&x, |x| format!("{x}")));
    env.add_filter("percent", |x: Value, d: Option<usize>| {
        let d = d.unwrap_or(0);
        shown(&x, |x| format!("{:.d$} %", 100.0 * x))
    });
    env
}

/// The template `name` (its source `source`, from `include_str!`) filled
/// with `facts`.
pub fn render(name: &str, source: &str, facts: impl Serialize) -> Result<String> {
    let mut env = environment();
    env.add_template(name, source)
        .with_context(|| format!("the template {name}"))?;
    let facts = crate::io::csv::typed(|| Value::from_serialize(&facts));
    env.get_template(name)?
        .render(facts)
        .with_context(|| format!("rendering the template {name}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The filters are the tables' formats; a missing fact is an error, not
    /// an empty cell; a `{% for %}` line leaves no line of its own, and the
    /// last newline stays. A lenient environment, or a filter that rounds
    /// differently, fails here.
    #[test]
    fn numbers_are_formatted_as_the_tables_were_and_a_missing_fact_is_an_error() {
        let t = "| a |\n{% for x in xs %}\n| {{ x|sci(1) }} | {{ x|fixed(2) }} |\n{% endfor %}\n\n";
        let xs = [5.5621e-7, 1.0 / 3.0, f64::NAN];
        let out = render("t", t, minijinja::context! { xs }).unwrap();
        assert_eq!(
            out,
            "| a |\n| 5.6e-7 | 0.00 |\n| 3.3e-1 | 0.33 |\n| – | – |\n\n"
        );
        let inf = f64::INFINITY;
        let out = render(
            "t",
            "{{ x|sci(2) }} {{ x|fixed(1) }} {{ x|plain }}",
            minijinja::context! { x => inf },
        );
        assert_eq!(out.unwrap(), "– – –");
        assert!(render("t", "{{ missing }}", minijinja::context! {}).is_err());
        // none is "not measured"; a name the facts lack stays an error
        // through a filter.
        let none: Option<f64> = None;
        let out = render("t", "{{ x|sci(2) }}", minijinja::context! { x => none }).unwrap();
        assert_eq!(out, "–");
        assert!(render("t", "{{ y|sci(2) }}", minijinja::context! {}).is_err());
        assert!(
            render(
                "t",
                "{{ r.y|fixed }}",
                minijinja::context! { r => minijinja::context! {} }
            )
            .is_err()
        );
    }

    /// A row whose floats a CSV file holds as text (`serialize_with =
    /// "fixed"`) gives the template its numbers, through [`facts!`] and
    /// through a `Serialize` value alike; a string where a number belongs
    /// is an error. The other filters: `{:e}`, `{}` and a percentage.
    #[test]
    fn a_csv_row_gives_the_template_numbers() {
        #[derive(Serialize)]
        struct Row {
            #[serde(serialize_with = "crate::io::csv::fixed")]
            x: f64,
            #[serde(serialize_with = "crate::io::csv::fixed")]
            y: f64,
        }
        let row = Row {
            x: 0.25,
            y: f64::NAN,
        };
        let t = "{{ r.x|sci(1) }} {{ r.x|percent }} {{ r.y|fixed(2) }}";
        let out = render("t", t, facts! { r => row }).unwrap();
        assert_eq!(out, "2.5e-1 25 % –");
        #[derive(Serialize)]
        struct Facts {
            r: Row,
        }
        let out = render(
            "t",
            t,
            Facts {
                r: Row {
                    x: 0.25,
                    y: f64::NAN,
                },
            },
        )
        .unwrap();
        assert_eq!(out, "2.5e-1 25 % –");
        assert!(render("t", "{{ s|sci }}", facts! { s => "0.25" }).is_err());
        let out = render(
            "t",
            "{{ a|exp }} {{ b|plain }}",
            facts! { a => 1e-6, b => 10.0 },
        )
        .unwrap();
        assert_eq!(out, "1e-6 10");
        // typed mode ends with the facts: the CSV text is back after.
        let csv =
            String::from_utf8(crate::io::csv::to_csv(&[Row { x: 0.25, y: 1.0 }], &[]).unwrap())
                .unwrap();
        assert!(csv.contains("2.500000000e-1"), "{csv}");
    }
}
