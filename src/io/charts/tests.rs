use super::*;

#[test]
fn tick_labels_read_well() {
    assert_eq!(tick_label(-7e-21, false, 6e-5), "0");
    assert_eq!(tick_label(10.0, false, 100.0), "10");
    assert_eq!(tick_label(0.25, false, 1.0), "0.25");
    assert_eq!(tick_label(2e-5, false, 6e-5), "2e-5");
    assert_eq!(tick_label(2.5e-5, false, 6e-5), "2.5e-5");
    assert_eq!(tick_label(1e-3, true, 1.0), "1e-3");
    assert_eq!(tick_label(30000.0, false, 1e5), "30000");
}

#[test]
fn log_axes_are_labelled_at_every_decade() {
    assert_eq!(
        decades(0.5e-9, 2e-3),
        (-9..=-3).map(|k| 10f64.powi(k)).collect::<Vec<_>>()
    );
    // Less than two decades: 1, 2, 5 in each.
    assert_eq!(decades(1.5, 30.0), vec![2.0, 5.0, 10.0, 20.0]);
    // Times of 2.0-2.15 s, padded by 1.5: 2 alone of 1, 2, 5 would be one
    // tick; every half mantissa gives more.
    assert_eq!(decades(2.0 / 1.5, 2.15 * 1.5), vec![1.5, 2.0, 2.5, 3.0]);
    // Every range the charts draw (at least a factor 2.25) has two ticks.
    for k in 0..200 {
        let lo = 10f64.powf(-3.0 + k as f64 * 0.037);
        assert!(decades(lo, 2.25 * lo).len() >= 2, "{lo}");
    }
}

/// A long title shrinks to the plot's width instead of running off both
/// sides; a short one keeps its size.
#[test]
fn titles_fit_the_plot() {
    use super::render::title_size;
    assert_eq!(title_size("A title", 720), 17);
    let long = "Iterations against relaxation.epsilon (inner = multigrid), problem 1, h = 1/256, and more words";
    let size = title_size(long, 720);
    assert!(size < 17 && (0.6 * size as f64 * long.chars().count() as f64) <= 720.0 - 28.0);
}

#[test]
fn svg_has_title_axes_and_every_series() {
    for (log_x, log_y) in [(false, false), (true, true), (true, false), (false, true)] {
        let chart = Chart::new(
            "A title",
            "x label [m]",
            "y label [s]",
            log_x,
            log_y,
            vec![
                Series::line("first", vec![(1.0, 2.0), (10.0, 20.0)]),
                Series::line("second", vec![(2.0, 1.0), (5.0, f64::NAN), (20.0, 3.0)]).dashed(),
                Series::line("third", vec![(3.0, 3.0)]).scatter(),
                Series::line("fourth", vec![(4.0, 3.0)]).failed(),
            ],
        );
        let svg = chart.to_svg().unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        for text in [
            "A title",
            "x label [m]",
            "y label [s]",
            "first",
            "second",
            "third",
            "fourth",
        ] {
            assert!(svg.contains(text), "missing {text}");
        }
    }
}

#[test]
fn round_off_is_drawn_as_zero() {
    let drawn = |points: Vec<(f64, f64)>| {
        Chart::new("t", "x", "y", false, false, vec![Series::line("s", points)])
            .with_y_resolution(1e-9)
            .drawable()[0]
            .clone()
    };
    assert_eq!(
        drawn(vec![(0.0, 1e-13), (1.0, -2e-13)]),
        vec![(0.0, 0.0), (1.0, 0.0)]
    );
    // A real value stays.
    assert_eq!(drawn(vec![(0.0, 1e-6)]), vec![(0.0, 1e-6)]);
}

#[test]
fn legend_labels_are_written_whole_and_the_panel_widens_for_them() {
    let long = "clarabel-condensed: not certified (no slope: 2 points)";
    let chart = Chart::new(
        "t",
        "x",
        "y",
        true,
        true,
        vec![
            Series::line(long, vec![(1.0, 1.0), (10.0, 10.0)]).failed(),
            Series::line("short", vec![(1.0, 2.0), (10.0, 20.0)]),
        ],
    );
    let svg = chart.to_svg().unwrap();
    assert!(svg.contains(long), "the long label is cut");
    assert!(!svg.contains('…'));
    assert!(chart.legend_width() > LEGEND_WIDTH);
    // A chart of short labels keeps the standard size.
    let short = Chart::new(
        "t",
        "x",
        "y",
        false,
        false,
        vec![Series::line("s", vec![(0.0, 1.0)])],
    );
    assert_eq!(short.legend_width(), LEGEND_WIDTH);
}

