//! The mask stages against the naive and float references, bit for bit on
//! random maps, and small masks pinned as ASCII pictures.

// ---------------------------------------------------------------------------
// Integer mask stages against the naive references, bit for bit.

use proptest::prelude::*;
use protogist::conspicuity::{Conspicuity, EdgeCell};
use protogist::disparity::DisparityCell;
use protogist::image::{ImageView, ImageViewMut};
use protogist::segment::SegmentParams;
use protogist::segment::{self as sg, Connectivity, Disk, Labeller, Ratio};
use protogist_host::reference::segment as rf;
use protogist_tests::{mask, show_mask};

/// A binary map from 1x1 to `max` x `max`, of random density.
fn binary_map(max: usize) -> impl Strategy<Value = (Vec<bool>, usize, usize)> {
    (1..=max, 1..=max, 0u32..=100).prop_flat_map(|(w, h, pct)| {
        proptest::collection::vec(proptest::bool::weighted(f64::from(pct) / 100.0), w * h)
            .prop_map(move |v| (v, w, h))
    })
}

/// A conspicuity map with OFF cells and few distinct values (many ties).
fn edge_map(max: usize) -> impl Strategy<Value = (Vec<EdgeCell>, usize, usize)> {
    (1..=max, 1..=max).prop_flat_map(|(w, h)| {
        proptest::collection::vec(proptest::option::weighted(0.6, 0u16..6), w * h).prop_map(
            move |v| {
                let cells = v
                    .into_iter()
                    .map(|c| {
                        c.map_or(EdgeCell::OFF, |c| {
                            EdgeCell::on(Conspicuity::from_bits(c * 64)).unwrap()
                        })
                    })
                    .collect();
                (cells, w, h)
            },
        )
    })
}

fn disk() -> impl Strategy<Value = Disk> {
    prop_oneof![Just(Disk::Cross), Just(Disk::Square)]
}

struct Lab {
    labels: Vec<u16>,
    parent: Vec<u16>,
    area: Vec<u32>,
}

impl Lab {
    fn new(w: usize, h: usize) -> Self {
        let cap = sg::label_capacity(w, h);
        Self {
            labels: vec![0; w * h],
            parent: vec![0; cap],
            area: vec![0; cap],
        }
    }
    fn get(&mut self, w: usize, h: usize) -> Labeller<'_> {
        Labeller::new(w, h, &mut self.labels, &mut self.parent, &mut self.area).unwrap()
    }
}

fn view(m: &[bool], w: usize, h: usize) -> ImageView<'_, bool> {
    ImageView::packed(m, w, h).unwrap()
}

fn core_close(disk: Disk, m: &[bool], w: usize, h: usize, n: u8) -> Vec<bool> {
    let mut out = m.to_vec();
    let (pw, ph) = sg::closing_size(w, h, n);
    let (mut padded, mut scratch) = (vec![false; pw * ph], vec![false; pw * ph]);
    sg::close(
        disk,
        &mut ImageViewMut::packed(&mut out, w, h).unwrap(),
        &mut ImageViewMut::packed(&mut padded, pw, ph).unwrap(),
        &mut ImageViewMut::packed(&mut scratch, pw, ph).unwrap(),
        n,
    )
    .unwrap();
    out
}

fn core_fill(m: &[bool], w: usize, h: usize) -> Vec<bool> {
    let mut out = vec![false; w * h];
    let mut lab = Lab::new(w, h);
    sg::fill_holes(
        &view(m, w, h),
        &mut ImageViewMut::packed(&mut out, w, h).unwrap(),
        &mut lab.get(w, h),
    )
    .unwrap();
    out
}

fn core_area_filter(m: &[bool], w: usize, h: usize, keep: Ratio) -> Vec<bool> {
    let mut out = vec![false; w * h];
    let mut lab = Lab::new(w, h);
    sg::area_filter(
        &view(m, w, h),
        &mut ImageViewMut::packed(&mut out, w, h).unwrap(),
        &mut lab.get(w, h),
        keep,
    )
    .unwrap();
    out
}

