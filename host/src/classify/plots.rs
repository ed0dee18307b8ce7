//! CMC, DET and ROC plots like the paper's Fig. 8, drawn with `plotters`
//! as PNG and SVG.
//!
//! **No text.** The host builds `plotters` without a font backend, so the
//! plots carry no axis labels or tick numbers (text would need fonts that
//! may not be installed). The axes are instead fixed and documented, with
//! light grey grid lines at known values:
//!
//! * **CMC**: x = rank 1 to N (a grid line per rank up to 20 ranks, else
//!   every 5th), y = recognition rate 0 to 1 (grid every 0.1). The chance
//!   rate `τ / N` is dashed magenta.
//! * **DET**: x = probit(FAR), y = probit(FRR), both from 0.05 % to 95 %
//!   (rates outside are clamped to the frame); grid lines at 0.1 %, 1 %,
//!   5 %, 10 %, 20 %, 40 % and 80 %, the 1 % and 10 % ones darker. The
//!   EER line FAR = FRR is dashed grey.
//! * **ROC**: x = FAR 0 to 1, y = verification rate 0 to 1 (grid every
//!   0.1). Random guessing (the diagonal) is dashed magenta.
//!
//! Each curve is drawn solid or dashed in its colour, as in Fig. 8.

use super::probit::probit;
use crate::error::{HostError, Result};
use crate::io::ensure_dir;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// One curve: points in the plot's data space (see [`PlotKind`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
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
/// Random-guess lines.
pub const MAGENTA: RGBColor = RGBColor(220, 0, 220);
const GRID: RGBColor = RGBColor(225, 225, 225);
const GRID_DARK: RGBColor = RGBColor(180, 180, 180);

/// DET axis limits (rates).
pub const DET_RANGE: (f64, f64) = (0.0005, 0.95);
const DET_GRID: [f64; 7] = [0.001, 0.01, 0.05, 0.1, 0.2, 0.4, 0.8];

type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

fn line<DB: DrawingBackend>(c: &mut Chart<'_, DB>, pts: Vec<(f64, f64)>, style: ShapeStyle) {
    // Errors only leave a line out of the picture: ignore them.
    let _ = c.draw_series(LineSeries::new(pts, style));
}

fn dashed<DB: DrawingBackend>(c: &mut Chart<'_, DB>, pts: Vec<(f64, f64)>, style: ShapeStyle) {
    let _ = c.draw_series(DashedLineSeries::new(pts, 8, 5, style));
}

/// Draws one plot onto `root` (any backend).
fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, kind: PlotKind, curves: &[Curve]) {
    let _ = root.fill(&WHITE);
    let det_lo = probit(DET_RANGE.0);
    let det_hi = probit(DET_RANGE.1);
    let (xr, yr) = match kind {
        PlotKind::Cmc { classes } => (1.0..(classes.max(2) as f64), 0.0..1.0),
        PlotKind::Det => (det_lo..det_hi, det_lo..det_hi),
        PlotKind::Roc => (0.0..1.0, 0.0..1.0),
    };
    let Ok(mut chart) = ChartBuilder::on(root).margin(6).build_cartesian_2d(xr, yr) else {
        return;
    };
    let map: Box<dyn Fn(f64) -> f64> = match kind {
        PlotKind::Det => Box::new(move |r: f64| probit(r).clamp(det_lo, det_hi)),
        _ => Box::new(|r| r),
    };
    let grid = |c: &mut Chart<'_, DB>, xs: &[f64], ys: &[f64], colour: RGBColor| {
        let (x0, x1) = (c.x_range().start, c.x_range().end);
        let (y0, y1) = (c.y_range().start, c.y_range().end);
        for &x in xs {
            line(c, vec![(x, y0), (x, y1)], colour.into());
        }
        for &y in ys {
            line(c, vec![(x0, y), (x1, y)], colour.into());
        }
    };
    let tenths: Vec<f64> = (0..=10).map(|k| f64::from(k) / 10.0).collect();
    match kind {
        PlotKind::Cmc { classes } => {
            let step = if classes <= 20 { 1 } else { 5 };
            let ranks: Vec<f64> = (1..=classes).step_by(step).map(|r| r as f64).collect();
            grid(&mut chart, &ranks, &tenths, GRID);
            let chance = (1..=classes)
                .map(|r| (r as f64, r as f64 / classes as f64))
                .collect();
            dashed(&mut chart, chance, MAGENTA.stroke_width(2));
        }
        PlotKind::Det => {
            let g: Vec<f64> = DET_GRID.iter().map(|&r| probit(r)).collect();
            grid(&mut chart, &g, &g, GRID);
            let dark = [probit(0.01), probit(0.1)];
            grid(&mut chart, &dark, &dark, GRID_DARK);
            dashed(
                &mut chart,
                vec![(det_lo, det_lo), (det_hi, det_hi)],
                GRID_DARK.stroke_width(1),
            );
        }
        PlotKind::Roc => {
            grid(&mut chart, &tenths, &tenths, GRID);
            dashed(
                &mut chart,
                vec![(0.0, 0.0), (1.0, 1.0)],
                MAGENTA.stroke_width(2),
            );
        }
    }
    for c in curves {
        let pts: Vec<(f64, f64)> = c.points.iter().map(|&(x, y)| (map(x), map(y))).collect();
        if c.dashed {
            dashed(&mut chart, pts, c.colour.stroke_width(2));
        } else {
            line(&mut chart, pts, c.colour.stroke_width(2));
        }
    }
    let _ = root.draw(&Rectangle::new(
        [
            (0, 0),
            (
                root.dim_in_pixel().0 as i32 - 1,
                root.dim_in_pixel().1 as i32 - 1,
            ),
        ],
        BLACK,
    ));
    let _ = root.present();
}

