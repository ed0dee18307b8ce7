//! The depth pass (`protogist::segment::depth`): by hand and against the
//! f32 reference (its settings' checks: `depth_pass_settings.rs`).

use proptest::prelude::*;
use protogist::conspicuity::{Conspicuity, EdgeCell};
use protogist::disparity::{from_pixels, DisparityCell};
use protogist::image::{ImageView, Rgb8};
use protogist::segment::{
    self as sg, segment_with_depth_pass, DepthPass, Holes, Masks, Ratio, Refine, SegmentError,
    SegmentParams, SegmentReport,
};
use protogist_host::reference::refine as rfr;
use protogist_host::reference::segment as rf;
use protogist_tests::SegmentStorage;

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
        searches: 2,
        clearance: 2,
        min_area: Ratio::new(1, 48),
        ..DepthPass::DEFAULT
    }),
    ..OPEN
};

/// The report and the masks, the masks refined against `left` (a grey
/// frame when `None`).
fn run_at(
    p: &SegmentParams,
    d: &[DisparityCell],
    c: &[EdgeCell],
    left: Option<&[Rgb8]>,
    (w, h): (usize, usize),
) -> Result<(SegmentReport, Vec<bool>), SegmentError> {
    let mut store = SegmentStorage::new(w, h);
    let mut masks = vec![false; usize::from(p.max_objects) * w * h];
    let grey = vec![
        Rgb8 {
            r: 90,
            g: 90,
            b: 90
        };
        w * h
    ];
    let frame = ImageView::packed(left.unwrap_or(&grey), w, h).unwrap();
    let r = segment_with_depth_pass(
        p,
        &ImageView::packed(d, w, h).unwrap(),
        &ImageView::packed(c, w, h).unwrap(),
        &frame,
        &mut store.buffers().unwrap(),
        Masks::Bools(&mut masks),
        &mut (),
    )?;
    Ok((r, masks))
}

fn run(
    p: &SegmentParams,
    d: &[DisparityCell],
    c: &[EdgeCell],
) -> Result<(SegmentReport, Vec<bool>), SegmentError> {
    run_at(p, d, c, None, (BW, BH))
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
    let (r, _) = run(&OPEN, &d, &c).unwrap();
    assert!(r.objects.is_empty(), "{:?}", r.objects);
    let (r, masks) = run(&PASS, &d, &c).unwrap();
    assert_eq!(r.objects.len(), 1, "{:?}", r.objects);
    assert_eq!(r.objects[0].delta, 12);
    let iou = iou_box(mask(&masks, 0), (12, 10, 30, 26));
    assert_eq!(iou, 1.0);
}

#[test]
fn the_pass_adds_to_the_colour_objects_and_never_repeats_one() {
    let list = [(4, 6, 18, 20, 7, true), (26, 12, 42, 28, 12, false)];
    let (d, c) = boxes(&list);
    let (colour, cm) = run(&OPEN, &d, &c).unwrap();
    assert_eq!(colour.objects.len(), 1, "{:?}", colour.objects);
    let (r, masks) = run(&PASS, &d, &c).unwrap();
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
        let (r, _) = run(&p, &d, &c).unwrap();
        assert_eq!(!r.objects.is_empty(), kept, "side {side}: {:?}", r.objects);
        assert!(r.objects.iter().all(|o| o.area >= 36), "{:?}", r.objects);
    }
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
    let (r, masks) = run(&with(0), &d, &c).unwrap();
    assert_eq!(r.objects.len(), 2, "{:?}", r.objects);
    assert!(iou_box(mask(&masks, 1), (20, 8, 26, 24)) > 0.6);
    let (r, _) = run(&with(8), &d, &c).unwrap();
    assert_eq!(r.objects.len(), 1, "{:?}", r.objects);
}

#[test]
fn cells_under_the_rise_above_their_row_are_not_the_pass_s() {
    // The background is at 2 px; a plain box 2 px above it is under the
    // rise of 3 px, one 3 px above it is not.
    for (disp, kept) in [(4, false), (5, true)] {
        let (d, c) = boxes(&[(12, 10, 30, 26, disp, false)]);
        let (r, _) = run(&PASS, &d, &c).unwrap();
        assert_eq!(
            r.objects.len(),
            usize::from(kept),
            "{disp} px: {:?}",
            r.objects
        );
    }
}

