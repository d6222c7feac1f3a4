//! Drawing a [`Chart`] with plotters: the plot on its axes (log axes
//! labelled at every decade, failed points as crosses, the resolution
//! floor) and the legend in its own panel right of the plot.

use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;

use super::*;

impl Chart {
    /// Draws the chart's own series (`points`: their drawable points) on
    /// the given axis ranges.
    pub(super) fn render(
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
            self.plot_in(&plot, points, (x0, x1), (y0, y1))?;
            self.draw_legend(&legend)?;
            root.present().map_err(|e| anyhow!("chart: {e}"))?;
        }
        Ok(svg)
    }

    /// Draws the plot (axes, series, no legend) into `plot`.
    pub(super) fn plot_in(
        &self,
        plot: &DrawingArea<SVGBackend<'_>, Shift>,
        points: &[Vec<(f64, f64)>],
        (x0, x1): (f64, f64),
        (y0, y1): (f64, f64),
    ) -> Result<()> {
        let scales = (x0.abs().max(x1.abs()), y0.abs().max(y1.abs()));
        let kx = match &self.x_ticks {
            Some(t) => t.iter().map(|p| p.0).collect(),
            None => decades(x0, x1),
        };
        let ky = decades(y0, y1);
        match (self.log_x, self.log_y) {
            (false, false) => self.draw(plot, points, x0..x1, y0..y1, scales),
            (true, false) => self.draw(
                plot,
                points,
                (x0..x1).log_scale().with_key_points(kx),
                y0..y1,
                scales,
            ),
            (false, true) => self.draw(
                plot,
                points,
                x0..x1,
                (y0..y1).log_scale().with_key_points(ky),
                scales,
            ),
            (true, true) => self.draw(
                plot,
                points,
                (x0..x1).log_scale().with_key_points(kx),
                (y0..y1).log_scale().with_key_points(ky),
                scales,
            ),
        }?;
        Ok(())
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
            .caption(
                &self.title,
                ("sans-serif", title_size(&self.title, area.dim_in_pixel().0)),
            )
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
                    let fill = color.filled();
                    match self.style(i).1 {
                        Marker::Circle => chart
                            .draw_series(pts.iter().map(|&p| Circle::new(p, 3, fill)))
                            .map(|_| ()),
                        Marker::Triangle => chart
                            .draw_series(pts.iter().map(|&p| TriangleMarker::new(p, 4, fill)))
                            .map(|_| ()),
                        Marker::Square => chart
                            .draw_series(pts.iter().map(|&p| {
                                EmptyElement::at(p) + Rectangle::new([(-3, -3), (3, 3)], fill)
                            }))
                            .map(|_| ()),
                    }
                    .map_err(err)?;
                }
                Style::Failed => {
                    chart
                        .draw_series(pts.iter().map(|&p| Cross::new(p, 5, color.stroke_width(2))))
                        .map_err(err)?;
                }
                _ => {}
            }
            // Point labels (a work-precision point's target), beside the
            // point in the series' colour; those a log axis cannot draw
            // are left out.
            let drawable = |&&((x, y), _): &&((f64, f64), String)| {
                x.is_finite()
                    && y.is_finite()
                    && (!self.log_x || x > 0.0)
                    && (!self.log_y || y > 0.0)
            };
            chart
                .draw_series(s.labels.iter().filter(drawable).map(|(p, text)| {
                    EmptyElement::at(*p)
                        + Text::new(
                            text.clone(),
                            (5, -14),
                            ("sans-serif", 10).into_font().color(&color),
                        )
                }))
                .map_err(err)?;
        }
        Ok(())
    }

    /// The legend's rows: a long label (merged series) takes several.
    fn legend_rows(&self) -> usize {
        self.series
            .iter()
            .filter(|s| s.legend)
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
    pub(super) fn legend_width(&self) -> u32 {
        let (_, font) = self.legend_font();
        let longest = self
            .series
            .iter()
            .filter(|s| s.legend)
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
        for (i, s) in self.series.iter().enumerate().filter(|(_, s)| s.legend) {
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
                    let (at, fill) = (((a + b) / 2, y), color.filled());
                    match self.style(i).1 {
                        Marker::Circle => area.draw(&Circle::new(at, 3, fill)),
                        Marker::Triangle => area.draw(&TriangleMarker::new(at, 4, fill)),
                        Marker::Square => area.draw(&Rectangle::new(
                            [(at.0 - 3, at.1 - 3), (at.0 + 3, at.1 + 3)],
                            fill,
                        )),
                    }
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
}

/// The title's font size: 17 px, or smaller so that the title fits the
/// plot's width in any renderer (its width estimated at 0.6 em a
/// character, wider than DejaVu Sans and Arial average; centred, a longer
/// title is cut on both sides), down to 10 px.
pub(super) fn title_size(title: &str, width: u32) -> u32 {
    let chars = title.chars().count().max(1) as f64;
    let fits = (width as f64 - 28.0) / (0.6 * chars);
    fits.floor().clamp(10.0, 17.0) as u32
}
