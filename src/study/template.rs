//! Prose in templates: a study's README section is a minijinja template
//! (`src/study/templates/NAME.md`, compiled in) filled with typed facts the
//! study computes from its findings. The sentences are read and edited as
//! text beside the paper; every number in them comes from the trials
//! (issue 76). This module is the engine's part: it knows no study.
//!
//! The environment is strict (a name the facts do not have is an error,
//! not an empty string), keeps a template's trailing newline, and drops
//! the newline after a block tag, so that `{% for %}` lines leave no blank
//! lines in a table. Two filters format numbers as the tables always have:
//! `x|sci(d)` is Rust's `{:.de}` (`5.6e-7`), `x|fixed(d)` is `{:.d}`; a
//! number that is not finite (NaN: not measured) reads `–`. Facts go in
//! as `Serialize` values or `minijinja::context!`, never through
//! `serde_json::Value`, which turns NaN into null.

use anyhow::{Context, Result};
use minijinja::{Environment, UndefinedBehavior};
use serde::Serialize;

/// `x` as `{:.de}`, or `–` when it is not finite.
pub fn sci(x: f64, digits: usize) -> String {
    if x.is_finite() {
        format!("{x:.digits$e}")
    } else {
        "–".into()
    }
}

/// `x` as `{:.d}`, or `–` when it is not finite.
pub fn fixed(x: f64, digits: usize) -> String {
    if x.is_finite() {
        format!("{x:.digits$}")
    } else {
        "–".into()
    }
}

/// The environment every section is rendered in.
fn environment() -> Environment<'static> {
    let mut env = Environment::new();
    env.set_undefined_behavior(UndefinedBehavior::Strict);
    env.set_keep_trailing_newline(true);
    env.set_trim_blocks(true);
    env.add_filter("sci", |x: f64, digits: Option<usize>| {
        sci(x, digits.unwrap_or(1))
    });
    env.add_filter("fixed", |x: f64, digits: Option<usize>| {
        fixed(x, digits.unwrap_or(1))
    });
    env
}

/// The template `name` (its source `source`, from `include_str!`) filled
/// with `facts`.
pub fn render(name: &str, source: &str, facts: impl Serialize) -> Result<String> {
    let mut env = environment();
    env.add_template(name, source)
        .with_context(|| format!("the template {name}"))?;
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
        assert_eq!(sci(f64::NAN, 2), "–");
        assert_eq!(fixed(f64::INFINITY, 1), "–");
        assert!(render("t", "{{ missing }}", minijinja::context! {}).is_err());
    }
}
