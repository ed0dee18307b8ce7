//! The DEM f32 reference (`protogist_host::reference::stereo`): the random-
//! dot anchor of the spec (§7), the synthetic demo scene, and bad input.

use protogist::image::{ImageView, ImageViewMut, Rgb8};
use protogist::synth::{render_disparity, render_left, render_right, SceneSpec};
use protogist_host::error::HostError;
use protogist_host::reference::stereo::table::{DemTable, DEFAULT_TABLE};
use protogist_host::reference::stereo::train::random_dot_pair;
use protogist_host::reference::stereo::{self as dem, DemParams, StereoError};
use protogist_host::stereo_cmd::{run_stereo, StereoOptions};
use protogist_tests::{SGM_P1, SGM_P2, SGM_PATHS};
use std::path::Path;

fn default_decoder() -> dem::Decoder {
    DemTable::parse(DEFAULT_TABLE).unwrap().to_decoder()
}

/// % of interior pixels of RDS at every d in 0..=15 whose argmax is off by
/// more than 1 px.
fn rds_bad1(params: &DemParams) -> f64 {
    let dec = default_decoder();
    let (w, h) = (72, 48);
    let (mut bad, mut n) = (0, 0);
    for d in 0..=15usize {
        // Seeds unlike the training ones.
        let (l, r) = random_dot_pair(w, h, d, 0xabcd_0000 + d as u64);
        let m = dem::stereo_grey(params, &dec, l, r);
        for y in 12..h - 12 {
            for x in 15 + 12..w - 12 {
                n += 1;
                let v = m.left_raw[y * w + x].unwrap();
                bad += usize::from((v - d as f32).abs() > 1.0);
            }
        }
    }
    100.0 * bad as f64 / n as f64
}

#[test]
fn random_dots_bad1_below_5_percent_unpooled_and_1_pooled() {
    let unpooled = rds_bad1(&DemParams {
        pool_radius: 0,
        ..DemParams::default()
    });
    let pooled = rds_bad1(&DemParams::default());
    eprintln!("RDS bad-1: unpooled {unpooled:.2} %, 5x5 pooled {pooled:.2} %");
    assert!(unpooled < 5.0, "{unpooled}");
    assert!(pooled < 1.0, "{pooled}");
}

/// The anchor holds with semi-global aggregation (the CLI's default
/// penalties and 5 paths), unpooled and after 5x5 pooling: on a uniform
/// disparity the smoothness term can only help, so the same 5 % bound.
#[test]
fn random_dots_bad1_below_5_percent_with_sgm() {
    let sgm = dem::Aggregation::Sgm {
        p1: SGM_P1,
        p2: SGM_P2,
        paths: SGM_PATHS,
    };
    for pool_radius in [0, 2] {
        let bad = rds_bad1(&DemParams {
            pool_radius,
            aggregation: sgm,
            ..DemParams::default()
        });
        eprintln!("RDS bad-1 with SGM, pool radius {pool_radius}: {bad:.2} %");
        assert!(bad < 5.0, "{bad}");
    }
}

fn render(spec: &SceneSpec, w: usize, h: usize) -> (Vec<Rgb8>, Vec<Rgb8>, Vec<u8>) {
    let (mut l, mut r, mut d) = (
        vec![Rgb8::default(); w * h],
        vec![Rgb8::default(); w * h],
        vec![0u8; w * h],
    );
    render_left(spec, &mut ImageViewMut::packed(&mut l, w, h).unwrap()).unwrap();
    render_right(spec, &mut ImageViewMut::packed(&mut r, w, h).unwrap()).unwrap();
    render_disparity(spec, &mut ImageViewMut::packed(&mut d, w, h).unwrap()).unwrap();
    (l, r, d)
}

#[test]
fn demo_scene_object_and_background_bad2() {
    let (w, h) = (160, 120);
    let spec = SceneSpec::demo(w, h);
    let (l, r, gt) = render(&spec, w, h);
    let params = DemParams::default();
    let m = dem::stereo(
        &params,
        &default_decoder(),
        &ImageView::packed(&l, w, h).unwrap(),
        &ImageView::packed(&r, w, h).unwrap(),
    )
    .unwrap();
    let obj = spec.objects[0].disparity;
    // Per region: (bad-2 over estimated pixels, density), away from the
    // left border where the right view has no match.
    let region = |want: u8| {
        let (mut n, mut est, mut bad) = (0, 0, 0);
        for y in 0..h {
            for x in 16..w {
                if gt[y * w + x] != want {
                    continue;
                }
                n += 1;
                if let Some(v) = m.disparity_f32[y * w + x] {
                    est += 1;
                    bad += usize::from((v - f32::from(want)).abs() > 2.0);
                }
            }
        }
        (
            100.0 * bad as f64 / est as f64,
            100.0 * est as f64 / n as f64,
        )
    };
    let (ob, od) = region(obj);
    let (bb, bd) = region(spec.background_disparity);
    eprintln!("demo: object bad-2 {ob:.1} % (density {od:.1} %), background {bb:.1} % ({bd:.1} %)");
    assert!(ob < 5.0 && od > 70.0, "object {ob} {od}");
    assert!(bb < 5.0 && bd > 70.0, "background {bb} {bd}");
}

