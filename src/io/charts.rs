//! SVG charts (plotters, SVG backend only: no system font libraries needed;
//! text is written as SVG `<text>`). One description type, [`Chart`], for
//! every chart the harness draws.

use std::path::Path;

use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;

use crate::io::output::write_atomic;

/// One named curve.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    /// Draw markers at the points (and lines between them unless `markers_only`).
    pub markers: bool,
    pub markers_only: bool,
    pub dashed: bool,
}

impl Series {
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            markers: false,
            markers_only: false,
            dashed: false,
        }
    }

    pub fn with_markers(mut self) -> Self {
        self.markers = true;
        self
    }

    pub fn scatter(mut self) -> Self {
        self.markers = true;
        self.markers_only = true;
        self
    }

    pub fn dashed(mut self) -> Self {
        self.dashed = true;
        self
    }
}

/// Where the legend goes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Legend {
    #[default]
    UpperRight,
    UpperLeft,
    LowerRight,
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
    pub legend: Legend,
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

impl Chart {
    /// Points that can be drawn: finite, and positive on a log axis.
    fn drawable(&self) -> Vec<Vec<(f64, f64)>> {
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
                    .collect()
            })
            .collect()
    }

    /// Renders the chart as SVG text.
    pub fn to_svg(&self) -> Result<String> {
        let points = self.drawable();
        let all: Vec<(f64, f64)> = points.iter().flatten().copied().collect();
        let range = |values: Vec<f64>, log: bool| -> (f64, f64) {
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
                let pad = if hi > lo {
                    0.05 * (hi - lo)
                } else {
                    lo.abs().max(1.0) * 0.05
                };
                (lo - pad, hi + pad)
            }
        };
        let (x0, x1) = range(all.iter().map(|p| p.0).collect(), self.log_x);
        let (y0, y1) = range(all.iter().map(|p| p.1).collect(), self.log_y);
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (820, 520)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| anyhow!("chart: {e}"))?;
            let scales = (x0.abs().max(x1.abs()), y0.abs().max(y1.abs()));
            match (self.log_x, self.log_y) {
                (false, false) => self.draw(&root, &points, x0..x1, y0..y1, scales),
                (true, false) => self.draw(&root, &points, (x0..x1).log_scale(), y0..y1, scales),
                (false, true) => self.draw(&root, &points, x0..x1, (y0..y1).log_scale(), scales),
                (true, true) => self.draw(
                    &root,
                    &points,
                    (x0..x1).log_scale(),
                    (y0..y1).log_scale(),
                    scales,
                ),
            }?;
            root.present().map_err(|e| anyhow!("chart: {e}"))?;
        }
        Ok(svg)
    }

    fn draw<X, Y>(
        &self,
        root: &DrawingArea<SVGBackend<'_>, Shift>,
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
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 20))
            .margin(14)
            .x_label_area_size(48)
            .y_label_area_size(78)
            .build_cartesian_2d(x, y)
            .map_err(err)?;
        let fmt = |log: bool, scale: f64| move |v: &f64| tick_label(*v, log, scale);
        let (fx, fy) = (fmt(self.log_x, scales.0), fmt(self.log_y, scales.1));
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
            let color = PALETTE[i % PALETTE.len()];
            let style = color.stroke_width(2);
            if !s.markers_only {
                if s.dashed {
                    chart
                        .draw_series(DashedLineSeries::new(pts.iter().copied(), 8, 5, style))
                        .map_err(err)?
                        .label(&s.name)
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                        });
                } else {
                    chart
                        .draw_series(LineSeries::new(pts.iter().copied(), style))
                        .map_err(err)?
                        .label(&s.name)
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                        });
                }
            }
            if s.markers {
                let anno = chart
                    .draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
                    .map_err(err)?;
                if s.markers_only {
                    anno.label(&s.name)
                        .legend(move |(x, y)| Circle::new((x + 10, y), 3, color.filled()));
                }
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(match self.legend {
                Legend::UpperRight => SeriesLabelPosition::UpperRight,
                Legend::UpperLeft => SeriesLabelPosition::UpperLeft,
                Legend::LowerRight => SeriesLabelPosition::LowerRight,
            })
            .draw()
            .map_err(err)?;
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

#[cfg(test)]
mod tests {
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
    fn svg_has_title_axes_and_every_series() {
        for (log_x, log_y) in [(false, false), (true, true), (true, false), (false, true)] {
            let chart = Chart {
                title: "A title".into(),
                x_label: "x label [m]".into(),
                y_label: "y label [s]".into(),
                log_x,
                log_y,
                series: vec![
                    Series::line("first", vec![(1.0, 2.0), (10.0, 20.0)]),
                    Series::line("second", vec![(2.0, 1.0), (5.0, f64::NAN), (20.0, 3.0)])
                        .with_markers()
                        .dashed(),
                    Series::line("third", vec![(3.0, 3.0)]).scatter(),
                ],
                legend: Legend::UpperLeft,
            };
            let svg = chart.to_svg().unwrap();
            assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
            for text in [
                "A title",
                "x label [m]",
                "y label [s]",
                "first",
                "second",
                "third",
            ] {
                assert!(svg.contains(text), "missing {text}");
            }
        }
    }
}
