//! Ground-plane inhibition (the v-disparity fit) against its f32 reference,
//! and the object filters of `SegmentParams` (`min_object`,
//! `max_object_width`): what they find, what they drop, and their typed
//! errors.

use proptest::prelude::*;
use protogist::conspicuity::{Conspicuity, EdgeCell};
use protogist::disparity::{from_pixels, Disparity, DisparityCell};
use protogist::image::{ImageView, ImageViewMut};
use protogist::segment::{self as sg, Ratio, SegmentParams};
use protogist_host::reference::segment as rf;
use protogist_tests::SegmentStorage;

/// A cell of `px` disparity (1/256 px resolution).
fn cell(px: f64) -> DisparityCell {
    DisparityCell::on(Disparity::from_bits((px * 256.0).round() as u16)).unwrap()
}

/// A wall at `wall` px above row `horizon`, a ground below it rising
/// linearly by `slope` px a row, and boxes `(x0, y0, x1, y1, px)` on top.
fn ground_scene(
    w: usize,
    h: usize,
    wall: f64,
    horizon: usize,
    slope: f64,
    boxes: &[(usize, usize, usize, usize, f64)],
) -> Vec<DisparityCell> {
    let mut d: Vec<_> = (0..w * h)
        .map(|i| {
            let y = i / w;
            cell(if y < horizon {
                wall
            } else {
                wall + slope * (y - horizon) as f64
            })
        })
        .collect();
    for &(x0, y0, x1, y1, px) in boxes {
        for y in y0..y1 {
            for x in x0..x1 {
                d[y * w + x] = cell(px);
            }
        }
    }
    d
}

fn fit(d: &[DisparityCell], w: usize, h: usize) -> Option<sg::GroundLine> {
    let mut rows = vec![0u32; sg::ground_rows_len(h)];
    sg::fit_ground(&ImageView::packed(d, w, h).unwrap(), &mut rows).unwrap()
}

fn px(bits: i64) -> f64 {
    bits as f64 / 256.0
}

#[test]
fn the_ground_line_is_found_and_only_the_ground_is_inhibited() {
    let (w, h) = (160, 120);
    let slope = 10.0 / 69.0;
    let object = (60, 60, 100, 95, 20.0);
    let d = ground_scene(w, h, 3.0, 50, slope, &[object]);
    let line = fit(&d, w, h).expect("a ground");
    // Q16 bits per row -> px per row.
    let got = line.slope as f64 / 65536.0 / 256.0;
    assert!((got - slope).abs() < 2e-3, "slope {got} vs {slope}");
    for y in [50, 80, 119] {
        let want = 3.0 + slope * (y - 50) as f64;
        assert!(
            (px(line.at(y)) - want).abs() < 0.1,
            "row {y}: {}",
            px(line.at(y))
        );
    }
    // Every ground row is on the line; the object's rows are not, where
    // it dominates them (it covers a quarter of each).
    assert!(line.rows >= 60, "{line:?}");
    let mut d_fg = d.clone();
    let off = sg::inhibit_ground(
        &line,
        3 * 256,
        &mut ImageViewMut::packed(&mut d_fg, w, h).unwrap(),
    )
    .unwrap();
    let is_object = |i: usize| {
        let (x, y) = (i % w, i / w);
        (object.0..object.2).contains(&x) && (object.1..object.3).contains(&y)
    };
    // Below the horizon only the object stays. Above it, the wall is
    // nearer than the line's extension plus the band up to row 29.3
    // (3 px > 3 + slope·(y − 50) + 3) and stays there (D_fg's lower
    // bound drops a wall); it is inhibited nearer the horizon.
    for (i, c) in d_fg.iter().enumerate() {
        let y = i / w;
        if (25..35).contains(&y) {
            continue;
        }
        let on = y < 25 || is_object(i);
        assert_eq!(c.is_on(), on, "cell ({}, {y})", i % w);
    }
    assert!(off as usize >= (h - 50) * w - 40 * 35);
}

