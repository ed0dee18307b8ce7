//! The text of the CMC, DET and ROC plots: margins, tick labels, axis
//! titles and the legend, laid out in the pixels of the built-in mono fonts.

use super::plot_style::{Chart, Curve, PlotKind, DET_RANGE, GRID_DARK, MAGENTA};
use super::probit::probit;
use crate::canvas::{font_for, text_width, HAnchor, TextMark, VAnchor, TEXT};
use embedded_graphics::mono_font::MonoFont;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

/// Font and margins of one plot, px.
#[derive(Clone, Copy, Debug)]
pub struct Layout {
    /// The font of every text.
    pub font: &'static MonoFont<'static>,
    /// Character width and height.
    cw: i32,
    ch: i32,
    /// Picture size.
    w: i32,
    h: i32,
    /// Margins around the plotting area.
    pub top: u32,
    /// Bottom margin: tick labels and the x title.
    pub bottom: u32,
    /// Left margin: tick labels.
    pub left: u32,
    /// Right margin: half a tick label.
    pub right: u32,
}

impl Layout {
    /// The layout of a `kind` plot of `(width, height)` pixels.
    pub fn new(kind: PlotKind, (width, height): (u32, u32)) -> Self {
        let font = font_for(width);
        let cw = font.character_size.width;
        let ch = font.character_size.height;
        // Widest y tick label: "0.2" or "0.1%".
        let tick_chars = if kind == PlotKind::Det { 4 } else { 3 };
        let to_i = |v: u32| i32::try_from(v).unwrap_or(i32::MAX);
        Self {
            font,
            cw: to_i(cw),
            ch: to_i(ch),
            w: to_i(width),
            h: to_i(height),
            top: ch + 8,
            bottom: 2 * ch + 10,
            left: tick_chars * cw + 8,
            right: 2 * cw + 4,
        }
    }
}

/// Axis texts of one kind: (data value, label) ticks and the titles.
struct Axes {
    x_ticks: Vec<(f64, String)>,
    y_ticks: Vec<(f64, String)>,
    x_title: &'static str,
    y_title: &'static str,
    name: &'static str,
}

fn axes(kind: PlotKind) -> Axes {
    let fifths = || -> Vec<(f64, String)> {
        (0..=5)
            .map(|k| f64::from(k) / 5.0)
            .map(|v| (v, format!("{v:.1}")))
            .collect()
    };
    match kind {
        PlotKind::Cmc { classes } => {
            // Rank 1 and every `step`th rank; crowded labels are thinned
            // later, by pixels.
            let step = [1, 2, 5, 10, 20, 50, 100, 200, 500, 1000]
                .into_iter()
                .find(|&s| classes / s <= 10)
                .unwrap_or(classes.max(1));
            let ranks = std::iter::once(1).chain((step..=classes).step_by(step).filter(|&r| r > 1));
            Axes {
                x_ticks: ranks.map(|r| (r as f64, r.to_string())).collect(),
                y_ticks: fifths(),
                x_title: "rank",
                y_title: "recognition rate",
                name: "CMC",
            }
        }
        PlotKind::Det => {
            let ticks: Vec<(f64, String)> = [0.001, 0.01, 0.05, 0.1, 0.2, 0.4, 0.8]
                .into_iter()
                .filter(|&r| r >= DET_RANGE.0 && r <= DET_RANGE.1)
                .map(|r: f64| {
                    let p = r * 100.0;
                    let text = if p < 1.0 {
                        format!("{p:.1}%")
                    } else {
                        format!("{p:.0}%")
                    };
                    (probit(r), text)
                })
                .collect();
            Axes {
                x_ticks: ticks.clone(),
                y_ticks: ticks,
                x_title: "false acceptance rate (FAR)",
                y_title: "false rejection rate (FRR)",
                name: "DET",
            }
        }
        PlotKind::Roc => Axes {
            x_ticks: fifths(),
            y_ticks: fifths(),
            x_title: "false acceptance rate (FAR)",
            y_title: "verification rate",
            name: "ROC",
        },
    }
}

/// Keeps the marks in order along one axis whose extents (from `extent`)
/// do not overlap the last kept one's, with a character's gap.
fn thinned(
    marks: Vec<TextMark>,
    extent: impl Fn(&TextMark) -> (i32, i32),
    gap: i32,
) -> Vec<TextMark> {
    let mut kept: Vec<TextMark> = Vec::with_capacity(marks.len());
    let mut end = i32::MIN;
    for m in marks {
        let (a, b) = extent(&m);
        if a >= end.saturating_add(gap) {
            end = b;
            kept.push(m);
        }
    }
    kept
}

