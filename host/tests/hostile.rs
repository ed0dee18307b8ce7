//! Issue 22's hostile inputs through the binary: each case fails with one
//! `error:` line (or succeeds as specified), and leaves no half-written
//! result.

use std::fs;
use std::path::Path;
use std::time::Instant;

mod common;
use common::{assert_one_line_error, protogist, text};

/// A textured `w x h` image, shifted `shift` px (a stereo pair's view).
fn view(w: u32, h: u32, shift: u32) -> image::RgbImage {
    image::RgbImage::from_fn(w, h, |x, y| {
        let v = ((x + shift) * 37 + y * 91 + ((x + shift) * y) % 23) as u8;
        image::Rgb([v, v.wrapping_mul(5), 255 - v])
    })
}

fn save(img: &image::RgbImage, path: &Path, format: image::ImageFormat) {
    img.save_with_format(path, format).unwrap();
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn a_truncated_jpeg_is_an_error_for_every_command_that_reads_images() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let good = cwd.join("good.jpg");
    save(&view(96, 64, 0), &good, image::ImageFormat::Jpeg);
    let bytes = fs::read(&good).unwrap();
    let cut = cwd.join("cut.jpg");
    fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let out = cwd.join("out");
    assert_one_line_error(
        &protogist(&["conspicuity", "--image", s(&cut), "--out", s(&out)], cwd),
        "is damaged (truncated or corrupt JPEG)",
    );
    for cmd in ["stereo", "run"] {
        assert_one_line_error(
            &protogist(
                &[
                    cmd,
                    "--left",
                    s(&cut),
                    "--right",
                    s(&good),
                    "--out",
                    s(&out),
                ],
                cwd,
            ),
            "is damaged",
        );
    }
    assert!(!out.exists());
    let ok = protogist(&["conspicuity", "--image", s(&good), "--out", s(&out)], cwd);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    // Accepted on request, with a warning.
    let ok = protogist(
        &[
            "conspicuity",
            "--image",
            s(&cut),
            "--out",
            s(&out),
            "--accept-damaged",
        ],
        cwd,
    );
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    let warn = text(&ok.stderr);
    assert!(
        warn.starts_with("warning: ") && warn.contains("is damaged"),
        "{warn}"
    );
}

