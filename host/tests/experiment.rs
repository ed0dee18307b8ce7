//! `protogist experiment` end to end on a tiny generated dataset, and the
//! model blob's input kinds.

mod common;

use common::{assert_one_line_error, protogist, text};
use protogist::mlp::{InputKind, MlpError, Model, ModelError};
use protogist_host::classify::mlp::Mlp;
use protogist_host::classify::quant::quantize_as;
use protogist_host::classify::shipped::SHIPPED_MODEL;
use protogist_host::rgbd::features::Condition;

#[test]
fn experiment_runs_end_to_end_and_writes_table_figures_and_models() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let out = protogist(
        &[
            "gen-rgbd",
            "--out",
            "data",
            "--categories",
            "3",
            "--instances",
            "2",
            "--frames",
            "10",
        ],
        dir,
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = protogist(
        &[
            "experiment",
            "--dataset",
            "data",
            "--out",
            "exp",
            "--hidden",
            "8",
            "--epochs",
            "10",
            "--conditions",
            "shape,range,colour3,all",
            "--json",
        ],
        dir,
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["classes"], 3);
    // 3 categories × 3 videos × frames 1 and 6: 18 per instance.
    assert_eq!(
        (json["train"].as_u64(), json["test"].as_u64()),
        (Some(18), Some(18))
    );
    let conds = json["conditions"].as_array().unwrap();
    let names: Vec<&str> = conds
        .iter()
        .map(|c| c["condition"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["shape", "range", "colour3", "all"]);
    for c in conds {
        for net in ["float", "int8"] {
            let ror = c[net]["ror"].as_f64().unwrap();
            assert!((0.0..=1.0).contains(&ror), "{c}");
            assert_eq!(c[net]["test"], 18);
        }
    }
    let exp = dir.join("exp");
    let md = std::fs::read_to_string(exp.join("table1.md")).unwrap();
    assert!(md.contains("| Shape + range + conspicuity + luminance |") && md.contains("int8"));
    for f in ["cmc", "det", "roc"] {
        for ext in ["png", "svg"] {
            assert!(exp.join(format!("fig8_{f}.{ext}")).is_file(), "{f}.{ext}");
        }
    }
    for (name, kind) in [
        ("shape", InputKind::Shape),
        ("range", InputKind::Range),
        ("colour3", InputKind::Colour3),
        ("all", InputKind::ShapeRangeConspicuityLuminance),
    ] {
        let blob = std::fs::read(exp.join(format!("models/{name}.bin"))).unwrap();
        let m = Model::parse(&blob).unwrap();
        assert_eq!(
            (m.input_kind(), m.inputs(), m.classes()),
            (kind, kind.input_len(), 3)
        );
    }
    // `eval` refuses an experiment blob of another kind than shape, with
    // a float sidecar that is otherwise fine.
    let ok = |args: &[&str]| {
        let o = protogist(args, dir);
        assert!(o.status.success(), "{args:?}: {}", text(&o.stderr));
    };
    ok(&[
        "gen-shapes",
        "--out",
        "shapes",
        "--classes",
        "3",
        "--per-class",
        "4",
    ]);
    ok(&[
        "train",
        "--dataset",
        "shapes",
        "--out",
        "m.bin",
        "--hidden",
        "4",
        "--epochs",
        "2",
    ]);
    std::fs::copy(exp.join("models/range.bin"), dir.join("m.bin")).unwrap();
    let out = protogist(
        &[
            "eval",
            "--model",
            "m.bin",
            "--dataset",
            "shapes",
            "--out",
            "ev",
        ],
        dir,
    );
    assert_one_line_error(
        &out,
        "the model takes range input (3600 values), given shape",
    );
    // A dataset that is not the layout: one line, typed.
    let out = protogist(
        &[
            "experiment",
            "--dataset",
            "exp",
            "--out",
            "x",
            "--epochs",
            "1",
        ],
        dir,
    );
    assert_one_line_error(&out, "not the RGB-D Object Dataset layout");
}

fn tiny_blob(c: Condition) -> Vec<u8> {
    let net = Mlp::new(c.input_len(), 3, 2, 1);
    let calib: Vec<Vec<i16>> = (0..4)
        .map(|i| {
            (0..c.input_len())
                .map(|j| ((i * 37 + j * 11) % 200) as i16 - 100)
                .collect()
        })
        .collect();
    quantize_as(
        &net,
        &calib,
        &[0, 1, 0, 1],
        &["a".into(), "b".into()],
        "",
        c.kind(),
    )
    .unwrap()
}

#[test]
fn blobs_record_their_input_kind_and_refuse_others() {
    assert_eq!(
        Model::parse(SHIPPED_MODEL).unwrap().input_kind(),
        InputKind::Shape
    );
    for c in Condition::PAPER {
        let blob = tiny_blob(c);
        let m = Model::parse(&blob).unwrap();
        assert_eq!((m.input_kind(), m.inputs()), (c.kind(), c.input_len()));
        assert_eq!(blob[6], c.kind().code());
        assert_eq!(m.expect_input(c.kind()), Ok(()));
        let other = if c == Condition::Range {
            InputKind::Luminance
        } else {
            InputKind::Range
        };
        assert_eq!(
            m.expect_input(other),
            Err(MlpError::InputKind {
                model: c.kind(),
                given: other
            })
        );
    }
    // A range code on a 720-input network: the length is the kind's.
    let mut b = tiny_blob(Condition::Shape);
    b[6] = InputKind::Range.code();
    let n = b.len() - 4;
    let crc = protogist::mlp::crc32(&b[..n]);
    b[n..].copy_from_slice(&crc.to_le_bytes());
    assert_eq!(
        Model::parse(&b),
        Err(ModelError::InputLength {
            code: 6,
            expected: 3600,
            got: 720
        })
    );
    b[6] = 9;
    assert!(matches!(
        Model::parse(&b),
        Err(ModelError::UnsupportedFormat {
            field: "input",
            code: 9
        })
    ));
    for k in InputKind::ALL {
        assert_eq!(InputKind::from_code(k.code()), Some(k));
    }
}
