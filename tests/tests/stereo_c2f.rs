//! Coarse-to-fine search of the DEM f32 reference (the reference of core's
//! engine, docs/STEREO.md): the search windows, their effect on the
//! decision and on the SGM costs, the random-dot anchor through two
//! levels, and the command's size check on Aloe (needs `cargo xtask
//! fetch-data`).

use protogist::image::{ImageView, Rgb8};
use protogist_host::dem_tables::decoder_for;
use protogist_host::reference::stereo::c2f::{
    level_max_disp, level_params, stereo_c2f, windows_from,
};
use protogist_host::reference::stereo::filters::Plane;
use protogist_host::reference::stereo::readout::Scores;
use protogist_host::reference::stereo::sgm::{costs, costs_in, EXCLUDED};
use protogist_host::reference::stereo::table::{DemTable, DEFAULT_TABLE};
use protogist_host::reference::stereo::train::random_dot_pair;
use protogist_host::reference::stereo::{
    self as dem, stereo_planes, stereo_planes_in, DemParams, DisparityMapsF, Windows,
};
use protogist_tests::{aloe_files, stereo_options, SGM_P1, SGM_P2, SGM_PATHS};

fn default_decoder() -> dem::Decoder {
    DemTable::parse(DEFAULT_TABLE).unwrap().to_decoder()
}

fn sgm() -> dem::Aggregation {
    dem::Aggregation::Sgm {
        p1: SGM_P1,
        p2: SGM_P2,
        paths: SGM_PATHS,
    }
}

fn rgb(p: &Plane) -> Vec<Rgb8> {
    p.data
        .iter()
        .map(|&v| {
            let g = v.round().clamp(0.0, 255.0) as u8;
            Rgb8::new(g, g, g)
        })
        .collect()
}

/// With no window, or windows spanning every candidate, the windowed
/// engine is the plain one; with a window, every left-referenced argmax
/// lies in it, even where the evidence points elsewhere.
#[test]
fn windows_restrict_the_decision_and_nothing_else() {
    let dec = default_decoder();
    let (w, h, d) = (64, 40, 9usize);
    let (l, r) = random_dot_pair(w, h, d, 0x5eed);
    for aggregation in [dem::Aggregation::Box, sgm()] {
        let params = DemParams {
            aggregation,
            ..DemParams::default()
        };
        let plain = stereo_planes(&params, &dec, vec![l.clone()], vec![r.clone()]);
        let none = stereo_planes_in(&params, &dec, vec![l.clone()], vec![r.clone()], None);
        assert_eq!(plain, none);
        let all = Windows {
            left: vec![Some((0, 15)); w * h],
            right: vec![Some((0, 15)); w * h],
            band: None,
        };
        let full = stereo_planes_in(&params, &dec, vec![l.clone()], vec![r.clone()], Some(&all));
        assert_eq!(plain, full, "{aggregation:?}");
        // A window that excludes the true disparity: 2..=5.
        let wrong = Windows {
            left: vec![Some((2, 5)); w * h],
            right: vec![Some((2, 5)); w * h],
            band: None,
        };
        let m = stereo_planes_in(
            &params,
            &dec,
            vec![l.clone()],
            vec![r.clone()],
            Some(&wrong),
        );
        // Where the border allows the whole window (x >= 5).
        let inside = m
            .left_raw
            .iter()
            .enumerate()
            .filter(|(p, _)| p % w >= 5)
            .filter_map(|(_, v)| *v)
            .all(|v| (2.0..=5.0).contains(&v));
        assert!(inside, "{aggregation:?}");
        let right_mostly = plain.left_raw[20 * w + 40].unwrap();
        assert!((right_mostly - d as f32).abs() <= 1.0, "{right_mostly}");
    }
}

