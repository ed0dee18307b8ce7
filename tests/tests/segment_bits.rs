//! `segment` runs its steps on bit maps; these tests hold it to the `bool`
//! and cell step functions (`segment.rs` holds those to the naive
//! references), bit for bit: every intermediate map, the report and the
//! masks, on random scenes, random parameters and the seeded synthetic
//! scenes.

use proptest::prelude::*;
use protogist::conspicuity::{Conspicuity, EdgeCell, EdgeParams, LuvTables};
use protogist::disparity::{from_pixels, Disparity, DisparityCell};
use protogist::image::{ImageView, ImageViewMut, Rgb8};
use protogist::segment::{self as sg, Disk, PsiMean, SegmentParams};
use protogist::synth::{render_disparity, render_left, SceneSpec};
use protogist_tests::SegmentStorage;

/// Every map of one object search, from the step functions.
#[derive(Debug, Default, PartialEq)]
struct Maps {
    d_fg: Vec<DisparityCell>,
    c_fg: Vec<EdgeCell>,
    d_obj_reg: Vec<DisparityCell>,
    c_obj_reg: Vec<EdgeCell>,
    region: Vec<bool>,
    c_obj: Vec<EdgeCell>,
    nms: Vec<bool>,
    closed: Vec<bool>,
    filled: Vec<bool>,
}

