//! The coarse-to-fine engine of core (`protogist::stereo::c2f`) against the
//! f32 reference `stereo_c2f` with the same settings (one level per c2f
//! level, no pooling, SGM, the same windows, band, paths, left-right check
//! and finest level): agreement on random-dot stereograms and on Aloe,
//! flat input, scratch, bad input.

use proptest::prelude::*;
use protogist::disparity::DisparityCell;
use protogist::image::{ImageView, Rgb8};
use protogist::stereo::c2f::{self, C2f, C2fParams, LeftRight};
use protogist::stereo::{self as qs, StereoError, StereoReport};
use protogist_host::reference::stereo::c2f::{level_params, stereo_c2f_from};
use protogist_host::reference::stereo::table::DemTable as HostTable;
use protogist_host::reference::stereo::{self as dem};
use protogist_host::storage::C2fStorage;
use protogist_tests::{aloe_160_rgb, rds_rgb, stereo_agreement};
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

/// The reference's parameters for `p` (what `protogist stereo --engine
/// reference` runs).
fn host_params(p: &C2fParams) -> dem::DemParams {
    protogist_host::dem_tables::params_of(p)
}

/// The decoder tables of every level of `p` (trained once per layout).
fn tables(p: &C2fParams) -> Vec<Vec<u8>> {
    static CACHE: OnceLock<Mutex<HashMap<u8, Vec<u8>>>> = OnceLock::new();
    let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
    let hp = host_params(p);
    (0..=usize::from(p.coarse))
        .map(|k| {
            let lp = level_params(&hp, k);
            let mut c = cache.lock().unwrap();
            c.entry(lp.max_disp)
                .or_insert_with(|| HostTable::from_decoder(&dem::train(&lp)).to_bytes())
                .clone()
        })
        .collect()
}

/// Runs core on an RGB pair.
fn run_core(
    p: &C2fParams,
    tables: &[Vec<u8>],
    l: &[Rgb8],
    r: &[Rgb8],
    w: usize,
    h: usize,
) -> Result<(Vec<DisparityCell>, StereoReport), StereoError> {
    let e = C2f::new(p)?;
    let ts: Vec<qs::DemTable<'_>> = tables
        .iter()
        .map(|t| qs::DemTable::parse(t))
        .collect::<Result<_, _>>()?;
    let mut st = C2fStorage::new(w, h, p);
    let mut out = vec![DisparityCell::OFF; w * h];
    let rep = e.run(
        &ts,
        &ImageView::packed(l, w, h).unwrap(),
        &ImageView::packed(r, w, h).unwrap(),
        &mut st.buffers(),
        &mut |x, y, c| out[y * w + x] = c,
        &mut (),
    )?;
    Ok((out, rep))
}

/// Runs the reference with the same tables.
fn run_float(
    p: &C2fParams,
    tables: &[Vec<u8>],
    l: &[Rgb8],
    r: &[Rgb8],
    w: usize,
    h: usize,
) -> dem::DisparityMapsF {
    let decs: Vec<dem::Decoder> = tables
        .iter()
        .map(|t| HostTable::parse(t).unwrap().to_decoder())
        .collect();
    stereo_c2f_from(
        &host_params(p),
        &decs,
        &ImageView::packed(l, w, h).unwrap(),
        &ImageView::packed(r, w, h).unwrap(),
        usize::from(p.radius),
        p.band.map(usize::from),
        usize::from(p.finest),
    )
    .unwrap()
}

