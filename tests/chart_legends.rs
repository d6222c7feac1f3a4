//! Charts a reader cannot misread: every chart of a run of the studies
//! (the smoke run, with every registered solver) has a legend of at most
//! [`MAX_LEGEND`] entries once drawn. A chart that lists every solver's
//! failed points apart, or stacks the problems of a map into one legend
//! (`stability_friction` had 25 entries), fails here. A series' failed
//! points (crosses) are drawn in the colour of its line (the sweep's
//! crosses once took the next series' colour).

use contactlab::io::charts::{Chart, MAX_LEGEND, Style, legend_entries};
use contactlab::settings::Settings;
use contactlab::study::lab::{Content, Lab, Quiet};
use contactlab::study::reproduce::{ReproduceSpec, studies};

#[test]
#[ignore = "heavy (every study of a smoke run: 60-90 s): `cargo test --release -- --ignored` runs it, and CI does"]
fn every_chart_of_a_run_has_a_legend_of_at_most_twelve() {
    let settings = Settings::default();
    let spec = ReproduceSpec::quick();
    let mut lab = Lab::new(settings.clone(), &|_| {}, &Quiet);
    let mut charts = 0;
    for study in studies(&spec, &settings) {
        let (artifacts, _) = study.run_for_report(&mut lab).unwrap();
        for a in &artifacts {
            if let Content::Chart(c) = &a.content {
                charts += 1;
                let n = legend_entries(c);
                assert!(n <= MAX_LEGEND, "{}: {n} legend entries", a.path);
                failed_points_in_their_series_colour(&a.path, c);
            }
        }
    }
    assert!(charts >= 40, "only {charts} charts");
}

/// Every `X, not certified` or `X: not certified` series has the colour of
/// the line of X.
fn failed_points_in_their_series_colour(path: &str, c: &Chart) {
    for s in c.series.iter().filter(|s| s.style == Style::Failed) {
        let Some(base) = s
            .name
            .strip_suffix(", not certified")
            .or_else(|| s.name.strip_suffix(": not certified"))
        else {
            continue;
        };
        if let Some(line) = c
            .series
            .iter()
            .find(|l| l.style != Style::Failed && l.name.starts_with(base))
        {
            assert!(
                s.color.is_some() && s.color == line.color,
                "{path}: '{}' in colour {:?}, its line '{}' in {:?}",
                s.name,
                s.color,
                line.name,
                line.color
            );
        }
    }
}
