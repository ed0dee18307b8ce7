//! Disparity completion over conspicuity regions (`protogist::complete`):
//! the runs form with bounded tables, as the pipeline runs it, bit for bit
//! against the independent reference, a hand-worked case, and bad input.

use proptest::prelude::*;
use protogist::complete::{
    complete_runs, region_table_len, run_rows_len, run_table_len, CompleteError, CompleteParams,
    CompleteReport, RegionTables, RowSpan, RunBuffers, SideColour, Tone, LABEL_ROWS,
};
use protogist::conspicuity::{Conspicuity, EdgeCell, Luv};
use protogist::disparity::{from_pixels, Disparity, DisparityCell};
use protogist::image::{ImageView, ImageViewMut};
use protogist::segment::bit_map_len;
use protogist_host::reference::complete as rf;
use protogist_host::stages::run_complete;

fn edge_on() -> EdgeCell {
    EdgeCell::on(Conspicuity::from_bits(100)).unwrap()
}

/// A random case: edges along a few random lines plus noise, colours from a
/// small palette, disparities with OFF cells.
#[allow(clippy::type_complexity)]
fn case() -> impl Strategy<
    Value = (
        Vec<EdgeCell>,
        Vec<Luv>,
        Vec<DisparityCell>,
        usize,
        usize,
        CompleteParams,
    ),
