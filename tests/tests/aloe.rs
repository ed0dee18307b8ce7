//! The conspicuity stage on real data: Middlebury Aloe (left view), area-
//! downscaled to 160 px wide, fixed point against the f32 reference.
//!
//! Needs `cargo xtask fetch-data`; `cargo xtask ci` fetches it and sets
//! `PROTOGIST_REQUIRE_DATA=1`, so there it cannot be skipped.

use protogist::conspicuity::{self as fx, EdgeParams, LuvTables};
use protogist::image::{ImageView, ImageViewMut, Rgb8};
use protogist_host::io::{area_downscale, load_rgb, to_core_rgb, working_size};
use protogist_host::reference::conspicuity::{self as fl, luv_to_f32, LuvF};
use protogist_host::stages::run_conspicuity;
use protogist_tests::data_file;

/// Aloe's left view area-downscaled to 160 px wide, or `None` when the data
/// is missing and not required.
fn aloe_left_160() -> Option<(Vec<Rgb8>, usize, usize)> {
    let img = load_rgb(&data_file("aloe/aloeL.jpg")?).unwrap();
    let (w, h) = working_size(img.width(), img.height(), 160).unwrap();
    let rgb = to_core_rgb(&area_downscale(&img, w, h));
    assert_eq!(w, 160);
    Some((rgb, w as usize, h as usize))
}

#[test]
fn aloe_160_fixed_against_float() {
    let Some((rgb, w, h)) = aloe_left_160() else {
        return;
    };
    let view = ImageView::packed(&rgb, w, h).unwrap();
    let params = EdgeParams::default();
    let fixed = run_conspicuity(&LuvTables::new(), &params, &rgb, w, h).unwrap();

    // Stage by stage, strict: CIELUV everywhere within its bound...
    let mut luv_r = vec![[0.0f32; 3]; w * h];
    fl::rgb_to_luv(&view, &mut ImageViewMut::packed(&mut luv_r, w, h).unwrap()).unwrap();
    for (a, b) in fixed.luv.iter().zip(&luv_r) {
        let a = luv_to_f32(*a);
        assert!((a[0] - b[0]).abs() <= fx::MAX_ERR_L, "{a:?} {b:?}");
        assert!((a[1] - b[1]).abs() <= fx::MAX_ERR_U, "{a:?} {b:?}");
        assert!((a[2] - b[2]).abs() <= fx::MAX_ERR_V, "{a:?} {b:?}");
    }
    // ...and C~ of the same (fixed, smoothed) input within half an LSB.
    let sm_f: Vec<LuvF> = fixed.smoothed.iter().map(|&p| luv_to_f32(p)).collect();
    let mut raw_same = vec![None; w * h];
    let sm_view = ImageView::packed(&sm_f, w, h).unwrap();
    fl::conspicuity(
        &sm_view,
        &mut ImageViewMut::packed(&mut raw_same, w, h).unwrap(),
    )
    .unwrap();
    for (a, b) in fixed.raw.iter().zip(&raw_same) {
        let a = f32::from(a.get().unwrap().to_bits());
        assert!((a - b.unwrap() * 64.0).abs() <= fx::MAX_ERR_CONSPICUITY_LSB);
    }

    // End to end with the default smoothing. A smoothing pass compares
    // distances, and a near-tie may go one way in fixed point and the other
    // in f32 (docs/ERROR_BOUNDS.md, section 5), so no global C~ bound exists.
    // What is derived: C~ is 2-Lipschitz in its 3x3 input, so at every pixel
    // |dC~| <= 2 * (largest smoothed-map difference in its 3x3) + 0.51 LSB.
    let float = fl::edge_conspicuity(&params, &view).unwrap();
    let mut raw_r = vec![None; w * h];
    let sm_r = ImageView::packed(&float.smoothed, w, h).unwrap();
    fl::conspicuity(&sm_r, &mut ImageViewMut::packed(&mut raw_r, w, h).unwrap()).unwrap();
    let diff: Vec<f32> = sm_f
        .iter()
        .zip(&float.smoothed)
        .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f32>().sqrt())
        .collect();
    let diff = ImageView::packed(&diff, w, h).unwrap();
    let mut flipped = 0;
    for y in 0..h {
        for x in 0..w {
            let m = neighbourhood_max(&diff, x, y);
            let bound = 2.0 * m + fx::MAX_ERR_CONSPICUITY_LSB / 64.0 + 1e-4;
            let (a, b) = (
                fixed.raw[y * w + x].get().unwrap().to_num::<f32>(),
                raw_r[y * w + x].unwrap(),
            );
            assert!(
                (a - b).abs() <= bound,
                "({x},{y}): {a} vs {b}, bound {bound}"
            );
            // Without a flip, K passes keep the CIELUV error plus K/2 LSB.
            flipped += usize::from(diff.get(x, y).unwrap() > 0.0998 + 2.0 / 128.0);
        }
    }
    // The edge sets: at least 99 % of pixels agree (fixed before the first run).
    let agree = fixed
        .edges
        .iter()
        .zip(&float.conspicuity)
        .filter(|(a, b)| a.is_on() == b.is_some())
        .count();
    let n = (w * h) as f64;
    eprintln!(
        "Aloe {w}x{h}: smoothed maps differ beyond the no-flip bound at {:.2} % of pixels; \
         edge sets agree on {:.2} %; edges fixed {} float {}",
        100.0 * flipped as f64 / n,
        100.0 * agree as f64 / n,
        fixed.on_count,
        float.on_count
    );
    assert!(agree as f64 >= 0.99 * n);
    assert!(fixed.on_count > 0);
}

fn neighbourhood_max(img: &ImageView<'_, f32>, x: usize, y: usize) -> f32 {
    let mut m = 0.0f32;
    for dy in -1..=1isize {
        for dx in -1..=1isize {
            let cx = x.saturating_add_signed(dx).min(img.width() - 1);
            let cy = y.saturating_add_signed(dy).min(img.height() - 1);
            m = m.max(img.get(cx, cy).unwrap());
        }
    }
    m
}

/// Without smoothing nothing can flip: every pixel's C~ is within the chain
/// bound E of docs/ERROR_BOUNDS.md section 4.
#[test]
fn aloe_160_without_smoothing_within_chain_bound_everywhere() {
    let Some((rgb, w, h)) = aloe_left_160() else {
        return;
    };
    let mut params = EdgeParams::default();
    params.smooth.iterations = 0;
    let fixed = run_conspicuity(&LuvTables::new(), &params, &rgb, w, h).unwrap();
    let float = fl::edge_conspicuity(&params, &ImageView::packed(&rgb, w, h).unwrap()).unwrap();
    let mut raw_r = vec![None; w * h];
    let sm_r = ImageView::packed(&float.smoothed, w, h).unwrap();
    fl::conspicuity(&sm_r, &mut ImageViewMut::packed(&mut raw_r, w, h).unwrap()).unwrap();
    let e = 2.0 * (fx::MAX_ERR_L.powi(2) + fx::MAX_ERR_U.powi(2) + fx::MAX_ERR_V.powi(2)).sqrt()
        + fx::MAX_ERR_CONSPICUITY_LSB / 64.0;
    let worst = fixed
        .raw
        .iter()
        .zip(&raw_r)
        .map(|(a, b)| (a.get().unwrap().to_num::<f32>() - b.unwrap()).abs())
        .fold(0.0f32, f32::max);
    eprintln!("Aloe without smoothing: worst |dC~| {worst:.4}, bound {e:.4}");
    assert!(worst <= e);
}
