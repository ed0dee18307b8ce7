//! `protogist stereo --speckle N`: the speckle filter on the final map of
//! either engine (docs/STEREO.md, "Third round: the speckle filter").
//! Skipped without the Aloe data unless `PROTOGIST_REQUIRE_DATA` is set.

use protogist_host::stereo_cmd::{run_stereo, Engine, StereoOptions};
use protogist_tests::{aloe_files, stereo_options};

/// The JSON of `protogist stereo` with `opts`.
fn json(opts: &StereoOptions) -> serde_json::Value {
    let s = run_stereo(opts).unwrap();
    serde_json::from_str(s.raw.as_deref().unwrap()).unwrap()
}

/// Through core's engine at 160 px: the filter turns OFF exactly the
/// fraction it reports, and nothing else (the ON fraction falls by it);
/// what it removes was mostly wrong, so bad-2 over estimated pixels falls.
/// Without `--speckle` the JSON reports no filter.
#[test]
fn the_filter_removes_what_it_reports_and_lowers_the_error_over_estimates() {
    let Some(files) = aloe_files() else { return };
    let dir = tempfile::tempdir().unwrap();
    let mut opts = stereo_options(files, 160, 32, dir.path());
    opts.readout.engine = Engine::Core;
    opts.readout.c2f = Some(2);
    opts.readout.c2f_band = Some(2);
    let plain = json(&opts);
    assert!(plain.get("speckle").is_none());
    opts.readout.speckle = Some(100);
    let filtered = json(&opts);
    let off = filtered["speckle"]["off_fraction"].as_f64().unwrap();
    let on = |v: &serde_json::Value| v["on_fraction"].as_f64().unwrap();
    assert!(off > 0.001, "removed {off}");
    assert!((on(&plain) - on(&filtered) - off).abs() < 1e-9);
    let est = |v: &serde_json::Value| v["final"]["bad2_estimated"].as_f64().unwrap();
    assert!(
        est(&filtered) < est(&plain),
        "{} vs {}",
        est(&filtered),
        est(&plain)
    );
}

/// A range without the filter, or a negative range, is a typed error
/// before any work.
#[test]
fn bad_speckle_options_are_typed_errors() {
    use protogist_host::error::HostError;
    let Some(files) = aloe_files() else { return };
    let dir = tempfile::tempdir().unwrap();
    let mut opts = stereo_options(files, 160, 32, dir.path());
    for (n, r) in [
        (None, Some(1.0)),
        (Some(10), Some(-1.0)),
        (Some(10), Some(f32::NAN)),
    ] {
        opts.readout.speckle = n;
        opts.readout.speckle_range = r;
        let e = run_stereo(&opts).unwrap_err();
        assert!(
            matches!(
                e,
                HostError::InvalidArgument {
                    name: "speckle-range",
                    ..
                }
            ),
            "{e}"
        );
    }
}