#[test]
fn flat_images_give_an_all_off_map() {
    let (w, h) = (64, 48);
    let px = vec![Rgb8::new(90, 90, 90); w * h];
    let v = ImageView::packed(&px, w, h).unwrap();
    let m = dem::stereo(&DemParams::default(), &default_decoder(), &v, &v).unwrap();
    assert!(m.disparity.iter().all(|c| c.is_off()));
    assert_eq!(m.off_texture, w * h);
}

#[test]
fn bad_input_is_a_typed_error() {
    let p = DemParams::default();
    let dec = default_decoder();
    let px = vec![Rgb8::default(); 64 * 48];
    let v = |w, h| ImageView::packed(&px[..w * h], w, h).unwrap();
    let run = |a: &ImageView<'_, Rgb8>, b: &ImageView<'_, Rgb8>| dem::stereo(&p, &dec, a, b);
    assert!(matches!(
        run(&v(64, 48), &v(60, 48)),
        Err(StereoError::SizeMismatch { .. })
    ));
    assert!(matches!(
        run(&v(20, 48), &v(20, 48)),
        Err(StereoError::TooSmall { .. })
    ));
    let narrow = DemParams { max_disp: 40, ..p };
    let wide = default_decoder_for(&narrow);
    assert!(matches!(
        dem::stereo(&narrow, &wide, &v(40, 40), &v(40, 40)),
        Err(StereoError::MaxDispTooLarge { .. })
    ));
    let other = DemParams { max_disp: 14, ..p };
    assert!(matches!(
        dem::stereo(&other, &dec, &v(64, 48), &v(64, 48)),
        Err(StereoError::DecoderMismatch { .. })
    ));
}

fn default_decoder_for(p: &DemParams) -> dem::Decoder {
    // An untrained decoder of the right layout: only the checks run.
    let layout = dem::layout_of(p);
    let n = usize::from(p.max_disp) + 1;
    dem::Decoder {
        layout,
        weights: vec![[0.0; 3]; layout.groups() * n],
        bias: vec![1.0; n],
    }
}

fn write_png(dir: &Path, name: &str, img: image::DynamicImage) -> std::path::PathBuf {
    let p = dir.join(name);
    img.save(&p).unwrap();
    p
}

#[test]
fn the_command_rejects_bad_files_with_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rgb = |w, h| image::DynamicImage::ImageRgb8(image::RgbImage::new(w, h));
    // Large enough for the engine's coarsest level (a quarter of the size).
    let left = write_png(d, "l.png", rgb(128, 96));
    let right = write_png(d, "r.png", rgb(128, 96));
    let small = write_png(d, "s.png", rgb(120, 96));
    let gt_small = write_png(
        d,
        "g.png",
        image::DynamicImage::ImageLuma8(image::GrayImage::from_pixel(10, 10, image::Luma([1]))),
    );
    let gt_rgb = write_png(d, "grgb.png", rgb(128, 96));
    let junk = d.join("junk.pfm");
    std::fs::write(&junk, b"Pf\n128 96\n-1\n\x00\x00").unwrap();
    let opts = |right: &Path, gt: Option<&Path>, max_disp| StereoOptions {
        gt: gt.map(Path::to_path_buf),
        max_disp,
        ..StereoOptions::new(left.clone(), right.to_path_buf(), d.join("out"))
    };
    let err = |o: StereoOptions| run_stereo(&o).unwrap_err();
    assert!(matches!(
        err(opts(&small, None, 15)),
        HostError::Stereo(StereoError::SizeMismatch { .. })
    ));
    assert!(matches!(
        err(opts(&right, Some(&gt_small), 15)),
        HostError::GroundTruthSize { .. }
    ));
    assert!(matches!(
        err(opts(&right, Some(&gt_rgb), 15)),
        HostError::BadGroundTruth { .. }
    ));
    assert!(matches!(
        err(opts(&right, Some(&junk), 15)),
        HostError::BadGroundTruth { .. }
    ));
    assert!(matches!(
        err(opts(&right, None, 200)),
        HostError::Stereo(StereoError::MaxDispTooLarge { .. })
    ));
    for e in [
        err(opts(&small, None, 15)),
        err(opts(&right, Some(&junk), 15)),
    ] {
        assert!(!e.to_string().contains('\n'), "{e}");
    }
    // A flat pair is not an error: every pixel is OFF.
    let s = run_stereo(&opts(&right, None, 15)).unwrap();
    assert_eq!(s.get("ON %"), Some("0.0"));
}
