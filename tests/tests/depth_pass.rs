//! The depth pass (`protogist::segment::depth`): its edges by hand, its
//! settings, and against the f32 reference.

use proptest::prelude::*;
use protogist::conspicuity::{Conspicuity, EdgeCell};
use protogist::disparity::{from_pixels, Disparity, DisparityCell};
use protogist::image::{ImageView, ImageViewMut};
use protogist::segment::{
    bit_map_len, depth_steps, segment_with_depth_pass, BitView, DepthPass, Masks, Ratio,
    SegmentError, SegmentParams, SegmentReport, DEPTH_EDGE, MAX_GROUND_BAND,
};
use protogist_host::reference::segment as rf;
use protogist_tests::SegmentStorage;

fn map(w: usize, h: usize, f: impl Fn(usize, usize) -> Option<u8>) -> Vec<DisparityCell> {
    (0..w * h)
        .map(|i| f(i % w, i / w).map_or(DisparityCell::OFF, from_pixels))
        .collect()
}

/// `depth_steps` over the whole frame (no `within`); the cells marked.
fn steps_everywhere(c: &mut [EdgeCell], d: &[DisparityCell], w: usize, h: usize, step: u16) -> u32 {
    depth_steps(
        &mut ImageViewMut::packed(c, w, h).unwrap(),
        &ImageView::packed(d, w, h).unwrap(),
        step,
        None,
    )
    .unwrap()
}

fn marked(edges: &[EdgeCell]) -> Vec<bool> {
    edges.iter().map(|e| e.get() == Some(DEPTH_EDGE)).collect()
}

#[test]
fn a_step_marks_the_cells_whose_pair_straddles_it() {
    // 7x5: columns 0..=2 at 2 px, 3..=6 at 7 px. The pairs of columns 2
    // and 3 straddle the step (5 px); border rows and columns stay.
    let (w, h) = (7, 5);
    let d = map(w, h, |x, _| Some(if x <= 2 { 2 } else { 7 }));
    let mut c = vec![EdgeCell::OFF; w * h];
    let n = steps_everywhere(&mut c, &d, w, h, 4 * 256);
    let want: Vec<bool> = (0..w * h)
        .map(|i| (1..h - 1).contains(&(i / w)) && (2..=3).contains(&(i % w)))
        .collect();
    assert_eq!(marked(&c), want);
    assert_eq!(n, 6);
    // A step under the least one marks nothing.
    let mut c = vec![EdgeCell::OFF; w * h];
    let n = steps_everywhere(&mut c, &d, w, h, 5 * 256 + 1);
    assert_eq!(n, 0);
}

#[test]
fn off_pairs_diagonals_and_stronger_edges() {
    let (w, h) = (5, 5);
    // One near cell in the middle of a far map: every cell of the ring
    // around it has the centre in one of its pairs (the edge midpoints by
    // their row or column, the corners by a diagonal), so the whole ring
    // is marked, but (1, 1), whose colour edge is stronger.
    let d = map(w, h, |x, y| Some(if (x, y) == (2, 2) { 9 } else { 1 }));
    let strong = EdgeCell::from_raw(Conspicuity::from_bits(100 << 6));
    let weak = EdgeCell::from_raw(Conspicuity::from_bits(5 << 6));
    let mut c = vec![EdgeCell::OFF; w * h];
    c[6] = strong; // (1, 1): a stronger colour edge keeps its value
    c[8] = weak; // (3, 1): a weaker one takes the depth edge
    steps_everywhere(&mut c, &d, w, h, 4 * 256);
    for (x, y) in [(1, 2), (3, 2), (2, 1), (2, 3), (3, 1), (1, 3), (3, 3)] {
        assert_eq!(c[y * w + x].get(), Some(DEPTH_EDGE), "({x}, {y})");
    }
    assert_eq!(c[6], strong);
    // The centre's own pairs are all far-far: not a step.
    assert_eq!(c[12], EdgeCell::OFF);
    // An OFF member makes no pair.
    let d = map(w, h, |x, y| {
        if (x, y) == (2, 2) {
            None
        } else {
            Some(if x < 2 { 1 } else { 9 })
        }
    });
    let mut c = vec![EdgeCell::OFF; w * h];
    steps_everywhere(&mut c, &d, w, h, 4 * 256);
    // Columns 0 and 1 at 1 px, 2 to 4 at 9 px, the centre OFF. (2, 1)
    // straddles the step in its row; so does the OFF centre itself, whose
    // row pair is (1, 2) and (3, 2). (1, 2)'s row pair holds the OFF
    // centre, and its vertical pair is 1 px and 1 px, but its diagonal
    // (0, 1)-(2, 3) is 1 and 9 px. (3, 2)'s pairs have no step apart from
    // the one through the OFF centre: left alone.
    assert_eq!(c[w + 2].get(), Some(DEPTH_EDGE));
    assert_eq!(c[2 * w + 2].get(), Some(DEPTH_EDGE));
    assert_eq!(c[2 * w + 1].get(), Some(DEPTH_EDGE));
    assert_eq!(c[2 * w + 3], EdgeCell::OFF);
}

