//! End-to-end tests of the `protogist` binary: the demo, the conspicuity
//! command, and bad input (non-zero exit, one `error:` line, no panic, no
//! panels left behind).

use image::{Rgb, RgbImage};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::{assert_one_line_error, protogist, text};

const DEMO_PANELS: [&str; 10] = [
    "left",
    "right",
    "gt_disparity",
    "gt_mask",
    "lightness",
    "smoothed",
    "conspicuity",
    "edges",
    "objects",
    "overview",
];
const IMAGE_PANELS: [&str; 6] = [
    "input",
    "lightness",
    "smoothed",
    "conspicuity",
    "edges",
    "overview",
];

fn assert_panels(dir: &Path, names: &[&str]) {
    for name in names {
        let path = dir.join(format!("{name}.png"));
        let img = image::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(img.width() > 0 && img.height() > 0);
    }
    let leftovers: Vec<_> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// Asserts a clean failure: non-zero exit, exactly one `error:` line on
/// stderr mentioning `needle`, no panic, and no PNG in `out`.
fn assert_fails(out: &Output, needle: &str, dir: &Path) {
    assert_one_line_error(out, needle);
    if dir.exists() {
        let pngs: Vec<PathBuf> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.to_string_lossy().contains(".png"))
            .collect();
        assert!(pngs.is_empty(), "{pngs:?}");
    }
}

fn gradient(w: u32, h: u32) -> RgbImage {
    RgbImage::from_fn(w, h, |x, y| {
        let inside = (x as i32 - w as i32 / 2).pow(2) + (y as i32 - h as i32 / 2).pow(2)
            < (h as i32 / 3).pow(2);
        if inside {
            Rgb([200, 60, 40])
        } else {
            Rgb([(x % 256) as u8, (y % 256) as u8, 128])
        }
    })
}

#[test]
fn demo_writes_every_panel_and_a_summary() {
    let tmp = tempfile::tempdir().unwrap();
    let out_dir = tmp.path().join("out");
    let out = protogist(&["demo", "--out", out_dir.to_str().unwrap()], tmp.path());
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_panels(&out_dir, &DEMO_PANELS);
    let stdout = text(&out.stdout);
    for key in [
        "160x120",
        "max C~",
        "edge pixels",
        "GT boundary",
        "core scratch",
        "output",
    ] {
        assert!(stdout.contains(key), "{key} missing from\n{stdout}");
    }
    let left = image::open(out_dir.join("left.png")).unwrap();
    assert_eq!((left.width(), left.height()), (160, 120));
    // The objects panel: the left view with the object's box and category
    // tab in protogist::draw's green (known) or magenta (unknown).
    let objects = image::open(out_dir.join("objects.png")).unwrap().to_rgb8();
    let drawn = |c: [u8; 3]| objects.pixels().filter(|p| p.0 == c).count();
    let (known, unknown) = (drawn([0, 255, 0]), drawn([255, 0, 255]));
    assert!(known + unknown > 150, "no box: {known} {unknown}");
    let black_text = objects.pixels().filter(|p| p.0 == [0, 0, 0]).count();
    assert!(black_text > 20, "no category text: {black_text}");
}

#[test]
fn no_arguments_runs_the_demo_into_protogist_out() {
    let tmp = tempfile::tempdir().unwrap();
    let out = protogist(&[], tmp.path());
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_panels(&tmp.path().join("protogist-out"), &DEMO_PANELS);
}