fn core_nms(c: &[EdgeCell], w: usize, h: usize) -> Vec<bool> {
    let mut out = vec![false; w * h];
    sg::non_max_suppression(
        &ImageView::packed(c, w, h).unwrap(),
        &mut ImageViewMut::packed(&mut out, w, h).unwrap(),
    )
    .unwrap();
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn dilate_and_erode_match_naive((m, w, h) in binary_map(20), disk in disk()) {
        let mut out = vec![false; w * h];
        sg::dilate(disk, &view(&m, w, h), &mut ImageViewMut::packed(&mut out, w, h).unwrap()).unwrap();
        prop_assert_eq!(&out, &rf::dilate(disk, &m, w, h));
        sg::erode(disk, &view(&m, w, h), &mut ImageViewMut::packed(&mut out, w, h).unwrap()).unwrap();
        prop_assert_eq!(&out, &rf::erode(disk, &m, w, h));
    }

    #[test]
    fn closing_matches_naive((m, w, h) in binary_map(20), disk in disk(), n in 0u8..5) {
        prop_assert_eq!(core_close(disk, &m, w, h, n), rf::close(disk, &m, w, h, n));
    }

    #[test]
    fn labels_match_naive((m, w, h) in binary_map(24), value in any::<bool>(), eight in any::<bool>()) {
        let conn = if eight { Connectivity::Eight } else { Connectivity::Four };
        let mut lab = Lab::new(w, h);
        let mut l = lab.get(w, h);
        let n = l.label(&view(&m, w, h), value, conn).unwrap();
        let (want, wn) = rf::label(&m, w, h, value, conn);
        prop_assert_eq!(n, wn);
        let got: Vec<u16> = l.labels().unwrap().pixels().collect();
        prop_assert_eq!(got, want);
    }

    #[test]
    fn nms_matches_naive((c, w, h) in edge_map(20)) {
        prop_assert_eq!(core_nms(&c, w, h), rf::non_max_suppression(&c, w, h));
    }

    #[test]
    fn fill_matches_naive((m, w, h) in binary_map(24)) {
        prop_assert_eq!(core_fill(&m, w, h), rf::fill_holes(&m, w, h));
    }

    #[test]
    fn area_filter_matches_naive((m, w, h) in binary_map(24), num in 0u16..6, den in 1u16..6) {
        let keep = Ratio::new(num, den);
        prop_assert_eq!(core_area_filter(&m, w, h, keep), rf::area_filter(&m, w, h, keep));
    }

    #[test]
    fn refine_border_matches_naive((psi, w, h) in edge_map(24), disk in disk(), n in 0u8..5) {
        let params = sg::SegmentParams { disk, refine_dilations: n, ..Default::default() };
        let (mut region, mut scratch, mut c_obj) = (vec![false; w * h], vec![false; w * h], vec![EdgeCell::OFF; w * h]);
        let mut lab = Lab::new(w, h);
        let pv = ImageView::packed(&psi, w, h).unwrap();
        sg::refine_border(
            &params, &pv, &pv,
            &mut ImageViewMut::packed(&mut region, w, h).unwrap(),
            &mut ImageViewMut::packed(&mut scratch, w, h).unwrap(),
            &mut lab.get(w, h),
            &mut ImageViewMut::packed(&mut c_obj, w, h).unwrap(),
        ).unwrap();
        prop_assert_eq!(&region, &rf::refine_region(disk, &psi, w, h, n));
        for ((c, r), p) in c_obj.iter().zip(&region).zip(&psi) {
            prop_assert_eq!(*c, if *r { *p } else { EdgeCell::OFF });
        }
    }
}

// ---------------------------------------------------------------------------
// Statistics steps against the float reference.