#[test]
fn maps_of_other_sizes_are_an_error() {
    let d = vec![DisparityCell::OFF; 12];
    let mut c = vec![EdgeCell::OFF; 15];
    assert!(matches!(
        depth_steps(
            &mut ImageViewMut::packed(&mut c, 5, 3).unwrap(),
            &ImageView::packed(&d, 4, 3).unwrap(),
            256,
            None,
        ),
        Err(SegmentError::SizeMismatch { .. })
    ));
}

#[test]
fn the_settings_are_checked() {
    assert!(DepthPass::DEFAULT.validate().is_ok());
    let bad = [
        DepthPass {
            step: 0,
            ..DepthPass::DEFAULT
        },
        DepthPass {
            step: MAX_GROUND_BAND + 1,
            ..DepthPass::DEFAULT
        },
        DepthPass {
            searches: 0,
            ..DepthPass::DEFAULT
        },
        DepthPass {
            searches: 17,
            ..DepthPass::DEFAULT
        },
        DepthPass {
            clearance: 17,
            ..DepthPass::DEFAULT
        },
        DepthPass {
            min_area: Ratio::new(1, 0),
            ..DepthPass::DEFAULT
        },
        DepthPass {
            min_area: Ratio::new(2, 1),
            ..DepthPass::DEFAULT
        },
    ];
    for b in bad {
        assert!(
            matches!(b.validate(), Err(SegmentError::BadParams(_))),
            "{b:?}"
        );
    }
    // 1/48 of 160x120 is 400 px; of 7x7, 49/48 rounded up.
    assert_eq!(DepthPass::DEFAULT.least_area(160, 120), 400);
    assert_eq!(DepthPass::DEFAULT.least_area(7, 7), 2);
}

// ---------------------------------------------------------------------------
// Against the f32 reference.

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Core's depth steps are the reference's: integer comparisons of
    /// `U8F8` values, which `f32` holds exactly (error bound: none).
    #[test]
    fn depth_steps_are_the_references(
        (w, h, d, c, within) in (3usize..40, 3usize..20).prop_flat_map(|(w, h)| (
            Just(w),
            Just(h),
            prop::collection::vec(prop::option::weighted(0.9, 0u16..(31 * 256)), w * h),
            prop::collection::vec(prop::option::weighted(0.3, 0u16..(128 << 6)), w * h),
            prop::option::of(prop::collection::vec(any::<bool>(), w * h)),
        )),
        step in 1u16..(8 * 256),
    ) {
        let d: Vec<DisparityCell> = d
            .iter()
            .map(|v| v.map_or(DisparityCell::OFF, |b| Some(Disparity::from_bits(b)).into()))
            .collect();
        let c: Vec<EdgeCell> = c
            .iter()
            .map(|v| v.map_or(EdgeCell::OFF, |b| EdgeCell::from_raw(Conspicuity::from_bits(b))))
            .collect();
        let df: Vec<Option<f32>> = d.iter().map(|v| v.get().map(f32::from)).collect();
        let edge = EdgeCell::from_raw(DEPTH_EDGE);
        let want = rf::depth_steps(&c, &df, (w, h), f32::from(step) / 256.0, edge, within.as_deref());
        let mut words = vec![0u32; bit_map_len(w, h)];
        let stride = words.len() / h;
        for (i, _) in within.iter().flatten().enumerate().filter(|(_, &on)| on) {
            words[(i / w) * stride + (i % w) / 32] |= 1 << (i % w % 32);
        }
        let bits = BitView::new(&words, w, h).unwrap();
        let mut got = c.clone();
        depth_steps(
            &mut ImageViewMut::packed(&mut got, w, h).unwrap(),
            &ImageView::packed(&d, w, h).unwrap(),
            step,
            within.is_some().then_some(&bits),
        )
        .unwrap();
        prop_assert_eq!(got, want);
    }
}