fn params(max_disp: u8) -> C2fParams {
    C2fParams {
        dem: qs::DemParams {
            max_disp,
            ..C2fParams::FULL.dem
        },
        ..C2fParams::FULL
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(8))]

    /// Random-dot pairs of uniform disparity: core agrees with the
    /// reference (99 % within 0.25 px, 99 % of OFF decisions), and finds
    /// the disparity.
    #[test]
    fn random_dot_pairs_agree(
        seed: u64,
        d in 0usize..=15,
        band in prop::option::of(1u8..=3),
        left_right in prop_oneof![
            Just(LeftRight::Off),
            Just(LeftRight::Read),
            Just(LeftRight::Derived)
        ],
        paths in prop_oneof![Just(3u8), Just(5u8)],
        finest in 0u8..=1,
    ) {
        let (w, h) = (96, 64);
        let p = C2fParams { band, left_right, paths, finest, ..params(15) };
        let ts = tables(&p);
        let (l, r) = rds_rgb(w, h, d, seed);
        let (core, rep) = run_core(&p, &ts, &l, &r, w, h).unwrap();
        let float = run_float(&p, &ts, &l, &r, w, h);
        let (close, agree, both) = stereo_agreement(&core, &float);
        prop_assert!(both > w * h / 2, "only {both} pixels ON in both");
        prop_assert!(close >= 99.0, "{close:.2} % within 0.25 px");
        prop_assert!(agree >= 99.0, "{agree:.2} % OFF agreement");
        prop_assert_eq!(rep.on, core.iter().filter(|c| c.get().is_some()).count());
        // Interior pixels right of the search range: core misses d by more
        // than 1 px on at most 1 % more of them than the reference, plus
        // one coarse pixel's footprint: a near tie at the coarsest level
        // (within the error bound, docs/ERROR_BOUNDS.md 7.5) may flip one
        // coarse decision, which moves the windows of its 4^K level-0
        // pixels (seed 8876650933446886780, d 5, band 3: one 4x4 block
        // OFF by the left-right check, kept in the regressions file; in 150
        // other random cases core's count never exceeded the reference's).
        let (bc, bf, n) = bad1(&core, &float, w, h, d);
        let footprint = 1 << (2 * p.coarse);
        prop_assert!(
            bc <= bf + n / 100 + footprint,
            "bad-1 core {bc}, reference {bf}, of {n}"
        );
    }
}

/// Pixels (core, reference, all) of the interior right of the search range
/// (x ≥ 31, 16 px from the other borders) off `d` by more than 1 px.
fn bad1(
    core: &[DisparityCell],
    float: &dem::DisparityMapsF,
    w: usize,
    h: usize,
    d: usize,
) -> (usize, usize, usize) {
    let (mut bc, mut bf, mut n) = (0, 0, 0);
    for y in 16..h - 16 {
        for x in 31..w - 16 {
            n += 1;
            let off = |v: f32| (v - d as f32).abs() > 1.0;
            bc += usize::from(core[y * w + x].get().is_none_or(|v| off(v.to_num())));
            bf += usize::from(float.disparity_f32[y * w + x].is_none_or(off));
        }
    }
    (bc, bf, n)
}

/// The random-dot anchor through the engine: over d = 0..=15, bad-1 of the
/// interior is below 5 % (the spec's bound), with and without a band.
#[test]
fn random_dots_bad1_below_5_percent() {
    let (w, h) = (96, 64);
    for band in [None, Some(2)] {
        let p = C2fParams { band, ..params(15) };
        let ts = tables(&p);
        let (mut bad, mut all) = (0, 0);
        for d in 0..=15usize {
            let (l, r) = rds_rgb(w, h, d, 0xc2f0 + d as u64);
            let (core, _) = run_core(&p, &ts, &l, &r, w, h).unwrap();
            let float = run_float(&p, &ts, &l, &r, w, h);
            let (bc, _, n) = bad1(&core, &float, w, h, d);
            bad += bc;
            all += n;
        }
        let pct = 100.0 * bad as f64 / all as f64;
        println!("RDS bad-1 core c2f, band {band:?}: {pct:.2} %");
        assert!(pct < 5.0, "band {band:?}: {pct}");
    }
}

