//! Plots drawn with `plotters` into in-memory RGB images, labelled with the
//! built-in mono fonts of `embedded-graphics` (no font files needed).

use crate::canvas::{draw_marks, font_for, text_width, HAnchor, TextMark, VAnchor};
use image::RgbImage;
use plotters::prelude::*;

/// A profile plot like the paper's Fig. 4: the 360 max-radius z-scores (red)
/// and the 360 min-radius z-scores (blue) of a shape vector, against the
/// angle bin from -180° (left) to 179° (right), with the zero line in grey.
/// `values` holds the 720 elements, max profile first.
///
/// Labels: the title and a legend ("max r" in red, "min r" in blue) along
/// the top, the z-score limits and 0 on the left, angles in degrees below.
pub fn shape_vector(values: &[f32], width: u32, height: u32) -> RgbImage {
    let mut buf = vec![255u8; (width * height * 3) as usize];
    let font = font_for(width);
    let (cw, ch) = (font.character_size.width, font.character_size.height);
    let mut marks = Vec::new();
    let half = values.len() / 2;
    let (max, min) = values.split_at(half);
    let limit = values.iter().fold(
        1.0f32,
        |m, v| if v.is_finite() { m.max(v.abs()) } else { m },
    );
    {
        let root = BitMapBackend::with_buffer(&mut buf, (width, height)).into_drawing_area();
        let chart = ChartBuilder::on(&root)
            .margin_top(ch + 4)
            .margin_bottom(ch + 4)
            .margin_left(4 * cw + 6)
            .margin_right(2 * cw + 2)
            .build_cartesian_2d(0f32..half as f32, -limit..limit);
        // Drawing into a memory buffer of the right size cannot fail, but a
        // failure would only leave the plot blank: ignore it.
        if let Ok(mut chart) = chart {
            let series = |v: &[f32]| -> Vec<(f32, f32)> {
                v.iter().enumerate().map(|(i, &z)| (i as f32, z)).collect()
            };
            let grey = RGBColor(170, 170, 170);
            let _ = chart.draw_series(LineSeries::new([(0.0, 0.0), (half as f32, 0.0)], grey));
            // Min first and wider: for a convex object the two coincide, and
            // the thin max line on top keeps both visible.
            let _ = chart.draw_series(LineSeries::new(series(min), BLUE.stroke_width(3)));
            let _ = chart.draw_series(LineSeries::new(series(max), RED.stroke_width(1)));
            let _ = root.draw(&Rectangle::new(
                [(0, 0), (width as i32 - 1, height as i32 - 1)],
                grey,
            ));
            marks = shape_marks(&chart, limit, half as f32, width, font);
        }
        let _ = root.present();
    }
    let mut img =
        RgbImage::from_raw(width, height, buf).unwrap_or_else(|| RgbImage::new(width, height));
    draw_marks(&mut img, &marks, font);
    img
}

type ShapeChart<'a, 'b> = ChartContext<
    'a,
    BitMapBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf32, plotters::coord::types::RangedCoordf32>,
>;

