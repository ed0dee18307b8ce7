//! The paper's Fig. 8: CMC, DET and ROC curves of every condition, as PNG
//! and SVG, with axis labels, tick values and a legend.
//!
//! The plot area is [`crate::classify::plots`]' (axes, grids, the random
//! guess dashed in magenta); this module frames it with text: the SVG
//! with `<text>` elements, the PNG with `embedded-graphics`' built-in
//! bitmap font (no system font needed). Colours and dashes are the
//! paper's: single modalities dashed, joint conditions solid; shape blue,
//! range purple, conspicuity brown, luminance grey, colour cyan, shape +
//! range red, all four green (and colour as three planes orange).

use super::features::Condition;
use crate::classify::metrics::Det;
use crate::classify::plots::{cmc_points, render_png, render_svg, Curve, PlotKind, MAGENTA};
use crate::classify::probit::probit;
use crate::error::{HostError, Result};
use crate::output::{ensure_dir, write_atomic};
use embedded_graphics::mono_font::{ascii::FONT_6X10, MonoTextStyle};
use embedded_graphics::pixelcolor::Rgb888;
use embedded_graphics::prelude::*;
use embedded_graphics::text::{Alignment, Text};
use plotters::style::RGBColor;
use std::path::Path;

/// The curves of all conditions, float and int8.
#[derive(Clone, Debug, Default)]
pub struct Fig8Curves {
    /// Float networks: condition, CMC rates (ranks 1..N), DET sweep.
    pub float: Vec<(Condition, Vec<f64>, Det)>,
    /// The int8 blobs, likewise.
    pub int8: Vec<(Condition, Vec<f64>, Det)>,
}

/// The paper's colour of a condition, and whether it is dashed.
pub fn style(c: Condition) -> (RGBColor, bool) {
    match c {
        Condition::Shape => (RGBColor(31, 90, 200), true),
        Condition::Range => (RGBColor(128, 0, 160), true),
        Condition::Conspicuity => (RGBColor(140, 80, 20), true),
        Condition::Luminance => (RGBColor(128, 128, 128), true),
        Condition::Colour => (RGBColor(0, 190, 210), true),
        Condition::Colour3 => (RGBColor(240, 140, 0), true),
        Condition::ShapeRange => (RGBColor(220, 20, 20), false),
        Condition::All => (RGBColor(20, 160, 40), false),
    }
}

const PLOT: (u32, u32) = (340, 320);
const AT: (i32, i32) = (52, 14);
const SIZE: (u32, u32) = (660, 370);
/// plots.rs draws its frame with this margin.
const MARGIN: f64 = 6.0;

/// Text of one figure: x label, y label, ticks `(value, text)` on each axis.
struct Axes {
    x: &'static str,
    y: &'static str,
    xt: Vec<(f64, String)>,
    yt: Vec<(f64, String)>,
    range: ((f64, f64), (f64, f64)),
}

fn axes(kind: PlotKind) -> Axes {
    let unit = |v: &[f64]| v.iter().map(|&t| (t, format!("{t}"))).collect::<Vec<_>>();
    match kind {
        PlotKind::Cmc { classes } => {
            let n = classes.max(2);
            let mut xt: Vec<(f64, String)> = vec![(1.0, "1".into())];
            let step = (n / 5).max(1);
            xt.extend((step..n).step_by(step).map(|r| (r as f64, r.to_string())));
            xt.push((n as f64, n.to_string()));
            xt.dedup_by(|a, b| a.0 == b.0);
            Axes {
                x: "rank",
                y: "recognition rate",
                xt,
                yt: unit(&[0.0, 0.2, 0.4, 0.6, 0.8, 1.0]),
                range: ((1.0, n as f64), (0.0, 1.0)),
            }
        }
        PlotKind::Det => {
            let lo = probit(crate::classify::plots::DET_RANGE.0);
            let hi = probit(crate::classify::plots::DET_RANGE.1);
            let t: Vec<(f64, String)> = [0.001, 0.01, 0.05, 0.2, 0.4, 0.8]
                .iter()
                .map(|&r| (probit(r), format!("{}", 100.0 * r)))
                .collect();
            Axes {
                x: "FAR (%)",
                y: "FRR (%)",
                xt: t.clone(),
                yt: t,
                range: ((lo, hi), (lo, hi)),
            }
        }
        PlotKind::Roc => Axes {
            x: "false acceptance rate",
            y: "verification rate",
            xt: unit(&[0.0, 0.2, 0.4, 0.6, 0.8, 1.0]),
            yt: unit(&[0.0, 0.2, 0.4, 0.6, 0.8, 1.0]),
            range: ((0.0, 1.0), (0.0, 1.0)),
        },
    }
}

