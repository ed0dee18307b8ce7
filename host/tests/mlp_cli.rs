//! `protogist train`, `eval` and `quantize` through the binary: a tiny
//! run, and bad input (non-zero exit, one `error:` line, no panic).

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
    let model = cwd.join("m/model.bin");
    let sidecar = cwd.join("m/model.bin.json");
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
    assert_eq!(json["float"]["classes"], 3);
    assert_eq!(json["int8"]["classes"], 3);
    assert!(json["top1_agreement"].as_f64().unwrap() > 0.0);
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
    // An empty dataset, and an image that does not decode.
    let none = cwd.join("none");
    fs::create_dir_all(&none).unwrap();
    assert_one_line_error(
        &protogist(
            &[
                "train",
                "--dataset",
                none.to_str().unwrap(),
                "--out",
                "x.bin",
            ],
            cwd,
        ),
        "no class subfolder",
    );
    fs::write(empty.join("b/broken.png"), b"not a png").unwrap();
    assert_one_line_error(
        &protogist(
            &[
                "train",
                "--dataset",
                empty.to_str().unwrap(),
                "--out",
                "x.bin",
            ],
            cwd,
        ),
        "cannot decode",
    );
    assert!(!cwd.join("x.bin").exists());
    // quantize: from the float sidecar it rebuilds train's blob bit for
    // bit; from a blob it emits the Rust source.
    let q = cwd.join("q.bin");
    let rs = cwd.join("fw/model.rs");
    let out = protogist(
        &[
            "quantize",
            "--model",
            sidecar.to_str().unwrap(),
            "--dataset",
            d,
            "--out",
            q.to_str().unwrap(),
        ],
        cwd,
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(fs::read(&q).unwrap(), fs::read(&model).unwrap());
    let out = protogist(
        &[
            "quantize",
            "--model",
            m,
            "--emit-rust",
            rs.to_str().unwrap(),
        ],
        cwd,
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let src = fs::read_to_string(&rs).unwrap();
    let n = fs::read(&model).unwrap().len();
    assert!(
        src.contains(&format!("pub static MODEL: [u8; {n}]")),
        "{src}"
    );
    // The array holds the blob byte for byte (the header comment names
    // the model's path, which may itself contain "0x").
    let body = &src[src.find("= [").expect("array") + 3..src.rfind("];").expect("end")];
    let bytes: Vec<u8> = body
        .split(',')
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(|t| u8::from_str_radix(t.trim_start_matches("0x"), 16).expect("hex byte"))
        .collect();
    assert_eq!(bytes, fs::read(&model).unwrap());
    assert_one_line_error(
        &protogist(&["quantize", "--model", m], cwd),
        "give --out, --emit-rust or both",
    );
    assert_one_line_error(
        &protogist(
            &[
                "quantize",
                "--model",
                sidecar.to_str().unwrap(),
                "--out",
                "z.bin",
            ],
            cwd,
        ),
        "a float model needs its training dataset",
    );

    // Bad blobs: corrupt, truncated, wrong version, not a model.
    let blob = fs::read(&model).unwrap();
    let bad_blob = cwd.join("badm/model.bin");
    fs::create_dir_all(bad_blob.parent().unwrap()).unwrap();
    fs::copy(&sidecar, cwd.join("badm/model.bin.json")).unwrap();
    let eval_blob = |bytes: &[u8]| {
        fs::write(&bad_blob, bytes).unwrap();
        protogist(
            &[
                "eval",
                "--model",
                bad_blob.to_str().unwrap(),
                "--dataset",
                d,
                "--out",
                "ev2",
            ],
            cwd,
        )
    };
    let mut corrupt = blob.clone();
    corrupt[100] ^= 0x10;
    assert_one_line_error(&eval_blob(&corrupt), "corrupt: CRC-32");
    assert_one_line_error(&eval_blob(&blob[..blob.len() - 9]), "truncated");
    let mut v3 = blob.clone();
    v3[4] = 3;
    assert_one_line_error(
        &eval_blob(&v3),
        "model version 3, this build reads versions 1 to 2",
    );
    assert_one_line_error(
        &eval_blob(b"{\"not\": \"a model\"}"),
        "not a protogist model",
    );
    assert!(!cwd.join("ev2").exists());

    // A float sidecar of the wrong shape, and one that is not JSON.
    let mut v: serde_json::Value = serde_json::from_slice(&fs::read(&sidecar).unwrap()).unwrap();
    v["b2"].as_array_mut().unwrap().pop();
    let bad = cwd.join("bad.bin");
    fs::copy(&model, &bad).unwrap();
    let bad_side = cwd.join("bad.bin.json");
    fs::write(&bad_side, serde_json::to_vec(&v).unwrap()).unwrap();
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
    fs::write(&bad_side, b"{ not json").unwrap();
    assert_one_line_error(&eval_bad(&bad), "bad.bin.json");
    fs::remove_file(&bad_side).unwrap();
    assert_one_line_error(&eval_bad(&bad), "bad.bin.json");
    assert_one_line_error(&eval_bad(&cwd.join("nope.bin")), "nope.bin");
}
