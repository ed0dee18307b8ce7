//! Fixed-point conspicuity against its f32 reference, stage by stage.
//!
//! The bounds are the ones derived in `docs/ERROR_BOUNDS.md` and stated as
//! constants in `protogist::conspicuity`.

use proptest::prelude::*;
use protogist::conspicuity::{self as fx, EdgeCell, Luv, LuvTables};
use protogist::image::{ImageView, ImageViewMut};
use protogist_host::reference::conspicuity::{self as fl, luv_to_f32, LuvF};
use protogist_tests::{rgb_image, EdgeStorage, RgbCase};
use std::sync::LazyLock;

static TABLES: LazyLock<LuvTables> = LazyLock::new(LuvTables::new);

/// CIELUV of a case, fixed point, packed.
fn fixed_luv(case: &RgbCase) -> Vec<Luv> {
    let (w, h) = (case.width, case.height);
    let mut out = vec![Luv::default(); w * h];
    fx::rgb_to_luv(
        &TABLES,
        &case.view(),
        &mut ImageViewMut::packed(&mut out, w, h).unwrap(),
    )
    .unwrap();
    out
}

fn float_luv(case: &RgbCase) -> Vec<LuvF> {
    let (w, h) = (case.width, case.height);
    let mut out = vec![[0.0; 3]; w * h];
    fl::rgb_to_luv(
        &case.view(),
        &mut ImageViewMut::packed(&mut out, w, h).unwrap(),
    )
    .unwrap();
    out
}

/// The end-to-end C~ bound without smoothing, CIELUV units: each pair
/// distance moves by at most twice the largest CIELUV error vector, plus
/// the rounding of C~.
fn chain_bound() -> f32 {
    let e = (fx::MAX_ERR_L.powi(2) + fx::MAX_ERR_U.powi(2) + fx::MAX_ERR_V.powi(2)).sqrt();
    2.0 * e + fx::MAX_ERR_CONSPICUITY_LSB / 64.0
}

fn fixed_conspicuity(luv: &[Luv], w: usize, h: usize) -> (Vec<EdgeCell>, u16) {
    let mut c = vec![EdgeCell::OFF; w * h];
    let mut rows = vec![Luv::default(); fx::row_scratch_len(w)];
    let max = fx::conspicuity(
        &ImageView::packed(luv, w, h).unwrap(),
        &mut ImageViewMut::packed(&mut c, w, h).unwrap(),
        &mut rows,
    )
    .unwrap();
    (c, max.to_bits())
}

