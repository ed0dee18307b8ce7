//! `protogist run` end to end on the synthetic scene written as files, and
//! its bad input.

use image::{GrayImage, Luma, Rgb, RgbImage};
use protogist::image::{ImageViewMut, Rgb8};
use protogist::synth::{render_disparity, render_left, render_mask, render_right, SceneSpec};
use std::path::Path;

mod common;
use common::{assert_one_line_error, protogist};

const W: usize = 160;
const H: usize = 120;

fn save_rgb(px: &[Rgb8], w: usize, path: &Path) {
    let img = RgbImage::from_fn(w as u32, (px.len() / w) as u32, |x, y| {
        let p = px[y as usize * w + x as usize];
        Rgb([p.r, p.g, p.b])
    });
    img.save(path).unwrap();
}

/// Writes the demo scene's left, right and GT disparity (x16) as PNGs;
/// returns its object mask.
fn write_scene(dir: &Path) -> Vec<u8> {
    let spec = SceneSpec::demo(W, H);
    let (mut l, mut r) = (vec![Rgb8::default(); W * H], vec![Rgb8::default(); W * H]);
    let (mut d, mut m) = (vec![0u8; W * H], vec![0u8; W * H]);
    render_left(&spec, &mut ImageViewMut::packed(&mut l, W, H).unwrap()).unwrap();
    render_right(&spec, &mut ImageViewMut::packed(&mut r, W, H).unwrap()).unwrap();
    render_disparity(&spec, &mut ImageViewMut::packed(&mut d, W, H).unwrap()).unwrap();
    render_mask(&spec, 0, &mut ImageViewMut::packed(&mut m, W, H).unwrap()).unwrap();
    save_rgb(&l, W, &dir.join("l.png"));
    save_rgb(&r, W, &dir.join("r.png"));
    GrayImage::from_fn(W as u32, H as u32, |x, y| {
        Luma([16 * d[y as usize * W + x as usize]])
    })
    .save(dir.join("gt.png"))
    .unwrap();
    m
}

#[test]
fn run_with_gt_disparity_finds_the_object_and_reports_it() {
    let dir = tempfile::tempdir().unwrap();
    let mask = write_scene(dir.path());
    let out = dir.path().join("out");
    let p = |f: &str| dir.path().join(f).display().to_string();
    let o = protogist(
        &[
            "run",
            "--left",
            &p("l.png"),
            "--right",
            &p("r.png"),
            "--gt-disparity",
            &p("gt.png"),
            "--gt-scale",
            "16",
            "--out",
            &out.display().to_string(),
        ],
        dir.path(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    // The GT-disparity chain's objects; core's pipeline (its own stereo)
    // is reported beside them.
    assert!(report["objects"].is_array());
    let objects = report["reference"]["objects"].as_array().unwrap();
    assert_eq!(objects.len(), 1);
    let o0 = &objects[0];
    assert_eq!(o0["shape_vector"].as_array().unwrap().len(), 720);
    // The box matches the GT mask's bounding box within 2 px.
    let (xs, ys): (Vec<usize>, Vec<usize>) = (0..W * H)
        .filter(|&i| mask[i] != 0)
        .map(|i| (i % W, i / W))
        .unzip();
    let gt_box = [
        *xs.iter().min().unwrap(),
        *ys.iter().min().unwrap(),
        xs.iter().max().unwrap() - xs.iter().min().unwrap() + 1,
        ys.iter().max().unwrap() - ys.iter().min().unwrap() + 1,
    ];
    let b = &o0["bbox"];
    let got = ["x", "y", "width", "height"].map(|k| b[k].as_u64().unwrap() as usize);
    for (g, e) in got.iter().zip(gt_box) {
        assert!(g.abs_diff(e) <= 2, "box {got:?} vs GT {gt_box:?}");
    }
    let range = o0["disparity_range_px"].as_array().unwrap();
    let (lo, hi) = (range[0].as_f64().unwrap(), range[1].as_f64().unwrap());
    assert!(
        lo <= 10.0 && 10.0 <= hi,
        "slice {lo}..{hi} misses the object's 10 px"
    );
    for panel in [
        "a_left",
        "b_disparity",
        "objects",
        "reference_i_object_mask",
        "reference_j_segregated_object",
        "reference_shape_vector_0",
    ] {
        assert!(out.join(format!("{panel}.png")).is_file(), "{panel}");
    }
}

#[test]
fn run_rejects_bad_input_and_leaves_no_output() {
    let dir = tempfile::tempdir().unwrap();
    write_scene(dir.path());
    let small = RgbImage::new(40, 30);
    small.save(dir.path().join("small.png")).unwrap();
    let p = |f: &str| dir.path().join(f).display().to_string();
    let out = dir.path().join("out");
    let outs = out.display().to_string();
    let cases: [(&[&str], &str); 4] = [
        (&["--right", &p("small.png")], "right is 40x30"),
        (&["--right", &p("r.png"), "--objects", "0"], "--objects"),
        (
            &["--right", &p("r.png"), "--preset", "fastest"],
            "--preset: unknown setting",
        ),
        (
            &["--right", &p("r.png"), "--gt-disparity", &p("small.png")],
            "ground truth",
        ),
    ];
    let left = p("l.png");
    for (extra, word) in cases {
        let mut args = vec!["run", "--left", &left];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", &outs]);
        assert_one_line_error(&protogist(&args, dir.path()), word);
        assert!(!out.join("report.json").exists(), "{args:?}");
    }
}

#[test]
fn run_takes_the_pipelines_named_settings() {
    let dir = tempfile::tempdir().unwrap();
    write_scene(dir.path());
    let p = |f: &str| dir.path().join(f).display().to_string();
    for preset in ["accurate", "paper"] {
        let out = dir.path().join(preset);
        let o = protogist(
            &[
                "run",
                "--left",
                &p("l.png"),
                "--right",
                &p("r.png"),
                "--preset",
                preset,
                "--out",
                &out.display().to_string(),
            ],
            dir.path(),
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap())
                .unwrap();
        assert_eq!(report["preset"], preset);
        assert!(
            !report["objects"].as_array().unwrap().is_empty(),
            "{preset}: {report}"
        );
    }
}
