//! `protogist stereo --preset held-out`: the setting chosen on the held-out
//! Motorcycle pair (docs/STEREO.md, "Settings chosen on a held-out pair"),
//! pinned against the targets it meets. Skipped without the data unless
//! `PROTOGIST_REQUIRE_DATA` is set (as in CI).

use protogist_host::stereo_cmd::Preset;
use protogist_tests::{aloe_files, motorcycle_files, stereo_bad2, stereo_options, PairFiles};
use std::path::Path;

/// bad-2 % (over estimated pixels, over all GT pixels) of `protogist stereo
/// --refine 0 --preset held-out` at `width` and `max_disp`.
fn held_out(files: PairFiles, width: u32, max_disp: u8, out: &Path) -> (f64, f64) {
    let mut opts = stereo_options(files, width, max_disp, out);
    opts.readout.preset = Some(Preset::HeldOut);
    stereo_bad2(&opts)
}

/// Both targets on Aloe, which played no part in the choice: bad-2 over
/// all GT pixels no worse than OpenCV SGBM under the same protocol (33.5 %
/// at 160 px, D 32; 32.9 % at 320 px, D 64; block 3, docs/BENCHMARKS.md;
/// the issue quotes 33.6 and 33.5 %), and at most 10 % over estimated
/// pixels.
#[test]
fn held_out_setting_meets_both_targets_on_aloe() {
    let dir = tempfile::tempdir().unwrap();
    for (width, max_disp, sgbm) in [(160, 32, 33.5), (320, 64, 32.9)] {
        let Some(files) = aloe_files() else { return };
        let (est, all) = held_out(files, width, max_disp, dir.path());
        eprintln!("Aloe {width}/D{max_disp} held-out: bad-2 est {est:.1} %, all {all:.1} %");
        assert!(all <= sgbm, "{width}: {all} > SGBM {sgbm}");
        assert!(
            est <= 10.0,
            "{width}: bad-2 over estimated pixels {est} > 10"
        );
    }
}

/// On the pair it was chosen on, the criterion's first condition: bad-2
/// over all GT pixels no worse than SGBM there (25.3 % at 160 px, 26.7 %
/// at 320 px, block 3, `scripts/opencv_baseline.py --pair motorcycle`).
#[test]
fn held_out_setting_beats_sgbm_over_all_gt_pixels_on_motorcycle() {
    let dir = tempfile::tempdir().unwrap();
    for (width, max_disp, sgbm) in [(160, 32, 25.3), (320, 64, 26.7)] {
        let Some(files) = motorcycle_files() else {
            return;
        };
        let (est, all) = held_out(files, width, max_disp, dir.path());
        eprintln!("Motorcycle {width}/D{max_disp} held-out: bad-2 est {est:.1} %, all {all:.1} %");
        assert!(all <= sgbm, "{width}: {all} > SGBM {sgbm}");
    }
}
