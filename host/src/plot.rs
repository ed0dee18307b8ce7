//! Plots drawn with `plotters` into in-memory RGB images (no fonts needed).

use image::RgbImage;
use plotters::prelude::*;

/// A profile plot like the paper's Fig. 4: the 360 max-radius z-scores (red)
/// and the 360 min-radius z-scores (blue) of a shape vector, against the
/// angle bin from -180° (left) to 179° (right), with the zero line in grey.
/// `values` holds the 720 elements, max profile first.
pub fn shape_vector(values: &[f32], width: u32, height: u32) -> RgbImage {
    let mut buf = vec![255u8; (width * height * 3) as usize];
    let half = values.len() / 2;
    let (max, min) = values.split_at(half);
    let limit = values.iter().fold(
        1.0f32,
        |m, v| if v.is_finite() { m.max(v.abs()) } else { m },
    );
    {
        let root = BitMapBackend::with_buffer(&mut buf, (width, height)).into_drawing_area();
        let chart = ChartBuilder::on(&root)
            .margin(4)
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
        }
        let _ = root.present();
    }
    RgbImage::from_raw(width, height, buf).unwrap_or_else(|| RgbImage::new(width, height))
}

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
}
