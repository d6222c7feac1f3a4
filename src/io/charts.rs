//! SVG charts (plotters, SVG backend only: no system font libraries needed;
//! text is written as SVG `<text>`). One description type, [`Chart`], for
//! every chart the harness draws, with the rules that make them readable:
//! the legend in its own panel right of the plot (never over data), log
//! axes labelled at every decade, values below the chart's resolution drawn
//! as zero (round-off is not structure), failed points drawn as crosses, and
//! one colour per solver across every chart ([`solver_color`]), series
//! that coincide drawn as one whose legend names them all
//! ([`overlap::merge_identical`]), and optional ticks at given values with
//! their own labels (the meshes of a convergence plot).

use std::path::Path;

use anyhow::Result;
use contactlab_solvers::registry;
use plotters::prelude::*;

use crate::io::output::write_atomic;

/// How a series is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Style {
    /// A line.
    #[default]
    Line,
    /// A line with a dot at each point.
    LineMarkers,
    /// Dots only.
    Dots,
    /// A dashed line (a reference level, or a second loop of one solver).
    Dashed,
    /// Crosses only: points whose answer failed (not certified, or stopped).
    Failed,
}

/// One named curve.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub style: Style,
    /// Index into the palette; None: by the series' position.
    pub color: Option<usize>,
    /// Whether the legend lists it (a chart with more than
    /// [`MAX_LEGEND`] entries lists its failed points once for all).
    pub legend: bool,
    /// Points labelled on the chart (a work-precision point's target).
    pub labels: Vec<((f64, f64), String)>,
}

/// The most entries a legend lists: beyond, a reader cannot match colours
/// to names.
pub const MAX_LEGEND: usize = 12;

impl Series {
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            style: Style::Line,
            color: None,
            legend: true,
            labels: Vec::new(),
        }
    }

    /// Labels drawn beside these points.
    pub fn with_labels(mut self, labels: Vec<((f64, f64), String)>) -> Self {
        self.labels = labels;
        self
    }

    pub fn with_markers(mut self) -> Self {
        self.style = Style::LineMarkers;
        self
    }

    pub fn scatter(mut self) -> Self {
        self.style = Style::Dots;
        self
    }

    pub fn dashed(mut self) -> Self {
        self.style = Style::Dashed;
        self
    }

    pub fn failed(mut self) -> Self {
        self.style = Style::Failed;
        self
    }

    /// One solver's certified points as a line with markers and, when there
    /// are any, its uncertified points as crosses in the same colour.
    pub fn certified_and_failed(
        solver: &str,
        certified: Vec<(f64, f64)>,
        failed: Vec<(f64, f64)>,
    ) -> Vec<Series> {
        let mut out = Vec::new();
        if !certified.is_empty() {
            out.push(
                Series::line(solver, certified)
                    .with_markers()
                    .of_solver(solver),
            );
        }
        if !failed.is_empty() {
            out.push(
                Series::line(format!("{solver}: not certified"), failed)
                    .failed()
                    .of_solver(solver),
            );
        }
        out
    }

    /// [`Series::certified_and_failed`] of points each labelled (a
    /// work-precision point with its target): the labels drawn beside
    /// the points, certified and failed alike.
    pub fn certified_and_failed_labelled(
        solver: &str,
        certified: Vec<((f64, f64), String)>,
        failed: Vec<((f64, f64), String)>,
    ) -> Vec<Series> {
        let labels: Vec<((f64, f64), String)> = certified.iter().chain(&failed).cloned().collect();
        let points = |p: Vec<((f64, f64), String)>| p.into_iter().map(|(p, _)| p).collect();
        let mut series = Series::certified_and_failed(solver, points(certified), points(failed));
        if let Some(first) = series.first_mut() {
            first.labels = labels;
        }
        series
    }

    /// The colour of `solver` (the same in every chart).
    pub fn of_solver(mut self, solver: &str) -> Self {
        self.color = Some(solver_color(solver));
        self
    }

    pub fn colored(mut self, index: usize) -> Self {
        self.color = Some(index);
        self
    }

    /// Black: a reference level or curve that is no solver's.
    pub fn black(mut self) -> Self {
        self.color = Some(BLACK_INDEX);
        self
    }
}

/// A chart: title, axis labels with units, scales, series.
#[derive(Clone, Debug, PartialEq)]
pub struct Chart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    pub series: Vec<Series>,
    /// On a linear y axis: values with |y| at most this are round-off, drawn
    /// as 0, and the axis spans at least ±10 times it.
    pub y_resolution: Option<f64>,
    /// Ticks of a log x axis at these values, with these labels (instead
    /// of decades).
    pub x_ticks: Option<Vec<(f64, String)>>,
}