/// Inside a window the costs are normalised over the window alone (0 at
/// its best, mean gap 1); outside they are [`EXCLUDED`]; the window's
/// candidates beyond the border (`top`) take its worst valid cost.
#[test]
fn windowed_costs_are_normalised_over_the_window() {
    // One pixel, 6 candidates, score raw(d)/total − bias(d) with bias 0.
    let scores = Scores {
        width: 1,
        height: 1,
        disparities: 6,
        raw: vec![6.0, 1.0, 4.0, 2.0, 0.0, 5.0],
        total: vec![1.0],
    };
    let bias = [0.0f32; 6];
    let plain = costs(&scores, &bias, |_| true, |_| 5);
    // Gaps to the best (6): 0 5 2 4 6 1, mean 3.
    let want: Vec<f32> = [0.0, 5.0, 2.0, 4.0, 6.0, 1.0]
        .iter()
        .map(|g| g / 3.0)
        .collect();
    let close = |a: &[f32], b: &[f32]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6);
    assert!(close(&plain, &want), "{plain:?}");
    // Window 1..=3, border at 4: gaps in the window to its best (4): 3 0 2,
    // mean 5/3; the rest excluded.
    let c = costs_in(&scores, &bias, |_| true, |_| 4, |_| Some((1, 3)));
    let g = |v: f32| v / (5.0 / 3.0);
    let want = [EXCLUDED, g(3.0), g(0.0), g(2.0), EXCLUDED, EXCLUDED];
    assert!(close(&c, &want), "{c:?}");
    // Window 2..=5, border at 3: valid 2, 3 (scores 4, 2: gaps 0, 2, mean
    // 1); 4 and 5 are beyond the border and take the worst, 2.
    let c = costs_in(&scores, &bias, |_| true, |_| 3, |_| Some((2, 5)));
    let want = [EXCLUDED, EXCLUDED, 0.0, 2.0, 2.0, 2.0];
    assert!(close(&c, &want), "{c:?}");
    // Without evidence, or with the window wholly beyond the border: 0 in
    // the window.
    let want = [EXCLUDED, EXCLUDED, 0.0, 0.0, 0.0, 0.0];
    let c = costs_in(&scores, &bias, |_| false, |_| 5, |_| Some((2, 5)));
    assert!(close(&c, &want), "{c:?}");
    let c = costs_in(&scores, &bias, |_| true, |_| 1, |_| Some((2, 5)));
    assert!(close(&c, &want), "{c:?}");
}

/// The windows map the parent pixel's argmax `d` to the `2·radius + 1`
/// candidates around `2d`, shifted into `0..=max_disp`, and a parent
/// without an estimate to the lowest window.
#[test]
fn windows_come_from_the_parent_pixel() {
    let coarse = DisparityMapsF {
        width: 2,
        height: 1,
        disparity: vec![],
        disparity_f32: vec![],
        left_raw: vec![Some(3.4), None],
        right_raw: vec![Some(0.2), Some(7.0)],
        off_texture: 0,
        off_ambiguous: 0,
        off_inconsistent: 0,
        why_off: vec![],
    };
    let ws = windows_from(&coarse, 5, 2, 2, None, 14);
    // x 0, 1 -> parent 0; x 2, 3 -> parent 1; x 4 -> parent 1 (clamped).
    let row = [
        Some((5, 9)),
        Some((5, 9)),
        Some((0, 4)),
        Some((0, 4)),
        Some((0, 4)),
    ];
    assert_eq!(&ws.left[..5], &row);
    assert_eq!(&ws.left[5..], &row);
    // 2 · 0.2 rounds to 0: 0..=4, not −2..=2; 2 · 7 = 14: 10..=14.
    let rrow = [
        Some((0, 4)),
        Some((0, 4)),
        Some((10, 14)),
        Some((10, 14)),
        Some((10, 14)),
    ];
    assert_eq!(&ws.right[..5], &rrow);
    // A range shorter than the window: the whole range.
    assert_eq!(
        windows_from(&coarse, 5, 2, 2, None, 3).left[0],
        Some((0, 3))
    );
    assert_eq!(level_max_disp(32, 1), 16);
    assert_eq!(level_max_disp(31, 2), 8);
}

