//! The panic probe's desktop run (`src/bin/panic-probe.rs`): every core
//! stage it links for the thumbv7em no-panic check also runs here, on the
//! demo scene, and succeeds. So the probe calls each stage with buffers it
//! accepts, not only with ones it rejects at once.

use std::process::Command;

#[test]
fn the_probe_runs_every_stage_to_success_on_the_demo_scene() {
    let out = Command::new(env!("CARGO_BIN_EXE_panic-probe"))
        .output()
        .expect("the probe binary runs");
    assert!(out.status.success(), "{out:?}");
    let text = String::from_utf8_lossy(&out.stdout);
    let bits = text
        .trim()
        .rsplit_once("stages ok 0b")
        .and_then(|(_, b)| u32::from_str_radix(b, 2).ok())
        .unwrap_or_else(|| panic!("no stage bits in {text:?}"));
    // Edge conspicuity, table, the stereo engine, completion, segmentation,
    // shape, model, top-k, identify, verify (bit 2 was the full-search
    // engine's, removed).
    assert_eq!(bits, ((1 << 12) - 1) & !(1 << 2), "{text}");
    assert!(text.contains("scene Ok(())"), "{text}");
}