/// The plot as an RGB image.
pub fn render_png(kind: PlotKind, curves: &[Curve], size: (u32, u32)) -> image::RgbImage {
    let mut buf = vec![255u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        draw(&root, kind, curves);
    }
    image::RgbImage::from_raw(size.0, size.1, buf).unwrap_or_else(|| image::RgbImage::new(1, 1))
}

/// The plot as an SVG document.
pub fn render_svg(kind: PlotKind, curves: &[Curve], size: (u32, u32)) -> String {
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, size).into_drawing_area();
        draw(&root, kind, curves);
    }
    s
}

/// Adds `{name}.png` and `{name}.svg` to `out` (an
/// [`Output::dir`](crate::output::Output::dir) result).
///
/// # Errors
/// [`HostError::Encode`].
pub fn add_plot(
    out: &mut crate::output::Output,
    name: &str,
    kind: PlotKind,
    curves: &[Curve],
    size: (u32, u32),
) -> Result<()> {
    let img = render_png(kind, curves, size);
    let mut png = std::io::Cursor::new(Vec::new());
    img.write_to(&mut png, image::ImageFormat::Png)
        .map_err(|source| HostError::Encode {
            name: name.to_owned(),
            source,
        })?;
    out.add(format!("{name}.png"), png.into_inner());
    out.add(
        format!("{name}.svg"),
        render_svg(kind, curves, size).into_bytes(),
    );
    Ok(())
}

/// Writes `DIR/{name}.png` and `DIR/{name}.svg` as one result of loose
/// files ([`add_plot`], [`crate::output`]); returns their paths.
///
/// # Errors
/// [`HostError::Io`], [`HostError::NotADirectory`] or
/// [`HostError::Encode`].
pub fn write_plot(
    dir: &Path,
    name: &str,
    kind: PlotKind,
    curves: &[Curve],
    size: (u32, u32),
) -> Result<[PathBuf; 2]> {
    ensure_dir(dir)?;
    let mut staged = crate::output::Output::dir(dir);
    add_plot(&mut staged, name, kind, curves, size)?;
    // Loose files: other results in `dir` are not this one's to replace.
    let mut out = crate::output::Output::files();
    for (path, bytes) in staged.into_files() {
        out.add(path, bytes);
    }
    out.commit()?;
    Ok([
        dir.join(format!("{name}.png")),
        dir.join(format!("{name}.svg")),
    ])
}

/// A CMC curve's points from the rates at ranks 1..N.
pub fn cmc_points(cmc: &[f64]) -> Vec<(f64, f64)> {
    cmc.iter()
        .enumerate()
        .map(|(k, &r)| ((k + 1) as f64, r))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(img: &image::RgbImage, colour: RGBColor) -> usize {
        img.pixels()
            .filter(|p| {
                let d = |a: u8, b: u8| a.abs_diff(b) < 40;
                d(p.0[0], colour.0) && d(p.0[1], colour.1) && d(p.0[2], colour.2)
            })
            .count()
    }

    #[test]
    fn plots_draw_curves_and_reference_lines() {
        let cmc = Curve {
            points: cmc_points(&[0.5, 0.8, 1.0]),
            colour: SHAPE_BLUE,
            dashed: false,
        };
        let img = render_png(
            PlotKind::Cmc { classes: 3 },
            std::slice::from_ref(&cmc),
            (200, 150),
        );
        assert!(count(&img, SHAPE_BLUE) > 100 && count(&img, MAGENTA) > 50);
        let det = Curve {
            points: vec![(0.5, 0.01), (0.1, 0.1), (0.01, 0.5)],
            colour: SHAPE_BLUE,
            dashed: true,
        };
        let img = render_png(PlotKind::Det, std::slice::from_ref(&det), (150, 150));
        assert!(count(&img, SHAPE_BLUE) > 50);
        let svg = render_svg(PlotKind::Roc, &[cmc], (150, 150));
        assert!(svg.starts_with("<svg") && svg.contains("polyline"));
    }

    #[test]
    fn tiny_sizes_do_not_panic() {
        for size in [(0, 0), (1, 1), (3, 200)] {
            let _ = render_png(PlotKind::Det, &[], size);
            let _ = render_svg(PlotKind::Cmc { classes: 0 }, &[], size);
        }
    }

    #[test]
    fn write_plot_writes_png_and_svg() {
        let dir = tempfile::tempdir().unwrap();
        let [png, svg] = write_plot(dir.path(), "roc", PlotKind::Roc, &[], (64, 64)).unwrap();
        assert!(image::open(&png).is_ok());
        assert!(std::fs::read_to_string(svg).unwrap().contains("</svg>"));
        // Only the two files: no temporary left.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }
}
