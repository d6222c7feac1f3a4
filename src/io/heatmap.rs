//! Heat maps of a tuning grid: one cell per pair of settings, coloured by
//! a value on a log scale (time to a certified answer), failed cells grey
//! with the reason, the best cell and the cells tied with it within the
//! timing noise marked, and a footer that explains the marks drawn. Drawn with plotters into SVG, as the charts are.

use anyhow::{Result, anyhow};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// One cell of the grid.
#[derive(Clone, Debug, PartialEq)]
pub enum Cell {
    /// A certified value, with its mark.
    Value { value: f64, mark: Mark },
    /// Not certified: the status, shortened.
    Failed(String),
}

/// How a certified cell compares with the best.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// The least value.
    Best,
    /// Within the measured noise of the best.
    Tie,
    None,
}

/// A grid of cells over two settings.
#[derive(Clone, Debug)]
pub struct HeatMap {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub x_values: Vec<String>,
    pub y_values: Vec<String>,
    /// cells[j][i]: the cell at y value j and x value i.
    pub cells: Vec<Vec<Cell>>,
    /// What the colour is (`seconds, median of 3 runs`).
    pub value_label: String,
}

const WIDTH: u32 = 900;
const HEIGHT: u32 = 620;
const LEFT: i32 = 150;
const TOP: i32 = 70;
const RIGHT: i32 = 190;
const BOTTOM: i32 = 110;

/// A colour of the viridis scale at t ∈ [0, 1] (a perceptually uniform,
/// colour-blind-safe sequential scale: van der Walt & Smith, matplotlib),
/// by linear interpolation between five of its stops.
fn viridis(t: f64) -> RGBColor {
    const STOPS: [(u8, u8, u8); 5] = [
        (68, 1, 84),
        (59, 82, 139),
        (33, 145, 140),
        (94, 201, 98),
        (253, 231, 37),
    ];
    let t = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let k = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - k as f64;
    let mix = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// A short number for a cell: `1.23`, `0.0456`, `1.2e3`.
pub fn short(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-2 || v.abs() >= 1e4) {
        format!("{v:.2e}")
    } else if v.abs() >= 100.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.3}")
    }
}

impl HeatMap {
    /// The footer: what each mark drawn means, only the marks drawn.
    pub fn legend(&self) -> String {
        let cells = || self.cells.iter().flatten();
        let marked = |m: Mark| cells().any(|c| matches!(c, Cell::Value { mark, .. } if *mark == m));
        let mut parts = Vec::new();
        if marked(Mark::Best) {
            parts.push("best (orange frame): least work, then least time");
        }
        if marked(Mark::Tie) {
            parts.push("=: of equal work, within the timing noise of the best");
        }
        if cells().any(|c| matches!(c, Cell::Failed(_))) {
            parts.push("x: not certified (grey)");
        }
        parts.join("; ")
    }

    /// The range of the certified values (None: no cell certified).
    fn range(&self) -> Option<(f64, f64)> {
        let values: Vec<f64> = self
            .cells
            .iter()
            .flatten()
            .filter_map(|c| match c {
                Cell::Value { value, .. } if *value > 0.0 && value.is_finite() => Some(*value),
                _ => None,
            })
            .collect();
        let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = values.iter().copied().fold(0.0f64, f64::max);
        lo.is_finite().then_some((lo, hi))
    }