fn float_conspicuity(luv: &[LuvF], w: usize, h: usize) -> (Vec<Option<f32>>, f32) {
    let mut c = vec![None; w * h];
    let max = fl::conspicuity(
        &ImageView::packed(luv, w, h).unwrap(),
        &mut ImageViewMut::packed(&mut c, w, h).unwrap(),
    )
    .unwrap();
    (c, max)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn luv_within_stated_bound(case in rgb_image(24)) {
        let (f, r) = (fixed_luv(&case), float_luv(&case));
        for (a, b) in f.iter().zip(&r) {
            let a = luv_to_f32(*a);
            prop_assert!((a[0] - b[0]).abs() <= fx::MAX_ERR_L, "L {a:?} {b:?}");
            prop_assert!((a[1] - b[1]).abs() <= fx::MAX_ERR_U, "u {a:?} {b:?}");
            prop_assert!((a[2] - b[2]).abs() <= fx::MAX_ERR_V, "v {a:?} {b:?}");
        }
    }

    /// Same fixed CIELUV input to both: the exact distance is rounded once.
    #[test]
    fn conspicuity_within_half_lsb_on_same_input(case in rgb_image(24)) {
        let (w, h) = (case.width, case.height);
        let luv = fixed_luv(&case);
        let luv_f: Vec<LuvF> = luv.iter().map(|&p| luv_to_f32(p)).collect();
        let (cf, max_f) = fixed_conspicuity(&luv, w, h);
        let (cr, max_r) = float_conspicuity(&luv_f, w, h);
        for (a, b) in cf.iter().zip(&cr) {
            let a = f32::from(a.get().unwrap().to_bits());
            let b = b.unwrap() * 64.0;
            prop_assert!((a - b).abs() <= fx::MAX_ERR_CONSPICUITY_LSB, "{a} vs {b}");
        }
        prop_assert!((f32::from(max_f) - max_r * 64.0).abs() <= fx::MAX_ERR_CONSPICUITY_LSB);
    }

    /// Same fixed input to one pass of both cells; pixels where a pair is a
    /// near-tie (the f32 comparison may go the other way) are excluded.
    #[test]
    fn smooth_step_within_half_lsb_away_from_ties(case in rgb_image(20)) {
        let (w, h) = (case.width, case.height);
        let luv = fixed_luv(&case);
        let mut sf = luv.clone();
        let mut rows = vec![Luv::default(); fx::row_scratch_len(w)];
        fx::smooth_step(&mut ImageViewMut::packed(&mut sf, w, h).unwrap(), &mut rows).unwrap();
        let mut sr: Vec<LuvF> = luv.iter().map(|&p| luv_to_f32(p)).collect();
        fl::smooth_step(&mut ImageViewMut::packed(&mut sr, w, h).unwrap());
        let src = ImageView::packed(&luv, w, h).unwrap();
        let mut compared = 0;
        for y in 0..h {
            for x in 0..w {
                if near_tie(&src, x, y) {
                    continue;
                }
                compared += 1;
                let a = luv_to_f32(sf[y * w + x]);
                let b = sr[y * w + x];
                for ch in 0..3 {
                    let err = (a[ch] - b[ch]).abs() * 64.0;
                    prop_assert!(err <= fx::MAX_ERR_SMOOTH_STEP_LSB, "({x},{y}) ch{ch}: {a:?} vs {b:?}");
                }
            }
        }
        prop_assert!(compared * 4 >= w * h * 3, "too many near-ties: {compared} of {}", w * h);
    }

    /// The whole chain without smoothing: C~ within the propagated bound,
    /// and the edge sets agree except where the float value lies within the
    /// bound of the threshold.
    #[test]
    fn edge_sets_agree_away_from_the_threshold(case in rgb_image(24)) {
        let (w, h) = (case.width, case.height);
        let e = chain_bound();
        let (mut cf, max_f) = fixed_conspicuity(&fixed_luv(&case), w, h);
        let (mut cr, max_r) = float_conspicuity(&float_luv(&case), w, h);
        for (a, b) in cf.iter().zip(&cr) {
            let (a, b) = (a.get().unwrap().to_num::<f32>(), b.unwrap());
            prop_assert!((a - b).abs() <= e, "C~ {a} vs {b}, bound {e}");
        }
        let max_fixed = fx::Conspicuity::from_bits(max_f);
        fx::threshold(&mut ImageViewMut::packed(&mut cf, w, h).unwrap(), max_fixed, 10).unwrap();
        let raw_r = cr.clone();
        fl::threshold(&mut ImageViewMut::packed(&mut cr, w, h).unwrap(), max_r, 10).unwrap();
        for ((a, b), raw) in cf.iter().zip(&cr).zip(&raw_r) {
            let margin = (raw.unwrap() - 0.1 * max_r).abs();
            if margin > 1.1 * e {
                prop_assert_eq!(a.is_on(), b.is_some(), "C~ {:?}, max {}", raw, max_r);
            }
        }
    }
}

/// True when some pair at `(x, y)` has distances to the centre within the
/// f32 evaluation error of each other (exact integers, Q12).
fn near_tie(src: &ImageView<'_, Luv>, x: usize, y: usize) -> bool {
    let at = |dx: isize, dy: isize| {
        let cx = (x as isize + dx).clamp(0, src.width() as isize - 1) as usize;
        let cy = (y as isize + dy).clamp(0, src.height() as isize - 1) as usize;
        src.get(cx, cy).unwrap().to_bits().map(i64::from)
    };
    let d2 = |a: [i64; 3], b: [i64; 3]| (0..3).map(|i| (a[i] - b[i]).pow(2)).sum::<i64>();
    let c = at(0, 0);
    fl::PAIRS.iter().any(|&(dx, dy)| {
        let (m, p) = (d2(c, at(-dx, -dy)), d2(c, at(dx, dy)));
        // f32 holds 24 bits: allow 2^-20 relative, plus one unit.
        m != p && (m - p).abs() <= m.max(p) / (1 << 20) + 1
    })
}