/// The stage composed from its public `bool`/cell steps (the definition).
fn by_steps(
    p: &SegmentParams,
    d: &[DisparityCell],
    c: &[EdgeCell],
    w: usize,
    h: usize,
) -> (sg::SegmentReport, Vec<bool>, Maps) {
    let n = w * h;
    let dv = ImageView::packed(d, w, h).unwrap();
    let cv = ImageView::packed(c, w, h).unwrap();
    let k = usize::from(p.max_objects);
    let mut masks = vec![false; k * n];
    let mut m = Maps {
        d_fg: vec![DisparityCell::OFF; n],
        c_fg: vec![EdgeCell::OFF; n],
        d_obj_reg: vec![DisparityCell::OFF; n],
        c_obj_reg: vec![EdgeCell::OFF; n],
        region: vec![false; n],
        c_obj: vec![EdgeCell::OFF; n],
        nms: vec![false; n],
        closed: vec![false; n],
        filled: vec![false; n],
    };
    let mut psi = vec![EdgeCell::OFF; n];
    let mut scratch = vec![false; n];
    let cap = sg::label_capacity(w, h);
    let (mut labels, mut parent, mut area) = (vec![0u16; n], vec![0u16; cap], vec![0u32; cap]);
    let mut lab = sg::Labeller::new(w, h, &mut labels, &mut parent, &mut area).unwrap();
    let mut report = sg::SegmentReport {
        stats: None,
        thresholds: None,
        ground: None,
        foreground: 0,
        objects: Default::default(),
    };
    macro_rules! v {
        ($m:expr) => {
            ImageView::packed(&$m, w, h).unwrap()
        };
    }
    macro_rules! vm {
        ($m:expr) => {
            &mut ImageViewMut::packed(&mut $m, w, h).unwrap()
        };
    }
    let Some(stats) = sg::selected_stats(p, &dv) else {
        return (report, masks, m);
    };
    let t = sg::thresholds(p, &stats);
    report.stats = Some(stats);
    report.thresholds = Some(t);
    report.foreground = sg::foreground(p, &dv, &t, vm!(m.d_fg)).unwrap();
    if p.ground_band.is_some() || p.row_background.is_some() {
        let mut rows = vec![0u32; sg::ground_rows_len(h)];
        let line = sg::fit_ground(&dv, &mut rows).unwrap();
        if let Some(band) = p.row_background {
            report.foreground += sg::foreground_rows(p, &dv, &t, &rows, band, vm!(m.d_fg)).unwrap();
        }
        if let (Some(band), Some(line)) = (p.ground_band, line) {
            report.ground = Some(line);
            report.foreground -= sg::inhibit_ground(&line, band, vm!(m.d_fg)).unwrap();
        }
    }
    let mw = p.max_object_width;
    let searches = if p.min_object.num == 0 && mw.num >= mw.den && p.max_aspect == 0 {
        k
    } else {
        k * sg::SEARCHES_PER_OBJECT
    };
    let mut mask = vec![false; n];
    for search in 0..searches {
        let index = report.objects.len();
        if index >= k {
            break;
        }
        sg::foreground_conspicuity(&cv, &v!(m.d_fg), vm!(m.c_fg)).unwrap();
        let counts = sg::slice_counts(&v!(m.c_fg), &v!(m.d_fg)).unwrap();
        let Some(slice) = sg::select_slice(&counts, p.exponent) else {
            break;
        };
        let range = sg::slice_range(p, &stats, slice.delta);
        sg::object_region(&v!(m.d_fg), &range, vm!(m.d_obj_reg)).unwrap();
        sg::object_conspicuity(&cv, &v!(m.d_obj_reg), vm!(psi)).unwrap();
        sg::above_mean(p.psi_mean, &v!(psi), &v!(m.d_obj_reg), vm!(m.c_obj_reg)).unwrap();
        sg::refine_border(
            p,
            &v!(psi),
            &v!(m.c_obj_reg),
            vm!(m.region),
            vm!(scratch),
            &mut lab,
            vm!(m.c_obj),
        )
        .unwrap();
        sg::non_max_suppression(&v!(m.c_obj), vm!(m.nms)).unwrap();
        m.closed.copy_from_slice(&m.nms);
        let (pw, ph) = sg::closing_size(w, h, p.closing_steps);
        let (mut padded, mut pad_scratch) = (vec![false; pw * ph], vec![false; pw * ph]);
        sg::close(
            p.disk,
            vm!(m.closed),
            &mut ImageViewMut::packed(&mut padded, pw, ph).unwrap(),
            &mut ImageViewMut::packed(&mut pad_scratch, pw, ph).unwrap(),
            p.closing_steps,
        )
        .unwrap();
        sg::fill_holes(&v!(m.closed), vm!(m.filled), &mut lab).unwrap();
        let regions = sg::area_filter(&v!(m.filled), vm!(mask), &mut lab, p.min_area).unwrap();
        // With `split_interiors`, the solid interiors of the mask, each
        // given back its contour within the filled map, are the objects.
        let least = (n as u64 * u64::from(p.min_object.num)).div_ceil(u64::from(p.min_object.den));
        let mut parts: Vec<Vec<bool>> = Vec::new();
        if p.split_interiors && u64::from(regions.area) >= 2 * least {
            let inner: Vec<bool> = mask.iter().zip(&m.closed).map(|(&a, &c)| a && !c).collect();
            let count = lab.label(&v!(inner), true, sg::Connectivity::Four).unwrap();
            let largest = lab.largest().map_or(0, |(_, a)| a);
            let keep = p.min_area;
            let mut cand: Vec<(u16, u32)> = (1..=count)
                .map(|l| (l, lab.area(l)))
                .filter(|&(_, a)| {
                    u64::from(a) >= least
                        && u64::from(a) * u64::from(keep.den)
                            >= u64::from(largest) * u64::from(keep.num)
                })
                .collect();
            cand.sort_by_key(|&(l, a)| (std::cmp::Reverse(a), l));
            cand.truncate(2 * sg::MAX_OBJECTS);
            let labels: Vec<u16> = lab.labels().unwrap().rows().flatten().copied().collect();
            for (l, a) in cand {
                let inside = (0..n)
                    .filter(|&i| labels[i] == l && m.d_obj_reg[i].is_on())
                    .count() as u32;
                if 2 * inside >= a && parts.len() < sg::MAX_OBJECTS {
                    let mut part: Vec<bool> = labels.iter().map(|&x| x == l).collect();
                    sg::dilate_n(p.disk, vm!(part), vm!(scratch), 2).unwrap();
                    for (q, &f) in part.iter_mut().zip(&m.filled) {
                        *q &= f;
                    }
                    parts.push(part);
                }
            }
            if parts.len() < 2 {
                parts.clear();
            }
        }
        let whole = parts.is_empty();
        if whole {
            parts.push(mask.clone());
        }
        for part in &parts {
            let index = report.objects.len();
            if index >= k {
                break;
            }
            let area = part.iter().filter(|&&b| b).count() as u32;
            let regions = sg::AreaReport { area, ..regions };
            // Masks under `min_object` of the frame are not objects.
            // ... and nor are boxes wider than `max_object_width` of it, or
            // more than `max_aspect` times as long as wide.
            let bbox = sg::bounding_box(&v!(part));
            let (bw, bh) = bbox.map_or((0, 0), |b| (b.width, b.height));
            let a = usize::from(p.max_aspect);
            let object = u64::from(area) * u64::from(p.min_object.den)
                >= (n as u64) * u64::from(p.min_object.num)
                && bw * usize::from(mw.den) <= w * usize::from(mw.num)
                && (a == 0 || (bw <= a * bh && bh <= a * bw));
            if object {
                let det = sg::Detection {
                    index,
                    delta: slice.delta,
                    range,
                    score: slice.score,
                    area,
                    bbox,
                    regions,
                };
                report.objects.push(det).unwrap();
                masks[index * n..(index + 1) * n].copy_from_slice(part);
            }
        }
        if !whole {
            // The inhibition takes every part.
            mask.copy_from_slice(&m.filled);
        }
        if report.objects.len() < k && search + 1 < searches {
            sg::inhibit(
                vm!(m.d_fg),
                &v!(m.d_obj_reg),
                &v!(m.region),
                &v!(mask),
                slice.delta,
            )
            .unwrap();
        }
    }
    (report, masks, m)
}