/// Tick labels, axis titles and the plot's name.
pub fn axis_marks<DB: DrawingBackend>(
    chart: &Chart<'_, DB>,
    kind: PlotKind,
    lay: &Layout,
) -> Vec<TextMark> {
    let ax = axes(kind);
    let (x0, x1) = (chart.x_range().start, chart.x_range().end);
    let (y0, y1) = (chart.y_range().start, chart.y_range().end);
    let inside = |v: f64, lo: f64, hi: f64| v >= lo - 1e-9 && v <= hi + 1e-9;
    let font = lay.font;
    let x_marks: Vec<TextMark> = ax
        .x_ticks
        .iter()
        .filter(|(v, _)| inside(*v, x0, x1))
        .map(|(v, t)| {
            let (px, py) = chart.backend_coord(&(*v, y0));
            TextMark::new(t.clone(), (px, py + 4), HAnchor::Centre, VAnchor::Top)
        })
        .collect();
    let x_marks = thinned(
        x_marks,
        |m| {
            let w = text_width(font, &m.text);
            (m.x - w / 2, m.x - w / 2 + w)
        },
        lay.cw,
    );
    // y ticks bottom to top, thinned by rows (upwards: negate).
    let y_marks: Vec<TextMark> = ax
        .y_ticks
        .iter()
        .filter(|(v, _)| inside(*v, y0, y1))
        .map(|(v, t)| {
            let (px, py) = chart.backend_coord(&(x0, *v));
            TextMark::new(t.clone(), (px - 4, py), HAnchor::Right, VAnchor::Middle)
        })
        .collect();
    let y_marks = thinned(y_marks, |m| (-m.y - lay.ch / 2, -m.y + lay.ch / 2), 2);
    let (left, _) = chart.backend_coord(&(x0, y1));
    let (right, _) = chart.backend_coord(&(x1, y0));
    let mut marks = x_marks;
    marks.extend(y_marks);
    marks.push(TextMark::new(
        ax.x_title,
        ((left + right) / 2, lay.h - 4),
        HAnchor::Centre,
        VAnchor::Bottom,
    ));
    // The y title across the top, over the y axis; the name at the right
    // if both fit.
    marks.push(TextMark::new(
        ax.y_title,
        (3, 4),
        HAnchor::Left,
        VAnchor::Top,
    ));
    let title_end = 3 + text_width(font, ax.y_title);
    if title_end + 2 * lay.cw + text_width(font, ax.name) <= lay.w - 3 {
        marks.push(TextMark::new(
            ax.name,
            (lay.w - 3, 4),
            HAnchor::Right,
            VAnchor::Top,
        ));
    }
    marks
}

/// One legend row: text, colour, dashed.
type Entry = (String, RGBColor, bool);

/// Draws the legend box and swatches onto `root` and adds its texts to
/// `marks`; leaves it out if it does not fit in the plotting area. It sits
/// where the curves are not: lower right (CMC, ROC) or upper right (DET).
pub fn legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    chart: &Chart<'_, DB>,
    kind: PlotKind,
    curves: &[Curve],
    lay: &Layout,
    marks: &mut Vec<TextMark>,
) {
    let mut entries: Vec<Entry> = curves
        .iter()
        .filter(|c| !c.label.is_empty())
        .map(|c| (c.label.clone(), c.colour, c.dashed))
        .collect();
    entries.push(match kind {
        PlotKind::Det => ("EER (FAR = FRR)".into(), GRID_DARK, true),
        _ => ("chance".into(), MAGENTA, true),
    });
    let (x0, x1) = (chart.x_range().start, chart.x_range().end);
    let (y0, y1) = (chart.y_range().start, chart.y_range().end);
    let (pl, pt) = chart.backend_coord(&(x0, y1));
    let (pr, pb) = chart.backend_coord(&(x1, y0));
    let swatch = 3 * lay.cw;
    let row = lay.ch + 4;
    let widest = entries
        .iter()
        .map(|(t, _, _)| text_width(lay.font, t))
        .max()
        .unwrap_or(0);
    let n = i32::try_from(entries.len()).unwrap_or(i32::MAX);
    let (bw, bh) = (swatch + widest + 14, n.saturating_mul(row) + 4);
    let inset = 6;
    if bw + 2 * inset > pr - pl || bh + 2 * inset > pb - pt {
        return;
    }
    let bx = pr - inset - bw;
    let by = match kind {
        PlotKind::Det => pt + inset,
        _ => pb - inset - bh,
    };
    let _ = root.draw(&Rectangle::new(
        [(bx, by), (bx + bw, by + bh)],
        WHITE.filled(),
    ));
    let _ = root.draw(&Rectangle::new([(bx, by), (bx + bw, by + bh)], GRID_DARK));
    for (k, (text, colour, dashed)) in (0..).zip(entries) {
        let y = by + 2 + k * row + row / 2;
        let ends = [(bx + 4, y), (bx + 4 + swatch, y)];
        let style = colour.stroke_width(2);
        let _ = if dashed {
            root.draw(&DashedPathElement::new(ends, 5, 3, style))
        } else {
            root.draw(&PathElement::new(ends, style))
        };
        marks.push(
            TextMark::new(text, (bx + 10 + swatch, y), HAnchor::Left, VAnchor::Middle)
                .coloured(TEXT),
        );
    }
}