/// Pixel position of data `(x, y)` in the figure.
fn pixel(a: &Axes, x: f64, y: f64) -> (i32, i32) {
    let ((x0, x1), (y0, y1)) = a.range;
    let w = f64::from(PLOT.0) - 2.0 * MARGIN;
    let h = f64::from(PLOT.1) - 2.0 * MARGIN;
    let px = MARGIN + (x - x0) / (x1 - x0) * w;
    let py = MARGIN + (1.0 - (y - y0) / (y1 - y0)) * h;
    (AT.0 + px.round() as i32, AT.1 + py.round() as i32)
}

/// Everything placed as text or legend: `(text, x, y, anchor)` and legend
/// entries `(label, colour, dashed)`.
type Layout = (
    Vec<(String, i32, i32, Alignment)>,
    Vec<(String, RGBColor, bool)>,
);

fn layout(a: &Axes, legend: &[(String, RGBColor, bool)], title: &str) -> Layout {
    let mut t = vec![];
    let bottom = AT.1 + PLOT.1 as i32;
    for (v, s) in &a.xt {
        t.push((
            s.clone(),
            pixel(a, *v, a.range.1 .0).0,
            bottom + 11,
            Alignment::Center,
        ));
    }
    for (v, s) in &a.yt {
        t.push((
            s.clone(),
            AT.0 - 4,
            pixel(a, a.range.0 .0, *v).1 + 3,
            Alignment::Right,
        ));
    }
    t.push((
        a.x.into(),
        AT.0 + PLOT.0 as i32 / 2,
        bottom + 25,
        Alignment::Center,
    ));
    t.push((a.y.into(), AT.0 + 4, AT.1 - 4, Alignment::Left));
    t.push((
        title.into(),
        AT.0 + PLOT.0 as i32 + 20,
        AT.1 + 8,
        Alignment::Left,
    ));
    (t, legend.to_vec())
}

fn legend_y(i: usize) -> i32 {
    AT.1 + 30 + 16 * i as i32
}

/// A canvas for `embedded-graphics` over an RGB image.
struct Canvas<'a>(&'a mut image::RgbImage);

impl OriginDimensions for Canvas<'_> {
    fn size(&self) -> Size {
        Size::new(self.0.width(), self.0.height())
    }
}

impl DrawTarget for Canvas<'_> {
    type Color = Rgb888;
    type Error = core::convert::Infallible;
    fn draw_iter<I: IntoIterator<Item = Pixel<Rgb888>>>(
        &mut self,
        pixels: I,
    ) -> core::result::Result<(), Self::Error> {
        for Pixel(p, c) in pixels {
            if let (Ok(x), Ok(y)) = (u32::try_from(p.x), u32::try_from(p.y)) {
                if x < self.0.width() && y < self.0.height() {
                    self.0.put_pixel(x, y, image::Rgb([c.r(), c.g(), c.b()]));
                }
            }
        }
        Ok(())
    }
}