#[test]
fn plain_objects_at_two_depths_are_two_objects_and_off_holes_are_filled() {
    // Each row's background (2 px) stays its most common plane.
    let (mut d, c) = boxes(&[(4, 6, 14, 30, 12, false), (28, 8, 38, 22, 20, false)]);
    // OFF cells inside the first box: the closing and the fill take them.
    for (x, y) in [(8, 15), (9, 15), (10, 15), (9, 16), (11, 20)] {
        d[y * BW + x] = DisparityCell::OFF;
    }
    let (r, masks) = run(&PASS, &d, &c).unwrap();
    assert_eq!(r.objects.len(), 2, "{:?}", r.objects);
    // The larger slice first.
    assert_eq!((r.objects[0].delta, r.objects[1].delta), (12, 20));
    assert_eq!(iou_box(mask(&masks, 0), (4, 6, 14, 30)), 1.0);
    assert_eq!(iou_box(mask(&masks, 1), (28, 8, 38, 22)), 1.0);
}

// ---------------------------------------------------------------------------
// The colour refinement.

/// A left image of `BW` x `BH`: `bg`, with `(x0, y0, x1, y1)` in `fg`.
fn two_colours(bg: Rgb8, fg: Rgb8, (x0, y0, x1, y1): (usize, usize, usize, usize)) -> Vec<Rgb8> {
    (0..BW * BH)
        .map(|i| {
            let (x, y) = (i % BW, i / BW);
            if (x0..x1).contains(&x) && (y0..y1).contains(&y) {
                fg
            } else {
                bg
            }
        })
        .collect()
}

const GREY: Rgb8 = Rgb8 {
    r: 100,
    g: 100,
    b: 100,
};
const TAN: Rgb8 = Rgb8 {
    r: 118,
    g: 104,
    b: 92,
};

fn refined(p: &SegmentParams, d: &[DisparityCell], c: &[EdgeCell], left: &[Rgb8]) -> Vec<bool> {
    let (r, masks) = run_at(p, d, c, Some(left), (BW, BH)).unwrap();
    assert_eq!(r.objects.len(), 1);
    mask(&masks, 0).to_vec()
}

#[test]
fn the_refinement_gives_a_slice_the_border_its_colour_has() {
    // The object is 16x14 in colour; the stereo lost a 2 px band of its
    // border to the background's disparity, so its slice is 12x10.
    let (d, c) = boxes(&[(12, 10, 24, 20, 12, false)]);
    let left = two_colours(GREY, TAN, (10, 8, 26, 22));
    let without = SegmentParams {
        depth_pass: PASS.depth_pass.map(|p| DepthPass { refine: None, ..p }),
        ..PASS
    };
    assert_eq!(
        iou_box(&refined(&without, &d, &c, &left), (12, 10, 24, 20)),
        1.0
    );
    let with = PASS;
    assert_eq!(
        iou_box(&refined(&with, &d, &c, &left), (10, 8, 26, 22)),
        1.0
    );
    // The object's colour only: a slice 2 px too wide is trimmed to it.
    let wide = boxes(&[(8, 6, 28, 24, 12, false)]);
    assert_eq!(
        iou_box(&refined(&with, &wide.0, &wide.1, &left), (10, 8, 26, 22)),
        1.0
    );
    // One colour everywhere: every cell is a tie and keeps its place.
    let grey = vec![GREY; BW * BH];
    assert_eq!(
        refined(&with, &d, &c, &grey),
        refined(&without, &d, &c, &grey)
    );
}

#[test]
fn a_left_image_of_another_size_is_an_error() {
    let (d, c) = boxes(&[(12, 10, 24, 20, 12, false)]);
    let left = vec![GREY; (BW + 1) * BH];
    let frame = ImageView::packed(&left, BW + 1, BH).unwrap();
    let mut store = SegmentStorage::new(BW, BH);
    let mut masks = vec![false; 3 * BW * BH];
    let r = segment_with_depth_pass(
        &PASS,
        &ImageView::packed(&d, BW, BH).unwrap(),
        &ImageView::packed(&c, BW, BH).unwrap(),
        &frame,
        &mut store.buffers().unwrap(),
        Masks::Bools(&mut masks),
        &mut (),
    );
    assert!(matches!(r, Err(SegmentError::SizeMismatch { got, .. }) if got == (BW + 1, BH)));
}

// ---------------------------------------------------------------------------
// Against the f32 reference.

/// Per box a colour offset and a shift, the background colour, and noise
/// per pixel.
type Paint = (Vec<([i16; 3], isize, isize, bool)>, [u8; 3], Vec<i16>);