/// `segment` on bit maps, with its maps expanded.
fn by_bits(
    p: &SegmentParams,
    d: &[DisparityCell],
    c: &[EdgeCell],
    w: usize,
    h: usize,
) -> (sg::SegmentReport, Vec<bool>, Maps) {
    let dv = ImageView::packed(d, w, h).unwrap();
    let cv = ImageView::packed(c, w, h).unwrap();
    let mut store = SegmentStorage::new(w, h);
    let mut masks = vec![false; usize::from(p.max_objects) * w * h];
    let mut bufs = store.buffers().unwrap();
    let report = sg::segment(p, &dv, &cv, &mut bufs, &mut masks).unwrap();
    let (doff, coff) = (DisparityCell::OFF, EdgeCell::OFF);
    let m = Maps {
        d_fg: bufs.d_fg().masked(&dv, doff).collect(),
        c_fg: bufs.d_fg().masked(&cv, coff).collect(),
        d_obj_reg: bufs.d_obj_reg().masked(&dv, doff).collect(),
        c_obj_reg: bufs.c_obj_reg().masked(&cv, coff).collect(),
        region: bufs.region().bools().collect(),
        c_obj: bufs.c_obj().masked(&cv, coff).collect(),
        nms: bufs.nms().bools().collect(),
        closed: bufs.closed().bools().collect(),
        filled: bufs.filled().bools().collect(),
    };
    (report, masks, m)
}

fn check(
    p: &SegmentParams,
    d: &[DisparityCell],
    c: &[EdgeCell],
    w: usize,
    h: usize,
) -> Result<(), TestCaseError> {
    let (r0, m0, maps0) = by_steps(p, d, c, w, h);
    let (r1, m1, maps1) = by_bits(p, d, c, w, h);
    prop_assert_eq!(r1, r0);
    prop_assert!(m1 == m0, "masks differ");
    // Field by field, for a readable failure.
    prop_assert!(maps1.d_fg == maps0.d_fg, "D_fg");
    prop_assert!(maps1.c_fg == maps0.c_fg, "C_fg");
    prop_assert!(maps1.d_obj_reg == maps0.d_obj_reg, "D_ObjReg");
    prop_assert!(maps1.c_obj_reg == maps0.c_obj_reg, "C_ObjReg");
    prop_assert!(maps1.region == maps0.region, "region");
    prop_assert!(maps1.c_obj == maps0.c_obj, "C_Obj");
    prop_assert!(maps1.nms == maps0.nms, "NMS");
    prop_assert!(maps1.closed == maps0.closed, "closed");
    prop_assert!(maps1.filled == maps0.filled, "filled");
    Ok(())
}