/// A disparity map: OFF cells, a background plane and a few object planes,
/// each with sub-pixel jitter, and edges ON at random.
#[allow(clippy::type_complexity)]
fn disparity_scene(
    max: usize,
) -> impl Strategy<Value = (Vec<DisparityCell>, Vec<EdgeCell>, usize, usize)> {
    (
        4..=max,
        4..=max,
        proptest::collection::vec(0u16..60 * 256, 1..4),
    )
        .prop_flat_map(|(w, h, planes)| {
            let n = w * h;
            let planes2 = planes.clone();
            (
                proptest::collection::vec(
                    (0..planes2.len(), 0u16..512, proptest::bool::weighted(0.1)),
                    n,
                ),
                proptest::collection::vec(proptest::option::weighted(0.4, 0u16..200), n),
            )
                .prop_map(move |(cells, edges)| {
                    let d = cells
                        .into_iter()
                        .map(|(p, jitter, off)| {
                            if off {
                                DisparityCell::OFF
                            } else {
                                let bits = planes[p].saturating_add(jitter).min(u16::MAX - 1);
                                DisparityCell::on(protogist::disparity::Disparity::from_bits(bits))
                                    .unwrap()
                            }
                        })
                        .collect();
                    let c = edges
                        .into_iter()
                        .map(|e| {
                            e.map_or(EdgeCell::OFF, |v| {
                                EdgeCell::on(Conspicuity::from_bits(v * 64)).unwrap()
                            })
                        })
                        .collect();
                    (d, c, w, h)
                })
        })
}

const Q: f32 = 4096.0;

fn to_f(d: &[DisparityCell]) -> Vec<rf::DispF> {
    d.iter()
        .map(|c| c.get().map(|v| f32::from(v.to_bits()) / 256.0))
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn statistics_match_the_float_reference(
        (d, c, w, h) in disparity_scene(32),
        exponent in 0u8..3,
        min_slice_radius in prop_oneof![Just(0u16), 0u16..=1024],
    ) {
        let params = SegmentParams { exponent, min_slice_radius, ..Default::default() };
        let dv = ImageView::packed(&d, w, h).unwrap();
        let df = to_f(&d);
        let fs = sg::selected_stats(&params, &dv);
        let rs = rf::selected_stats(&params, &df, w, h);
        prop_assert_eq!(fs.is_some(), rs.is_some());
        let (Some(fs), Some(rs)) = (fs, rs) else { return Ok(()) };
        prop_assert_eq!(fs.count, rs.count);
        // mean and σ are rounded once to 1/4096 px (σ after a rounded variance).
        prop_assert!((fs.mean as f32 / Q - rs.mean).abs() <= 0.6 / Q + 1e-5 * rs.mean, "{fs:?} {rs:?}");
        prop_assert!((fs.sigma as f32 / Q - rs.sigma).abs() <= 1.0 / Q + 1e-4 * rs.sigma, "{fs:?} {rs:?}");
        let (ft, rt) = (sg::thresholds(&params, &fs), rf::thresholds(&params, &rs));
        prop_assert!((ft.low as f32 / Q - rt.low).abs() <= 2.0 / Q + 1e-4 * rt.low);
        prop_assert!((ft.high as f32 / Q - rt.high).abs() <= 3.0 / Q + 1e-4 * rt.high);
        let fr = sg::slice_radius(&params, &fs) as f32 / Q;
        prop_assert!((fr - rf::slice_radius(&params, &rs)).abs() <= 1.0 / Q + 1e-4 * fr);
        // D_fg agrees away from the thresholds ...
        let mut d_fg = vec![DisparityCell::OFF; w * h];
        sg::foreground(&params, &dv, &ft, &mut ImageViewMut::packed(&mut d_fg, w, h).unwrap()).unwrap();
        let r_fg = rf::foreground(&params, &df, w, h, &rt);
        for ((a, b), v) in d_fg.iter().zip(&r_fg).zip(&df) {
            let near = v.is_some_and(|v| (v - rt.low).abs() < 4.0 / Q || (v - rt.high).abs() < 4.0 / Q);
            if !near {
                prop_assert_eq!(a.is_on(), b.is_some());
            }
        }
        // ... and exactly with the same (fixed) thresholds; then A^C and δ are exact.
        let same = rf::ThresholdsF { low: ft.low as f32 / Q, high: ft.high as f32 / Q };
        let r_fg = rf::foreground(&params, &df, w, h, &same);
        for (a, b) in d_fg.iter().zip(&r_fg) {
            prop_assert_eq!(a.is_on(), b.is_some());
        }
        let cv = ImageView::packed(&c, w, h).unwrap();
        let mut c_fg = vec![EdgeCell::OFF; w * h];
        sg::foreground_conspicuity(&cv, &ImageView::packed(&d_fg, w, h).unwrap(), &mut ImageViewMut::packed(&mut c_fg, w, h).unwrap()).unwrap();
        prop_assert_eq!(&c_fg, &rf::foreground_conspicuity(&c, &r_fg));
        let counts = sg::slice_counts(&ImageView::packed(&c_fg, w, h).unwrap(), &ImageView::packed(&d_fg, w, h).unwrap()).unwrap();
        let rcounts = rf::slice_counts(&c_fg, &r_fg);
        prop_assert_eq!(&counts.counts[..], &rcounts.0[..]);
        prop_assert_eq!(counts.planes, rcounts.1);
        let (a, b) = (sg::select_slice(&counts, exponent), rf::select_slice(&rcounts, exponent));
        prop_assert_eq!(a.map(|s| (s.delta, s.cells, s.score as f64)), b);
    }
}