/// A left image for [`blocky`]'s boxes: a background colour, box `k` in
/// it plus `paint.0[k].0` (close colours, so that the noise and the
/// means decide), moved by `paint.0[k].1, .2` px, and noise.
fn painted(
    (w, h): (usize, usize),
    list: &[(usize, usize, usize, usize, u8, bool)],
    (boxes, bg, noise): &Paint,
) -> Vec<Rgb8> {
    let mut img = vec![*bg; w * h];
    for (&(x0, y0, bw, bh, _, _), &(delta, dx, dy, window)) in list.iter().zip(boxes) {
        let colour: [u8; 3] =
            core::array::from_fn(|i| (i16::from(bg[i]) + delta[i]).clamp(0, 255) as u8);
        for y in 0..h {
            for x in 0..w {
                let (sx, sy) = (x as isize - dx, y as isize - dy);
                let inside = (x0 as isize..(x0 + bw) as isize).contains(&sx)
                    && (y0 as isize..(y0 + bh) as isize).contains(&sy);
                // A window: the middle third shows the background.
                let (ox, oy) = (3 * (sx - x0 as isize), 3 * (sy - y0 as isize));
                let middle = (bw as isize..2 * bw as isize).contains(&ox)
                    && (bh as isize..2 * bh as isize).contains(&oy);
                if inside && !(window && middle) {
                    img[y * w + x] = colour;
                }
            }
        }
    }
    img.iter()
        .zip(noise)
        .map(|(p, &n)| {
            let c = |v: u8| (i16::from(v) + n).clamp(0, 255) as u8;
            Rgb8 {
                r: c(p[0]),
                g: c(p[1]),
                b: c(p[2]),
            }
        })
        .collect()
}

/// A blocky scene: background 2 px; boxes `(x, y, w, h, d, outlined)`
/// clipped to the frame; `off` cells OFF.
fn blocky(
    (w, h): (usize, usize),
    list: &[(usize, usize, usize, usize, u8, bool)],
    off: &[bool],
) -> (Vec<DisparityCell>, Vec<EdgeCell>) {
    let mut d = vec![from_pixels(2); w * h];
    let mut c = vec![EdgeCell::OFF; w * h];
    for &(x0, y0, bw, bh, disp, outlined) in list {
        for y in y0..(y0 + bh).min(h) {
            for x in x0..(x0 + bw).min(w) {
                d[y * w + x] = from_pixels(disp);
                let ring = x == x0 || y == y0 || x + 1 == x0 + bw || y + 1 == y0 + bh;
                c[y * w + x] = if outlined {
                    EdgeCell::on(Conspicuity::from_num(if ring { 40 } else { 5 })).unwrap()
                } else {
                    EdgeCell::OFF
                };
            }
        }
    }
    for (v, &o) in d.iter_mut().zip(off) {
        if o {
            *v = DisparityCell::OFF;
        }
    }
    (d, c)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// The pass's objects are the reference's, mask for mask: its
    /// decisions compare `U8F8` values, which `f64` holds exactly, with
    /// the rows' dominant disparities kept to 1/256 px in both (error
    /// bound: none).
    #[test]
    fn the_pass_is_the_references(
        (w, h, list, off) in (24usize..56, 16usize..40).prop_flat_map(|(w, h)| (
            Just(w),
            Just(h),
            prop::collection::vec(
                (0..w, 0..h, 4usize..20, 4usize..20, 3u8..30, any::<bool>()),
                0..5,
            ),
            prop::collection::vec(prop::bool::weighted(0.05), w * h),
        )),
        rise in 1u16..(6 * 256),
        radius in 0u16..(3 * 256),
        closing in 0u8..4,
        searches in 1u8..5,
        clearance in 0u8..4,
        den in 16u16..200,
        refine in prop::option::weighted(0.8, (0u8..4, 0u8..5, 1u8..5)),
        holes in prop::option::weighted(0.8, (1u8..5, 0u8..3, 1u8..5, 0u8..3, 4u16..40)),
        paint in (
            prop::collection::vec(
                (prop::array::uniform3(-40i16..41), -3isize..4, -3isize..4, any::<bool>()),
                5,
            ),
            prop::array::uniform3(40u8..216),
            prop::collection::vec(-20i16..21, 56 * 40),
        ),
        // D_fg's settings: the pass's foreground is written with D_fg, in
        // the same sweep, whatever they are.
        (fg_high, row_background, ground_band) in (
            prop_oneof![Just(100u16), 1u16..4],
            prop::option::of(0u16..1024),
            prop::option::of(0u16..1024),
        ),
    ) {
        let (d, c) = blocky((w, h), &list, &off);
        let left = painted((w, h), &list, &paint);
        let refine = refine.map(|(core, reach, ring)| Refine { core, reach, ring });
        let holes = holes.map(|(band, gap, ring, opening, den)| Holes {
            band, gap, ring, opening, min_area: Ratio::new(1, den),
        });
        let pass = DepthPass {
            holes,
            rise, radius, closing, searches, clearance, min_area: Ratio::new(1, den), refine,
        };
        let colour_only = SegmentParams {
            max_objects: 4,
            fg_high: Ratio::new(fg_high, 1),
            row_background,
            ground_band,
            ..OPEN
        };
        let p = SegmentParams { depth_pass: Some(pass), ..colour_only };
        let (colour, cm) = run_at(&colour_only, &d, &c, Some(&left), (w, h)).unwrap();
        let (r, masks) = run_at(&p, &d, &c, Some(&left), (w, h)).unwrap();
        let n = colour.objects.len();
        let colour_masks: Vec<Vec<bool>> =
            (0..n).map(|k| cm[k * w * h..(k + 1) * w * h].to_vec()).collect();
        let df: Vec<rf::DispF> = d.iter().map(|v| v.get().map(f32::from)).collect();
        // The pass sees the colour masks filled; then every mask loses
        // its holes.
        let pass_masks = rf::depth_pass(&p, &df, &colour_masks, Some(&left), w, h);
        let holed = |m: &Vec<bool>| match &holes {
            Some(hs) => rfr::open_holes(hs, m, &left, w, h),
            None => m.clone(),
        };
        let want: Vec<Vec<bool>> = colour_masks.iter().chain(&pass_masks).map(holed).collect();
        let got: Vec<Vec<bool>> =
            (0..r.objects.len()).map(|k| masks[k * w * h..(k + 1) * w * h].to_vec()).collect();
        prop_assert_eq!(&got, &want);
        // The colour objects' reports, with the areas of their masks.
        for (k, (a, b)) in r.objects.iter().zip(&colour.objects).enumerate() {
            let area = want[k].iter().filter(|&&m| m).count() as u32;
            prop_assert_eq!(a, &sg::Detection { area, ..*b });
        }
        prop_assert_eq!(r.objects.len(), n + pass_masks.len());
    }
}

