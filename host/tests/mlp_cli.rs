//! `protogist train` and `protogist eval` through the binary: a tiny run,
//! and bad input (non-zero exit, one `error:` line, no panic).

use std::fs;
use std::path::Path;

mod common;
use common::{assert_one_line_error, protogist, text};

#[test]
fn train_and_eval_run_and_reject_bad_input() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let ds = cwd.join("shapes");
    let d = ds.to_str().unwrap();
    let gen = protogist(
        &[
            "gen-shapes",
            "--out",
            d,
            "--classes",
            "3",
            "--per-class",
            "4",
            "--size",
            "48",
        ],
        cwd,
    );
    assert!(gen.status.success(), "{}", text(&gen.stderr));
    let model = cwd.join("m/model.json");
    let m = model.to_str().unwrap();
    let train = |extra: &[&str]| {
        let mut a = vec!["train", "--dataset", d, "--epochs", "5", "--out", m];
        a.extend_from_slice(extra);
        protogist(&a, cwd)
    };
    let out = train(&["--hidden", "4"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("6 train, 6 test"),
        "{}",
        text(&out.stdout)
    );
    let ev = cwd.join("eval");
    let e = ev.to_str().unwrap();
    let out = protogist(
        &["eval", "--model", m, "--dataset", d, "--out", e, "--json"],
        cwd,
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["classes"], 3);
    for f in ["cmc.png", "det.svg", "roc.png", "metrics.json"] {
        assert!(ev.join(f).is_file(), "{f}");
    }

    // Bad input.
    assert_one_line_error(
        &protogist(&["train", "--dataset", "missing", "--out", "x.json"], cwd),
        "missing: not a directory",
    );
    assert_one_line_error(&train(&["--hidden", "0"]), "--hidden must be at least 1");
    assert_one_line_error(&train(&["--test-fraction", "1"]), "--test-fraction");
    let empty = cwd.join("empty");
    fs::create_dir_all(empty.join("a")).unwrap();
    fs::create_dir_all(empty.join("b")).unwrap();
    fs::copy(
        fs::read_dir(ds.join("00_square"))
            .unwrap()
            .next()
            .unwrap()
            .unwrap()
            .path(),
        empty.join("a/one.png"),
    )
    .unwrap();
    assert_one_line_error(
        &protogist(
            &[
                "train",
                "--dataset",
                empty.to_str().unwrap(),
                "--out",
                "x.json",
            ],
            cwd,
        ),
        "class folder has no PNG or JPEG image",
    );
    assert!(!cwd.join("x.json").exists());
    // A model of the wrong shape, and one that is not JSON.
    let mut v: serde_json::Value = serde_json::from_slice(&fs::read(&model).unwrap()).unwrap();
    v["b2"].as_array_mut().unwrap().pop();
    let bad = cwd.join("bad.json");
    fs::write(&bad, serde_json::to_vec(&v).unwrap()).unwrap();
    let eval_bad = |p: &Path| {
        protogist(
            &[
                "eval",
                "--model",
                p.to_str().unwrap(),
                "--dataset",
                d,
                "--out",
                e,
            ],
            cwd,
        )
    };
    assert_one_line_error(&eval_bad(&bad), "b2 has 2 values, expected 3");
    fs::write(&bad, b"{ not json").unwrap();
    assert_one_line_error(&eval_bad(&bad), "bad.json");
    assert_one_line_error(&eval_bad(&cwd.join("nope.json")), "nope.json");
}