/// The random-dot anchor through one coarse level: every d of 0..=15 is
/// found within 1 px on more than 95 % of the interior pixels (the spec's
/// 5 % bound), with the box read-out, with SGM, and with SGM decoding the
/// fine level from the groups within 2 px of the window's centre.
#[test]
fn random_dots_bad1_below_5_percent_coarse_to_fine() {
    let (w, h) = (96, 64);
    for (aggregation, band) in [
        (dem::Aggregation::Box, None),
        (sgm(), None),
        (sgm(), Some(2)),
    ] {
        let params = DemParams {
            aggregation,
            ..DemParams::default()
        };
        let decs = [
            default_decoder(),
            decoder_for(&level_params(&params, 1), None).unwrap(),
        ];
        let (mut bad, mut n) = (0, 0);
        for d in 0..=15usize {
            let (l, r) = random_dot_pair(w, h, d, 0xc2f0_0000 + d as u64);
            let (lr, rr) = (rgb(&l), rgb(&r));
            let m = stereo_c2f(
                &params,
                &decs,
                &ImageView::packed(&lr, w, h).unwrap(),
                &ImageView::packed(&rr, w, h).unwrap(),
                2,
                band,
            )
            .unwrap();
            for y in 16..h - 16 {
                for x in 15 + 16..w - 16 {
                    n += 1;
                    let v = m.left_raw[y * w + x];
                    bad += usize::from(v.is_none_or(|v| (v - d as f32).abs() > 1.0));
                }
            }
        }
        let pct = 100.0 * bad as f64 / n as f64;
        eprintln!("RDS bad-1 coarse to fine, {aggregation:?}, band {band:?}: {pct:.2} %");
        assert!(pct < 5.0, "{aggregation:?}, band {band:?}: {pct}");
    }
}

/// A pixel with a window is decoded from the groups whose shift is within
/// `band` px of the window's centre: window 6..=10 (centre 8), band 2,
/// shifts 6, 8, 10 of 3 carriers = 9 groups; a pixel without a window
/// from all 3 x 8 groups (shifts 0, 2, .., 14, one level). A band wider
/// than the range gives the unbanded left-referenced argmax.
#[test]
fn the_band_selects_the_groups_near_the_window() {
    use protogist_host::reference::stereo::{filters, readout};
    let dec_params = DemParams {
        levels: 1,
        ..DemParams::default()
    };
    let dec = decoder_for(&dec_params, None).unwrap();
    let (w, h, d) = (48, 24, 8usize);
    let (l, r) = random_dot_pair(w, h, d, 0xba4d);
    let (ml, mr) = (
        filters::monocular_planes(&dec_params, vec![l.clone()]),
        filters::monocular_planes(&dec_params, vec![r.clone()]),
    );
    let mut ws = Windows {
        left: vec![Some((6, 10)); w * h],
        right: vec![None; w * h],
        band: Some(2),
    };
    let (_, _, [vl, vr]) = readout::scores_banded(&dec_params, &dec, &ml, &mr, w, h, &ws, 2);
    // Left pixel x >= 14 has every shift's cell; right pixel x < w − 14 too.
    assert_eq!(vl[10 * w + 30], 9.0);
    assert_eq!(vr[10 * w + 20], 24.0);
    // Band 64: the same decision as without a band (float order aside).
    ws.band = Some(64);
    let wide = stereo_planes_in(
        &dec_params,
        &dec,
        vec![l.clone()],
        vec![r.clone()],
        Some(&ws),
    );
    ws.band = None;
    let plain = stereo_planes_in(&dec_params, &dec, vec![l], vec![r], Some(&ws));
    let same = wide
        .left_raw
        .iter()
        .zip(&plain.left_raw)
        .filter(|(a, b)| match (a, b) {
            (Some(a), Some(b)) => (a - b).abs() <= 0.01,
            (None, None) => true,
            _ => false,
        })
        .count();
    assert!(same * 100 >= 99 * w * h, "{same} of {}", w * h);
}

