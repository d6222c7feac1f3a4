//! Small multiples: one small chart per series group on a grid under one
//! title (Tufte's small multiples), for histories that overlap on one axis
//! (the inner loops of nine solvers, from ten to ten thousand iterations).
//! Each panel has its own axes and title and no legend (its title names
//! what it shows).

use anyhow::{Result, anyhow};
use plotters::prelude::*;

use super::Chart;

/// Charts drawn as panels of one figure.
#[derive(Clone, Debug, PartialEq)]
pub struct Panels {
    pub title: String,
    pub panels: Vec<Chart>,
    pub columns: usize,
}

const PANEL_WIDTH: u32 = 400;
const PANEL_HEIGHT: u32 = 270;
const TITLE_HEIGHT: u32 = 40;

impl Panels {
    /// Renders the panels as SVG text.
    pub fn to_svg(&self) -> Result<String> {
        let columns = self.columns.max(1);
        let rows = self.panels.len().div_ceil(columns).max(1);
        let (w, h) = (
            PANEL_WIDTH * columns as u32,
            TITLE_HEIGHT + PANEL_HEIGHT * rows as u32,
        );
        let err = |e: DrawingAreaErrorKind<_>| anyhow!("panels '{}': {e}", self.title);
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
            root.fill(&WHITE).map_err(err)?;
            let size = super::render::title_size(&self.title, w);
            let (top, grid) = root.split_vertically(TITLE_HEIGHT);
            top.titled(&self.title, ("sans-serif", size)).map_err(err)?;
            let areas = grid.split_evenly((rows, columns));
            for (chart, area) in self.panels.iter().zip(&areas) {
                let (shown, points, xr, yr) = chart.prepared();
                shown.plot_in(area, &points, xr, yr)?;
            }
            root.present().map_err(err)?;
        }
        Ok(svg)
    }
}
