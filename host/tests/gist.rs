//! `protogist gen-scenes` and `protogist gist-eval` end to end: determinism,
//! ground-truth consistency, a tiny benchmark run, and every bad input.

use protogist_host::scenes::load::{load_set, SceneSet};
use protogist_host::scenes::BoxPx;
use std::fs;
use std::path::Path;

mod common;
use common::{assert_one_line_error, protogist, text};

const MODEL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/shapes_model.bin");

fn gen(dir: &Path, out: &str, extra: &[&str]) {
    let mut args = vec!["gen-scenes", "--out", out];
    args.extend_from_slice(extra);
    if !extra.contains(&"--scenes") {
        args.extend_from_slice(&["--scenes", "4"]);
    }
    let o = protogist(&args, dir);
    assert!(o.status.success(), "{}", text(&o.stderr));
}

/// Every file of a set, by relative path.
fn files(root: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(root).unwrap().display().to_string();
                out.push((rel, fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn the_same_seed_gives_the_same_bytes_and_splits_differ() {
    let dir = tempfile::tempdir().unwrap();
    gen(dir.path(), "a", &["--seed", "5"]);
    gen(dir.path(), "b", &["--seed", "5"]);
    gen(dir.path(), "c", &["--seed", "5", "--split", "train"]);
    let (a, b, c) = (
        files(&dir.path().join("a")),
        files(&dir.path().join("b")),
        files(&dir.path().join("c")),
    );
    assert!(a.len() > 4 * 5, "{} files", a.len());
    assert_eq!(a, b);
    let left = |set: &[(String, Vec<u8>)]| {
        set.iter()
            .find(|(n, _)| n.ends_with("scene_0000/left.png"))
            .map(|(_, b)| b.clone())
            .unwrap()
    };
    assert_ne!(left(&a), left(&c));
    // A scene does not depend on how many are asked for.
    gen(dir.path(), "d", &["--seed", "5", "--scenes", "2"]);
    let d = files(&dir.path().join("d"));
    let scene1 = |set: &[(String, Vec<u8>)]| -> Vec<(String, Vec<u8>)> {
        set.iter()
            .filter(|(n, _)| n.starts_with("scene_0001"))
            .cloned()
            .collect()
    };
    assert_eq!(scene1(&a), scene1(&d));
}

#[test]
fn truth_agrees_with_masks_and_disparity() {
    let dir = tempfile::tempdir().unwrap();
    gen(dir.path(), "s", &["--objects", "2..4", "--seed", "9"]);
    let set: SceneSet = load_set(&dir.path().join("s")).unwrap();
    assert_eq!(set.scenes.len(), 4);
    for s in &set.scenes {
        assert!((2..=4).contains(&s.truth.objects.len()));
        for (o, m) in s.truth.objects.iter().zip(&s.masks) {
            let w = s.width as u32;
            let found = BoxPx::of(w, s.height as u32, |x, y| m[(y * w + x) as usize] != 0);
            assert_eq!(found, Some(o.bbox));
            let area = m.iter().filter(|&&v| v != 0).count();
            assert_eq!(area, o.area);
            for (&v, d) in m.iter().zip(&s.disparity) {
                if v != 0 {
                    assert_eq!(d.map(f64::from), Some(o.disparity));
                }
            }
            // Objects are in front of whatever the frame holds elsewhere
            // in their rows' background (the scene's nearest layer).
            assert!(o.disparity > 2.0);
        }
    }
}

fn eval(dir: &Path, scenes: &str, model: &str, out: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "gist-eval",
        "--scenes",
        scenes,
        "--model",
        model,
        "--out",
        out,
    ];
    args.extend_from_slice(extra);
    protogist(&args, dir)
}

#[test]
fn gen_scenes_then_gist_eval_reports_and_draws() {
    let dir = tempfile::tempdir().unwrap();
    gen(dir.path(), "s", &["--scenes", "3"]);
    let o = eval(
        dir.path(),
        "s",
        MODEL,
        "gt",
        &["--mode", "gt-disparity", "--json"],
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let on_disk: serde_json::Value =
        serde_json::from_slice(&fs::read(dir.path().join("gt/report.json")).unwrap()).unwrap();
    assert_eq!(report, on_disk);
    assert_eq!(report["overall"]["scenes"], 3);
    assert_eq!(report["scenes"].as_array().unwrap().len(), 3);
    let objects: u64 = report["scenes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["objects"].as_u64().unwrap())
        .sum();
    assert_eq!(report["overall"]["objects"].as_u64(), Some(objects));
    let img = image::open(dir.path().join("gt/overview.png")).unwrap();
    assert!(img.width() >= 320 && img.height() >= 240);

    let o = eval(dir.path(), "s", MODEL, "ref", &["--objects", "2"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(out.contains("mode core, K = 2, preset default"), "{out}");
    assert!(out.contains("recall") && out.contains("gist"), "{out}");

    // Every named setting of the pipeline runs, under its name.
    for (name, _) in protogist::pipeline::PipelineParams::NAMED {
        let o = eval(dir.path(), "s", MODEL, name, &["--preset", name, "--json"]);
        assert!(o.status.success(), "{name}: {}", text(&o.stderr));
        let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(report["preset"], name);
        assert_eq!(report["overall"]["scenes"], 3);
    }
    let o = eval(dir.path(), "s", MODEL, "x", &["--preset", "fastest"]);
    assert_one_line_error(
        &o,
        "--preset: unknown setting \"fastest\" (default, paper, accurate)",
    );
}

/// Rewrites one file of scene 0 of set `s` in a fresh copy.
fn broken(dir: &Path, name: &str, f: impl FnOnce(&Path)) -> String {
    let src = dir.join("s");
    let dst = dir.join(name);
    for (rel, bytes) in files(&src) {
        let p = dst.join(rel);
        fs::create_dir_all(p.parent().unwrap()).unwrap();
        fs::write(p, bytes).unwrap();
    }
    f(&dst.join("scene_0000"));
    name.into()
}

#[test]
fn bad_input_is_a_typed_error_naming_the_file_and_leaves_no_report() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    gen(d, "s", &["--scenes", "2", "--objects", "2"]);
    // A complete report first, so we can see it go.
    let o = eval(d, "s", MODEL, "out", &["--mode", "gt-disparity"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(d.join("out/report.json").is_file());

    let check = |scenes: &str, model: &str, needle: &str| {
        let o = eval(d, scenes, model, "out", &["--mode", "gt-disparity"]);
        assert_one_line_error(&o, needle);
        assert!(!d.join("out/report.json").exists(), "{needle}");
    };
    let missing_left = broken(d, "m1", |s| fs::remove_file(s.join("left.png")).unwrap());
    check(&missing_left, MODEL, "scene_0000/left.png");
    let missing_index = broken(d, "m2", |s| {
        fs::remove_file(s.parent().unwrap().join("index.json")).unwrap()
    });
    check(&missing_index, MODEL, "index.json");
    let bad_index = broken(d, "m3", |s| {
        fs::write(s.parent().unwrap().join("index.json"), "{").unwrap()
    });
    check(&bad_index, MODEL, "scene index");
    let missing_mask = broken(d, "m4", |s| fs::remove_file(s.join("mask_1.png")).unwrap());
    check(&missing_mask, MODEL, "mask_1.png");

    // Truth that disagrees with its images.
    let edit_truth = |s: &Path, from: &str, to: &str| {
        let p = s.join("truth.json");
        let t = fs::read_to_string(&p).unwrap();
        assert!(t.contains(from), "{t}");
        fs::write(&p, t.replacen(from, to, 1)).unwrap();
    };
    let moved_box = broken(d, "t1", |s| edit_truth(s, "\"x\": ", "\"x\": 1"));
    check(&moved_box, MODEL, "mask_0.png: its box is");
    let wrong_disparity = broken(d, "t2", |s| {
        edit_truth(s, "\"disparity\": ", "\"disparity\": 1")
    });
    check(&wrong_disparity, MODEL, "disparity.pfm: disparity");
    let small_right = broken(d, "t3", |s| {
        image::RgbImage::new(20, 10)
            .save(s.join("right.png"))
            .unwrap()
    });
    check(
        &small_right,
        MODEL,
        "right.png: is 20x10, truth.json says 160x120",
    );
    let extra_object = broken(d, "t4", |s| {
        edit_truth(s, "\"objects\": [", "\"objects\": [{}, ")
    });
    check(&extra_object, MODEL, "truth.json");
    let foreign_class = broken(d, "t5", |s| {
        edit_truth(s, "\"class\": \"", "\"class\": \"x")
    });
    check(&foreign_class, MODEL, "is not one of index.json's");

    // Models: missing, corrupt, and of other classes than the scenes'.
    check("s", "nothing.bin", "nothing.bin");
    fs::write(d.join("junk.bin"), b"not a model").unwrap();
    check("s", "junk.bin", "junk.bin");
    let g = protogist(
        &[
            "gen-shapes",
            "--out",
            "shapes",
            "--classes",
            "2",
            "--per-class",
            "4",
            "--size",
            "32",
        ],
        d,
    );
    assert!(g.status.success(), "{}", text(&g.stderr));
    let t = protogist(
        &[
            "train",
            "--dataset",
            "shapes",
            "--hidden",
            "4",
            "--epochs",
            "2",
            "--out",
            "two.bin",
        ],
        d,
    );
    assert!(t.status.success(), "{}", text(&t.stderr));
    check("s", "two.bin", "model two.bin has no class");
    let o = eval(d, "s", MODEL, "out", &["--objects", "9"]);
    assert_one_line_error(&o, "--objects");
}