fn pfm(w: usize, h: usize, v: f32) -> Vec<u8> {
    let mut b = format!("Pf\n{w} {h}\n-1.0\n").into_bytes();
    for _ in 0..w * h {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b
}

#[test]
fn ground_truth_without_a_pixel_or_with_impossible_values_is_an_error() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let (l, r) = (cwd.join("l.png"), cwd.join("r.png"));
    save(&view(128, 96, 0), &l, image::ImageFormat::Png);
    save(&view(128, 96, 3), &r, image::ImageFormat::Png);
    let gt = cwd.join("gt.pfm");
    let out = cwd.join("out");
    let stereo = |extra: &[&str]| {
        let mut a = vec![
            "stereo",
            "--left",
            s(&l),
            "--right",
            s(&r),
            "--gt",
            s(&gt),
            "--out",
            s(&out),
        ];
        a.extend_from_slice(extra);
        protogist(&a, cwd)
    };
    for (v, needle) in [
        (f32::NAN, "no ground-truth pixel"),
        (f32::INFINITY, "no ground-truth pixel"),
        (-2.0, "is not in [0, 128)"),
        (1e30, "is not in [0, 128)"),
        // 3.0 byte-swapped.
        (
            f32::from_bits(3.0f32.to_bits().swap_bytes()),
            "byte-swapped",
        ),
    ] {
        fs::write(&gt, pfm(128, 96, v)).unwrap();
        assert_one_line_error(&stereo(&[]), needle);
    }
    let mut long = pfm(128, 96, 3.0);
    long.extend_from_slice(b"junk");
    fs::write(&gt, long).unwrap();
    assert_one_line_error(&stereo(&[]), "4 trailing bytes");
    // An all-zero PNG: every pixel unknown.
    let png = cwd.join("gt.png");
    image::GrayImage::new(128, 96).save(&png).unwrap();
    assert_one_line_error(
        &protogist(
            &[
                "stereo",
                "--left",
                s(&l),
                "--right",
                s(&r),
                "--gt",
                s(&png),
                "--out",
                s(&out),
            ],
            cwd,
        ),
        "no ground-truth pixel",
    );
    assert!(!out.exists());
    // A valid map still scores.
    fs::write(&gt, pfm(128, 96, 3.0)).unwrap();
    let ok = stereo(&[]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    assert!(text(&ok.stdout).contains("bad-1/2/4"));
}

#[test]
fn nan_float_flags_are_usage_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    for flag in ["--gt-scale=nan", "--gt-scale=inf"] {
        let out = protogist(
            &["stereo", "--left", "l", "--right", "r", "--out", "o", flag],
            cwd,
        );
        assert_eq!(out.status.code(), Some(2), "{flag}");
        let err = text(&out.stderr);
        assert!(err.contains("not a finite number"), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
    }
}

#[test]
fn sizes_and_parameters_are_refused_before_any_work() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    // An 8000x6000 pair: only the headers are read before the refusal.
    let big = cwd.join("big.png");
    let mut png = std::io::Cursor::new(Vec::new());
    image::GrayImage::new(8000, 6000)
        .write_to(&mut png, image::ImageFormat::Png)
        .unwrap();
    fs::write(&big, png.get_ref()).unwrap();
    let out = cwd.join("out");
    let start = Instant::now();
    // The f32 engine's planes exceed the default limit; core's pipeline
    // (about 1 GiB at this size) exceeds a lower one.
    for (cmd, extra, limit) in [
        ("stereo", ["--engine", "reference"], "4096"),
        ("run", ["--max-memory", "512"], "512"),
    ] {
        let mut args = vec![
            cmd,
            "--left",
            s(&big),
            "--right",
            s(&big),
            "--width",
            "8000",
            "--out",
            s(&out),
        ];
        args.extend(extra);
        assert_one_line_error(
            &protogist(&args, cwd),
            &format!("MiB, over the limit of {limit} MiB (raise it with --max-memory MIB)"),
        );
    }
    assert_one_line_error(
        &protogist(
            &["segment-eval", "--width", "50000", "--height", "50000"],
            cwd,
        ),
        "50000 px exceeds the 8192 px limit",
    );
    let (l, r) = (cwd.join("l.png"), cwd.join("r.png"));
    save(&view(160, 120, 0), &l, image::ImageFormat::Png);
    save(&view(160, 120, 3), &r, image::ImageFormat::Png);
    assert_one_line_error(
        &protogist(
            &[
                "run",
                "--left",
                s(&l),
                "--right",
                s(&r),
                "--max-disp",
                "160",
                "--out",
                s(&out),
            ],
            cwd,
        ),
        "must be below half the working width 160, got 160",
    );
    assert_one_line_error(
        &protogist(
            &[
                "train",
                "--dataset",
                "none",
                "--hidden",
                "70000",
                "--out",
                "m.bin",
            ],
            cwd,
        ),
        "70000 is over the model blob's limit of 65535",
    );
    assert_one_line_error(
        &protogist(&["train-dem", "--radius", "8", "--out", s(&out)], cwd),
        "8 px: core's kernels hold radii 1..=7",
    );
    // None of these decoded a frame or trained anything (a generous
    // bound; the figures in the errors are what the test checks).
    assert!(start.elapsed().as_secs() < 60);
    assert!(!out.exists());
}

#[test]
fn quantize_says_what_the_model_file_is() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let random = cwd.join("random.bin");
    fs::write(&random, [0x9c, 0x11, 0x42, 0x07, 0xee, 0x00, 0x13]).unwrap();
    let empty = cwd.join("empty.bin");
    fs::write(&empty, b"").unwrap();
    for (p, needle) in [
        (
            &random,
            "is neither a PGML model blob nor a JSON float sidecar",
        ),
        (&empty, "is empty"),
    ] {
        assert_one_line_error(
            &protogist(&["quantize", "--model", s(p), "--emit-rust", "x.rs"], cwd),
            needle,
        );
    }
    assert!(!cwd.join("x.rs").exists());
}