fn png(kind: PlotKind, curves: &[Curve], lay: &Layout) -> image::RgbImage {
    let mut img = image::RgbImage::from_pixel(SIZE.0, SIZE.1, image::Rgb([255; 3]));
    let plot = render_png(kind, curves, PLOT);
    image::imageops::replace(&mut img, &plot, i64::from(AT.0), i64::from(AT.1));
    let style = MonoTextStyle::new(&FONT_6X10, Rgb888::BLACK);
    let mut canvas = Canvas(&mut img);
    for (s, x, y, al) in &lay.0 {
        let _ = Text::with_alignment(s, Point::new(*x, *y), style, *al).draw(&mut canvas);
    }
    let lx = AT.0 + PLOT.0 as i32 + 20;
    for (i, (s, col, dashed)) in lay.1.iter().enumerate() {
        let y = legend_y(i);
        for k in 0..28 {
            if !dashed || k % 9 < 6 {
                for dy in 0..2 {
                    canvas.0.put_pixel(
                        (lx + k) as u32,
                        (y + dy) as u32,
                        image::Rgb([col.0, col.1, col.2]),
                    );
                }
            }
        }
        let _ = Text::new(s, Point::new(lx + 34, y + 4), style).draw(&mut canvas);
    }
    img
}

fn svg(kind: PlotKind, curves: &[Curve], lay: &Layout) -> String {
    let inner = render_svg(kind, curves, PLOT).replacen(
        "<svg ",
        &format!("<svg x=\"{}\" y=\"{}\" ", AT.0, AT.1),
        1,
    );
    let mut s = format!(
        "<svg width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} {1}\" xmlns=\"http://www.w3.org/2000/svg\">\n<rect width=\"{0}\" height=\"{1}\" fill=\"white\"/>\n{inner}\n",
        SIZE.0, SIZE.1
    );
    let esc = |t: &str| t.replace('&', "&amp;").replace('<', "&lt;");
    for (t, x, y, al) in &lay.0 {
        let anchor = match al {
            Alignment::Left => "start",
            Alignment::Center => "middle",
            Alignment::Right => "end",
        };
        s.push_str(&format!(
            "<text x=\"{x}\" y=\"{y}\" font-family=\"sans-serif\" font-size=\"11\" text-anchor=\"{anchor}\">{}</text>\n",
            esc(t)
        ));
    }
    let lx = AT.0 + PLOT.0 as i32 + 20;
    for (i, (t, c, dashed)) in lay.1.iter().enumerate() {
        let y = legend_y(i);
        let dash = if *dashed {
            " stroke-dasharray=\"6 3\""
        } else {
            ""
        };
        s.push_str(&format!(
            "<line x1=\"{lx}\" y1=\"{y}\" x2=\"{}\" y2=\"{y}\" stroke=\"rgb({},{},{})\" stroke-width=\"2\"{dash}/>\n<text x=\"{}\" y=\"{}\" font-family=\"sans-serif\" font-size=\"11\">{}</text>\n",
            lx + 28, c.0, c.1, c.2, lx + 34, y + 4, esc(t)
        ));
    }
    s.push_str("</svg>\n");
    s
}

fn write_one(dir: &Path, name: &str, kind: PlotKind, curves: &[Curve], lay: &Layout) -> Result<()> {
    let img = png(kind, curves, lay);
    let mut buf = std::io::Cursor::new(Vec::new());
    img.write_to(&mut buf, image::ImageFormat::Png)
        .map_err(|source| HostError::Encode {
            name: name.to_owned(),
            source,
        })?;
    write_atomic(&dir.join(format!("{name}.png")), buf.get_ref())?;
    write_atomic(
        &dir.join(format!("{name}.svg")),
        svg(kind, curves, lay).as_bytes(),
    )
}