> {
    (
        1usize..=24,
        1usize..=24,
        0u8..=3,
        0u32..=6,
        0u16..=8,
        prop_oneof![Just(u16::MAX), 0u16..=6 * 256],
    )
        .prop_flat_map(|(w, h, guard, min_trusted, tilt_rows, tilt_band)| {
            let n = w * h;
            (
                proptest::collection::vec(0u8..100, n),
                proptest::collection::vec(0u8..4, n),
                proptest::collection::vec(proptest::option::weighted(0.8, 0u16..=20 * 256), n),
                0usize..=w,
                Just((w, h, guard, min_trusted, tilt_rows, tilt_band)),
            )
                .prop_map(
                    |(
                        noise,
                        palette,
                        disp,
                        col,
                        (w, h, guard, min_trusted, tilt_rows, tilt_band),
                    )| {
                        let edges = noise
                            .iter()
                            .enumerate()
                            .map(|(i, &r)| {
                                if i % w == col || r < 8 {
                                    edge_on()
                                } else {
                                    EdgeCell::OFF
                                }
                            })
                            .collect();
                        let colour = palette
                            .iter()
                            .map(|&c| Luv::from_bits(i16::from(c) * 900, -i16::from(c) * 300, 50))
                            .collect();
                        let disparity = disp
                            .iter()
                            .map(|d| match d {
                                Some(bits) => {
                                    DisparityCell::on(Disparity::from_bits(*bits)).unwrap()
                                }
                                None => DisparityCell::OFF,
                            })
                            .collect();
                        (
                            edges,
                            colour,
                            disparity,
                            w,
                            h,
                            CompleteParams {
                                guard,
                                min_trusted,
                                tilt_rows,
                                tilt_band,
                            },
                        )
                    },
                )
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// The pipeline's form (`run_complete`: runs, one [`Tone`] per pixel)
    /// against the reference given the tones' colours.
    #[test]
    fn core_matches_the_reference_bit_for_bit((edges, colour, disp, w, h, params) in case()) {
        let (core_out, core_report) = run_complete(&params, &edges, &colour, &disp, w, h).unwrap();
        let toned: Vec<Luv> = colour.iter().map(|&c| Tone::of(c).to_luv()).collect();
        let (ref_out, ref_report) = rf::complete(&params, &edges, &toned, &disp, w, h);
        prop_assert_eq!(core_out, ref_out);
        prop_assert_eq!(core_report, ref_report);
    }

    /// The runs form with the full colour against the reference.
    #[test]
    fn the_runs_form_matches_the_reference_with_full_colour(
        (edges, colour, disp, w, h, params) in case()
    ) {
        let (ref_out, ref_report) = rf::complete(&params, &edges, &colour, &disp, w, h);
        let (runs_out, runs_report) = by_runs(&params, &edges, &colour, &disp, w, h, run_table_len(w, h));
        prop_assert_eq!(&runs_out, &ref_out);
        prop_assert_eq!(runs_report, ref_report);
    }
}

/// [`complete_runs`] with region tables for every label and `runs` run-table
/// entries.
fn by_runs<C: SideColour>(
    params: &CompleteParams,
    edges: &[EdgeCell],
    colour: &[C],
    disp: &[DisparityCell],
    w: usize,
    h: usize,
    runs: usize,
) -> (Vec<DisparityCell>, CompleteReport) {
    let tables = (runs, region_table_len(w, h));
    try_by_runs(params, edges, (colour, w, h), disp, (w, h), tables).unwrap()
}

/// [`complete_runs`] on a `colour` map of its own size, with `(runs,
/// regions)` entries in the run and region tables.
fn try_by_runs<C: SideColour>(
    params: &CompleteParams,
    edges: &[EdgeCell],
    (colour, cw, ch): (&[C], usize, usize),
    disp: &[DisparityCell],
    (w, h): (usize, usize),
    (runs, regions): (usize, usize),
) -> Result<(Vec<DisparityCell>, CompleteReport), CompleteError> {
    let (mut open, mut trusted) = (vec![0u32; bit_map_len(w, h)], vec![0u32; bit_map_len(w, h)]);
    let (mut table, mut rows) = (vec![0u16; runs], vec![0u32; run_rows_len(w)]);
    let mut labels = vec![0u16; LABEL_ROWS * w];
    let (mut total, mut below, mut lo, mut hi) = (
        vec![0u32; regions],
        vec![0u32; regions],
        vec![0u8; regions],
        vec![0u8; regions],
    );
    let mut spans = vec![RowSpan::default(); regions];
    let mut out = disp.to_vec();
    let report = complete_runs(
        params,
        &ImageView::packed(edges, w, h).unwrap(),
        &ImageView::packed(colour, cw, ch).unwrap(),
        &mut ImageViewMut::packed(&mut out, w, h).unwrap(),
        &mut RunBuffers {
            open: &mut open,
            trusted: &mut trusted,
            runs: &mut table,
            rows: &mut rows,
            labels: &mut labels,
        },
        &mut RegionTables {
            total: &mut total,
            below: &mut below,
            lo: &mut lo,
            hi: &mut hi,
            tilt: &mut spans,
        },
    )?;
    Ok((out, report))
}

#[test]
fn a_tall_region_is_completed_along_its_tilt() {
    // A ground seen from row 1 down: its disparity grows by 1 px every 2
    // rows (2 px at the top, 9 px at the bottom), under an edge row (the
    // horizon) and with an OFF hole near its top. The median is 5 or 6
    // px; along the tilt the horizon's cells, which join the ground, and
    // the hole take the ground's value at their own row.
    let mut rows: Vec<String> = vec!["|".repeat(12)];
    for y in 1..16 {
        let d = char::from_digit(2 + (y as u32 - 1) / 2, 10).unwrap();
        rows.push(std::iter::repeat_n(d, 12).collect());
    }
    rows[3].replace_range(5..7, "..");
    let refs: Vec<&str> = rows.iter().map(String::as_str).collect();
    let (edges, disp, w, h) = parse(&refs);
    let colour = vec![Luv::default(); w * h];
    let px = |v: &[DisparityCell], x: usize, y: usize| {
        v[y * w + x].get().map(|d| (d.to_bits() + 128) >> 8)
    };
    // Trusted rows 2..=15 (row 1 is next to the edge); the tilt is fitted
    // to rows 4, 8 and 12 (every TILT_ROW_STEP-th): slope 1/2 px a row
    // through the median, 6 px, at their mean row 8, so row 0 is at 2 px
    // and row 3 at 3.5, rounded up to 4. With one median per region the
    // horizon and the hole take 6 px, and so does a region spanning fewer
    // rows than `tilt_rows`.
    let rows_apart = |tilt_rows| CompleteParams {
        tilt_rows,
        ..CompleteParams::default()
    };
    for (params, tilted, horizon, hole) in [
        (rows_apart(10), 1, 2, 4),
        (CompleteParams::MEDIAN, 0, 6, 6),
        (rows_apart(15), 0, 6, 6),
    ] {
        let (out, report) = by_runs(&params, &edges, &colour, &disp, w, h, run_table_len(w, h));
        assert_eq!(report.tilted, tilted);
        assert_eq!(px(&out, 4, 0), Some(horizon), "{:?}", show(&out, w));
        assert_eq!(px(&out, 5, 3), Some(hole), "{:?}", show(&out, w));
        let (rf_out, rf_report) = rf::complete(&params, &edges, &colour, &disp, w, h);
        assert_eq!((&out, report), (&rf_out, rf_report));
    }
}

/// A wall at 2 px with an object's halo, 9 px, in its lower left corner:
/// fitted to every trusted cell its tilt rises towards the halo and fills
/// the hole in row 13 at 3 px; fitted to the cells within 4 px of its
/// median (2 px) it stays flat.
#[test]
fn a_halo_does_not_tilt_a_wall() {
    let mut rows: Vec<String> = vec!["|".repeat(12)];
    for y in 1..16 {
        let mut r = "2".repeat(12);
        if y >= 11 {
            r.replace_range(0..4, "9999");
        }
        rows.push(r);
    }
    rows[13].replace_range(9..10, ".");
    let refs: Vec<&str> = rows.iter().map(String::as_str).collect();
    let (edges, disp, w, h) = parse(&refs);
    let colour = vec![Luv::default(); w * h];
    let band = |tilt_band| CompleteParams {
        tilt_rows: 10,
        tilt_band,
        ..CompleteParams::default()
    };
    for (params, hole) in [
        (band(u16::MAX), 3),
        (band(4 * 256), 2),
        (CompleteParams::MEDIAN, 2),
    ] {
        let (out, report) = by_runs(&params, &edges, &colour, &disp, w, h, run_table_len(w, h));
        let got = out[13 * w + 9].get().map(|d| (d.to_bits() + 128) >> 8);
        assert_eq!(got, Some(hole), "{params:?} {:?}", show(&out, w));
        assert_eq!(report.tilted, u16::from(params.tilt_rows > 0));
        let (rf_out, rf_report) = rf::complete(&params, &edges, &colour, &disp, w, h);
        assert_eq!((&out, report), (&rf_out, rf_report));
    }
}

#[test]
fn runs_past_the_run_table_are_counted_and_left_unchanged() {
    // Three strips of 7 between edge columns, 5 rows: 15 runs; an OFF hole
    // in row 2 of the third strip.
    let (a, b) = ("5555555|5555555|5555555", "5555555|5555555|555.555");
    let (edges, disp, w, h) = parse(&[a, a, b, a, a]);
    let hole = 2 * w + 19;
    let colour = vec![Luv::default(); w * h];
    let params = CompleteParams::default();
    let (all, report) = by_runs(&params, &edges, &colour, &disp, w, h, run_table_len(w, h));
    assert_eq!((report.regions, report.runs_unlabelled), (3, 0));
    assert!(all[hole].is_on(), "{:?}", show(&all, w));
    // With 4 entries only row 0 and the first run of row 1 are labelled:
    // the third strip's median comes from row 0, and the hole, in a run
    // past the table, keeps its value.
    let (few, report) = by_runs(&params, &edges, &colour, &disp, w, h, 4);
    assert_eq!((report.regions, report.runs_unlabelled), (3, 11));
    assert!(!few[hole].is_on(), "{:?}", show(&few, w));
    assert_eq!(report.regions_with_median, 3);
    // No table at all: nothing changes.
    let (none, report) = by_runs(&params, &edges, &colour, &disp, w, h, 0);
    assert_eq!((report.regions, report.runs_unlabelled), (0, 15));
    assert_eq!(none, disp);
}

#[test]
fn short_run_buffers_are_typed_errors() {
    let (edges, disp, w, h) = parse(&["55|55", "55|55"]);
    let colour = vec![Tone::default(); w * h];
    let mut out = disp.clone();
    let (mut open, mut trusted) = (vec![0u32; bit_map_len(w, h)], vec![0u32; 1]);
    let (mut table, mut rows) = (vec![0u16; 8], vec![0u32; run_rows_len(w)]);
    let mut labels = vec![0u16; LABEL_ROWS * w];
    let (mut total, mut below, mut lo, mut hi) =
        (vec![0u32; 4], vec![0u32; 4], vec![0u8; 4], vec![0u8; 4]);
    let err = complete_runs(
        &CompleteParams::default(),
        &ImageView::packed(&edges, w, h).unwrap(),
        &ImageView::packed(&colour, w, h).unwrap(),
        &mut ImageViewMut::packed(&mut out, w, h).unwrap(),
        &mut RunBuffers {
            open: &mut open,
            trusted: &mut trusted,
            runs: &mut table,
            rows: &mut rows,
            labels: &mut labels,
        },
        &mut RegionTables {
            total: &mut total,
            below: &mut below,
            lo: &mut lo,
            hi: &mut hi,
            tilt: &mut [],
        },
    )
    .unwrap_err();
    assert_eq!(
        err,
        CompleteError::Image(protogist::image::ImageError::BufferTooSmall { needed: 2, got: 1 })
    );
}

/// Parses rows of `0`-`9` (whole px), `.` (OFF) and `|` (an edge cell, OFF).
fn parse(rows: &[&str]) -> (Vec<EdgeCell>, Vec<DisparityCell>, usize, usize) {
    let (w, h) = (rows[0].len(), rows.len());
    let mut edges = Vec::new();
    let mut disp = Vec::new();
    for row in rows {
        for ch in row.chars() {
            edges.push(if ch == '|' { edge_on() } else { EdgeCell::OFF });
            disp.push(match ch.to_digit(10) {
                Some(d) => from_pixels(d as u8),
                None => DisparityCell::OFF,
            });
        }
    }
    (edges, disp, w, h)
}

fn show(d: &[DisparityCell], w: usize) -> Vec<String> {
    d.chunks(w)
        .map(|r| {
            r.iter()
                .map(|c| match c.get() {
                    Some(v) => char::from_digit(u32::from(v.to_bits() >> 8), 10).unwrap_or('*'),
                    None => '.',
                })
                .collect()
        })
        .collect()
}

#[test]
fn a_border_goes_to_the_side_it_looks_like_and_holes_take_the_region_median() {
    // Left region disparity 3 with a wrong spill value 7 next to the edge
    // and an OFF hole; right region 7 with an OFF occlusion strip; the edge
    // column is OFF. Colour: the edge cells look like the right side.
    let (edges, disp, w, h) = parse(&[
        "3333337|..77777",
        "33.3337|..77777",
        "3333337|..77777",
        "3333333|.777777",
    ]);
    let colour: Vec<Luv> = (0..w * h)
        .map(|i| {
            if i % w >= 7 {
                Luv::from_bits(6000, 0, 0)
            } else {
                Luv::from_bits(2000, 0, 0)
            }
        })
        .collect();
    let (out, report) =
        run_complete(&CompleteParams::default(), &edges, &colour, &disp, w, h).unwrap();
    assert_eq!(
        show(&out, w),
        [
            "333333377777777",
            "333333377777777",
            "333333377777777",
            "333333377777777",
        ],
        "{:#?}",
        show(&out, w)
    );
    assert_eq!(report.regions, 2);
    assert_eq!(report.regions_with_median, 2);
    // Replaced: the spill cells and the guard ring of ON cells; filled: the
    // hole, the occlusion strip and the edge column.
    assert_eq!(report.filled, 1 + 7 + 4);
}

#[test]
fn a_region_without_trusted_cells_is_left_alone() {
    // Everything OFF: nothing to take a median of.
    let (edges, disp, w, h) = parse(&["...|...", "...|..."]);
    let colour = vec![Luv::default(); w * h];
    let (out, report) =
        run_complete(&CompleteParams::default(), &edges, &colour, &disp, w, h).unwrap();
    assert_eq!(out, disp);
    assert_eq!(report.regions_with_median, 0);
    assert_eq!(report.filled + report.replaced, 0);
}

#[test]
fn bad_input_is_a_typed_error_or_a_reported_skip() {
    let (w, h) = (8, 4);
    let edges = vec![EdgeCell::OFF; w * h];
    let colour = vec![Luv::default(); w * h];
    let disp = vec![from_pixels(2); w * h];
    let run = |colour: &[Luv], cw: usize, ch: usize, regions: usize| {
        let tables = (run_table_len(w, h), regions);
        let params = CompleteParams::default();
        try_by_runs(&params, &edges, (colour, cw, ch), &disp, (w, h), tables).map(|r| r.1)
    };
    // Maps of different sizes.
    let small = vec![Luv::default(); 4];
    let err = run(&small, 2, 2, 4).unwrap_err();
    assert!(matches!(err, CompleteError::Image(_)), "{err:?}");
    // Region tables of capacity 1 (label 0 only): the one region is skipped.
    let report = run(&colour, w, h, 1).unwrap();
    assert_eq!((report.regions, report.regions_skipped), (1, 1));
    // With room for it, it is not.
    let report = run(&colour, w, h, 4).unwrap();
    assert_eq!((report.regions, report.regions_skipped), (1, 0));
}

/// The pipeline's run table holds the runs of non-edge cells of seeded
/// synthetic scenes at 160x120 three times over.
#[test]
fn the_default_run_table_holds_the_runs_of_synthetic_scenes() {
    use protogist::complete::DEFAULT_RUN_CAPACITY;
    use protogist::conspicuity::{EdgeParams, LuvTables};
    use protogist::image::Rgb8;
    use protogist::synth::{render_left, SceneSpec};
    let (w, h) = (160, 120);
    let mut most = 0;
    for seed in 0..64 {
        let spec = SceneSpec::random(seed, w, h);
        let mut rgb = vec![Rgb8::default(); w * h];
        render_left(&spec, &mut ImageViewMut::packed(&mut rgb, w, h).unwrap()).unwrap();
        let maps = protogist_host::stages::run_conspicuity(
            &LuvTables::new(),
            &EdgeParams::default(),
            &rgb,
            w,
            h,
        )
        .unwrap();
        let runs: usize = maps
            .edges
            .chunks(w)
            .map(|row| {
                (0..w)
                    .filter(|&x| row[x].is_off() && (x == 0 || row[x - 1].is_on()))
                    .count()
            })
            .sum();
        most = most.max(runs);
    }
    eprintln!("most runs of non-edge cells, 64 scenes at 160x120: {most}");
    assert!(most > h && 3 * most < DEFAULT_RUN_CAPACITY, "{most}");
}