#[test]
fn demo_takes_a_frame_size_and_rejects_zero() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("o");
    let d = dir.to_str().unwrap();
    let out = protogist(
        &["demo", "--out", d, "--width", "96", "--height", "72"],
        tmp.path(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let left = image::open(dir.join("left.png")).unwrap();
    assert_eq!((left.width(), left.height()), (96, 72));
    // Below what the stereo engine's coarsest level needs (5 taps at a
    // quarter of the frame, 20 px): a clear error.
    let small = tmp.path().join("s");
    let out = protogist(
        &[
            "demo",
            "--out",
            small.to_str().unwrap(),
            "--width",
            "24",
            "--height",
            "18",
        ],
        tmp.path(),
    );
    assert_fails(&out, "smaller than the filter support", &small);

    let zero = tmp.path().join("z");
    let out = protogist(
        &["demo", "--out", zero.to_str().unwrap(), "--height", "0"],
        tmp.path(),
    );
    assert_fails(&out, "--height", &zero);
    let out = protogist(
        &["demo", "--out", zero.to_str().unwrap(), "--width", "9000"],
        tmp.path(),
    );
    assert_fails(&out, "exceeds", &zero);
}

#[test]
fn conspicuity_downscales_png_and_jpeg_to_the_working_width() {
    let tmp = tempfile::tempdir().unwrap();
    let img = gradient(640, 480);
    for ext in ["png", "jpg"] {
        let input = tmp.path().join(format!("in.{ext}"));
        img.save(&input).unwrap();
        let dir = tmp.path().join(format!("out-{ext}"));
        let out = protogist(
            &[
                "conspicuity",
                "--image",
                input.to_str().unwrap(),
                "--out",
                dir.to_str().unwrap(),
            ],
            tmp.path(),
        );
        assert!(out.status.success(), "{}", text(&out.stderr));
        assert_panels(&dir, &IMAGE_PANELS);
        let small = image::open(dir.join("input.png")).unwrap();
        assert_eq!((small.width(), small.height()), (160, 120));
        let stdout = text(&out.stdout);
        assert!(
            stdout.contains("640x480") && !stdout.contains("GT"),
            "{stdout}"
        );
    }
}

#[test]
fn conspicuity_keeps_narrow_inputs_and_handles_one_pixel() {
    let tmp = tempfile::tempdir().unwrap();
    for (w, h, width) in [(100, 30, "160"), (1, 1, "160"), (300, 7, "40")] {
        let input = tmp.path().join(format!("in{w}x{h}.png"));
        gradient(w, h).save(&input).unwrap();
        let dir = tmp.path().join(format!("o{w}x{h}"));
        let out = protogist(
            &[
                "conspicuity",
                "--image",
                input.to_str().unwrap(),
                "--out",
                dir.to_str().unwrap(),
                "--width",
                width,
            ],
            tmp.path(),
        );
        assert!(out.status.success(), "{w}x{h}: {}", text(&out.stderr));
        assert_panels(&dir, &IMAGE_PANELS);
        let got = image::open(dir.join("input.png")).unwrap();
        let expected = if w == 300 { (40, 1) } else { (w, h) };
        assert_eq!((got.width(), got.height()), expected);
    }
}

/// Runs `conspicuity` on `input` into a fresh directory; returns both.
fn run_on(input: &Path, tmp: &Path, extra: &[&str]) -> (Output, PathBuf) {
    let dir = tmp.join("out");
    let mut args = vec![
        "conspicuity",
        "--image",
        input.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    (protogist(&args, tmp), dir)
}

#[test]
fn a_missing_file_is_a_clean_error() {
    let tmp = tempfile::tempdir().unwrap();
    let (out, dir) = run_on(&tmp.path().join("nope.png"), tmp.path(), &[]);
    assert_fails(&out, "nope.png", &dir);
}

#[test]
fn random_bytes_named_png_are_a_clean_error() {
    let tmp = tempfile::tempdir().unwrap();
    let input = tmp.path().join("noise.png");
    let bytes: Vec<u8> = (0u32..4096)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    fs::write(&input, bytes).unwrap();
    let (out, dir) = run_on(&input, tmp.path(), &[]);
    assert_fails(&out, "noise.png", &dir);
}

#[test]
fn a_truncated_png_is_a_clean_error() {
    let tmp = tempfile::tempdir().unwrap();
    let full = tmp.path().join("full.png");
    gradient(200, 150).save(&full).unwrap();
    let bytes = fs::read(&full).unwrap();
    for keep in [bytes.len() / 2, 40, 8] {
        let input = tmp.path().join("cut.png");
        fs::write(&input, &bytes[..keep]).unwrap();
        let (out, dir) = run_on(&input, tmp.path(), &[]);
        assert_fails(&out, "cut.png", &dir);
    }
}

#[test]
fn an_empty_file_is_a_clean_error() {
    let tmp = tempfile::tempdir().unwrap();
    let input = tmp.path().join("empty.png");
    fs::write(&input, b"").unwrap();
    let (out, dir) = run_on(&input, tmp.path(), &[]);
    assert_fails(&out, "empty.png", &dir);
}

#[test]
fn width_zero_is_a_typed_error() {
    let tmp = tempfile::tempdir().unwrap();
    let input = tmp.path().join("ok.png");
    gradient(20, 10).save(&input).unwrap();
    let (out, dir) = run_on(&input, tmp.path(), &["--width", "0"]);
    assert_fails(&out, "--width must be at least 1", &dir);
}

#[test]
fn bad_arguments_are_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    let out = protogist(&["conspicuity", "--bogus"], tmp.path());
    assert_eq!(out.status.code(), Some(2));
    assert_fails(&out, "--bogus", tmp.path());
    let out = protogist(&["demo", "--width", "-3"], tmp.path());
    assert_fails(&out, "-3", tmp.path());
    let out = protogist(&["demo", "--width", "wide"], tmp.path());
    assert_fails(&out, "--width", tmp.path());
}

#[test]
fn an_output_path_that_is_a_file_is_a_clean_error() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("taken");
    fs::write(&file, b"x").unwrap();
    let out = protogist(&["demo", "--out", file.to_str().unwrap()], tmp.path());
    assert_fails(&out, "not a directory", tmp.path());
}

#[test]
fn gen_shapes_writes_class_folders_and_rejects_bad_counts() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("shapes");
    let d = dir.to_str().unwrap();
    let out = protogist(
        &[
            "gen-shapes",
            "--out",
            d,
            "--classes",
            "3",
            "--per-class",
            "2",
        ],
        tmp.path(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("square rounded-square star5"));
    for class in ["00_square", "01_rounded-square", "02_star5"] {
        assert_eq!(fs::read_dir(dir.join(class)).unwrap().count(), 2, "{class}");
    }
    let bad = tmp.path().join("bad");
    let b = bad.to_str().unwrap();
    for (args, needle) in [
        (vec!["--classes", "0"], "--classes must be at least 1"),
        (vec!["--per-class", "0"], "--per-class must be at least 1"),
        (vec!["--classes", "20"], "--classes: 20 asked, 19 available"),
        (vec!["--size", "8"], "--size: 8 px"),
    ] {
        let mut all = vec!["gen-shapes", "--out", b];
        all.extend(args);
        assert_fails(&protogist(&all, tmp.path()), needle, &bad);
        assert!(!bad.exists(), "nothing written for {needle}");
    }
}