/// Aloe at 160 px with 32 disparities (needs `cargo xtask fetch-data`):
/// the bounds, 99 % within 0.25 px and 99 % OFF agreement.
/// With the right map read out and with it derived from the left sums.
#[test]
fn aloe_160_d32_agrees() {
    let Some((l, r, w, h)) = aloe_160_rgb() else {
        return;
    };
    use LeftRight::{Derived, Off, Read};
    for (left_right, paths, finest) in [
        (Read, 5, 0),
        (Off, 5, 0),
        (Derived, 5, 0),
        (Derived, 3, 0),
        (Derived, 3, 1),
    ] {
        let p = C2fParams {
            left_right,
            paths,
            finest,
            band: if finest > 0 { Some(1) } else { Some(2) },
            ..params(31)
        };
        let ts = tables(&p);
        let (core, rep) = run_core(&p, &ts, &l, &r, w, h).unwrap();
        let float = run_float(&p, &ts, &l, &r, w, h);
        let (close, agree, both) = stereo_agreement(&core, &float);
        println!("aloe 160 c2f (left-right {left_right:?}, {paths} paths, finest {finest}): {close:.2} % within 0.25 px, {agree:.2} % OFF agreement, {both} ON in both, {rep:?}");
        assert!(both > w * h / 2, "{both}");
        assert!(close >= 99.0, "{close}");
        assert!(agree >= 99.0, "{agree}");
    }
}

/// The right map derived from the left sums, and no left-right check at
/// all: the right eye's cells are not evaluated (exactly the left eye's
/// half of the count), and the map differs from the read-out one's only
/// through the left-right check: every pixel ON in both has the same
/// disparity; without the check no pixel is inconsistent and every pixel
/// ON with it is ON without it.
#[test]
fn the_derived_right_map_skips_the_right_eye() {
    let (w, h) = (96, 64);
    let (l, r) = rds_rgb(w, h, 6, 11);
    let read = C2fParams {
        band: None,
        ..params(15)
    };
    let derived = C2fParams {
        left_right: LeftRight::Derived,
        ..read
    };
    let off = C2fParams {
        left_right: LeftRight::Off,
        ..read
    };
    let ts = tables(&read);
    let (a, rep_a) = run_core(&read, &ts, &l, &r, w, h).unwrap();
    let (b, rep_b) = run_core(&derived, &ts, &l, &r, w, h).unwrap();
    // Without a band left x and right w − 1 − x see the same shifts.
    assert_eq!(2 * rep_b.cells, rep_a.cells);
    let mut both = 0;
    for (x, y) in a.iter().zip(&b) {
        if let (Some(x), Some(y)) = (x.get(), y.get()) {
            assert_eq!(x, y);
            both += 1;
        }
    }
    assert!(both > w * h / 2, "{both}");
    assert_eq!(rep_a.off_texture, rep_b.off_texture);
    assert_eq!(rep_a.off_ambiguous, rep_b.off_ambiguous);
    let (c, rep_c) = run_core(&off, &ts, &l, &r, w, h).unwrap();
    assert_eq!(rep_c.cells, rep_b.cells);
    assert_eq!(rep_c.off_inconsistent, 0);
    assert!(rep_a.off_inconsistent > 0, "{rep_a:?}");
    assert_eq!(rep_c.on, rep_a.on + rep_a.off_inconsistent);
    for (x, y) in a.iter().zip(&c) {
        if x.is_on() {
            assert_eq!(x, y);
        }
    }
}

/// The 2x2 rounded means of an RGB frame (the engine's level step).
fn halve(img: &[Rgb8], w: usize, h: usize) -> Vec<Rgb8> {
    let (wh, hh) = (w / 2, h / 2);
    let mut out = Vec::with_capacity(wh * hh);
    for y in 0..hh {
        for x in 0..wh {
            let px =
                [(0, 0), (1, 0), (0, 1), (1, 1)].map(|(dx, dy)| img[(2 * y + dy) * w + 2 * x + dx]);
            let mean = |c: fn(&Rgb8) -> u8| {
                ((px.iter().map(|p| u16::from(c(p))).sum::<u16>() + 2) / 4) as u8
            };
            out.push(Rgb8::new(mean(|p| p.r), mean(|p| p.g), mean(|p| p.b)));
        }
    }
    out
}

