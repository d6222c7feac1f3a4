//! Charts a reader cannot misread: every chart of a run of the studies
//! (the smoke run, with every registered solver) has a legend of at most
//! [`MAX_LEGEND`] entries once drawn. A chart that lists every solver's
//! failed points apart, or stacks the problems of a map into one legend
//! (`stability_friction` had 25 entries), fails here.

use contactlab::io::charts::{MAX_LEGEND, legend_entries};
use contactlab::settings::Settings;
use contactlab::study::lab::{Content, Lab, Quiet};
use contactlab::study::reproduce::{ReproduceSpec, studies};

#[test]
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
            }
        }
    }
    assert!(charts >= 40, "only {charts} charts");
}