#[test]
fn flat_empty_and_frontal_maps_have_no_ground() {
    let (w, h) = (64, 48);
    // One plane: slope 0 is a wall, not a ground.
    assert_eq!(fit(&vec![from_pixels(7); w * h], w, h), None);
    // No disparity at all.
    assert_eq!(fit(&vec![DisparityCell::OFF; w * h], w, h), None);
    // A frontal object over the lower half of a wall.
    let d = ground_scene(w, h, 3.0, h, 0.0, &[(0, 24, 64, 48, 15.0)]);
    assert_eq!(fit(&d, w, h), None);
    // A ground on under a quarter of the rows.
    let d = ground_scene(w, h, 3.0, h - 10, 0.2, &[]);
    assert_eq!(fit(&d, w, h), None);
    let d = ground_scene(w, h, 3.0, h - 14, 0.2, &[]);
    assert!(fit(&d, w, h).is_some());
}

#[test]
fn a_short_row_buffer_is_a_typed_error() {
    let d = vec![from_pixels(7); 8 * 6];
    let mut rows = vec![0u32; 5];
    let r = sg::fit_ground(&ImageView::packed(&d, 8, 6).unwrap(), &mut rows);
    assert!(matches!(r, Err(sg::SegmentError::Image(_))), "{r:?}");
    assert!(!r.unwrap_err().to_string().is_empty());
    // The background by rows reads the same row estimates.
    let dv = ImageView::packed(&d, 8, 6).unwrap();
    let t = sg::thresholds(&OPEN, &sg::selected_stats(&OPEN, &dv).unwrap());
    let mut fg = vec![DisparityCell::OFF; 8 * 6];
    let mut fv = ImageViewMut::packed(&mut fg, 8, 6).unwrap();
    let r = sg::foreground_rows(&OPEN, &dv, &t, &rows, 256, &mut fv);
    assert!(matches!(r, Err(sg::SegmentError::Image(_))), "{r:?}");
}