/// Whether positive values spread enough for a log axis: all positive and
/// a decade or more between the smallest and the largest. A parameter that
/// varies over less (a relaxation factor ω in (0, 2)) reads on a linear one.
pub fn suits_log_axis(values: impl IntoIterator<Item = f64>) -> bool {
    let (lo, hi) = values
        .into_iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    lo > 0.0 && hi.is_finite() && hi >= 10.0 * lo
}

/// Twenty colours: Tableau 10, then the light shade of each (Tableau 20).
const PALETTE: [RGBColor; 20] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(174, 199, 232),
    RGBColor(255, 152, 150),
    RGBColor(152, 223, 138),
    RGBColor(255, 187, 120),
    RGBColor(197, 176, 213),
    RGBColor(196, 156, 148),
    RGBColor(247, 182, 210),
    RGBColor(199, 199, 199),
    RGBColor(219, 219, 141),
    RGBColor(158, 218, 229),
];

/// The shape of a series' markers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    Circle,
    Triangle,
    Square,
}

/// The colour and marker of style index `k` (a solver's place in the
/// registry, or a series' position): the colour cycles through the twenty,
/// the marker changes every ten, so that no two of the first sixty indices
/// share both (the registry's solvers each have their own colour and
/// marker, the same in every chart).
pub fn style_of(k: usize) -> (RGBColor, Marker) {
    let marker = match (k / 10) % 3 {
        0 => Marker::Circle,
        1 => Marker::Triangle,
        _ => Marker::Square,
    };
    (PALETTE[k % PALETTE.len()], marker)
}

const BLACK_INDEX: usize = usize::MAX;

/// The style index of a solver (see [`style_of`]): its place in the
/// registry (Python solvers registered at run time after the built-in
/// ones); a name the registry does not know, by its bytes.
pub fn solver_color(solver: &str) -> usize {
    registry::names()
        .iter()
        .position(|n| *n == solver)
        .unwrap_or_else(|| 60 + solver.bytes().map(usize::from).sum::<usize>() % 60)
}

const WIDTH: u32 = 980;
const HEIGHT: u32 = 520;
/// The legend panel's width, right of the plot.
const LEGEND_WIDTH: u32 = 260;

/// Key points of a log axis: every decade in range (with 2 and 5 between
/// when the range spans less than two decades).
fn decades(lo: f64, hi: f64) -> Vec<f64> {
    // A log axis with nothing on it (no positive finite value: a chart
    // whose series are all empty) has no decades; log10(0) as an i32 is
    // i32::MIN, and the range from it asked for 17 GB.
    if !(lo > 0.0 && lo.is_finite() && hi.is_finite() && hi >= lo) {
        return Vec::new();
    }
    let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let mut out: Vec<f64> = (a..=b).map(|k| 10f64.powi(k)).collect();
    if hi / lo < 100.0 {
        out = (a..=b)
            .flat_map(|k| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(k)))
            .collect();
    }
    out.retain(|v| *v >= lo && *v <= hi);
    // A range within a factor of ten can hold one of 1, 2, 5 or none, and
    // one tick cannot be read as a scale: then every half mantissa (1, 1.5,
    // 2, ..., 9.5). The axis spans at least a factor 2.25 (the data's range
    // padded by 1.5 each way), an interval of length at least 1.25 in
    // mantissa, so at least two of them fall in it.
    if out.len() < 2 {
        out = (a..=b)
            .flat_map(|k| (2..20).map(move |m| m as f64 / 2.0 * 10f64.powi(k)))
            .filter(|v| *v >= lo && *v <= hi)
            .collect();
    }
    out
}