/// `finest: 1` is the engine on the half-size pair (one coarse level less,
/// `⌈D/2⌉`), each cell spread over its 2x2 block (the last block column
/// and row also over an odd frame's leftover column and row) with its
/// disparity doubled; the counts are per frame pixel.
#[test]
fn the_finest_level_is_the_half_size_run_spread() {
    for (w, h) in [(96, 64), (97, 65)] {
        let (l, r) = rds_rgb(w, h, 6, 5);
        let full = C2fParams {
            finest: 1,
            left_right: LeftRight::Derived,
            ..params(15)
        };
        let half = C2fParams {
            coarse: full.coarse - 1,
            finest: 0,
            ..C2fParams {
                dem: qs::DemParams {
                    max_disp: full.level_max_disp(1),
                    ..full.dem
                },
                ..full
            }
        };
        let ts = tables(&full);
        let (a, rep) = run_core(&full, &ts, &l, &r, w, h).unwrap();
        let (wh, hh) = (w / 2, h / 2);
        let (lh, rh) = (halve(&l, w, h), halve(&r, w, h));
        let (b, _) = run_core(&half, &ts[1..], &lh, &rh, wh, hh).unwrap();
        for y in 0..h {
            for x in 0..w {
                let q = (y / 2).min(hh - 1) * wh + (x / 2).min(wh - 1);
                let want = b[q].get().map(|d| d.to_bits() * 2);
                assert_eq!(
                    a[y * w + x].get().map(|d| d.to_bits()),
                    want,
                    "({x}, {y}) at {w}x{h}"
                );
            }
        }
        let on = a.iter().filter(|c| c.get().is_some()).count();
        assert_eq!(rep.on, on);
        assert_eq!(
            rep.on + rep.off_texture + rep.off_ambiguous + rep.off_inconsistent,
            w * h
        );
        assert!(on > w * h / 2, "{on}");
    }
}

/// Flat images have no texture: every pixel OFF, no panic.
#[test]
fn flat_images_give_an_all_off_map() {
    let (w, h) = (80, 64);
    let p = params(15);
    let ts = tables(&p);
    let img = vec![Rgb8::new(90, 120, 30); w * h];
    let (out, rep) = run_core(&p, &ts, &img, &img, w, h).unwrap();
    assert!(out.iter().all(|c| c.get().is_none()));
    assert_eq!(rep.off_texture, w * h);
}

/// The engine's count of cells: without a band every pixel of every level
/// evaluates the cells of every shift `s = 2·ks` inside the row (`s <= x`
/// left-referenced, `x + s < w` right-referenced), for each carrier; with
/// a band, fewer.
#[test]
fn the_cell_count_is_every_shift_inside_the_row() {
    let (w, h) = (96, 64);
    let (l, r) = rds_rgb(w, h, 4, 7);
    let all = C2fParams {
        band: None,
        ..params(15)
    };
    let ts = tables(&all);
    let (_, rep) = run_core(&all, &ts, &l, &r, w, h).unwrap();
    let carriers = usize::from(all.dem.carriers);
    let step = usize::from(all.dem.shift_step);
    let expected: usize = (0..=usize::from(all.coarse))
        .map(|k| {
            let (wk, hk) = (w >> k, h >> k);
            let shifts = (usize::from(all.level_max_disp(k)) + 1).div_ceil(step);
            // Left x and right w − 1 − x see the same shifts.
            let row: usize = (0..wk).map(|x| shifts.min(x / step + 1)).sum();
            2 * carriers * hk * row
        })
        .sum();
    assert_eq!(rep.cells, expected);
    let banded = C2fParams {
        band: Some(2),
        ..all
    };
    let (_, rep_b) = run_core(&banded, &ts, &l, &r, w, h).unwrap();
    assert!(
        rep_b.cells > 0 && rep_b.cells < expected / 2,
        "{}",
        rep_b.cells
    );
}

