//! `protogist stereo --engine core` (core's fixed-point coarse-to-fine
//! engine) against `--engine reference` (the f32 `stereo_c2f`) at the same
//! named point, through the command: the same metrics on Aloe, and a typed
//! error for an unknown point.
//!
//! **Why the two engines' bad-2 agree within 0.5 point.** A GT pixel counts
//! differently in bad-2 (over all GT pixels) only if its status flips: its
//! OFF decision differs between the engines, or both are ON and their
//! estimates lie on either side of GT ± 2 px (which needs them more than
//! 0.25 px apart, or within 0.25 px of that boundary). So
//! `|Δ bad-2 (all)| ≤ 100 · flips / N_gt`. The agreement test
//! (`stereo_c2f_core::aloe_160_d32_agrees`, same engine and tables) requires
//! at least 99 % of the pixels ON in both within 0.25 px and 99 % of the
//! OFF decisions to agree, which alone allows about 2 points; on Aloe 160
//! px D32 at the point `full` it measures 99.79 % within 0.25 px
//! and 99.29 % OFF agreement, and 77 of the 21,532 GT pixels flip (0.36
//! point; the difference itself is 0.19 point, flips going both ways:
//! measured 2026-11-21 on the 2-core build machine with both maps,
//! `engine::run` against `stereo_c2f`; at 320 px D64, 0.17 point flip). The disagreements are near ties of
//! the SGM path sums (the costs' `Q8` rounding), and the OFF ones sit on
//! the left-right check's tolerance; neither depends on the GT, so flips
//! split between the two directions. 0.5 point (the lead's criterion) is
//! then above the measured flips, and a mapping error (a penalty, the
//! margin, the left-right tolerance, the window or the band given to one
//! engine and not the other) moves far more pixels than the near ties: it
//! fails this test: checked by hand, P2 given P1's value moved bad-2 (est)
//! by 1.4 points, a left-right tolerance of 2 given to one engine only by
//! 1.3 points. bad-2 over estimated pixels changes in the
//! same way, over the estimated pixels (density 80 %), so the same bound
//! holds with those flips; it is checked at 0.5 point too.
//!
//! **Density.** It differs only by the GT pixels whose OFF decision
//! differs: at most 1 % of all pixels by the 99 % OFF agreement, so at
//! most `1 · N / N_gt` points, derived here from the run's own counts.

use protogist_host::error::HostError;
use protogist_host::stereo_cmd::{run_stereo, Engine, Lr, StereoOptions};
use protogist_tests::{aloe_files, stereo_options};
use std::path::Path;

/// The final metrics and `engine` of the command's JSON.
fn run_json(opts: &StereoOptions) -> serde_json::Value {
    let s = run_stereo(opts).unwrap();
    serde_json::from_str(s.raw.as_deref().unwrap()).unwrap()
}

#[test]
fn core_and_reference_agree_on_aloe_160() {
    let dir = tempfile::tempdir().unwrap();
    for (point, lr) in [
        ("full", None),
        ("fast", None),
        ("half", None),
        ("full", Some(Lr::Off)),
    ] {
        let Some(files) = aloe_files() else { return };
        let base = StereoOptions {
            point: point.into(),
            lr,
            ..stereo_options(files, 160, 32, dir.path())
        };
        let core = run_json(&StereoOptions {
            engine: Engine::Core,
            ..base.clone()
        });
        let reference = run_json(&StereoOptions {
            engine: Engine::Reference,
            ..base
        });
        let name = format!("{point} {lr:?}");
        assert_eq!(core["engine"], "core");
        assert_eq!(reference["engine"], "reference");
        let (c, r) = (&core["final"], &reference["final"]);
        let f = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap();
        eprintln!(
            "Aloe 160/D32 {name}: bad-2 est core {:.2} ref {:.2}, all core {:.2} ref {:.2}, \
             density core {:.2} ref {:.2}, ms core {:.1} ref {:.1}",
            f(c, "bad2_estimated"),
            f(r, "bad2_estimated"),
            f(c, "bad2_all"),
            f(r, "bad2_all"),
            f(c, "density"),
            f(r, "density"),
            f(&core, "stereo_ms"),
            f(&reference, "stereo_ms"),
        );
        for k in ["bad2_estimated", "bad2_all"] {
            let d = (f(c, k) - f(r, k)).abs();
            assert!(
                d <= 0.5,
                "{name} {k}: core {} reference {}",
                f(c, k),
                f(r, k)
            );
        }
        let pixels = f(&core, "width") * f(&core, "height");
        let bound = pixels / f(c, "gt_pixels");
        let d = (f(c, "density") - f(r, "density")).abs();
        assert!(d <= bound, "{name} density: {d} > {bound}");
    }
}

/// A random-dot pair shifted by 4 px, as PNGs in `dir` (96x64: the
/// coarsest of 2 coarse levels holds the filters).
fn rds_files(dir: &Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let (w, h, d) = (96u32, 64u32, 4u32);
    let dot = |x: u32, y: u32| {
        let mut s = u64::from(y * 1000 + x).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        s ^= s >> 29;
        if s & 1 == 0 {
            40u8
        } else {
            220
        }
    };
    let l = image::RgbImage::from_fn(w, h, |x, y| image::Rgb([dot(x, y); 3]));
    let r = image::RgbImage::from_fn(w, h, |x, y| image::Rgb([dot(x + d, y); 3]));
    let (lp, rp) = (dir.join("l.png"), dir.join("r.png"));
    l.save(&lp).unwrap();
    r.save(&rp).unwrap();
    (lp, rp)
}

#[test]
fn every_point_runs_and_an_unknown_point_is_a_typed_error() {
    let dir = tempfile::tempdir().unwrap();
    let (l, r) = rds_files(dir.path());
    let mut base = stereo_options((l, r, dir.path().join("none")), 96, 15, dir.path());
    base.gt = None;
    // Every named point finds the shift on most pixels, both engines.
    for (point, _) in protogist::stereo::c2f::C2fParams::NAMED {
        for engine in [Engine::Core, Engine::Reference] {
            let v = run_json(&StereoOptions {
                point: point.into(),
                engine,
                ..base.clone()
            });
            assert_eq!(v["engine"], engine.name());
            assert!(v["on_fraction"].as_f64().unwrap() > 0.5, "{point}: {v}");
        }
    }
    let bad = StereoOptions {
        point: "r2b1l3p".into(),
        ..base
    };
    match run_stereo(&bad) {
        Err(HostError::InvalidArgument { name, .. }) => assert_eq!(name, "point"),
        other => panic!("{other:?}"),
    }
}