// ---------------------------------------------------------------------------
// The pass in figure-ground.

const BW: usize = 48;
const BH: usize = 36;

/// Background 2 px; boxes `(x0, y0, x1, y1, d, outlined)`: an outlined box
/// has a strong ring and a weak inside in C, a plain one nothing in C (an
/// object of its surroundings' colour).
fn boxes(list: &[(usize, usize, usize, usize, u8, bool)]) -> (Vec<DisparityCell>, Vec<EdgeCell>) {
    let mut d = vec![from_pixels(2); BW * BH];
    let mut c = vec![EdgeCell::OFF; BW * BH];
    for &(x0, y0, x1, y1, disp, outlined) in list {
        for y in y0..y1 {
            for x in x0..x1 {
                d[y * BW + x] = from_pixels(disp);
                let ring = x == x0 || y == y0 || x + 1 == x1 || y + 1 == y1;
                if outlined {
                    c[y * BW + x] =
                        EdgeCell::on(Conspicuity::from_num(if ring { 40 } else { 5 })).unwrap();
                }
            }
        }
    }
    (d, c)
}

/// The whole frame as S, no upper cut, up to 3 objects.
const OPEN: SegmentParams = SegmentParams {
    top_bottom_strip: Ratio::new(0, 1),
    left_strip: Ratio::new(0, 1),
    fg_high: Ratio::new(100, 1),
    max_objects: 3,
    ..SegmentParams::PAPER
};

const PASS: SegmentParams = SegmentParams {
    depth_pass: Some(DepthPass {
        step: 4 * 256,
        searches: 2,
        clearance: 2,
        min_area: Ratio::new(1, 48),
    }),
    ..OPEN
};

/// The report, the masks and C as the searches left it.
fn run(
    p: &SegmentParams,
    d: &[DisparityCell],
    c: &[EdgeCell],
) -> Result<(SegmentReport, Vec<bool>, Vec<EdgeCell>), SegmentError> {
    let mut store = SegmentStorage::new(BW, BH);
    let mut masks = vec![false; usize::from(p.max_objects) * BW * BH];
    let mut c = c.to_vec();
    let mut first = vec![0u32; bit_map_len(BW, BH)];
    let r = segment_with_depth_pass(
        p,
        &ImageView::packed(d, BW, BH).unwrap(),
        &mut ImageViewMut::packed(&mut c, BW, BH).unwrap(),
        &mut store.buffers().unwrap(),
        Masks::Bools(&mut masks),
        &mut (),
        &mut first,
    )?;
    Ok((r, masks, c))
}

fn mask(masks: &[bool], k: usize) -> &[bool] {
    &masks[k * BW * BH..(k + 1) * BW * BH]
}

/// Intersection over union of a mask and a box.
fn iou_box(m: &[bool], (x0, y0, x1, y1): (usize, usize, usize, usize)) -> f64 {
    let inside = |i: usize| (x0..x1).contains(&(i % BW)) && (y0..y1).contains(&(i / BW));
    let (mut i, mut u) = (0, 0);
    for (k, &on) in m.iter().enumerate() {
        i += usize::from(on && inside(k));
        u += usize::from(on || inside(k));
    }
    i as f64 / u.max(1) as f64
}

#[test]
fn an_object_without_colour_edges_is_found_by_the_pass_only() {
    let (d, c) = boxes(&[(12, 10, 30, 26, 12, false)]);
    let (r, _, after) = run(&OPEN, &d, &c).unwrap();
    assert!(r.objects.is_empty(), "{:?}", r.objects);
    assert_eq!(after, c, "without the pass C is not written");
    let (r, masks, after) = run(&PASS, &d, &c).unwrap();
    assert_eq!(r.objects.len(), 1, "{:?}", r.objects);
    let iou = iou_box(mask(&masks, 0), (12, 10, 30, 26));
    assert!(iou > 0.8, "{iou}");
    assert!(after.iter().any(|e| e.get() == Some(DEPTH_EDGE)));
}