/// Writes `fig8_{cmc,det,roc}.{png,svg}` (float networks) and
/// `fig8_{cmc,det,roc}_int8.{png,svg}` to `dir`.
///
/// # Errors
/// I/O and encoding errors.
pub fn write_fig8(dir: &Path, c: &Fig8Curves) -> Result<()> {
    ensure_dir(dir)?;
    for (set, suffix, what) in [
        (&c.float, "", "float networks"),
        (&c.int8, "_int8", "int8 networks"),
    ] {
        let classes = set.first().map_or(2, |(_, r, _)| r.len());
        let mut legend: Vec<(String, RGBColor, bool)> = set
            .iter()
            .map(|(k, _, _)| {
                let (col, d) = style(*k);
                (
                    k.label()
                        .replace(" + conspicuity + luminance", " + consp. + lum."),
                    col,
                    d,
                )
            })
            .collect();
        let curve = |pts: Vec<(f64, f64)>, k: Condition| {
            let (colour, dashed) = style(k);
            Curve {
                points: pts,
                colour,
                dashed,
                label: k.label().to_string(),
            }
        };
        let cmc: Vec<Curve> = set
            .iter()
            .map(|(k, r, _)| curve(cmc_points(r), *k))
            .collect();
        let det: Vec<Curve> = set
            .iter()
            .map(|(k, _, d)| curve(d.points().iter().map(|p| (p.far, p.frr)).collect(), *k))
            .collect();
        let roc: Vec<Curve> = set.iter().map(|(k, _, d)| curve(d.roc(), *k)).collect();
        let det_legend = legend.clone();
        legend.push(("random guess".into(), MAGENTA, true));
        for (name, kind, curves, leg) in [
            ("cmc", PlotKind::Cmc { classes }, cmc, &legend),
            ("det", PlotKind::Det, det, &det_legend),
            ("roc", PlotKind::Roc, roc, &legend),
        ] {
            let lay = layout(
                &axes(kind),
                leg,
                &format!("{} ({what})", name.to_uppercase()),
            );
            write_one(dir, &format!("fig8_{name}{suffix}"), kind, &curves, &lay)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn styles_follow_the_paper() {
        for c in Condition::PAPER {
            let joint = matches!(c, Condition::ShapeRange | Condition::All);
            assert_eq!(style(c).1, !joint, "{c:?}");
        }
        let colours: std::collections::HashSet<_> = Condition::PAPER
            .iter()
            .map(|&c| {
                style(c).0 .0 as u32 * 65536 + style(c).0 .1 as u32 * 256 + style(c).0 .2 as u32
            })
            .collect();
        assert_eq!(colours.len(), 7);
    }

    #[test]
    fn figures_have_text_and_every_curve() {
        let det = Det::sweep(&[0.9, 0.8, 0.7], &[0.1, 0.5, 0.75]).unwrap();
        let curves = Fig8Curves {
            float: vec![
                (Condition::Shape, vec![0.5, 0.8, 1.0], det.clone()),
                (Condition::All, vec![0.7, 0.9, 1.0], det.clone()),
            ],
            int8: vec![(Condition::Range, vec![0.4, 0.7, 1.0], det)],
        };
        let dir = tempfile::tempdir().unwrap();
        write_fig8(dir.path(), &curves).unwrap();
        let svg = std::fs::read_to_string(dir.path().join("fig8_roc.svg")).unwrap();
        for t in [
            "verification rate",
            "Shape",
            "random guess",
            "stroke-dasharray",
        ] {
            assert!(svg.contains(t), "{t}");
        }
        let img = image::open(dir.path().join("fig8_cmc.png"))
            .unwrap()
            .to_rgb8();
        let has = |c: RGBColor| img.pixels().filter(|p| p.0 == [c.0, c.1, c.2]).count();
        assert!(has(style(Condition::Shape).0) > 50 && has(style(Condition::All).0) > 50);
        // Text: black pixels left of the plot (tick values).
        let black = (0..AT.0 as u32)
            .flat_map(|x| (0..SIZE.1).map(move |y| (x, y)))
            .filter(|&(x, y)| img.get_pixel(x, y).0 == [0, 0, 0])
            .count();
        assert!(black > 20, "{black}");
        assert!(dir.path().join("fig8_det_int8.png").is_file());
    }
}