/// Bad input to the coarse-to-fine driver is a typed error: no decoder, a
/// coarse level below the filter support, a coarse decoder of another
/// `max_disp`.
#[test]
fn coarse_to_fine_bad_input_is_a_typed_error() {
    use protogist_host::reference::stereo::StereoError;
    let params = DemParams::default();
    let fine = default_decoder();
    let (w, h) = (40, 40);
    let img = vec![Rgb8::new(9, 9, 9); w * h];
    let v = ImageView::packed(&img, w, h).unwrap();
    assert!(matches!(
        stereo_c2f(&params, &[], &v, &v, 2, None),
        Err(StereoError::BadParams(_))
    ));
    // 40 -> 20 -> 10 px: below the support of the default filters.
    let decs = [
        fine.clone(),
        decoder_for(&level_params(&params, 1), None).unwrap(),
        decoder_for(&level_params(&params, 2), None).unwrap(),
    ];
    assert!(matches!(
        stereo_c2f(&params, &decs, &v, &v, 2, None),
        Err(StereoError::TooSmall { .. })
    ));
    // The fine decoder where the coarse one belongs.
    let (w, h) = (96, 64);
    let img = vec![Rgb8::new(9, 9, 9); w * h];
    let v = ImageView::packed(&img, w, h).unwrap();
    assert!(matches!(
        stereo_c2f(&params, &[fine.clone(), fine], &v, &v, 2, None),
        Err(StereoError::DecoderMismatch { .. })
    ));
}

/// `protogist stereo` refuses a pair whose coarsest level cannot hold the
/// filters before it trains any decoder: a typed error.
#[test]
fn the_command_checks_the_coarsest_level_first() {
    use protogist_host::error::HostError;
    use protogist_host::reference::stereo::StereoError;
    let dir = tempfile::tempdir().unwrap();
    let Some(files) = aloe_files() else {
        return;
    };
    let opts = stereo_options(files, 64, 8, dir.path());
    let e = protogist_host::stereo_cmd::run_stereo(&opts).unwrap_err();
    assert!(
        matches!(
            e,
            HostError::Stereo(StereoError::TooSmall { got: (16, _), .. })
        ),
        "{e}"
    );
}

/// `spread`: a level-1 map over a 5x3 frame, each pixel over its 2x2 block
/// (the last column and row of blocks also over the odd frame's leftover
/// column and row), disparities doubled, the OFF counts per frame pixel.
#[test]
fn spread_fills_each_block_and_counts_frame_pixels() {
    use protogist::disparity::{Disparity, DisparityCell};
    use protogist_host::reference::stereo::c2f::spread;
    use protogist_host::reference::stereo::OffReason;
    let on = |d: f32| DisparityCell::on(Disparity::from_num(d)).unwrap();
    let level = DisparityMapsF {
        width: 2,
        height: 1,
        disparity: vec![on(3.25), DisparityCell::OFF],
        disparity_f32: vec![Some(3.25), None],
        left_raw: vec![Some(3.25), Some(1.5)],
        right_raw: vec![None, Some(2.0)],
        off_texture: 0,
        off_ambiguous: 0,
        off_inconsistent: 1,
        why_off: vec![None, Some(OffReason::Inconsistent)],
    };
    let m = spread(&level, 1, (5, 3));
    assert_eq!((m.width, m.height), (5, 3));
    for y in 0..3 {
        for x in 0..5 {
            let p = y * 5 + x;
            if x < 2 {
                assert_eq!(m.disparity[p], on(6.5), "({x}, {y})");
                assert_eq!(m.disparity_f32[p], Some(6.5));
                assert_eq!((m.left_raw[p], m.right_raw[p]), (Some(6.5), None));
                assert_eq!(m.why_off[p], None);
            } else {
                assert!(m.disparity[p].is_off(), "({x}, {y})");
                assert_eq!((m.left_raw[p], m.right_raw[p]), (Some(3.0), Some(4.0)));
                assert_eq!(m.why_off[p], Some(OffReason::Inconsistent));
            }
        }
    }
    assert_eq!(
        (m.off_texture, m.off_ambiguous, m.off_inconsistent),
        (0, 0, 9)
    );
}