#[test]
fn the_pass_adds_to_the_colour_objects_and_never_repeats_one() {
    let list = [(4, 6, 18, 20, 7, true), (26, 12, 42, 28, 12, false)];
    let (d, c) = boxes(&list);
    let (colour, cm, _) = run(&OPEN, &d, &c).unwrap();
    assert_eq!(colour.objects.len(), 1, "{:?}", colour.objects);
    let (r, masks, _) = run(&PASS, &d, &c).unwrap();
    assert_eq!(r.objects.len(), 2, "{:?}", r.objects);
    // The colour object first, with the colour pass's own mask.
    assert_eq!(r.objects[0], colour.objects[0]);
    assert_eq!(mask(&masks, 0), mask(&cm, 0));
    assert!(iou_box(mask(&masks, 1), (26, 12, 42, 28)) > 0.8);
    assert_eq!(r.objects[1].index, 1);
    // No cell in both.
    assert!(!mask(&masks, 0)
        .iter()
        .zip(mask(&masks, 1))
        .any(|(a, b)| *a && *b));
}

#[test]
fn objects_of_the_pass_under_its_least_area_are_left_out() {
    // 6x6 = 36 px, a 48th of 48x36 is 36: kept; 5x5 is not (with no
    // least area it is: the filter is what leaves it out).
    for (side, kept) in [(6, true), (5, false)] {
        let (d, c) = boxes(&[(20, 14, 20 + side, 14 + side, 12, false)]);
        let p = SegmentParams {
            disk: protogist::segment::Disk::Cross,
            refine_dilations: 0,
            closing_steps: 0,
            ..PASS
        };
        let (r, _, _) = run(&p, &d, &c).unwrap();
        assert_eq!(!r.objects.is_empty(), kept, "side {side}: {:?}", r.objects);
        assert!(r.objects.iter().all(|o| o.area >= 36), "{:?}", r.objects);
    }
}

#[test]
fn a_short_foreground_copy_is_a_typed_error() {
    let (d, c) = boxes(&[(12, 10, 30, 26, 12, false)]);
    let mut store = SegmentStorage::new(BW, BH);
    let mut masks = vec![false; 3 * BW * BH];
    let mut c = c;
    let mut first = vec![0u32; bit_map_len(BW, BH) - 1];
    let r = segment_with_depth_pass(
        &PASS,
        &ImageView::packed(&d, BW, BH).unwrap(),
        &mut ImageViewMut::packed(&mut c, BW, BH).unwrap(),
        &mut store.buffers().unwrap(),
        Masks::Bools(&mut masks),
        &mut (),
        &mut first,
    );
    assert!(
        matches!(r, Err(SegmentError::MasksTooSmall { .. })),
        "{r:?}"
    );
    let bad = SegmentParams {
        depth_pass: Some(DepthPass {
            searches: 0,
            ..DepthPass::DEFAULT
        }),
        ..OPEN
    };
    assert!(matches!(
        bad.validate(),
        Err(SegmentError::BadParams("depth_pass.searches"))
    ));
}

#[test]
fn the_colour_objects_clearance_is_left_out_of_the_pass() {
    // A plain box 6 px wide, 2 px right of an outlined one (a halo's
    // place): found by the pass with no clearance; with 8 square
    // dilations of the outlined box's mask it lies in the clearance.
    let (d, c) = boxes(&[(4, 8, 18, 24, 7, true), (20, 8, 26, 24, 12, false)]);
    let with = |clearance| SegmentParams {
        depth_pass: Some(DepthPass {
            clearance,
            ..PASS.depth_pass.unwrap()
        }),
        ..PASS
    };
    let (r, masks, _) = run(&with(0), &d, &c).unwrap();
    assert_eq!(r.objects.len(), 2, "{:?}", r.objects);
    assert!(iou_box(mask(&masks, 1), (20, 8, 26, 24)) > 0.6);
    let (r, _, _) = run(&with(8), &d, &c).unwrap();
    assert_eq!(r.objects.len(), 1, "{:?}", r.objects);
}