/// The shape plot's texts: title and legend on top, ticks left and below.
fn shape_marks(
    chart: &ShapeChart<'_, '_>,
    limit: f32,
    bins: f32,
    width: u32,
    font: &embedded_graphics::mono_font::MonoFont<'_>,
) -> Vec<TextMark> {
    let w = i32::try_from(width).unwrap_or(i32::MAX);
    let cw = i32::try_from(font.character_size.width).unwrap_or(1);
    let (left, _) = chart.backend_coord(&(0.0, limit));
    let (right, bottom) = chart.backend_coord(&(bins, -limit));
    let mut marks = Vec::new();
    // The limits' labels hang inside the plot's height, clear of the title
    // row and the angle labels.
    for (v, anchor) in [
        (limit, VAnchor::Top),
        (0.0, VAnchor::Middle),
        (-limit, VAnchor::Bottom),
    ] {
        let (_, y) = chart.backend_coord(&(0.0, v));
        let text = if v == 0.0 {
            "0".into()
        } else {
            format!("{v:.1}")
        };
        marks.push(TextMark::new(text, (left - 3, y), HAnchor::Right, anchor));
    }
    // Five angle ticks if they fit, else the ends and the middle.
    let degrees: &[i32] = if right - left >= 25 * cw {
        &[-180, -90, 0, 90, 180]
    } else {
        &[-180, 0, 180]
    };
    for &d in degrees {
        let (x, _) = chart.backend_coord(&((d + 180) as f32 * bins / 360.0, -limit));
        marks.push(TextMark::new(
            d.to_string(),
            (x, bottom + 3),
            HAnchor::Centre,
            VAnchor::Top,
        ));
    }
    // Legend at the top right, the title at the top left if there is room.
    let (max_r, min_r) = ("max r", "min r");
    let legend_w = text_width(font, max_r) + cw + text_width(font, min_r);
    let x_min = w - 3 - text_width(font, min_r);
    marks.push(TextMark::new(min_r, (w - 3, 2), HAnchor::Right, VAnchor::Top).coloured(BLUE_TEXT));
    marks.push(
        TextMark::new(max_r, (x_min - cw, 2), HAnchor::Right, VAnchor::Top).coloured(RED_TEXT),
    );
    let title = "z-score by angle";
    if 3 + text_width(font, title) + cw + legend_w <= w - 3 {
        marks.push(TextMark::new(title, (3, 2), HAnchor::Left, VAnchor::Top));
    }
    marks
}

/// Legend text colours: the lines' colours, a little darker.
const RED_TEXT: image::Rgb<u8> = image::Rgb([210, 0, 0]);
const BLUE_TEXT: image::Rgb<u8> = image::Rgb([0, 0, 210]);

#[cfg(test)]
mod tests {
    #[test]
    fn the_plot_draws_both_profiles() {
        let v: Vec<f32> = (0..720).map(|i| if i < 360 { 1.0 } else { -1.0 }).collect();
        let img = super::shape_vector(&v, 200, 100);
        let red = img.pixels().filter(|p| p.0[0] > 200 && p.0[1] < 80).count();
        let blue = img.pixels().filter(|p| p.0[2] > 200 && p.0[0] < 80).count();
        assert!(red > 100 && blue > 100, "red {red} blue {blue}");
    }

    #[test]
    fn the_plot_is_labelled_on_three_sides() {
        use crate::canvas::TEXT;
        let v: Vec<f32> = (0..720).map(|i| ((i % 360) as f32 / 60.0).sin()).collect();
        let (w, h) = (160u32, 120u32);
        let img = super::shape_vector(&v, w, h);
        let count = |x0: u32, y0: u32, x1: u32, y1: u32, c: [u8; 3]| {
            (y0..y1)
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .filter(|&(x, y)| img.get_pixel(x, y).0 == c)
                .count()
        };
        // 5x8 font at 160 px: tick labels left of x = 26 and below y = 108.
        let y_ticks = count(1, 12, 24, 108, TEXT.0);
        let x_ticks = count(20, 110, w - 1, h - 1, TEXT.0);
        let legend_red = count(w / 2, 1, w - 1, 11, super::RED_TEXT.0);
        let legend_blue = count(w / 2, 1, w - 1, 11, super::BLUE_TEXT.0);
        let title = count(1, 1, w / 2, 11, TEXT.0);
        assert!(
            y_ticks > 30 && x_ticks > 30 && legend_red > 15 && legend_blue > 15 && title > 30,
            "{y_ticks} {x_ticks} {legend_red} {legend_blue} {title}"
        );
        // A narrow plot drops the title rather than overlap the legend.
        let narrow = super::shape_vector(&v, 90, 60);
        let title = (1..8)
            .flat_map(|y| (1..20).map(move |x| (x, y)))
            .filter(|&(x, y)| narrow.get_pixel(x, y).0 == TEXT.0)
            .count();
        assert_eq!(title, 0);
    }

    #[test]
    fn tiny_plots_do_not_panic() {
        for (w, h) in [(0, 0), (1, 1), (10, 200), (200, 10)] {
            let img = super::shape_vector(&[0.5; 720], w, h);
            assert_eq!(img.dimensions(), (w, h));
        }
    }
}