#[test]
fn a_log_axis_only_for_values_over_a_decade() {
    // ω in (0, 2) reads on a linear axis; r from 0.1 to 1000 on a log one.
    assert!(!suits_log_axis([0.8, 1.0, 1.2, 1.5, 1.8]));
    assert!(suits_log_axis([0.1, 1.0, 10.0, 1000.0]));
    assert!(!suits_log_axis([0.0, 1.0, 100.0]));
    assert!(!suits_log_axis(std::iter::empty()));
}

#[test]
fn series_that_coincide_are_one_legend_row_naming_them_all() {
    let same = vec![(1.0, 1.0), (10.0, 0.1)];
    let chart = Chart::new(
        "t",
        "x",
        "y",
        true,
        true,
        vec![
            Series::line("clarabel", same.clone()).of_solver("clarabel"),
            Series::line("clarabel-faer", same).of_solver("clarabel-faer"),
            Series::line("newton", vec![(1.0, 2.0), (10.0, 0.5)]).of_solver("newton"),
        ],
    );
    let svg = chart.to_svg().unwrap();
    assert!(svg.contains("clarabel / clarabel-faer (same points)"));
    // Neither has a row of its own; newton keeps its row.
    assert!(!svg.contains("\nclarabel\n") && !svg.contains("\nclarabel-faer\n"));
    assert!(svg.contains("\nnewton\n"));
}

/// Every registered solver has its own colour and marker, the same in
/// every chart, and the first sixty style indices are all distinct (so 16
/// solvers, or more, never share one): with ten colours `clarabel` and
/// `tnnmg` shared theirs.
#[test]
fn every_solver_has_its_own_colour_and_marker() {
    let styles: Vec<_> = (0..60).map(style_of).collect();
    for i in 0..styles.len() {
        for j in i + 1..styles.len() {
            assert_ne!(styles[i], styles[j], "style indices {i} and {j}");
        }
    }
    let names = registry::names();
    let mut of_solvers: Vec<usize> = names.iter().map(|n| solver_color(n)).collect();
    of_solvers.sort();
    of_solvers.dedup();
    assert_eq!(of_solvers.len(), names.len());
    // The first sixteen differ in colour alone, not only in marker.
    let colours: Vec<_> = (0..16).map(|k| style_of(k).0).collect();
    for i in 0..16 {
        for j in i + 1..16 {
            assert_ne!(colours[i], colours[j], "colours {i} and {j}");
        }
    }
}

/// A legend of more than twelve entries lists the failed points once:
/// twenty solvers with failures give twenty lines and one cross entry, and
/// the crosses keep their solvers' colours on the plot.
#[test]
fn a_long_legend_lists_the_failed_points_once() {
    let mut series = Vec::new();
    for k in 0..10 {
        let name = format!("solver {k}");
        series.extend(Series::certified_and_failed(
            &name,
            vec![(1.0, 1.0 + k as f64), (2.0, 2.0 + k as f64)],
            vec![(3.0, 5.0 + k as f64)],
        ));
    }
    let chart = Chart::new("many", "x", "y", false, false, series);
    assert_eq!(chart.series.len(), 20);
    assert_eq!(legend_entries(&chart), 11);
    let svg = chart.to_svg().unwrap();
    assert!(svg.contains("not certified (crosses, in each solver"));
    assert!(!svg.contains("solver 3: not certified"));
    // A short legend is left as it is.
    let few = Chart::new(
        "few",
        "x",
        "y",
        false,
        false,
        Series::certified_and_failed("a", vec![(1.0, 1.0)], vec![(2.0, 2.0)]),
    );
    assert_eq!(legend_entries(&few), 2);
}

#[test]
fn a_log_chart_with_nothing_positive_on_it_renders_without_decades() {
    // A verify chart whose solvers all failed has only empty series, or a
    // zero error; its log axis then has no positive value. Before the
    // guard, log10(0) as an i32 (i32::MIN) made `decades` ask for 17 GB.
    assert!(decades(0.0, 1.0).is_empty());
    assert!(decades(f64::NAN, 1.0).is_empty());
    assert!(decades(1.0, f64::INFINITY).is_empty());
    assert!(decades(2.0, 1.0).is_empty());
    for series in [
        vec![Series::line("empty", vec![])],
        vec![Series::line("zero", vec![(1.0, 0.0), (2.0, 0.0)])],
    ] {
        let chart = Chart::new("Nothing", "h", "error", true, true, series);
        let svg = chart.to_svg().unwrap();
        assert!(svg.contains("Nothing"));
    }
}
