//! The phase refinement of core (`protogist::stereo::phase`) against its
//! f32 reference (`protogist_host::reference::stereo::phase`): agreement
//! on random-dot stereograms and on Aloe, the refinement's accuracy on
//! pairs of known disparity, the streaming form, flat input and bad input.

use proptest::prelude::*;
use protogist::disparity::{Disparity, DisparityCell};
use protogist::image::{ImageView, ImageViewMut, Rgb8};
use protogist::rng::SplitMix64;
use protogist::stereo::phase::{self, Phase, PhaseParams, Refiner};
use protogist::stereo::StereoError;
use protogist_host::reference::stereo::phase as reference;
use protogist_host::storage::PhaseStorage;
use protogist_tests::{aloe_160_rgb, rds_rgb};

/// Core's and the reference's refinement of `cells` on the pair.
fn both(
    p: &PhaseParams,
    max_disp: u8,
    l: &[Rgb8],
    r: &[Rgb8],
    w: usize,
    h: usize,
    cells: &[DisparityCell],
) -> (Vec<DisparityCell>, Vec<DisparityCell>, usize, usize) {
    let (lv, rv) = (
        ImageView::packed(l, w, h).unwrap(),
        ImageView::packed(r, w, h).unwrap(),
    );
    let mut core = cells.to_vec();
    let ph = Phase::new(p, max_disp).unwrap();
    let mut s = PhaseStorage::new(w, Some(p), max_disp);
    let n_core = phase::refine(
        &ph,
        &lv,
        &rv,
        &mut ImageViewMut::packed(&mut core, w, h).unwrap(),
        s.buffers(),
    )
    .unwrap();
    let mut float = cells.to_vec();
    let n_ref = reference::refine(&(*p).into(), max_disp, &lv, &rv, &mut float).unwrap();
    (core, float, n_core, n_ref)
}

/// % of the pixels ON in both within 0.25 px, and whether the OFF
/// decisions are identical.
fn agreement(a: &[DisparityCell], b: &[DisparityCell]) -> (f64, bool) {
    let (mut on, mut close) = (0usize, 0usize);
    for (a, b) in a.iter().zip(b) {
        if let (Some(a), Some(b)) = (a.get(), b.get()) {
            on += 1;
            close += usize::from((a.to_num::<f32>() - b.to_num::<f32>()).abs() <= 0.25);
        }
    }
    let same_off = a.iter().zip(b).all(|(a, b)| a.is_on() == b.is_on());
    (100.0 * close as f64 / on.max(1) as f64, same_off)
}

/// A coarse map: disparity `d + offset` on 2x2 blocks, the offset in
/// `±spread` px, a tenth of the blocks OFF.
fn coarse(w: usize, h: usize, d: f32, spread: f32, seed: u64) -> Vec<DisparityCell> {
    let mut rng = SplitMix64::new(seed);
    let (bw, bh) = (w.div_ceil(2), h.div_ceil(2));
    let blocks: Vec<DisparityCell> = (0..bw * bh)
        .map(|_| {
            let u = (rng.next_u64() >> 11) as f32 / (1u64 << 53) as f32;
            if rng.below(10) == 0 {
                DisparityCell::OFF
            } else {
                DisparityCell::from_raw(Disparity::from_num(
                    (d + spread * (2.0 * u - 1.0)).max(0.0),
                ))
            }
        })
        .collect();
    (0..w * h)
        .map(|i| blocks[(i / w / 2) * bw + (i % w) / 2])
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Random-dot pairs of uniform disparity, a coarse map off by up to
    /// 1.5 px: core within 0.25 px of the reference on at least 99 % of
    /// the pixels, the same pixels ON, the same count refined.
    #[test]
    fn core_agrees_with_the_reference_on_random_dots(
        d in 0usize..=12,
        seed in any::<u64>(),
        radius in 2u8..=4,
        pool in 0u8..=2,
    ) {
        let (w, h) = (64, 40);
        let (l, r) = rds_rgb(w, h, d, seed);
        let p = PhaseParams { radius, pool, ..PhaseParams::DEFAULT };
        let cells = coarse(w, h, d as f32, 1.5, seed ^ 1);
        let (core, float, _, _) = both(&p, 15, &l, &r, w, h, &cells);
        let (close, same_off) = agreement(&core, &float);
        prop_assert!(close >= 99.0, "{close:.2} % within 0.25 px");
        prop_assert!(same_off);
    }
}