/// The slice is `δ ± σ_S · 2/5`, widened to `min_slice_radius`: an object
/// whose cells lie on the whole-px plane below δ (as completed cells do)
/// falls outside the paper's ±0.8 px but inside ±1 px.
#[test]
fn slice_is_at_least_the_least_radius() {
    const ONE: i64 = 1 << sg::STAT_FRAC_BITS;
    let narrow = sg::SelectedStats {
        count: 100,
        mean: 8 << sg::STAT_FRAC_BITS,
        sigma: 2 << sg::STAT_FRAC_BITS,
    };
    let paper = SegmentParams::default();
    let r = sg::slice_range(&paper, &narrow, 9);
    // 2 px · 2/5 = 0.8 px = 3276.8 / 4096, rounded half up.
    assert_eq!((r.low, r.high), (9 * ONE - 3277, 9 * ONE + 3277));
    assert!(!r.contains_bits(8 * 256));
    let floor = SegmentParams {
        min_slice_radius: 256,
        ..paper
    };
    let r = sg::slice_range(&floor, &narrow, 9);
    assert_eq!((r.low, r.high), (8 * ONE, 10 * ONE));
    assert!(r.contains_bits(8 * 256) && r.contains_bits(10 * 256));
    assert!(!r.contains_bits(8 * 256 - 1) && !r.contains_bits(10 * 256 + 1));
    // A wider σ_S is left alone.
    let wide = sg::SelectedStats {
        sigma: 5 << sg::STAT_FRAC_BITS,
        ..narrow
    };
    assert_eq!(
        sg::slice_range(&floor, &wide, 9),
        sg::slice_range(&paper, &wide, 9)
    );
    assert_eq!(sg::slice_radius(&paper, &wide), 2 << sg::STAT_FRAC_BITS);
}

// ---------------------------------------------------------------------------
// Small masks pinned as ASCII pictures.

fn assert_mask(got: &[bool], w: usize, want: (Vec<bool>, usize, usize)) {
    assert_eq!(w, want.1);
    assert_eq!(
        show_mask(got, w),
        show_mask(&want.0, want.1),
        "\ngot:\n{}\nwant:\n{}",
        show_mask(got, w).join("\n"),
        show_mask(&want.0, want.1).join("\n")
    );
}

#[test]
fn nms_keeps_ridges_and_drops_shoulders() {
    // A vertical ridge of 9 between shoulders of 5, a lone 3, a plateau of 2s.
    let rows = ["05950..", "05950.3", "05950..", "....22.", "....22."];
    let (w, h) = (rows[0].len(), rows.len());
    let c: Vec<EdgeCell> = rows
        .iter()
        .flat_map(|r| r.chars())
        .map(|ch| match ch.to_digit(10) {
            Some(v) => EdgeCell::on(Conspicuity::from_num(v)).unwrap(),
            None => EdgeCell::OFF,
        })
        .collect();
    // Every ON cell of the ridge picture is a maximum along its column (ties
    // survive), so NMS keeps the ridge and its shoulders; OFF stays OFF.
    assert_mask(
        &core_nms(&c, w, h),
        w,
        mask!["#####..", "#####.#", "#####..", "....##.", "....##."],
    );
    // A cone: every cell is a maximum along the line tangent to its ring
    // (ties or the outside below it), so all survive; a cell is suppressed
    // only when it is strictly below a neighbour on each of the 4 lines, as
    // the bottom of the bowl on the right and the 1s between cone and bowl.
    let rows = [
        "123212222",
        "246422222",
        "369632212",
        "246422222",
        "123212222",
    ];
    let cone: Vec<EdgeCell> = rows
        .iter()
        .flat_map(|r| r.chars())
        .map(|ch| EdgeCell::on(Conspicuity::from_num(ch.to_digit(10).unwrap())).unwrap())
        .collect();
    let got = core_nms(&cone, 9, 5);
    assert_eq!(got, rf::non_max_suppression(&cone, 9, 5));
    assert_mask(
        &got,
        9,
        mask![
            "####.####",
            "#########",
            "#######.#",
            "#########",
            "####.####"
        ],
    );
}

