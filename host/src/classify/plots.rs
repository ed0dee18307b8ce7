//! CMC, DET and ROC plots like the paper's Fig. 8, drawn with `plotters`
//! as PNG and SVG, labelled with the built-in mono fonts of
//! `embedded-graphics` (no font files needed).
//!
//! Every plot has a title, tick labels and a title on each axis, and a
//! legend naming each curve ([`Curve::label`]) and the reference line. In
//! the PNG the text is drawn onto the bitmap by [`crate::canvas`]; in the
//! SVG it is `<text>` in a monospace font of the same size.
//!
//! * **CMC**: x = rank 1 to N (grid line per rank up to 20 ranks, else
//!   every 5th), y = recognition rate 0 to 1 (grid every 0.1). The chance
//!   rate `τ / N` is dashed magenta.
//! * **DET**: x = FAR, y = FRR, both on probit axes from 0.05 % to 95 %
//!   (rates outside are clamped to the frame); grid lines at 0.1 %, 1 %,
//!   5 %, 10 %, 20 %, 40 % and 80 %, the 1 % and 10 % ones darker. The
//!   EER line FAR = FRR is dashed grey.
//! * **ROC**: x = FAR 0 to 1, y = verification rate 0 to 1 (grid every
//!   0.1). Random guessing (the diagonal) is dashed magenta.
//!
//! Each curve is drawn solid or dashed in its colour, as in Fig. 8.

use super::plot_text::{axis_marks, legend, Layout};
use super::probit::probit;
use crate::canvas::{draw_marks, TextMark};
use crate::canvas::{HAnchor, VAnchor};
use crate::error::{HostError, Result};
use crate::output::ensure_dir;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::{Path, PathBuf};

use super::plot_style::{Chart, DET_GRID, GRID, GRID_DARK};
pub use super::plot_style::{Curve, PlotKind, DET_RANGE, MAGENTA, ORANGE, SHAPE_BLUE};

fn line<DB: DrawingBackend>(c: &mut Chart<'_, DB>, pts: Vec<(f64, f64)>, style: ShapeStyle) {
    // Errors only leave a line out of the picture: ignore them.
    let _ = c.draw_series(LineSeries::new(pts, style));
}

fn dashed<DB: DrawingBackend>(c: &mut Chart<'_, DB>, pts: Vec<(f64, f64)>, style: ShapeStyle) {
    let _ = c.draw_series(DashedLineSeries::new(pts, 8, 5, style));
}