/// The refinement recovers the disparity: on random-dot pairs of known
/// disparity, from a coarse map off by up to 1.5 px (mean error 0.75 px),
/// the pixels away from the left border (where the right eye has no
/// match) end with a mean error below 0.2 px and at least 75 % of them
/// within 0.25 px (the coarse map: about 17 %).
#[test]
fn the_refinement_recovers_the_disparity_from_an_offset_coarse_map() {
    let (w, h) = (96, 48);
    for (d, seed) in [(3usize, 1u64), (7, 2), (12, 3)] {
        let (l, r) = rds_rgb(w, h, d, seed);
        let cells = coarse(w, h, d as f32, 1.5, seed + 10);
        let (core, _, _, _) = both(&PhaseParams::DEFAULT, 15, &l, &r, w, h, &cells);
        let stats = |m: &[DisparityCell]| {
            let errs: Vec<f32> = m
                .iter()
                .enumerate()
                .filter(|(i, _)| i % w >= d + 4)
                .filter_map(|(_, c)| c.get())
                .map(|v| (v.to_num::<f32>() - d as f32).abs())
                .collect();
            let n = errs.len() as f32;
            (
                errs.iter().sum::<f32>() / n,
                100.0 * errs.iter().filter(|&&e| e <= 0.25).count() as f32 / n,
            )
        };
        let ((mean, close), (mean0, close0)) = (stats(&core), stats(&cells));
        assert!(
            mean0 >= 0.6 && close0 <= 25.0,
            "d {d}: coarse {mean0:.3} px, {close0:.1} %"
        );
        assert!(
            mean <= 0.2 && close >= 75.0,
            "d {d}: refined {mean:.3} px, {close:.1} % within 0.25 px"
        );
    }
}

/// On Aloe (160 px), with a coarse map of random disparities 0..=20 per
/// 2x2 block (real textures, weak ones included, at every shift): at
/// least 99 % of the ON pixels within 0.25 px of the reference.
#[test]
fn core_agrees_with_the_reference_on_aloe() {
    let Some((l, r, w, h)) = aloe_160_rgb() else {
        eprintln!("skipped: no Aloe data (cargo xtask fetch-data)");
        return;
    };
    for seed in 0..3u64 {
        let cells = coarse(w, h, 10.0, 10.0, seed);
        let (core, float, _, _) = both(&PhaseParams::DEFAULT, 31, &l, &r, w, h, &cells);
        let (close, same_off) = agreement(&core, &float);
        assert!(close >= 99.0, "seed {seed}: {close:.2} % within 0.25 px");
        assert!(same_off);
    }
}

/// The streaming form ([`Refiner::push`], cells in row-major order, each
/// row passed on when complete) gives the whole-map form's cells.
#[test]
fn pushing_cells_row_by_row_is_the_whole_map_refinement() {
    let (w, h) = (50, 30);
    let (l, r) = rds_rgb(w, h, 5, 9);
    let cells = coarse(w, h, 5.0, 1.5, 4);
    let (whole, _, _, _) = both(&PhaseParams::DEFAULT, 15, &l, &r, w, h, &cells);
    let (lv, rv) = (
        ImageView::packed(&l, w, h).unwrap(),
        ImageView::packed(&r, w, h).unwrap(),
    );
    let ph = Phase::new(&PhaseParams::DEFAULT, 15).unwrap();
    let mut s = PhaseStorage::new(w, Some(&PhaseParams::DEFAULT), 15);
    let mut refiner = Refiner::new(&ph, &lv, &rv, s.buffers()).unwrap();
    let mut out = vec![DisparityCell::OFF; w * h];
    let mut order = Vec::new();
    for (i, &c) in cells.iter().enumerate() {
        refiner.push(i % w, i / w, c, &mut |x, y, c| {
            out[y * w + x] = c;
            order.push(y * w + x);
        });
    }
    assert!(out == whole, "the streamed cells differ");
    assert_eq!(order, (0..w * h).collect::<Vec<_>>());
    // Rows out of order reload the rings: the same cells.
    let mut s2 = PhaseStorage::new(w, Some(&PhaseParams::DEFAULT), 15);
    let mut refiner = Refiner::new(&ph, &lv, &rv, s2.buffers()).unwrap();
    let mut back = cells.clone();
    for (y, row) in back.chunks_exact_mut(w).enumerate().rev() {
        refiner.refine_row(y, row);
    }
    assert!(back == whole, "rows out of order differ");
}