fn params() -> impl Strategy<Value = SegmentParams> {
    (
        prop_oneof![Just(Disk::Cross), Just(Disk::Square)],
        0u8..6,
        0u8..6,
        any::<bool>(),
        1u8..=4,
        0u8..3,
        (
            proptest::option::of(0u16..2048),
            0u16..3,
            1u16..=4,
            0u8..4,
            any::<bool>(),
            proptest::option::of(0u16..1024),
            prop_oneof![Just(0u16), 0u16..=512],
        ),
    )
        .prop_map(
            |(
                disk,
                refine,
                close,
                on_cells,
                k,
                exponent,
                (ground, min_object, width, aspect, split, rows, min_slice_radius),
            )| {
                SegmentParams {
                    disk,
                    refine_dilations: refine,
                    closing_steps: close,
                    psi_mean: if on_cells {
                        PsiMean::OnCells
                    } else {
                        PsiMean::Region
                    },
                    max_objects: k,
                    exponent,
                    ground_band: ground,
                    min_object: sg::Ratio::new(min_object, 64),
                    max_object_width: sg::Ratio::new(width, 4),
                    max_aspect: aspect,
                    split_interiors: split,
                    row_background: rows,
                    min_slice_radius,
                    ..SegmentParams::default()
                }
            },
        )
}