/// Ground scenes with sub-pixel jitter, OFF cells and up to two objects,
/// and their horizon row.
#[allow(clippy::type_complexity)]
fn jittered_ground() -> impl Strategy<Value = (Vec<DisparityCell>, usize, usize, usize)> {
    (
        16usize..=64,
        16usize..=64,
        (1.0f64..6.0, 0.1f64..0.45, 0.05f64..0.4),
        proptest::collection::vec((0.0f64..1.0, 0.0f64..1.0, 4.0f64..12.0), 0..3),
        any::<u64>(),
    )
        .prop_map(|(w, h, (wall, horizon, slope), objects, seed)| {
            let horizon = (h as f64 * horizon) as usize;
            let boxes: Vec<_> = objects
                .iter()
                .map(|&(fx, fy, rise)| {
                    let (x0, y0) = (
                        (fx * (w / 2) as f64) as usize,
                        (fy * (h / 2) as f64) as usize,
                    );
                    (
                        x0,
                        y0,
                        x0 + w / 5,
                        y0 + h / 4,
                        wall + slope * h as f64 + rise,
                    )
                })
                .collect();
            let mut d = ground_scene(w, h, wall, horizon, slope, &boxes);
            let mut s = seed;
            for c in &mut d {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let r = (s >> 33) as u32;
                if r % 10 == 0 {
                    *c = DisparityCell::OFF;
                } else if let Some(v) = c.get() {
                    // Up to ±0.2 px.
                    let j = (r >> 8) % 103;
                    let b = (i32::from(v.to_bits()) + j as i32 - 51).max(0) as u16;
                    *c = DisparityCell::on(Disparity::from_bits(b)).unwrap();
                }
            }
            (d, w, h, horizon)
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn ground_fit_matches_the_float_reference((d, w, h, horizon) in jittered_ground(), band in 0u16..1024) {
        let line = fit(&d, w, h);
        let df: Vec<rf::DispF> = d.iter().map(|c| c.get().map(|v| f32::from(v.to_bits()) / 256.0)).collect();
        let rl = rf::fit_ground(&df, w, h);
        prop_assert_eq!(line.is_some(), rl.is_some(), "{:?} {:?}", line, rl);
        let (Some(line), Some(rl)) = (line, rl) else { return Ok(()) };
        // Integer and float least squares may put a noisy row at the edge
        // of a refinement's 1/4 px band in or out: the lines agree to a
        // quarter of a pixel over the rows of the ground.
        for y in horizon..h {
            let (a, b) = (px(line.at(y)), rl.at(y));
            prop_assert!((a - b).abs() <= 0.25, "row {}: {} vs {} ({:?}, {:?})", y, a, b, line, rl);
        }
        // Inhibition agrees away from the band's edge (as far as the lines).
        let mut d_fg = d.clone();
        sg::inhibit_ground(&line, band, &mut ImageViewMut::packed(&mut d_fg, w, h).unwrap()).unwrap();
        let r_fg = rf::inhibit_ground(&rl, f32::from(band) / 256.0, &df, w);
        for (i, ((a, b), v)) in d_fg.iter().zip(&r_fg).zip(&df).enumerate() {
            let (y, band) = (i / w, f64::from(band) / 256.0);
            let (lo, hi) = (px(line.at(y)).min(rl.at(y)), px(line.at(y)).max(rl.at(y)));
            if v.is_some_and(|v| f64::from(v) < lo + band - 0.01 || f64::from(v) > hi + band + 0.01) {
                prop_assert_eq!(a.is_on(), b.is_some());
            }
        }
    }
}

// ---------------------------------------------------------------------------
// The object filters.

const BW: usize = 48;
const BH: usize = 36;

/// Background 2 px; boxes `(x0, y0, x1, y1, d)` with a strong outline and a
/// weak inside in C.
fn boxes(list: &[(usize, usize, usize, usize, u8)]) -> (Vec<DisparityCell>, Vec<EdgeCell>) {
    let mut d = vec![from_pixels(2); BW * BH];
    let mut c = vec![EdgeCell::OFF; BW * BH];
    for &(x0, y0, x1, y1, disp) in list {
        for y in y0..y1 {
            for x in x0..x1 {
                d[y * BW + x] = from_pixels(disp);
                let ring = x == x0 || y == y0 || x + 1 == x1 || y + 1 == y1;
                c[y * BW + x] =
                    EdgeCell::on(Conspicuity::from_num(if ring { 40 } else { 5 })).unwrap();
            }
        }
    }
    (d, c)
}

fn detect(
    p: &SegmentParams,
    d: &[DisparityCell],
    c: &[EdgeCell],
) -> Result<(sg::SegmentReport, Vec<bool>), sg::SegmentError> {
    let mut store = SegmentStorage::new(BW, BH);
    let mut masks = vec![false; usize::from(p.max_objects) * BW * BH];
    let r = sg::segment(
        p,
        &ImageView::packed(d, BW, BH).unwrap(),
        &ImageView::packed(c, BW, BH).unwrap(),
        &mut store.buffers().unwrap(),
        &mut masks,
    )?;
    Ok((r, masks))
}

/// The whole frame as S, no upper cut: every box is foreground.
const OPEN: SegmentParams = SegmentParams {
    top_bottom_strip: Ratio::new(0, 1),
    left_strip: Ratio::new(0, 1),
    fg_high: Ratio::new(100, 1),
    max_objects: 3,
    ..SegmentParams::PAPER
};

#[test]
fn small_masks_are_not_objects_and_the_search_goes_on() {
    // A 20x14 box at 9 px, a 4x4 one at 6 px (under 1/64 of the 1728-px
    // frame), and a 10x10 one at 5 px.
    let (d, c) = boxes(&[(4, 4, 24, 18, 9), (30, 4, 34, 8, 6), (30, 22, 40, 32, 5)]);
    let (all, _) = detect(&OPEN, &d, &c).unwrap();
    let all: Vec<u32> = all.objects.iter().map(|o| o.area).collect();
    assert_eq!(all.len(), 3, "{all:?}");
    let big: Vec<u32> = all.iter().copied().filter(|&a| a >= 27).collect();
    assert_eq!(big.len(), 2, "{all:?}");
    let p = SegmentParams {
        min_object: Ratio::new(1, 64),
        ..OPEN
    };
    let (r, masks) = detect(&p, &d, &c).unwrap();
    let areas: Vec<u32> = r.objects.iter().map(|o| o.area).collect();
    assert_eq!(areas, big);
    // Slots are the reported objects' in order; the last one stays clear.
    for (k, o) in r.objects.iter().enumerate() {
        assert_eq!(o.index, k);
        let n = masks[k * BW * BH..(k + 1) * BW * BH]
            .iter()
            .filter(|&&m| m)
            .count();
        assert_eq!(n as u32, o.area);
    }
    assert!(!masks[2 * BW * BH..].iter().any(|&m| m));
}

#[test]
fn frame_wide_masks_are_not_objects() {
    // A band across the whole width at 6 px (a horizon's edge) and a box.
    let (d, c) = boxes(&[(0, 2, 48, 8, 6), (10, 14, 30, 30, 9)]);
    let (all, _) = detect(&OPEN, &d, &c).unwrap();
    // S is `x > w·left`, so column 0 is never foreground: the band's mask
    // spans the rest of the width (the closing adds no cap up to the
    // frame's edge).
    assert!(all
        .objects
        .iter()
        .any(|o| o.bbox.is_some_and(|b| b.x == 1 && b.width == BW - 1)));
    let p = SegmentParams {
        max_object_width: Ratio::new(3, 4),
        ..OPEN
    };
    let (r, _) = detect(&p, &d, &c).unwrap();
    assert!(!r.objects.is_empty());
    for o in &r.objects {
        let b = o.bbox.unwrap();
        assert!(b.width * 4 <= BW * 3, "{b:?}");
    }
    assert!(r.objects[0].bbox.is_some_and(|b| b.x >= 8 && b.width <= 24));
}

#[test]
fn elongated_masks_are_not_objects() {
    // A 30x5 strip at 14 px (a horizon's band, 6 times as long as wide),
    // a 5x26 post at 9 px, and a 12x10 box at 6 px, all clear of the
    // border.
    let (d, c) = boxes(&[(6, 5, 36, 10, 14), (38, 5, 43, 31, 9), (10, 18, 22, 28, 6)]);
    let (all, _) = detect(&OPEN, &d, &c).unwrap();
    let long = |b: sg::BoundingBox| b.width > 4 * b.height || b.height > 4 * b.width;
    assert!(
        all.objects
            .iter()
            .filter(|o| o.bbox.is_some_and(long))
            .count()
            >= 2,
        "{:?}",
        all.objects
    );
    let p = SegmentParams {
        max_aspect: 4,
        ..OPEN
    };
    let (r, _) = detect(&p, &d, &c).unwrap();
    assert!(!r.objects.is_empty(), "{all:?} {r:?}");
    for o in &r.objects {
        assert!(!o.bbox.is_some_and(long), "{o:?}");
    }
    assert!(r.objects[0].bbox.is_some_and(|b| b.x >= 9 && b.y >= 17));
}

#[test]
fn an_object_in_front_of_a_far_wall_is_foreground_by_its_row() {
    // An 18x10 box at 20 px raises the frame's mean to 4 px and its
    // band's lower bound to about 4.5 px; a 10x10 box at 4 px, in other
    // rows, stands 2 px in front of the 2 px wall: under the band, but
    // nearer than its rows' background.
    let (d, c) = boxes(&[(4, 2, 22, 12, 20), (30, 16, 40, 26, 4)]);
    let far = |r: &sg::SegmentReport| {
        r.objects.iter().any(|o| {
            o.bbox
                .is_some_and(|b| b.x >= 28 && b.y >= 14 && b.width <= 12)
        })
    };
    let (paper, _) = detect(&OPEN, &d, &c).unwrap();
    assert!(!far(&paper), "{paper:?}");
    let p = SegmentParams {
        row_background: Some(256),
        ..OPEN
    };
    let (r, _) = detect(&p, &d, &c).unwrap();
    assert!(far(&r), "{r:?}");
    // A band of the box's 2 px: nothing more than the paper.
    let (wide, _) = detect(
        &SegmentParams {
            row_background: Some(2 * 256),
            ..p
        },
        &d,
        &c,
    )
    .unwrap();
    assert!(!far(&wide), "{wide:?}");
}

#[test]
fn touching_objects_of_one_slice_are_split_by_their_contours() {
    // Two 16x16 boxes side by side at 9 px: one slice, one closed
    // component of contours, so the paper's mask holds both.
    let (d, c) = boxes(&[(6, 8, 22, 24, 9), (22, 8, 38, 24, 9)]);
    let (merged, _) = detect(&OPEN, &d, &c).unwrap();
    assert_eq!(merged.objects.len(), 1, "{merged:?}");
    assert!(merged.objects[0].bbox.is_some_and(|b| b.width >= 30));
    let p = SegmentParams {
        split_interiors: true,
        ..OPEN
    };
    let (r, masks) = detect(&p, &d, &c).unwrap();
    assert_eq!(r.objects.len(), 2, "{r:?}");
    let mut xs: Vec<usize> = r.objects.iter().map(|o| o.bbox.unwrap().x).collect();
    xs.sort_unstable();
    assert!(xs[0] <= 7 && (20..=23).contains(&xs[1]), "{xs:?}");
    for (k, o) in r.objects.iter().enumerate() {
        let b = o.bbox.unwrap();
        assert!(
            (14..=18).contains(&b.width) && (14..=18).contains(&b.height),
            "{b:?}"
        );
        let n = masks[k * BW * BH..(k + 1) * BW * BH]
            .iter()
            .filter(|&&m| m)
            .count();
        assert_eq!(n as u32, o.area);
        assert!(o.area >= 200, "{o:?}");
    }
    // K caps the parts.
    let (one, _) = detect(
        &SegmentParams {
            max_objects: 1,
            ..p
        },
        &d,
        &c,
    )
    .unwrap();
    assert_eq!(one.objects.len(), 1);
}

#[test]
fn a_ring_is_one_object_when_interiors_are_split() {
    // An 80x64 frame at 2 px; a 60x50 box at 9 px with a 30x26 hole at
    // the background's 2 px, both outlined in C, with a weak inside. The
    // hole is an interior of the mask too, but not in the slice: not an
    // object of its own.
    let (w, h) = (80, 64);
    let mut d = vec![from_pixels(2); w * h];
    let mut c = vec![EdgeCell::OFF; w * h];
    let edge = EdgeCell::on(Conspicuity::from_num(40)).unwrap();
    for y in 8..58 {
        for x in 10..70 {
            let hole = (25..55).contains(&x) && (19..45).contains(&y);
            if !hole {
                d[y * w + x] = from_pixels(9);
            }
            let outer = x == 10 || y == 8 || x == 69 || y == 57;
            // The hole's outline on the box's side (C_ObjReg is C within
            // the slice).
            let around = (24..56).contains(&x) && (18..46).contains(&y);
            let inner = around && !hole && (x == 24 || y == 18 || x == 55 || y == 45);
            if outer || inner {
                c[y * w + x] = edge;
            } else if !hole {
                // A weak inside, as `boxes` draws it.
                c[y * w + x] = EdgeCell::on(Conspicuity::from_num(5)).unwrap();
            }
        }
    }
    let p = SegmentParams {
        split_interiors: true,
        ..OPEN
    };
    let run = |p: &SegmentParams| {
        let mut store = SegmentStorage::new(w, h);
        let mut masks = vec![false; usize::from(p.max_objects) * w * h];
        sg::segment(
            p,
            &ImageView::packed(&d, w, h).unwrap(),
            &ImageView::packed(&c, w, h).unwrap(),
            &mut store.buffers().unwrap(),
            &mut masks,
        )
        .unwrap()
    };
    let (r, paper) = (run(&p), run(&OPEN));
    assert_eq!(r.objects.len(), 1, "{r:?}");
    assert_eq!(r.objects, paper.objects);
    assert!(r.objects[0]
        .bbox
        .is_some_and(|b| b.width >= 58 && b.height >= 48));
}

#[test]
fn bad_filter_and_ground_parameters_are_typed_errors() {
    let (d, c) = boxes(&[(10, 10, 30, 26, 9)]);
    let p = OPEN;
    assert!(detect(&p, &d, &c).is_ok());
    for (bad, name) in [
        (
            SegmentParams {
                ground_band: Some(sg::MAX_GROUND_BAND + 1),
                ..p
            },
            "ground_band",
        ),
        (
            SegmentParams {
                row_background: Some(sg::MAX_GROUND_BAND + 1),
                ..p
            },
            "row_background",
        ),
        (
            SegmentParams {
                min_slice_radius: sg::MAX_GROUND_BAND + 1,
                ..p
            },
            "min_slice_radius",
        ),
        (
            SegmentParams {
                min_object: Ratio::new(2, 1),
                ..p
            },
            "min_object",
        ),
        (
            SegmentParams {
                min_object: Ratio::new(1, 0),
                ..p
            },
            "min_object",
        ),
        (
            SegmentParams {
                max_object_width: Ratio::new(0, 4),
                ..p
            },
            "max_object_width",
        ),
        (
            SegmentParams {
                max_object_width: Ratio::new(5, 4),
                ..p
            },
            "max_object_width",
        ),
    ] {
        let r = detect(&bad, &d, &c);
        assert_eq!(r.as_ref().err(), Some(&sg::SegmentError::BadParams(name)));
        assert!(r.unwrap_err().to_string().contains(name));
    }
    // The product's setting is valid.
    protogist::pipeline::PipelineParams::DEFAULT
        .segment
        .validate()
        .unwrap();
}