impl Chart {
    pub fn new(
        title: impl Into<String>,
        x: &str,
        y: &str,
        log_x: bool,
        log_y: bool,
        series: Vec<Series>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x.into(),
            y_label: y.into(),
            log_x,
            log_y,
            series,
            y_resolution: None,
            x_ticks: None,
        }
    }

    /// Ticks of the x axis at `ticks`' values, labelled by their text.
    pub fn with_x_ticks(mut self, ticks: Vec<(f64, String)>) -> Self {
        self.x_ticks = Some(ticks);
        self
    }

    pub fn with_y_resolution(mut self, resolution: f64) -> Self {
        self.y_resolution = Some(resolution).filter(|r| r.is_finite() && *r > 0.0);
        self
    }

    /// Points that can be drawn: finite, positive on a log axis, round-off
    /// set to zero.
    fn drawable(&self) -> Vec<Vec<(f64, f64)>> {
        let floor = if self.log_y { None } else { self.y_resolution };
        self.series
            .iter()
            .map(|s| {
                s.points
                    .iter()
                    .copied()
                    .filter(|&(x, y)| {
                        x.is_finite()
                            && y.is_finite()
                            && (!self.log_x || x > 0.0)
                            && (!self.log_y || y > 0.0)
                    })
                    .map(|(x, y)| match floor {
                        Some(r) if y.abs() <= r => (x, 0.0),
                        _ => (x, y),
                    })
                    .collect()
            })
            .collect()
    }

    fn color(&self, i: usize) -> RGBColor {
        self.style(i).0
    }

    /// The colour and marker of series `i`.
    fn style(&self, i: usize) -> (RGBColor, Marker) {
        match self.series[i].color.unwrap_or(i) {
            BLACK_INDEX => (BLACK, Marker::Circle),
            k => style_of(k),
        }
    }

    /// Renders the chart as SVG text.
    pub fn to_svg(&self) -> Result<String> {
        let (shown, points, xr, yr) = self.prepared();
        shown.render(&points, xr, yr)
    }

    /// What is drawn: the chart with identical series merged and its
    /// legend fitted, the drawable points, and the axis ranges.
    #[allow(clippy::type_complexity)]
    fn prepared(&self) -> (Chart, Vec<Vec<(f64, f64)>>, (f64, f64), (f64, f64)) {
        let points = self.drawable();
        let all: Vec<(f64, f64)> = points.iter().flatten().copied().collect();
        let range = |values: Vec<f64>, log: bool, floor: Option<f64>| -> (f64, f64) {
            let (lo, hi) = values
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                    (a.min(v), b.max(v))
                });
            if !lo.is_finite() {
                return if log { (0.1, 10.0) } else { (0.0, 1.0) };
            }
            if log {
                let (lo, hi) = if lo == hi {
                    (lo / 2.0, hi * 2.0)
                } else {
                    (lo, hi)
                };
                (lo / 1.5, hi * 1.5)
            } else {
                let (lo, hi) = match floor {
                    Some(r) => (lo.min(-10.0 * r).min(0.0), hi.max(10.0 * r).max(0.0)),
                    None => (lo, hi),
                };
                let pad = if hi > lo {
                    0.05 * (hi - lo)
                } else {
                    lo.abs().max(1.0) * 0.05
                };
                (lo - pad, hi + pad)
            }
        };
        let floor = if self.log_y { None } else { self.y_resolution };
        let (x0, x1) = range(all.iter().map(|p| p.0).collect(), self.log_x, None);
        let (y0, y1) = range(all.iter().map(|p| p.1).collect(), self.log_y, floor);
        let unit = |v: f64, lo: f64, hi: f64, log: bool| {
            if log {
                (v / lo).ln() / (hi / lo).ln()
            } else {
                (v - lo) / (hi - lo)
            }
        };
        let (series, points) = overlap::merge_identical(&self.series, &points, &|(x, y)| {
            (unit(x, x0, x1, self.log_x), unit(y, y0, y1, self.log_y))
        });
        let (series, points) = fit_legend(series, points);
        let shown = Chart {
            series,
            ..self.clone()
        };
        (shown, points, (x0, x1), (y0, y1))
    }

    /// Writes the chart to `path` (atomically).
    pub fn write(&self, path: &Path) -> Result<()> {
        write_atomic(path, self.to_svg()?.as_bytes())
    }
}

/// The series with a legend of at most [`MAX_LEGEND`] entries where
/// grouping can make it so: beyond, the failed points (crosses, each in its
/// solver's colour) are listed once, as one entry in black.
fn fit_legend(
    mut series: Vec<Series>,
    mut points: Vec<Vec<(f64, f64)>>,
) -> (Vec<Series>, Vec<Vec<(f64, f64)>>) {
    let listed = series.iter().filter(|s| s.legend).count();
    let failed = series.iter().filter(|s| s.style == Style::Failed).count();
    if listed > MAX_LEGEND && failed > 1 {
        for s in series.iter_mut().filter(|s| s.style == Style::Failed) {
            s.legend = false;
        }
        series.push(
            Series::line(
                "not certified (crosses, in each solver's colour)",
                Vec::new(),
            )
            .failed()
            .black(),
        );
        points.push(Vec::new());
    }
    (series, points)
}

/// The number of entries the legend of `chart` lists once drawn.
pub fn legend_entries(chart: &Chart) -> usize {
    let points = chart.drawable();
    let (series, _) = fit_legend(chart.series.clone(), points);
    series.iter().filter(|s| s.legend).count()
}

/// A tick label: `0` for round-off around zero, integers without decimals,
/// scientific notation on log axes and for very small or large values.
pub fn tick_label(v: f64, log: bool, scale: f64) -> String {
    if !log && v.abs() <= 1e-9 * scale {
        return "0".into();
    }
    let a = v.abs();
    if log || !(1e-2..1e5).contains(&a) {
        let text = format!("{v:.1e}");
        return text.replace(".0e", "e");
    }
    if (v - v.round()).abs() <= 1e-9 * a.max(1.0) {
        return format!("{}", v.round() as i64);
    }
    let text = format!("{v:.3}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

pub mod overlap;
mod panels;
mod render;

pub use panels::Panels;
#[cfg(test)]
mod tests;