/// A flat pair has no phase (`P = 0`): every cell is kept as it was.
#[test]
fn a_flat_pair_keeps_the_coarse_map() {
    let (w, h) = (40, 24);
    let flat = vec![Rgb8::new(90, 120, 30); w * h];
    let cells = coarse(w, h, 4.0, 1.5, 2);
    let (core, float, nc, nr) = both(&PhaseParams::DEFAULT, 15, &flat, &flat, w, h, &cells);
    assert!(core == cells, "core changed a flat pair's map");
    assert!(float == cells, "the reference changed a flat pair's map");
    assert_eq!((nc, nr), (0, 0));
}

#[test]
fn the_arc_tangent_is_within_its_bound() {
    let mut worst = 0.0f64;
    for i in 0..4096 {
        let a = std::f64::consts::TAU * f64::from(i) / 4096.0 - std::f64::consts::PI;
        for m in [1.0, 37.0, 1e4, 1e8] {
            let (x, y) = ((m * a.cos()).round() as i32, (m * a.sin()).round() as i32);
            let Some(t) = phase::atan2_turns(y, x) else {
                assert_eq!((x, y), (0, 0));
                continue;
            };
            let exact = f64::from(y).atan2(f64::from(x));
            let mut err = (f64::from(t) / 65536.0 * std::f64::consts::TAU - exact).abs();
            err = err.min(std::f64::consts::TAU - err);
            worst = worst.max(err);
        }
    }
    // 0.0038 rad from the polynomial, 2^-15 from the quotient, 2^-16 turn.
    assert!(worst <= 0.0039 + 1e-4, "worst {worst}");
    assert_eq!(phase::atan2_turns(0, 0), None);
}

/// A camera with no pixels.
struct Empty;

impl protogist::stereo::c2f::RgbRows for Empty {
    fn size(&self) -> (usize, usize) {
        (0, 0)
    }
    fn rgb_row(&self, _: usize, _: &mut [Rgb8]) {}
}

#[test]
fn bad_input_gets_a_typed_error() {
    let p = PhaseParams::DEFAULT;
    for bad in [
        PhaseParams {
            wavelength: 1.0,
            ..p
        },
        PhaseParams {
            wavelength: f32::NAN,
            ..p
        },
        PhaseParams {
            sigma_per_wavelength: 0.0,
            ..p
        },
        PhaseParams { radius: 0, ..p },
        PhaseParams { radius: 6, ..p },
        PhaseParams { pool: 5, ..p },
    ] {
        assert!(
            matches!(Phase::new(&bad, 15), Err(StereoError::BadParams(_))),
            "{bad:?}"
        );
    }
    let ph = Phase::new(&p, 15).unwrap();
    let (l, r) = rds_rgb(30, 20, 2, 1);
    let (lv, rv) = (
        ImageView::packed(&l, 30, 20).unwrap(),
        ImageView::packed(&r[..30 * 19], 30, 19).unwrap(),
    );
    let mut s = PhaseStorage::new(30, Some(&p), 15);
    assert!(matches!(
        Refiner::new(&ph, &lv, &rv, s.buffers()),
        Err(StereoError::SizeMismatch { .. })
    ));
    let rv = ImageView::packed(&r, 30, 20).unwrap();
    let mut short = PhaseStorage::new(29, Some(&p), 15);
    assert!(matches!(
        Refiner::new(&ph, &lv, &rv, short.buffers()),
        Err(StereoError::Buffer { .. })
    ));
    let mut map = vec![DisparityCell::OFF; 30 * 19];
    assert!(matches!(
        phase::refine(
            &ph,
            &lv,
            &rv,
            &mut ImageViewMut::packed(&mut map, 30, 19).unwrap(),
            s.buffers()
        ),
        Err(StereoError::Buffer { .. })
    ));
    assert!(matches!(
        Refiner::new(&ph, &Empty, &Empty, s.buffers()),
        Err(StereoError::TooSmall { .. })
    ));
}