/// Draws one plot onto `root` (any backend); returns the text to put on
/// it, which the caller draws in its backend's way, and the layout.
fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    kind: PlotKind,
    curves: &[Curve],
) -> (Vec<TextMark>, Layout) {
    let _ = root.fill(&WHITE);
    let lay = Layout::new(kind, root.dim_in_pixel());
    let det_lo = probit(DET_RANGE.0);
    let det_hi = probit(DET_RANGE.1);
    let (xr, yr) = match kind {
        PlotKind::Cmc { classes } => (1.0..(classes.max(2) as f64), 0.0..1.0),
        PlotKind::Det => (det_lo..det_hi, det_lo..det_hi),
        PlotKind::Roc => (0.0..1.0, 0.0..1.0),
    };
    let Ok(mut chart) = ChartBuilder::on(root)
        .margin_top(lay.top)
        .margin_bottom(lay.bottom)
        .margin_left(lay.left)
        .margin_right(lay.right)
        .build_cartesian_2d(xr, yr)
    else {
        return (Vec::new(), lay);
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
    let mut marks = axis_marks(&chart, kind, &lay);
    legend(root, &chart, kind, curves, &lay, &mut marks);
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
    (marks, lay)
}

/// The plot as an RGB image.
pub fn render_png(kind: PlotKind, curves: &[Curve], size: (u32, u32)) -> image::RgbImage {
    let mut buf = vec![255u8; size.0 as usize * size.1 as usize * 3];
    let (marks, lay) = {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        draw(&root, kind, curves)
    };
    let mut img = image::RgbImage::from_raw(size.0, size.1, buf)
        .unwrap_or_else(|| image::RgbImage::new(1, 1));
    draw_marks(&mut img, &marks, lay.font);
    img
}

/// The plot as an SVG document.
pub fn render_svg(kind: PlotKind, curves: &[Curve], size: (u32, u32)) -> String {
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, size).into_drawing_area();
        let (marks, lay) = draw(&root, kind, curves);
        // The SVG backend writes text as `<text>` without font files.
        let px = f64::from(lay.font.character_size.height);
        for m in &marks {
            let [r, g, b] = m.colour.0;
            let colour = RGBColor(r, g, b);
            let style = TextStyle::from(("monospace", px * 1.24).into_font())
                .color(&colour)
                .pos(Pos::new(
                    match m.h {
                        HAnchor::Left => HPos::Left,
                        HAnchor::Centre => HPos::Center,
                        HAnchor::Right => HPos::Right,
                    },
                    match m.v {
                        VAnchor::Top => VPos::Top,
                        VAnchor::Middle => VPos::Center,
                        VAnchor::Bottom => VPos::Bottom,
                    },
                ));
            let _ = root.draw_text(&m.text, &style, (m.x, m.y));
        }
        let _ = root.present();
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
    use crate::classify::plot_text::Layout;

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
            label: "shape".into(),
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
            label: "shape".into(),
            points: vec![(0.5, 0.01), (0.1, 0.1), (0.01, 0.5)],
            colour: SHAPE_BLUE,
            dashed: true,
        };
        let img = render_png(PlotKind::Det, std::slice::from_ref(&det), (150, 150));
        assert!(count(&img, SHAPE_BLUE) > 50);
        let svg = render_svg(PlotKind::Roc, &[cmc], (150, 150));
        assert!(svg.starts_with("<svg") && svg.contains("polyline"));
    }

    /// Text pixels ([`crate::canvas::TEXT`]) in the inclusive rectangle.
    fn ink(img: &image::RgbImage, (x0, y0): (u32, u32), (x1, y1): (u32, u32)) -> usize {
        (y0..=y1)
            .flat_map(|y| (x0..=x1).map(move |x| (x, y)))
            .filter(|&(x, y)| img.get_pixel(x, y).0 == crate::canvas::TEXT.0)
            .count()
    }

    fn curve(label: &str) -> Curve {
        Curve {
            label: label.into(),
            points: vec![(0.01, 0.3), (0.1, 0.8), (0.5, 0.95)],
            colour: SHAPE_BLUE,
            dashed: false,
        }
    }

    #[test]
    fn every_plot_has_text_in_its_label_areas() {
        for kind in [PlotKind::Cmc { classes: 30 }, PlotKind::Det, PlotKind::Roc] {
            for (w, h) in [(480, 360), (320, 240), (200, 150)] {
                let img = render_png(kind, &[curve("c")], (w, h));
                let lay = Layout::new(kind, (w, h));
                let (top, bottom, left) = (lay.top, h - lay.bottom, lay.left);
                // y tick labels left of the plotting area.
                let y_ticks = ink(&img, (1, top), (left - 2, bottom));
                // x tick labels and the x title below it.
                let x_text = ink(&img, (left, bottom + 2), (w - 2, h - 2));
                // The y title and the name above it.
                let titles = ink(&img, (1, 1), (w - 2, top - 2));
                let msg = format!("{kind:?} {w}x{h}: {y_ticks} {x_text} {titles}");
                assert!(y_ticks > 40 && x_text > 80 && titles > 40, "{msg}");
            }
        }
    }

    #[test]
    fn the_legend_names_the_curves() {
        let (w, h) = (480, 360);
        for kind in [PlotKind::Cmc { classes: 10 }, PlotKind::Det, PlotKind::Roc] {
            let lay = Layout::new(kind, (w, h));
            let area = |img: &image::RgbImage| {
                ink(
                    img,
                    (lay.left + 1, lay.top + 1),
                    (w - lay.right - 1, h - lay.bottom - 1),
                )
            };
            let short = area(&render_png(kind, &[curve("a")], (w, h)));
            let long = area(&render_png(kind, &[curve("a longer name")], (w, h)));
            let two = area(&render_png(kind, &[curve("a"), curve("b")], (w, h)));
            // The reference line's entry alone has text too.
            let none = area(&render_png(kind, &[], (w, h)));
            assert!(none > 40, "{kind:?}: no reference entry");
            assert!(
                long > short + 40 && two > short + 5 && short > none,
                "{kind:?}"
            );
        }
        let svg = render_svg(
            PlotKind::Cmc { classes: 10 },
            &[curve("int8 model")],
            (w, h),
        );
        for text in [
            "int8 model",
            "chance",
            "rank",
            "recognition rate",
            "CMC",
            "0.4",
            "10",
        ] {
            assert!(
                svg.contains(&format!(">\n{text}\n</text>")),
                "SVG lacks {text}"
            );
        }
        assert!(svg.contains("<text") && svg.contains("monospace"));
    }

    #[test]
    fn many_ranks_are_thinned_to_fit() {
        let img = render_png(PlotKind::Cmc { classes: 500 }, &[], (200, 150));
        let svg = render_svg(PlotKind::Cmc { classes: 500 }, &[], (200, 150));
        // Ranks 1, 50, 100, ... 500 at most: not 500 labels.
        assert!(
            svg.matches("<text").count() < 25,
            "{}",
            svg.matches("<text").count()
        );
        assert!(ink(&img, (1, 1), (199, 149)) > 100);
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