/// The scratch at 160x120 with 32 disparities, by the `const fn`: within
/// the 96 KB.
#[test]
fn scratch_at_160x120() {
    let b = c2f::scratch_bytes(160, 120, &C2fParams::FULL);
    println!("c2f scratch 160x120 D32: {b} bytes");
    assert!(b <= 96 * 1024, "{b}");
    // The point `fast`: the half-size map refined by phase, whose buffers
    // come on top of the engine's.
    let phase = protogist::stereo::phase::PhaseParams::DEFAULT;
    let p3 = C2fParams::FAST;
    assert_eq!(p3.phase, Some(phase));
    let bp = c2f::scratch_bytes(160, 120, &p3);
    let own = protogist::stereo::phase::scratch_bytes(160, &phase, p3.dem.max_disp);
    println!("c2f scratch 160x120 D32 with phase: {bp} bytes ({own} the refinement's)");
    assert!(bp <= 96 * 1024, "{bp}");
    assert!(own > 0 && bp >= own, "{bp} {own}");
    // The buffers the const fns size are the ones the run needs: one
    // element less in any of them is a typed error.
    let p = params(15);
    let ts = tables(&p);
    let (w, h) = (96, 64);
    let (l, r) = rds_rgb(w, h, 4, 7);
    let parsed: Vec<qs::DemTable<'_>> =
        ts.iter().map(|t| qs::DemTable::parse(t).unwrap()).collect();
    let e = C2f::new(&p).unwrap();
    let lv = ImageView::packed(&l, w, h).unwrap();
    let rv = ImageView::packed(&r, w, h).unwrap();
    for which in 0..9 {
        let mut st = C2fStorage::new(w, h, &p);
        match which {
            0 => st.grey.pop().map(drop),
            1 => st.rgb.pop().map(drop),
            2 => st.z.pop().map(drop),
            3 => st.col.pop().map(drop),
            4 => st.scores.pop().map(drop),
            5 => st.costs.pop().map(drop),
            6 => st.sums.pop().map(drop),
            7 => st.picks.pop().map(drop),
            _ => st.maps.pop().map(drop),
        };
        let mut cells = 0;
        let got = e.run(
            &parsed,
            &lv,
            &rv,
            &mut st.buffers(),
            &mut |_, _, _| cells += 1,
            &mut (),
        );
        assert!(
            matches!(got, Err(StereoError::Buffer { .. })),
            "{which}: {got:?}"
        );
        assert_eq!(cells, 0, "{which}");
    }
}

/// Bad input is a typed error before any cell is produced.
#[test]
fn bad_input_is_a_typed_error() {
    let p = params(15);
    let ts = tables(&p);
    let parsed: Vec<qs::DemTable<'_>> =
        ts.iter().map(|t| qs::DemTable::parse(t).unwrap()).collect();
    let e = C2f::new(&p).unwrap();
    let (w, h) = (64, 48);
    let (l, r) = rds_rgb(w, h, 4, 7);
    let lv = ImageView::packed(&l, w, h).unwrap();
    let rv = ImageView::packed(&r, w, h).unwrap();
    let mut st = C2fStorage::new(w, h, &p);
    let mut run =
        |tables: &[qs::DemTable<'_>], a: &ImageView<'_, Rgb8>, b: &ImageView<'_, Rgb8>| {
            let mut cells = 0;
            let got = e.run(
                tables,
                a,
                b,
                &mut st.buffers(),
                &mut |_, _, _| cells += 1,
                &mut (),
            );
            (got, cells)
        };
    // Tables: too few, in the wrong order.
    let (got, cells) = run(&parsed[..2], &lv, &rv);
    assert!(matches!(got, Err(StereoError::BadParams(_))), "{got:?}");
    assert_eq!(cells, 0);
    let swapped = [parsed[1], parsed[0], parsed[2]];
    let (got, _) = run(&swapped, &lv, &rv);
    assert!(
        matches!(got, Err(StereoError::DecoderMismatch { .. })),
        "{got:?}"
    );
    // Sizes: different, and a coarse level below the filter support.
    let small = ImageView::packed(&l[..w * 40], w, 40).unwrap();
    let (got, _) = run(&parsed, &lv, &small);
    assert!(
        matches!(got, Err(StereoError::SizeMismatch { .. })),
        "{got:?}"
    );
    let (got, _) = run(&parsed, &small, &small);
    assert!(
        matches!(
            got,
            Err(StereoError::TooSmall {
                min: 15,
                got: (16, 10)
            })
        ),
        "{got:?}"
    );
    // Parameters the engine does not run.
    for bad in [
        C2fParams {
            dem: qs::DemParams { levels: 2, ..p.dem },
            ..p
        },
        C2fParams {
            dem: qs::DemParams {
                pool_radius: 1,
                ..p.dem
            },
            ..p
        },
        C2fParams { coarse: 0, ..p },
        C2fParams { coarse: 4, ..p },
        C2fParams {
            p1: 2.0,
            p2: 1.0,
            ..p
        },
        C2fParams { p2: f32::NAN, ..p },
        C2fParams { paths: 4, ..p },
        C2fParams { paths: 8, ..p },
        C2fParams { finest: 3, ..p },
    ] {
        assert!(
            matches!(C2f::new(&bad), Err(StereoError::BadParams(_))),
            "{bad:?}"
        );
    }
}

