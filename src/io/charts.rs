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

use anyhow::{Result, anyhow};
use contactlab_solvers::registry;
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
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
}

impl Series {
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            style: Style::Line,
            color: None,
        }
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

/// Ten distinguishable colours (Tableau 10).
const PALETTE: [RGBColor; 10] = [
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
];

const BLACK_INDEX: usize = usize::MAX;

/// The palette index of a solver: its place in the registry.
pub fn solver_color(solver: &str) -> usize {
    registry::names()
        .iter()
        .position(|n| *n == solver)
        .unwrap_or_else(|| solver.bytes().map(usize::from).sum::<usize>())
        % PALETTE.len()
}

const WIDTH: u32 = 980;
const HEIGHT: u32 = 520;
/// The legend panel's width, right of the plot.
const LEGEND_WIDTH: u32 = 260;

/// Key points of a log axis: every decade in range (with 2 and 5 between
/// when the range spans less than two decades).
fn decades(lo: f64, hi: f64) -> Vec<f64> {
    let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let mut out: Vec<f64> = (a..=b).map(|k| 10f64.powi(k)).collect();
    if hi / lo < 100.0 {
        out = (a..=b)
            .flat_map(|k| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(k)))
            .collect();
    }
    out.retain(|v| *v >= lo && *v <= hi);
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
        match self.series[i].color.unwrap_or(i) {
            BLACK_INDEX => BLACK,
            k => PALETTE[k % PALETTE.len()],
        }
    }

    /// Renders the chart as SVG text.
    pub fn to_svg(&self) -> Result<String> {
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
        let shown = Chart {
            series,
            ..self.clone()
        };
        shown.render(&points, (x0, x1), (y0, y1))
    }

    /// Draws the chart's own series (`points`: their drawable points) on
    /// the given axis ranges.
    fn render(
        &self,
        points: &[Vec<(f64, f64)>],
        (x0, x1): (f64, f64),
        (y0, y1): (f64, f64),
    ) -> Result<String> {
        let mut svg = String::new();
        {
            // The legend widens to its longest label instead of cutting it.
            let legend_width = self.legend_width();
            let root =
                SVGBackend::with_string(&mut svg, (WIDTH - LEGEND_WIDTH + legend_width, HEIGHT))
                    .into_drawing_area();
            root.fill(&WHITE).map_err(|e| anyhow!("chart: {e}"))?;
            let (plot, legend) = root.split_horizontally(WIDTH - LEGEND_WIDTH);
            let scales = (x0.abs().max(x1.abs()), y0.abs().max(y1.abs()));
            let kx = match &self.x_ticks {
                Some(t) => t.iter().map(|p| p.0).collect(),
                None => decades(x0, x1),
            };
            let ky = decades(y0, y1);
            match (self.log_x, self.log_y) {
                (false, false) => self.draw(&plot, points, x0..x1, y0..y1, scales),
                (true, false) => self.draw(
                    &plot,
                    points,
                    (x0..x1).log_scale().with_key_points(kx),
                    y0..y1,
                    scales,
                ),
                (false, true) => self.draw(
                    &plot,
                    points,
                    x0..x1,
                    (y0..y1).log_scale().with_key_points(ky),
                    scales,
                ),
                (true, true) => self.draw(
                    &plot,
                    points,
                    (x0..x1).log_scale().with_key_points(kx),
                    (y0..y1).log_scale().with_key_points(ky),
                    scales,
                ),
            }?;
            self.draw_legend(&legend)?;
            root.present().map_err(|e| anyhow!("chart: {e}"))?;
        }
        Ok(svg)
    }

    fn draw<X, Y>(
        &self,
        area: &DrawingArea<SVGBackend<'_>, Shift>,
        points: &[Vec<(f64, f64)>],
        x: X,
        y: Y,
        scales: (f64, f64),
    ) -> Result<()>
    where
        X: AsRangedCoord<Value = f64>,
        Y: AsRangedCoord<Value = f64>,
        X::CoordDescType: ValueFormatter<f64>,
        Y::CoordDescType: ValueFormatter<f64>,
    {
        let err = |e: DrawingAreaErrorKind<_>| anyhow!("chart '{}': {e}", self.title);
        let mut chart = ChartBuilder::on(area)
            .caption(&self.title, ("sans-serif", 17))
            .margin(14)
            .x_label_area_size(48)
            .y_label_area_size(78)
            .build_cartesian_2d(x, y)
            .map_err(err)?;
        let fmt = |log: bool, scale: f64| move |v: &f64| tick_label(*v, log, scale);
        let fy = fmt(self.log_y, scales.1);
        let fx = |v: &f64| match &self.x_ticks {
            Some(ticks) => ticks
                .iter()
                .find(|t| (t.0 - v).abs() <= 1e-9 * t.0.abs())
                .map_or_else(|| tick_label(*v, self.log_x, scales.0), |t| t.1.clone()),
            None => tick_label(*v, self.log_x, scales.0),
        };
        chart
            .configure_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(err)?;
        for (i, (s, pts)) in self.series.iter().zip(points).enumerate() {
            let color = self.color(i);
            let style = color.stroke_width(2);
            match s.style {
                Style::Line | Style::LineMarkers => {
                    chart
                        .draw_series(LineSeries::new(pts.iter().copied(), style))
                        .map_err(err)?;
                }
                Style::Dashed => {
                    chart
                        .draw_series(DashedLineSeries::new(pts.iter().copied(), 8, 5, style))
                        .map_err(err)?;
                }
                Style::Dots | Style::Failed => {}
            }
            match s.style {
                Style::LineMarkers | Style::Dots => {
                    chart
                        .draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
                        .map_err(err)?;
                }
                Style::Failed => {
                    chart
                        .draw_series(pts.iter().map(|&p| Cross::new(p, 5, color.stroke_width(2))))
                        .map_err(err)?;
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// The legend's rows: a long label (merged series) takes several.
    fn legend_rows(&self) -> usize {
        self.series
            .iter()
            .map(|s| overlap::lines(&s.name).len())
            .sum()
    }

    /// The legend's row height and font size in pixels.
    fn legend_font(&self) -> (i32, i32) {
        let rows = self.legend_rows().max(1) as i32;
        let row = (((HEIGHT as i32) - 60) / rows).clamp(9, 17);
        (row, (row - 3).clamp(8, 13))
    }

    /// The legend panel's width: [`LEGEND_WIDTH`], or wider so that the
    /// longest label is written whole (a character taken as 0.62 of the
    /// font size, generous for sans-serif).
    fn legend_width(&self) -> u32 {
        let (_, font) = self.legend_font();
        let longest = self
            .series
            .iter()
            .flat_map(|s| overlap::lines(&s.name))
            .map(|l| l.chars().count())
            .max()
            .unwrap_or(0) as f64;
        let needed = (50.0 + longest * 0.62 * font as f64).ceil() as u32;
        LEGEND_WIDTH.max(needed)
    }

    /// The legend, in its own panel: one row per series, its sample drawn
    /// as on the plot, its label whole.
    fn draw_legend(&self, area: &DrawingArea<SVGBackend<'_>, Shift>) -> Result<()> {
        let err = |e: DrawingAreaErrorKind<_>| anyhow!("chart '{}' legend: {e}", self.title);
        let rows = self.legend_rows().max(1) as i32;
        let (row, font) = self.legend_font();
        let width = self.legend_width() as i32;
        let (left, top) = (6, 40);
        let bottom = top + rows * row + 6;
        area.draw(&Rectangle::new(
            [(left, top - 6), (width - 4, bottom)],
            BLACK.stroke_width(1),
        ))
        .map_err(err)?;
        let mut at = 0;
        for (i, s) in self.series.iter().enumerate() {
            let lines = overlap::lines(&s.name);
            let y = top + at * row + row / 2;
            at += lines.len() as i32;
            let color = self.color(i);
            let (a, b) = (left + 6, left + 30);
            match s.style {
                Style::Line | Style::LineMarkers => {
                    area.draw(&PathElement::new(
                        vec![(a, y), (b, y)],
                        color.stroke_width(2),
                    ))
                    .map_err(err)?;
                }
                Style::Dashed => {
                    for k in 0..3 {
                        let x = a + k * 9;
                        area.draw(&PathElement::new(
                            vec![(x, y), (x + 5, y)],
                            color.stroke_width(2),
                        ))
                        .map_err(err)?;
                    }
                }
                _ => {}
            }
            match s.style {
                Style::LineMarkers | Style::Dots => {
                    area.draw(&Circle::new(((a + b) / 2, y), 3, color.filled()))
                        .map_err(err)?;
                }
                Style::Failed => {
                    area.draw(&Cross::new(((a + b) / 2, y), 5, color.stroke_width(2)))
                        .map_err(err)?;
                }
                _ => {}
            }
            for (k, line) in lines.into_iter().enumerate() {
                area.draw(&Text::new(
                    line,
                    (b + 6, y - font / 2 + k as i32 * row),
                    ("sans-serif", font).into_font().color(&BLACK),
                ))
                .map_err(err)?;
            }
        }
        Ok(())
    }

    /// Writes the chart to `path` (atomically).
    pub fn write(&self, path: &Path) -> Result<()> {
        write_atomic(path, self.to_svg()?.as_bytes())
    }
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
#[cfg(test)]
mod tests;
