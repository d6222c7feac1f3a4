//! The comparison as tables for a paper: one booktabs table per law
//! (`compare_given_friction.tex`, `compare_coulomb.tex`), a group row per
//! problem and mesh, every column of the Markdown table in two panels that
//! fit a page's width (the verdict and the work above, the answer against
//! the reference below). A view of the trials, as the Markdown table is.

use anyhow::Result;
use contactlab_solvers::Law;

use crate::certificate::BoundKind;
use crate::io::latex::{ClaimMarks, Tabular, math, number, text};
use crate::study::compare::{STUDY, iterations};
use crate::study::runner::Measured;
use crate::study::template;

/// The file of `law`'s table.
pub fn file_name(law: Law) -> String {
    format!("compare_{}.tex", law.as_str())
}

/// One table per law the trials solved, with its file name.
pub fn tables(measured: &[Measured], source: &str) -> Result<Vec<(String, String)>> {
    [Law::GivenFriction, Law::Coulomb]
        .into_iter()
        .filter_map(|law| {
            let rows: Vec<&Measured> = measured.iter().filter(|m| m.trial.law == law).collect();
            (!rows.is_empty()).then(|| Ok((file_name(law), table(law, &rows, source)?)))
        })
        .collect()
}

fn table(law: Law, rows: &[&Measured], source: &str) -> Result<String> {
    let reference = rows
        .iter()
        .find_map(|m| m.trial.reference)
        .unwrap_or("none");
    let claims = ClaimMarks::of(
        rows.iter()
            .map(|m| (m.trial.status.as_str(), m.trial.solver_status.as_str())),
    );
    let studies: Vec<String> = {
        let mut v = Vec::new();
        for m in rows.iter().filter(|m| m.trial.study != STUDY) {
            let s = format!("* {}", m.trial.study.replace('_', " "));
            if !v.contains(&s) {
                v.push(s);
            }
        }
        v
    };
    let caption = template::render(
        "compare_caption",
        include_str!("../templates/compare_caption.tex"),
        template::facts! {
            law => law.as_str(),
            reference,
            claims => claims.caption(),
            studies,
            source,
        },
    )?;
    let label = file_name(law);
    let mut verdict = Tabular::new(
        &caption,
        label.trim_end_matches(".tex"),
        vec![
            "solver".into(),
            "status".into(),
            "certificate".into(),
            "iterations".into(),
            "time (s)".into(),
        ],
    );
    let mut answer = Tabular::new(
        &caption,
        label.trim_end_matches(".tex"),
        vec![
            "solver".into(),
            math("\\Delta u"),
            math("\\Delta p"),
            math("\\Delta q"),
            math("\\|\\Delta v\\|_A"),
            "bound".into(),
            "separated".into(),
        ],
    );
    // A group per problem and mesh, in the order they first appear.
    let mut groups = Vec::new();
    for m in rows {
        let key = (m.trial.scene.as_str(), m.trial.h);
        if !groups.contains(&key) {
            groups.push(key);
        }
    }
    for (scene, h) in groups {
        let title = format!("{}, $h = {h}$", text(&capitalized(scene)));
        verdict.group(title.clone());
        answer.group(title);
        for m in rows
            .iter()
            .filter(|m| m.trial.scene == scene && m.trial.h == h)
        {
            verdict.row(verdict_cells(m, &claims));
            answer.row(answer_cells(m));
        }
    }
    Ok(Tabular::stacked(&[verdict, answer]))
}

/// The solver's name, starred when the trial is another study's
/// (the paper's settings), the star named in the caption.
fn solver_cell(m: &Measured) -> String {
    let r = &m.trial;
    if r.study == STUDY {
        text(r.solver.name)
    } else {
        format!("{}$^*$", text(r.solver.name))
    }
}

/// A trial's verdict and work: solver, status, certificate, iterations,
/// time.
fn verdict_cells(m: &Measured, claims: &ClaimMarks) -> Vec<String> {
    let r = &m.trial;
    let status = claims.status(r.status.as_str(), r.solver_status.as_str());
    vec![
        solver_cell(m),
        status,
        number(r.residual()),
        text(&iterations(r)),
        format!("{:.3}", m.timing.seconds_min),
    ]
}

/// A trial's answer against the reference: solver, Δu, Δp, Δq, ‖Δv‖_A,
/// its error bound, the separated share of Γ_K.
fn answer_cells(m: &Measured) -> Vec<String> {
    let r = &m.trial;
    let or_dash = |x: Option<f64>| x.map_or("--".to_string(), number);
    let bound = match r.error_bound() {
        Some(b) if b.kind == BoundKind::AtOwnBound => {
            format!("{}$^\\dagger$", number(b.displacement))
        }
        Some(b) => number(b.displacement),
        None => "--".into(),
    };
    vec![
        solver_cell(m),
        or_dash(r.displacement_error()),
        or_dash(r.pressure_error()),
        or_dash(r.agreement.map(|a| a.traction_max)),
        or_dash(r.agreement.map(|a| a.energy)),
        bound,
        format!("{:.1}\\%", 100.0 * r.separated_fraction),
    ]
}

fn capitalized(s: &str) -> String {
    let mut c = s.chars();
    c.next()
        .map(|f| f.to_uppercase().chain(c).collect())
        .unwrap_or_default()
}