/// Blocky scenes: a background plane (flat or tilting like a ground) and rectangles at other planes, with
/// sub-pixel jitter and OFF cells; C ON at random, stronger on rectangle
/// outlines. Widths cross the 32-pixel word boundaries.
#[allow(clippy::type_complexity)]
fn scene() -> impl Strategy<Value = (Vec<DisparityCell>, Vec<EdgeCell>, usize, usize)> {
    (
        prop_oneof![1usize..=8, 28usize..=36, 60usize..=70],
        1usize..=40,
        proptest::collection::vec(
            (0usize..70, 0usize..40, 1usize..40, 1usize..30, 3u8..40),
            0..4,
        ),
        (0u8..4, 0u16..3),
        0u32..=100,
        0u32..=40,
    )
        .prop_flat_map(|(w, h, rects, (bg, tilt), edge_pct, off_pct)| {
            let n = w * h;
            (
                proptest::collection::vec((0u16..200, 0u32..100, 0u32..100, 1u16..6), n),
                Just((w, h, rects, bg, tilt, edge_pct, off_pct)),
            )
                .prop_map(|(noise, (w, h, rects, bg, tilt, edge_pct, off_pct))| {
                    // A background tilting towards the bottom (a ground) or flat.
                    let mut d: Vec<_> = (0..w * h)
                        .map(|i| {
                            let b = u16::from(bg) * 256 + (i / w) as u16 * tilt * 40;
                            DisparityCell::on(Disparity::from_bits(b)).unwrap()
                        })
                        .collect();
                    let mut ring = vec![false; w * h];
                    for &(x0, y0, rw, rh, disp) in &rects {
                        for y in y0..(y0 + rh).min(h) {
                            for x in x0..(x0 + rw).min(w) {
                                d[y * w + x] = from_pixels(disp);
                                ring[y * w + x] =
                                    x == x0 || y == y0 || x + 1 == x0 + rw || y + 1 == y0 + rh;
                            }
                        }
                    }
                    let mut c = vec![EdgeCell::OFF; w * h];
                    for (i, &(jit, e, off, v)) in noise.iter().enumerate() {
                        if off < off_pct {
                            d[i] = DisparityCell::OFF;
                        } else if let Some(v0) = d[i].get() {
                            let b = (v0.to_bits() + jit).min(u16::MAX - 1);
                            d[i] = DisparityCell::on(Disparity::from_bits(b)).unwrap();
                        }
                        if ring[i] || e < edge_pct {
                            // Few levels: ties are frequent.
                            let v = if ring[i] { v + 3 } else { v };
                            c[i] = EdgeCell::on(Conspicuity::from_bits(v * 64)).unwrap();
                        }
                    }
                    (d, c, w, h)
                })
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn segment_on_bits_matches_the_steps((d, c, w, h) in scene(), p in params()) {
        check(&p, &d, &c, w, h)?;
    }
}

#[test]
fn segment_on_bits_matches_the_steps_on_seeded_scenes() {
    let (w, h) = (160, 120);
    let tables = LuvTables::new();
    // The 24 scenes of the IoU check, and the demo scene the firmware runs.
    for seed in 0..25u64 {
        let spec = if seed < 24 {
            SceneSpec::random(seed, w, h)
        } else {
            SceneSpec::demo(w, h)
        };
        let mut rgb = vec![Rgb8::default(); w * h];
        render_left(&spec, &mut ImageViewMut::packed(&mut rgb, w, h).unwrap()).unwrap();
        let edges =
            protogist_host::stages::run_conspicuity(&tables, &EdgeParams::default(), &rgb, w, h)
                .unwrap();
        let mut gt = vec![0u8; w * h];
        render_disparity(&spec, &mut ImageViewMut::packed(&mut gt, w, h).unwrap()).unwrap();
        let d: Vec<_> = gt.iter().map(|&v| from_pixels(v)).collect();
        let product = protogist::pipeline::PipelineParams::DEFAULT.segment;
        for (k, base) in [
            (1, SegmentParams::default()),
            (4, SegmentParams::default()),
            (4, product),
        ] {
            let p = SegmentParams {
                max_objects: k,
                ..base
            };
            check(&p, &d, &edges.edges, w, h).unwrap();
        }
    }
}

// ---------------------------------------------------------------------------
// The shape stage on a bit mask against the same stage on its bytes.

use protogist::shape::{self as sh, RadialProfile, ShapeElem, SHAPE_LEN};

fn pack(m: &[u8], w: usize) -> Vec<u32> {
    let stride = sg::words_per_row(w);
    let mut out = vec![0u32; stride * (m.len() / w)];
    for (i, &v) in m.iter().enumerate() {
        if v != 0 {
            let (x, y) = (i % w, i / w);
            out[y * stride + x / 32] |= 1 << (x % 32);
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn shape_on_bits_matches_shape_on_bytes(
        (m, w, h) in (prop_oneof![1usize..=8, 28usize..=36, 60usize..=70], 1usize..=40, 0u32..=100)
            .prop_flat_map(|(w, h, pct)| (
                proptest::collection::vec(proptest::bool::weighted(f64::from(pct) / 100.0), w * h),
                Just(w),
                Just(h),
            ))
            .prop_map(|(m, w, h)| (m.into_iter().map(u8::from).collect::<Vec<u8>>(), w, h))
    ) {
        let words = pack(&m, w);
        let bits = sg::BitView::new(&words, w, h).unwrap();
        let bytes = ImageView::packed(&m, w, h).unwrap();
        prop_assert_eq!(sh::centroid_bits(&bits), sh::centroid(&bytes));
        let (mut a, mut b) = (Vec::new(), Vec::new());
        sh::for_each_contour_bit(&bits, |x, y| a.push((x, y)));
        sh::for_each_contour_pixel(&bytes, |x, y| b.push((x, y)));
        prop_assert_eq!(a, b);
        let (mut pa, mut pb) = (RadialProfile::new(), RadialProfile::new());
        let (mut va, mut vb) = ([ShapeElem::ZERO; SHAPE_LEN], [ShapeElem::ZERO; SHAPE_LEN]);
        let ra = sh::shape_vector_bits(&bits, &mut pa, &mut va);
        let rb = sh::shape_vector(&bytes, &mut pb, &mut vb);
        prop_assert_eq!(ra, rb);
        prop_assert_eq!(pa, pb);
        prop_assert!(va == vb);
    }
}