#[test]
fn a_ring_gets_its_hole_back_and_a_solid_box_stays_whole() {
    // Two outlined boxes of 18x18 at 12 and 20 px, of one colour; the
    // first shows the background through a window, its middle third.
    let (d, c) = boxes(&[(4, 8, 22, 26, 12, true), (26, 8, 44, 26, 20, true)]);
    let list = [(4, 8, 18, 18, 12, true), (26, 8, 18, 18, 20, true)];
    let paint: Paint = (
        vec![([60, -40, 20], 0, 0, true), ([60, -40, 20], 0, 0, false)],
        [90, 120, 90],
        vec![0; BW * BH],
    );
    let left = painted((BW, BH), &list, &paint);
    let filled = SegmentParams {
        depth_pass: PASS.depth_pass.map(|p| DepthPass { holes: None, ..p }),
        ..PASS
    };
    let (r0, m0) = run_at(&filled, &d, &c, Some(&left), (BW, BH)).unwrap();
    // The window is a ninth of the box; the mask is larger than the box.
    let holed = SegmentParams {
        depth_pass: PASS.depth_pass.map(|p| DepthPass {
            holes: Some(Holes {
                min_area: Ratio::new(1, 20),
                ..Holes::DEFAULT
            }),
            ..p
        }),
        ..PASS
    };
    let (r1, m1) = run_at(&holed, &d, &c, Some(&left), (BW, BH)).unwrap();
    assert_eq!(r0.objects.len(), 2, "{:?}", r0.objects);
    assert_eq!(r1.objects.len(), 2, "{:?}", r1.objects);
    let window = |i: usize| (10..16).contains(&(i % BW)) && (14..20).contains(&(i / BW));
    for k in 0..2 {
        let (before, after) = (mask(&m0, k), mask(&m1, k));
        let ring = r0.objects[k].delta == 12;
        // Filled, the ring covers its window.
        let outline = if ring {
            (4, 8, 22, 26)
        } else {
            (26, 8, 44, 26)
        };
        assert!(iou_box(before, outline) > 0.8);
        assert!((0..BW * BH)
            .filter(|&i| ring && window(i))
            .all(|i| before[i]));
        for (i, (&b, &a)) in before.iter().zip(after).enumerate() {
            assert_eq!(a, b && !(ring && window(i)), "object {k}, cell {i}");
        }
        let area = after.iter().filter(|&&m| m).count() as u32;
        assert_eq!(r1.objects[k].area, area);
        assert_eq!(
            r1.objects[k].area + if ring { 36 } else { 0 },
            r0.objects[k].area
        );
    }
}