/// Every one of the 2^24 sRGB colours, not a sample: the CIELUV bound holds
/// everywhere, and the reported maxima show how much margin it has.
#[test]
fn luv_bound_holds_for_every_srgb_colour() {
    let mut worst = [0.0f32; 3];
    for r in 0..=255u8 {
        for g in 0..=255u8 {
            for b in 0..=255u8 {
                let p = protogist::image::Rgb8::new(r, g, b);
                let a = luv_to_f32(TABLES.convert(p));
                let e = fl::convert(p);
                for ch in 0..3 {
                    worst[ch] = worst[ch].max((a[ch] - e[ch]).abs());
                }
            }
        }
    }
    eprintln!("max |error| L* u* v*: {worst:?}");
    assert!(worst[0] <= fx::MAX_ERR_L, "{worst:?}");
    assert!(worst[1] <= fx::MAX_ERR_U, "{worst:?}");
    assert!(worst[2] <= fx::MAX_ERR_V, "{worst:?}");
}

/// The stage end to end with the default smoothing: the intermediate maps a
/// caller observes are exactly what `edge_conspicuity` leaves in the buffers.
#[test]
fn whole_stage_matches_its_steps() {
    use protogist::synth::{render_left, SceneSpec};
    let (w, h) = (48, 36);
    let mut px = vec![protogist::image::Rgb8::default(); w * h];
    render_left(
        &SceneSpec::demo(w, h),
        &mut ImageViewMut::packed(&mut px, w, h).unwrap(),
    )
    .unwrap();
    let rgb = ImageView::packed(&px, w, h).unwrap();
    let mut store = EdgeStorage::new(w, h);
    let params = fx::EdgeParams::default();
    let mut bufs = store.buffers().unwrap();
    let report = fx::edge_conspicuity(&TABLES, &params, &rgb, &mut bufs).unwrap();
    let checksum = bufs.checksum();
    let EdgeStorage {
        luv,
        smoothed: sm,
        cmap: c,
        ..
    } = store;

    let case = RgbCase {
        data: px.clone(),
        width: w,
        height: h,
        stride: w,
    };
    assert_eq!(luv, fixed_luv(&case));
    let mut sm2 = luv.clone();
    let mut rows2 = vec![Luv::default(); fx::row_scratch_len(w)];
    fx::smooth(
        &params.smooth,
        &mut ImageViewMut::packed(&mut sm2, w, h).unwrap(),
        &mut rows2,
    )
    .unwrap();
    assert_eq!(sm, sm2);
    assert_ne!(sm, luv, "smoothing changed nothing");
    let (mut c2, max) = fixed_conspicuity(&sm2, w, h);
    assert_eq!(max, report.max.to_bits());
    let on = fx::threshold(
        &mut ImageViewMut::packed(&mut c2, w, h).unwrap(),
        report.max,
        10,
    )
    .unwrap();
    assert_eq!((c, on), (c2, report.on_count));
    assert!(report.on_count > 0 && (report.on_count as usize) < w * h / 2);
    assert_ne!(checksum, 0);
}

/// Degenerate shapes through the whole default stage, fixed against float:
/// 1x1, a single row and a single column (every neighbour is replicated).
#[test]
fn one_pixel_rows_and_columns_run_and_agree() {
    for (w, h) in [(1, 1), (7, 1), (1, 7), (2, 2)] {
        let px: Vec<protogist::image::Rgb8> = (0..w * h)
            .map(|i| protogist::image::Rgb8::new((i * 37) as u8, (200 - i * 25) as u8, 90))
            .collect();
        let rgb = ImageView::packed(&px, w, h).unwrap();
        let mut store = EdgeStorage::new(w, h);
        let params = fx::EdgeParams::default();
        let mut bufs = store.buffers().unwrap();
        let report = fx::edge_conspicuity(&TABLES, &params, &rgb, &mut bufs).unwrap();
        let float = fl::edge_conspicuity(&params, &rgb).unwrap();
        if w * h == 1 {
            // A lone pixel has no pair to differ from.
            assert_eq!((report.max.to_bits(), report.on_count), (0, 0));
        }
        for (a, b) in bufs.conspicuity().pixels().zip(&float.conspicuity) {
            assert_eq!(a.is_on(), b.is_some(), "{w}x{h}");
        }
        assert!(
            (report.max.to_num::<f32>() - float.max).abs() < 1.0,
            "{w}x{h}"
        );
    }
}
