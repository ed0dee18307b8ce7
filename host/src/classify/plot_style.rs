//! The vocabulary the plots share: curves, plot kinds, colours and the
//! DET axis limits ([`super::plots`] draws, [`super::plot_text`] labels).

use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

/// One curve: points in the plot's data space (see [`PlotKind`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    /// Its name in the legend, e.g. `float model`.
    pub label: String,
    /// (x, y) points.
    pub points: Vec<(f64, f64)>,
    /// Line colour.
    pub colour: RGBColor,
    /// Dashed (single modality in Fig. 8) or solid (joint).
    pub dashed: bool,
}

/// Which plot: decides the axes and the reference lines.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlotKind {
    /// Points (rank, rate); `classes` is N.
    Cmc {
        /// Number of classes N.
        classes: usize,
    },
    /// Points (FAR, FRR) as rates; drawn on probit axes.
    Det,
    /// Points (FAR, verification rate).
    Roc,
}

/// The Fig. 8 colour of the shape modality.
pub const SHAPE_BLUE: RGBColor = RGBColor(31, 90, 200);
/// A second curve's colour, apart from the reference lines'.
pub const ORANGE: RGBColor = RGBColor(230, 120, 0);
/// Random-guess lines.
pub const MAGENTA: RGBColor = RGBColor(220, 0, 220);
pub(super) const GRID: RGBColor = RGBColor(225, 225, 225);
pub(super) const GRID_DARK: RGBColor = RGBColor(180, 180, 180);

/// DET axis limits (rates).
pub const DET_RANGE: (f64, f64) = (0.0005, 0.95);
pub(super) const DET_GRID: [f64; 7] = [0.001, 0.01, 0.05, 0.1, 0.2, 0.4, 0.8];

pub(super) type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;