    /// Renders the heat map as SVG text.
    pub fn to_svg(&self) -> Result<String> {
        let err = |e: DrawingAreaErrorKind<_>| anyhow!("heat map: {e}");
        let (nx, ny) = (self.x_values.len().max(1), self.y_values.len().max(1));
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (WIDTH, HEIGHT)).into_drawing_area();
            root.fill(&WHITE).map_err(err)?;
            let font = |size: i32| ("sans-serif", size).into_font().color(&BLACK);
            let centered = |size: i32| font(size).pos(Pos::new(HPos::Center, VPos::Center));
            root.draw(&Text::new(
                self.title.clone(),
                (WIDTH as i32 / 2, 24),
                centered(18),
            ))
            .map_err(err)?;
            let (w, h) = (
                (WIDTH as i32 - LEFT - RIGHT) / nx as i32,
                (HEIGHT as i32 - TOP - BOTTOM) / ny as i32,
            );
            let range = self.range();
            let unit = |v: f64| match range {
                Some((lo, hi)) if hi > lo => (v / lo).ln() / (hi / lo).ln(),
                _ => 0.5,
            };
            for (j, row) in self.cells.iter().enumerate() {
                // The first y value at the bottom, as on an axis.
                let y0 = TOP + (ny - 1 - j) as i32 * h;
                for (i, cell) in row.iter().enumerate() {
                    let x0 = LEFT + i as i32 * w;
                    let (fill, text, dark) = match cell {
                        Cell::Value { value, mark } => {
                            let t = unit(*value);
                            let label = match mark {
                                Mark::Best => format!("best {}", short(*value)),
                                Mark::Tie => format!("= {}", short(*value)),
                                Mark::None => short(*value),
                            };
                            (viridis(t), label, t < 0.6)
                        }
                        Cell::Failed(why) => (RGBColor(215, 215, 215), format!("x {why}"), false),
                    };
                    root.draw(&Rectangle::new([(x0, y0), (x0 + w, y0 + h)], fill.filled()))
                        .map_err(err)?;
                    root.draw(&Rectangle::new(
                        [(x0, y0), (x0 + w, y0 + h)],
                        WHITE.stroke_width(2),
                    ))
                    .map_err(err)?;
                    if matches!(
                        cell,
                        Cell::Value {
                            mark: Mark::Best,
                            ..
                        }
                    ) {
                        root.draw(&Rectangle::new(
                            [(x0 + 3, y0 + 3), (x0 + w - 3, y0 + h - 3)],
                            RGBColor(255, 127, 14).stroke_width(4),
                        ))
                        .map_err(err)?;
                    }
                    let color = if dark { WHITE } else { BLACK };
                    root.draw(&Text::new(
                        text,
                        (x0 + w / 2, y0 + h / 2),
                        ("sans-serif", 13)
                            .into_font()
                            .color(&color)
                            .pos(Pos::new(HPos::Center, VPos::Center)),
                    ))
                    .map_err(err)?;
                }
            }
            // Axes: every value a tick, the labels outside the grid.
            for (i, v) in self.x_values.iter().enumerate() {
                root.draw(&Text::new(
                    v.clone(),
                    (LEFT + i as i32 * w + w / 2, TOP + ny as i32 * h + 16),
                    centered(13),
                ))
                .map_err(err)?;
            }
            for (j, v) in self.y_values.iter().enumerate() {
                root.draw(&Text::new(
                    v.clone(),
                    (LEFT - 10, TOP + (ny - 1 - j) as i32 * h + h / 2),
                    font(13).pos(Pos::new(HPos::Right, VPos::Center)),
                ))
                .map_err(err)?;
            }
            root.draw(&Text::new(
                self.x_label.clone(),
                (LEFT + nx as i32 * w / 2, TOP + ny as i32 * h + 44),
                centered(14),
            ))
            .map_err(err)?;
            root.draw(&Text::new(
                self.y_label.clone(),
                (16, TOP + ny as i32 * h / 2),
                font(14)
                    .pos(Pos::new(HPos::Center, VPos::Center))
                    .transform(FontTransform::Rotate270),
            ))
            .map_err(err)?;
            root.draw(&Text::new(
                self.legend(),
                (LEFT + nx as i32 * w / 2, HEIGHT as i32 - 24),
                centered(12),
            ))
            .map_err(err)?;
            // The colour bar: its ends and its middle labelled.
            let (bx, by, bh) = (WIDTH as i32 - RIGHT + 30, TOP, ny as i32 * h);
            for k in 0..bh {
                let t = 1.0 - k as f64 / (bh - 1).max(1) as f64;
                root.draw(&Rectangle::new(
                    [(bx, by + k), (bx + 18, by + k + 1)],
                    viridis(t).filled(),
                ))
                .map_err(err)?;
            }
            if let Some((lo, hi)) = range {
                let mid = (lo * hi).sqrt();
                for (v, y) in [(hi, by), (mid, by + bh / 2), (lo, by + bh)] {
                    root.draw(&Text::new(
                        short(v),
                        (bx + 24, y),
                        font(12).pos(Pos::new(HPos::Left, VPos::Center)),
                    ))
                    .map_err(err)?;
                }
            }
            root.draw(&Text::new(
                self.value_label.clone(),
                (bx, by + bh + 24),
                font(12).pos(Pos::new(HPos::Left, VPos::Center)),
            ))
            .map_err(err)?;
            root.present().map_err(err)?;
        }
        Ok(svg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_cell_and_every_value_is_drawn() {
        let map = HeatMap {
            title: "t".into(),
            x_label: "r".into(),
            y_label: "ε".into(),
            x_values: vec!["1e3".into(), "1e5".into()],
            y_values: vec!["1e-4".into(), "1e-6".into()],
            cells: vec![
                vec![
                    Cell::Value {
                        value: 1.0,
                        mark: Mark::Best,
                    },
                    Cell::Failed("max_iterations".into()),
                ],
                vec![
                    Cell::Value {
                        value: 1.01,
                        mark: Mark::Tie,
                    },
                    Cell::Value {
                        value: 3.0,
                        mark: Mark::None,
                    },
                ],
            ],
            value_label: "seconds".into(),
        };
        let svg = map.to_svg().unwrap();
        for text in [
            "best 1.000",
            "x max_iterations",
            "= 1.010",
            "3.000",
            "1e3",
            "1e-6",
        ] {
            assert!(svg.contains(text), "{text} not in the SVG");
        }
        // The footer explains only what is drawn: no tie, no failure here.
        let mut plain = map.clone();
        plain.cells = vec![vec![
            Cell::Value {
                value: 1.0,
                mark: Mark::Best,
            },
            Cell::Value {
                value: 2.0,
                mark: Mark::None,
            },
        ]];
        plain.y_values.truncate(1);
        assert_eq!(
            plain.legend(),
            "best (orange frame): least work, then least time"
        );
        assert!(svg.contains("orange frame") && svg.contains("=: of equal work"));
        assert_eq!(viridis(0.0), RGBColor(68, 1, 84));
        assert_eq!(viridis(1.0), RGBColor(253, 231, 37));
    }
}