#[test]
fn closing_bridges_small_gaps_only() {
    let (m, w, h) = mask![
        "..............",
        "..............",
        "...###.###....",
        "...#.......#..",
        "...#.......#..",
        "...#########..",
        "..............",
        "..............",
    ];
    // The cross does not bridge a 1-px gap in a straight line (the cross
    // centred just above the gap misses the line) but fills inner corners;
    // the full 3x3 square bridges it.
    assert_mask(
        &core_close(Disk::Cross, &m, w, h, 1),
        w,
        mask![
            "..............",
            "..............",
            "...###.###....",
            "...##...####..",
            "...###.#####..",
            "...#########..",
            "..............",
            "..............",
        ],
    );
    assert_mask(
        &core_close(Disk::Square, &m, w, h, 1),
        w,
        mask![
            "..............",
            "..............",
            "...#######....",
            "...#########..",
            "...#########..",
            "...#########..",
            "..............",
            "..............",
        ],
    );
    // The closing is the unbounded plane's: it never erodes from the image
    // border, and it adds nothing there that it would not add inside.
    let full = vec![true; w * h];
    assert_eq!(core_close(Disk::Square, &full, w, h, 4), full);
    let (m, w, h) = mask!["#.#"];
    assert_mask(&core_close(Disk::Cross, &m, w, h, 1), w, mask!["#.#"]);
    assert_mask(&core_close(Disk::Square, &m, w, h, 1), w, mask!["###"]);
}

/// A closing of the frame itself, its erosions counting the outside as ON,
/// caps a shape near the frame's edge up to it. The unbounded plane's
/// closing gives a lone pixel back anywhere in the frame, and an edge along
/// the border stays one pixel wide.
#[test]
fn closing_adds_no_cap_at_the_frame_edge() {
    let (w, h) = (9, 7);
    for disk in [Disk::Cross, Disk::Square] {
        for n in 1..=sg::MAX_CLOSING_STEPS {
            for i in 0..w * h {
                let mut m = vec![false; w * h];
                m[i] = true;
                assert_eq!(core_close(disk, &m, w, h, n), m, "{disk:?} n {n} pixel {i}");
            }
        }
    }
    let (m, w, h) = mask!["..........", "..######..", "..........", "..........",];
    assert_mask(
        &core_close(Disk::Square, &m, w, h, 4),
        w,
        mask!["..........", "..######..", "..........", "..........",],
    );
}

#[test]
fn fill_fills_closed_contours_only() {
    let (m, w, h) = mask![
        "##########",
        "#...#....#",
        "#...#.##..",
        "#####.#.#.",
        "......##..",
    ];
    // Left box closed (its inside is filled); right box open at the border;
    // the small diamond-ish ring is closed only 8-wise, which is closed for
    // the 4-connected background.
    assert_mask(
        &core_fill(&m, w, h),
        w,
        mask![
            "##########",
            "#####....#",
            "#####.##..",
            "#####.###.",
            "......##..",
        ],
    );
}

#[test]
fn area_filter_drops_regions_below_a_fifth() {
    let (m, w, h) = mask![
        "######.....#",
        "######......",
        "######...##.",
        "######...##.",
        "............",
    ];
    // Areas 24, 1 and 4: 4 < 24/5 and 1 < 24/5 are dropped.
    assert_mask(
        &core_area_filter(&m, w, h, Ratio::new(1, 5)),
        w,
        mask![
            "######......",
            "######......",
            "######......",
            "######......",
            "............",
        ],
    );
    // At 1/6 the 2x2 square (4 = 24/6) stays.
    let kept = core_area_filter(&m, w, h, Ratio::new(1, 6));
    assert!(kept[2 * w + 9] && !kept[11]);
}