/// The firmware's decoder tables are what `protogist train-dem --levels 1
/// --max-disp 31 | 16 | 8` writes: the training reproduced bit for bit.
#[test]
fn firmware_tables_are_reproduced_by_training() {
    let shipped: [&[u8]; 3] = [
        include_bytes!("../../firmware-sim/data/dem_c2f_l0.bin"),
        include_bytes!("../../firmware-sim/data/dem_c2f_l1.bin"),
        include_bytes!("../../firmware-sim/data/dem_c2f_l2.bin"),
    ];
    let trained = tables(&C2fParams::FULL);
    assert_eq!(trained.len(), 3);
    for (k, (t, s)) in trained.iter().zip(shipped).enumerate() {
        assert!(
            t.as_slice() == s,
            "level {k}: the shipped table differs from training"
        );
    }
}

/// A phase kernel that marks every cell it is given (the refined count is
/// the row's length), to show that `C2f::<K>::with_kernel` hands the phase
/// step to the kernel it names and `C2f::new` to the portable one.
struct Marking;

const MARK: u16 = 7;

impl protogist::stereo::phase::PhaseKernel for Marking {
    fn phase_row3(
        _max_disp: u8,
        _lambda_q8: i32,
        _zl: &[[i16; 2]],
        _zr: &[[i16; 2]],
        cells: &mut [DisparityCell],
    ) -> usize {
        cells.fill(DisparityCell::from_raw(protogist::fixed::U8F8::from_bits(
            MARK,
        )));
        cells.len()
    }
}

#[test]
fn the_engine_runs_the_phase_step_of_the_kernel_it_is_given() {
    let p = C2fParams {
        finest: 1,
        phase: Some(protogist::stereo::phase::PhaseParams::DEFAULT),
        ..params(15)
    };
    let ts = tables(&p);
    let parsed: Vec<qs::DemTable<'_>> =
        ts.iter().map(|t| qs::DemTable::parse(t).unwrap()).collect();
    let (w, h) = (96, 64);
    let (l, r) = rds_rgb(w, h, 4, 7);
    let (lv, rv) = (
        ImageView::packed(&l, w, h).unwrap(),
        ImageView::packed(&r, w, h).unwrap(),
    );
    fn marked<K: protogist::stereo::phase::PhaseKernel>(
        e: &C2f<K>,
        parsed: &[qs::DemTable<'_>],
        (lv, rv): (&ImageView<'_, Rgb8>, &ImageView<'_, Rgb8>),
        p: &C2fParams,
    ) -> usize {
        let (w, h) = lv.size();
        let mut st = C2fStorage::new(w, h, p);
        let mut marked = 0;
        let mut sink = |_: usize, _: usize, c: DisparityCell| {
            marked += usize::from(c.raw().to_bits() == MARK);
        };
        e.run(parsed, lv, rv, &mut st.buffers(), &mut sink, &mut ())
            .unwrap();
        marked
    }
    let marking = C2f::<Marking>::with_kernel(&p).unwrap();
    let portable = C2f::new(&p).unwrap();
    let run = |marking_kernel: bool| {
        if marking_kernel {
            marked(&marking, &parsed, (&lv, &rv), &p)
        } else {
            marked(&portable, &parsed, (&lv, &rv), &p)
        }
    };
    assert_eq!(run(true), w * h);
    assert!(run(false) < w * h / 10, "{}", run(false));
}
