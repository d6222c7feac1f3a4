//! The comparison as tables for a paper: one booktabs table per law
//! (`compare_given_friction.tex`, `compare_coulomb.tex`), eight columns,
//! a group row per problem and mesh. A view of the trials, as the Markdown
//! table is.

use contactlab_solvers::Law;

use crate::io::latex::{Tabular, math, number, text};
use crate::study::compare::STUDY;
use crate::study::runner::Measured;

/// The file of `law`'s table.
pub fn file_name(law: Law) -> String {
    format!("compare_{}.tex", law.as_str())
}

/// One table per law the trials solved, with its file name.
pub fn tables(measured: &[Measured], source: &str) -> Vec<(String, String)> {
    [Law::GivenFriction, Law::Coulomb]
        .into_iter()
        .filter_map(|law| {
            let rows: Vec<&Measured> = measured.iter().filter(|m| m.trial.law == law).collect();
            (!rows.is_empty()).then(|| (file_name(law), table(law, &rows, source)))
        })
        .collect()
}

fn table(law: Law, rows: &[&Measured], source: &str) -> String {
    let what = match law {
        Law::GivenFriction => {
            "the given-friction subproblem, paper (10), at g = 𝓕p of the reference"
        }
        Law::Coulomb => "the Coulomb problem, paper (9)",
    };
    let reference = rows
        .iter()
        .find_map(|m| m.trial.reference)
        .unwrap_or("none");
    let comment = format!(
        "{what}: each solver against the reference ({reference}, the most accurate certified answer of the exact solvers). \
         Delta: max difference from the reference over its largest value (u: displacements, p: pressures, q: friction tractions); \
         certificate: the largest violation of the law's conditions in the problem's scales; iterations: [friction:] outer [/ inner]; \
         time: minimum over the runs ({source})"
    );
    let header = vec![
        "solver".into(),
        "status".into(),
        math("\\Delta u"),
        math("\\Delta p"),
        math("\\Delta q"),
        "certificate".into(),
        "iterations".into(),
        "time (s)".into(),
    ];
    let mut t = Tabular::new(&comment, header);
    // A group per problem and mesh, in the order they first appear.
    let mut groups = Vec::new();
    for m in rows {
        let key = (m.trial.scene.as_str(), m.trial.h);
        if !groups.contains(&key) {
            groups.push(key);
        }
    }
    for (scene, h) in groups {
        t.group(format!("{}, $h = {h}$", text(&capitalized(scene))));
        for m in rows
            .iter()
            .filter(|m| m.trial.scene == scene && m.trial.h == h)
        {
            t.row(cells(m));
        }
    }
    t.render()
}

/// One trial's eight cells.
fn cells(m: &Measured) -> Vec<String> {
    let r = &m.trial;
    {
        let solver = if r.study == STUDY {
            r.solver.name.to_string()
        } else {
            format!("{} ({})", r.solver.name, r.study.replace('_', " "))
        };
        let iterations = match (r.friction_iterations, r.inner_iterations) {
            (0, 0) => format!("{}", r.outer_iterations),
            (0, i) => format!("{} / {i}", r.outer_iterations),
            (f, 0) => format!("{f}: {}", r.outer_iterations),
            (f, i) => format!("{f}: {} / {i}", r.outer_iterations),
        };
        let or_dash = |x: Option<f64>| x.map_or("--".to_string(), number);
        vec![
            text(&solver),
            text(r.status.as_str()),
            or_dash(r.displacement_error()),
            or_dash(r.pressure_error()),
            or_dash(r.agreement.map(|a| a.traction_max)),
            number(r.residual()),
            text(&iterations),
            format!("{:.3}", m.timing.seconds_min),
        ]
    }
}

fn capitalized(s: &str) -> String {
    let mut c = s.chars();
    c.next()
        .map(|f| f.to_uppercase().chain(c).collect())
        .unwrap_or_default()
}
