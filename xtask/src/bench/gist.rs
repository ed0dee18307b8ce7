//! The end-to-end benchmark section (issue 20): `gen-scenes` then
//! `gist-eval --json` per chain, side by side.

use super::{protogist_json, Section, NOT_YET};

/// Scenes, seed and size of the benchmark set.
const SCENES: &str = "200";
const SEED: &str = "1";
/// The chains measured: label, `--mode`, `--preset`.
const MODES: [(&str, &str, &str); 5] = [
    ("core pipeline (the product)", "core", "default"),
    (
        "core pipeline, `accurate` preset (full search at half size, phase step, band relabelling, hole by disparity)",
        "core",
        "accurate",
    ),
    ("f32 reference chain", "reference", "default"),
    (
        "core pipeline on ground-truth disparity (stereo upper bound)",
        "gt-disparity",
        "default",
    ),
    (
        "core pipeline, `accurate` preset, on ground-truth disparity",
        "gt-disparity",
        "accurate",
    ),
];

fn pct(v: &serde_json::Value) -> String {
    v.as_f64()
        .map_or_else(|| "n/a".into(), |x| format!("{:.1} %", 100.0 * x))
}

pub fn section() -> Section {
    let title = "End-to-end: objects and categories from a stereo pair (gen-scenes)";
    let dir = std::env::temp_dir().join(format!("protogist-gist-bench-{}", std::process::id()));
    let scenes = dir.join("scenes");
    let scenes_arg = scenes.display().to_string();
    let mut body = format!(
        "{SCENES} test scenes at 160x120 (1 to 4 objects of the 19 `gen-shapes` classes, seed {SEED}), \
         the shipped model, K = 4 detections per scene, matched to the truth greedily by box IoU >= 0.5. \
         Top-1 and top-5 are over matched objects; gist is the share of scenes whose every object \
         is matched and called by its class, with no other detection claiming a class. \
         Unknown is the share of detections the model's Δ rejects; low-contrast recall and top-1 are over \
         the objects (one in five) drawn without contrast to their surroundings. \
         ms/scene is the detector's time per scene on one of 2 worker threads.\n\n\
         ```\ncargo run --release -- gen-scenes --out scenes --scenes {SCENES} --seed {SEED} --split test\n\
         cargo run --release -- gist-eval --scenes scenes --model host/data/shapes_model.bin \
         [--mode reference|gt-disparity] [--preset accurate] --out OUT\n```\n\n"
    );
    let made = super::protogist(&[
        "gen-scenes",
        "--out",
        &scenes_arg,
        "--scenes",
        SCENES,
        "--seed",
        SEED,
        "--split",
        "test",
    ]);
    let reports: Vec<(&str, Option<serde_json::Value>)> = MODES
        .iter()
        .map(|&(label, mode, preset)| {
            let out = dir.join(format!("{mode}-{preset}")).display().to_string();
            let r = made.as_ref().ok().and_then(|_| {
                protogist_json(&[
                    "gist-eval",
                    "--scenes",
                    &scenes_arg,
                    "--model",
                    "host/data/shapes_model.bin",
                    "--mode",
                    mode,
                    "--preset",
                    preset,
                    "--json",
                    "--out",
                    &out,
                ])
            });
            (label, r)
        })
        .collect();
    let _ = std::fs::remove_dir_all(&dir);
    body.push_str(
        "| chain | recall | precision | mask IoU | top-1 | top-5 | gist | unknown | low-contrast recall / top-1 | ms/scene |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    for (label, r) in &reports {
        let Some(t) = r.as_ref().map(|r| &r["overall"]) else {
            body.push_str(&format!("| {label} | {NOT_YET} | | | | | | | | |\n"));
            continue;
        };
        body.push_str(&format!(
            "| {label} | {} | {} | {} | {} | {} | {} | {} | {} / {} | {} |\n",
            pct(&t["recall"]),
            pct(&t["precision"]),
            t["mask_iou"]
                .as_f64()
                .map_or_else(|| "n/a".into(), |v| format!("{v:.3}")),
            pct(&t["top1"]),
            pct(&t["top5"]),
            pct(&t["gist"]),
            pct(&t["unknown"]),
            pct(&t["low_contrast_recall"]),
            pct(&t["low_contrast_top1"]),
            t["ms_per_scene"]
                .as_f64()
                .map_or_else(|| "n/a".into(), |v| format!("{v:.1}")),
        ));
    }
    body.push_str(
        "\nBy number of objects in the scene (recall / precision / top-1):\n\n\
         | chain | 1 object | 2 objects | 3 objects | 4 objects |\n|---|---|---|---|---|\n",
    );
    for (label, r) in &reports {
        let cells: Vec<String> = (1..=4)
            .map(|n| {
                r.as_ref()
                    .and_then(|r| r["by_objects"].as_array())
                    .and_then(|groups| groups.iter().find(|g| g[0] == n))
                    .map_or_else(
                        || NOT_YET.into(),
                        |g| {
                            let t = &g[1];
                            format!(
                                "{} / {} / {}",
                                pct(&t["recall"]),
                                pct(&t["precision"]),
                                pct(&t["top1"])
                            )
                        },
                    )
            })
            .collect();
        body.push_str(&format!("| {label} | {} |\n", cells.join(" | ")));
    }
    Section { title, body }
}
