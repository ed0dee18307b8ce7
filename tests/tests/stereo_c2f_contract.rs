//! The coarse-to-fine engine of core (`protogist::stereo::c2f`) on its own:
//! flat input, the cell count, scratch sizes, bad input, the shipped decoder
//! tables and the phase kernel it is given. Agreement with the f32
//! reference is `stereo_c2f_core.rs`.

use protogist::disparity::DisparityCell;
use protogist::image::{ImageView, Rgb8};
use protogist::stereo::c2f::{self, C2f, C2fParams};
use protogist::stereo::{self as qs, StereoError};
use protogist_host::storage::C2fStorage;
use protogist_tests::c2f::{params, run_core, tables};
use protogist_tests::rds_rgb;

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

/// The product's tables (`half-narrow`, kernels of radius 2) are what
/// `protogist train-dem --levels 1 --max-disp 31 | 16 | 8 --radius 2`
/// writes, and differ from the design's.
#[test]
fn narrow_tables_are_reproduced_by_training() {
    let shipped: [&[u8]; 3] = [
        include_bytes!("../../firmware-sim/data/dem_c2f_narrow_l0.bin"),
        include_bytes!("../../firmware-sim/data/dem_c2f_narrow_l1.bin"),
        include_bytes!("../../firmware-sim/data/dem_c2f_narrow_l2.bin"),
    ];
    let design: [&[u8]; 3] = [
        include_bytes!("../../firmware-sim/data/dem_c2f_l0.bin"),
        include_bytes!("../../firmware-sim/data/dem_c2f_l1.bin"),
        include_bytes!("../../firmware-sim/data/dem_c2f_l2.bin"),
    ];
    let trained = tables(&C2fParams::HALF_NARROW);
    assert_eq!(trained.len(), 3);
    for (k, ((t, s), d)) in trained.iter().zip(shipped).zip(design).enumerate() {
        assert!(
            t.as_slice() == s,
            "level {k}: the shipped narrow table differs from training"
        );
        assert!(s != d, "level {k}: the narrow table is the design's");
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