fn gen(cwd: &Path, out: &Path, per_class: &str, seed: &str) {
    let g = protogist(
        &[
            "gen-shapes",
            "--out",
            s(out),
            "--classes",
            "3",
            "--per-class",
            per_class,
            "--size",
            "48",
            "--seed",
            seed,
        ],
        cwd,
    );
    assert!(g.status.success(), "{}", text(&g.stderr));
}

#[test]
fn eval_scores_a_separate_test_folder_and_train_writes_one_result() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let (train_dir, test_dir) = (cwd.join("train"), cwd.join("test"));
    gen(cwd, &train_dir, "4", "1");
    gen(cwd, &test_dir, "3", "2");
    let model = cwd.join("m.bin");
    let train = |out: &Path| {
        protogist(
            &[
                "train",
                "--dataset",
                s(&train_dir),
                "--hidden",
                "4",
                "--epochs",
                "5",
                "--test-fraction",
                "0",
                "--out",
                s(out),
            ],
            cwd,
        )
    };
    let out = train(&model);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let ev = cwd.join("ev");
    let eval = |dataset: &Path| {
        protogist(
            &[
                "eval",
                "--model",
                s(&model),
                "--dataset",
                s(dataset),
                "--out",
                s(&ev),
                "--json",
            ],
            cwd,
        )
    };
    let out = eval(&test_dir);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    // Every image of the test folder is a probe.
    assert_eq!(json["float"]["test"], 9);
    assert_eq!(json["int8"]["test"], 9);
    assert_eq!(json["float"]["train"], 12);
    // The training folder, with nothing held out: the old error.
    assert_one_line_error(&eval(&train_dir), "give a separate test folder");
    // A class folder the model does not know.
    let odd = test_dir.join("zz_unknown");
    fs::create_dir(&odd).unwrap();
    fs::copy(
        fs::read_dir(test_dir.join("00_square"))
            .unwrap()
            .next()
            .unwrap()
            .unwrap()
            .path(),
        odd.join("a.png"),
    )
    .unwrap();
    assert_one_line_error(
        &eval(&test_dir),
        "class \"zz_unknown\" is not one of the model's classes",
    );
    // A blob that cannot be replaced: neither file of the new result is
    // written, the old pair stays whole.
    let blocked = cwd.join("blocked.bin");
    fs::create_dir(&blocked).unwrap();
    let out = train(&blocked);
    assert_one_line_error(&out, "is a directory");
    assert!(!cwd.join("blocked.bin.json").exists());
    // A sidecar written with another blob is named as such.
    let t = cwd.join("t.bin");
    fs::copy(&model, &t).unwrap();
    let mut side: serde_json::Value =
        serde_json::from_slice(&fs::read(cwd.join("m.bin.json")).unwrap()).unwrap();
    let crc = side["blob_crc32"].as_u64().unwrap();
    side["blob_crc32"] = (crc ^ 1).into();
    fs::write(cwd.join("t.bin.json"), serde_json::to_vec(&side).unwrap()).unwrap();
    assert_one_line_error(
        &protogist(
            &[
                "eval",
                "--model",
                s(&t),
                "--dataset",
                s(&test_dir),
                "--out",
                s(&ev),
            ],
            cwd,
        ),
        "come from different runs",
    );
}

#[test]
fn run_writes_its_panels_and_report_as_one_result() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let (l, r) = (cwd.join("l.png"), cwd.join("r.png"));
    save(&view(96, 72, 0), &l, image::ImageFormat::Png);
    save(&view(96, 72, 3), &r, image::ImageFormat::Png);
    let out = cwd.join("out");
    // report.json cannot be written: no panel may be left either.
    fs::create_dir_all(out.join("report.json")).unwrap();
    let run = || {
        protogist(
            &["run", "--left", s(&l), "--right", s(&r), "--out", s(&out)],
            cwd,
        )
    };
    assert_one_line_error(&run(), "is a directory");
    let names = |d: &Path| -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    assert_eq!(names(&out), ["report.json"]);
    fs::remove_dir(out.join("report.json")).unwrap();
    let ok = run();
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    let written = names(&out);
    assert!(written.iter().any(|n| n == "report.json"), "{written:?}");
    assert!(written.iter().any(|n| n == "overview.png"), "{written:?}");
    assert!(!written.iter().any(|n| n.contains(".tmp")), "{written:?}");
}
