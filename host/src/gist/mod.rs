//! `protogist gist-eval` (issue 20 §2): the end-to-end benchmark. Runs a
//! detector ([`detect`]) on every scene of a `gen-scenes` set, matches its
//! detections to the ground truth and reports the measures of [`score`],
//! overall and by the number of objects in the scene, with an
//! [`overview`] picture.
//!
//! Inputs are loaded and checked in full (scenes against their truth, the
//! model against the scenes' classes) before anything runs. Outputs:
//! `OUT/overview.png`, then `OUT/report.json` last, each written
//! atomically; a `report.json` from an earlier run is removed before the
//! inputs are even read, so a folder holds a `report.json` only when the
//! last run into it completed.

pub mod detect;
pub mod overview;
pub mod score;

use crate::error::{HostError, Result};
use crate::output::{ensure_dir, write_atomic};
use crate::reference::stereo::DemParams;
use crate::scenes::load::{check_classes, load_set, Scene};
use crate::summary::Summary;
use detect::{make_detector, Classifier, Detection, Mode, Shared};
use protogist::mlp::Model;
use protogist::segment::{SegmentParams, MAX_OBJECTS};
use rayon::prelude::*;
use score::{score_scene, SceneScore, Totals, MIN_IOU};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The `format` of `report.json`.
pub const REPORT_FORMAT: &str = "protogist-gist-eval-1";
/// Example scenes in the overview, per number of objects.
const EXAMPLES_PER_COUNT: usize = 2;

/// Options of `protogist gist-eval`.
#[derive(Clone, Debug, PartialEq, Eq, clap::Args)]
pub struct GistEvalOptions {
    /// Scene set written by `protogist gen-scenes`.
    #[arg(long)]
    pub scenes: PathBuf,
    /// The int8 classifier blob (e.g. host/data/shapes_model.bin).
    #[arg(long)]
    pub model: PathBuf,
    /// Objects to detect per scene, most salient first (K).
    #[arg(long, default_value_t = 4)]
    pub objects: u8,
    /// The pipeline's named setting (`default`, `paper` or `accurate`:
    /// `protogist::pipeline::PipelineParams::NAMED`).
    #[arg(long, default_value = "default")]
    pub preset: String,
    /// The mirror check (`PipelineParams::mirror_check`, the model's
    /// per-class symmetry) on or off, whatever the preset says; on, it
    /// checks the objects the preset's bar sends to it
    /// (`PipelineParams::mirror_below_q16`: the default's unsure ones,
    /// every object of the accurate preset).
    #[arg(long, value_name = "on|off", value_parser = parse_on_off)]
    pub mirror_check: Option<bool>,
    /// With the mirror check, the bar under which an object's own best
    /// cosine sends it to the check (`PipelineParams::mirror_below_q16`),
    /// instead of the preset's: 0 checks no object, 1 or more every one.
    #[arg(long, value_name = "COS", value_parser = parse_bar)]
    pub mirror_below: Option<u32>,
    /// Which chain runs.
    #[arg(long, value_enum, default_value = "core")]
    pub mode: Mode,
    /// Print the report as JSON instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Output directory (created if missing).
    #[arg(long)]
    pub out: PathBuf,
}

/// `on` or `off`.
fn parse_on_off(s: &str) -> std::result::Result<bool, String> {
    match s {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("{s:?}: on or off")),
    }
}

/// A cosine bar as Q16 (`u32::MAX` from 1 up: every object).
fn parse_bar(s: &str) -> std::result::Result<u32, String> {
    match s.parse::<f64>() {
        Ok(v) if v >= 1.0 => Ok(u32::MAX),
        Ok(v) if v >= 0.0 => Ok((v * 65536.0).round() as u32),
        _ => Err(format!("{s:?}: a cosine from 0")),
    }
}

/// `report.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// [`REPORT_FORMAT`].
    pub format: &'static str,
    /// The chain.
    pub mode: Mode,
    /// The pipeline's named setting (`--preset`).
    pub preset: String,
    /// Whether the mirror check ran (the preset's, or `--mirror-check`).
    pub mirror_check: bool,
    /// Its bar: the objects whose own best cosine is under it are checked
    /// (`None`: every object).
    pub mirror_below: Option<f64>,
    /// The scene set.
    pub scenes_dir: String,
    /// The model file.
    pub model: String,
    /// K.
    pub max_objects: u8,
    /// Least box IoU of a match.
    pub min_iou: f64,
    /// Worker threads (times per scene are per thread).
    pub threads: usize,
    /// Wall time of the detection, s.
    pub wall_s: f64,
    /// Over all scenes.
    pub overall: Totals,
    /// By number of objects in the scene: `(n, totals)`.
    pub by_objects: Vec<(usize, Totals)>,
    /// Every scene.
    pub scenes: Vec<SceneScore>,
}

/// The stereo model of the reference chain: the default parameters with a
/// search range of 31 px per 160 px of width (the scenes reach 28).
///
/// # Errors
/// As [`crate::dem_tables::decoder_for`].
pub fn reference_dem(width: usize) -> Result<(DemParams, crate::reference::stereo::Decoder)> {
    let max_disp = (31 * width).div_ceil(160).min(usize::from(u8::MAX));
    let params = DemParams {
        max_disp: u8::try_from(max_disp).unwrap_or(u8::MAX),
        ..DemParams::default()
    };
    let decoder = crate::dem_tables::decoder_for(&params, None)?;
    Ok((params, decoder))
}

/// Runs `mode` on every scene in parallel (a detector per worker); per
/// scene its detections and the detector's time, ms.
///
/// # Errors
/// The first detector error.
pub fn run_detector(
    mode: Mode,
    shared: &Shared<'_>,
    scenes: &[Scene],
) -> Result<Vec<(Vec<Detection>, f64)>> {
    scenes
        .par_iter()
        .map_init(
            || make_detector(mode, shared),
            |det, scene| {
                let t = Instant::now();
                let d = det.detect(scene)?;
                Ok((d, t.elapsed().as_secs_f64() * 1e3))
            },
        )
        .collect()
}

fn fmt_rate(r: Option<f64>) -> String {
    r.map_or_else(|| "n/a".into(), |v| format!("{:.1} %", 100.0 * v))
}

fn push_totals(s: &mut Summary, label: &str, t: &Totals) {
    s.push(
        label,
        format!(
            "{} scenes, {} objects, {} detections: recall {}, precision {}, mask IoU {}, top-1 {}, top-5 {}, gist {}; unknown {}, low-contrast recall {}, top-1 {}",
            t.scenes,
            t.objects,
            t.detections,
            fmt_rate(t.recall),
            fmt_rate(t.precision),
            t.mask_iou.map_or_else(|| "n/a".into(), |v| format!("{v:.3}")),
            fmt_rate(t.top1),
            fmt_rate(t.top5),
            fmt_rate(t.gist),
            fmt_rate(t.unknown),
            fmt_rate(t.low_contrast_recall),
            fmt_rate(t.low_contrast_top1),
        ),
    );
}

/// Loads the model blob at `path`.
///
/// # Errors
/// [`HostError::Io`] or [`HostError::BadModel`] naming it.
pub fn load_model(path: &Path) -> Result<Vec<u8>> {
    let bytes = std::fs::read(path).map_err(|e| HostError::io(path, e))?;
    Model::parse(&bytes).map_err(|e| {
        crate::classify::model::bad_model(path, crate::classify::quant::model_error(e))
    })?;
    Ok(bytes)
}

/// `protogist gist-eval`.
///
/// # Errors
/// Bad options, a scene set or model that cannot be used (checked before
/// anything runs), a stage's error, or unwritable output.
pub fn gist_eval(opts: &GistEvalOptions) -> Result<Summary> {
    let start = Instant::now();
    if opts.objects == 0 || usize::from(opts.objects) > MAX_OBJECTS {
        return Err(HostError::InvalidArgument {
            name: "objects",
            reason: format!("{} is outside 1..={MAX_OBJECTS}", opts.objects),
        });
    }
    // This run's report replaces any earlier one, complete or not.
    let report_path = opts.out.join("report.json");
    if report_path.is_file() {
        std::fs::remove_file(&report_path).map_err(|e| HostError::io(&report_path, e))?;
    }
    let blob = load_model(&opts.model)?;
    let model = Model::parse(&blob)
        .map_err(|e| crate::classify::model::bad_model(&opts.model, format!("{e:?}")))?;
    let set = load_set(&opts.scenes)?;
    let names: Vec<String> = (0..model.classes())
        .filter_map(|c| model.class_name(c).map(str::to_string))
        .collect();
    check_classes(&set, &opts.model, &names)?;
    ensure_dir(&opts.out)?;

    let mut preset = crate::product::preset(&opts.preset)?;
    if let Some(on) = opts.mirror_check {
        preset = preset.with_mirror_check(on);
    }
    if let Some(bar) = opts.mirror_below {
        preset.mirror_below_q16 = bar;
    }
    let shared = Shared {
        preset,
        segment: SegmentParams {
            max_objects: opts.objects,
            ..preset.segment
        },
        classifier: Classifier { model },
        dem: if opts.mode.needs_reference_stereo() {
            Some(reference_dem(set.index.width as usize)?)
        } else {
            None
        },
        blob: &blob,
        tables: Vec::new(),
    };
    let mut shared = shared;
    if opts.mode.runs_core() {
        let params = detect::core_params(&shared, set.index.width as usize);
        shared.tables = crate::product::tables_for(&params)?;
    }
    shared.segment.validate()?;
    let t = Instant::now();
    let results = run_detector(opts.mode, &shared, &set.scenes)?;
    let wall_s = t.elapsed().as_secs_f64();
    let scores: Vec<SceneScore> = set
        .scenes
        .iter()
        .zip(&results)
        .map(|(scene, (dets, ms))| score_scene(scene, dets, *ms))
        .collect();
    let overall = Totals::of(&scores);
    let by_objects: Vec<(usize, Totals)> = (1..=4)
        .filter_map(|n| {
            let t = Totals::of(scores.iter().filter(|s| s.objects == n));
            (t.scenes > 0).then_some((n, t))
        })
        .collect();

    // Overview: the first scenes of each object count.
    let mut tiles = Vec::new();
    for n in 1..=4 {
        for (k, s) in scores
            .iter()
            .enumerate()
            .filter(|(_, s)| s.objects == n)
            .take(EXAMPLES_PER_COUNT)
        {
            let img = overview::tile(&set.scenes[k], &results[k].0, s.gist);
            tiles.push((s.scene.clone(), img));
        }
    }
    let report = Report {
        format: REPORT_FORMAT,
        mode: opts.mode,
        preset: opts.preset.clone(),
        // Only core's pipeline runs the check; the reference chain
        // classifies each mask plainly.
        mirror_check: opts.mode.runs_core() && shared.preset.mirror_check,
        mirror_below: (shared.preset.mirror_below_q16 < u32::MAX)
            .then(|| f64::from(shared.preset.mirror_below_q16) / 65536.0),
        scenes_dir: opts.scenes.display().to_string(),
        model: opts.model.display().to_string(),
        max_objects: opts.objects,
        min_iou: MIN_IOU,
        threads: rayon::current_num_threads(),
        wall_s,
        overall,
        by_objects,
        scenes: scores,
    };
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| HostError::io(opts.out.join("report.json"), e.into()))?;
    let png = crate::panels::Panel::new("overview", overview::overview(tiles)).encode_png()?;
    write_atomic(&opts.out.join("overview.png"), &png)?;
    write_atomic(&report_path, format!("{json}\n").as_bytes())?;

    let mut s = Summary::new(format!(
        "protogist gist-eval: {} scenes of {}, mode {}, K = {}, preset {}, mirror check {}",
        report.overall.scenes,
        opts.scenes.display(),
        opts.mode.name(),
        opts.objects,
        opts.preset,
        match (report.mirror_check, report.mirror_below) {
            (false, _) => "off".to_string(),
            (true, None) => "on".to_string(),
            (true, Some(b)) => format!("on under {b:.3}"),
        }
    ));
    push_totals(&mut s, "all scenes", &report.overall);
    for (n, t) in &report.by_objects {
        push_totals(&mut s, &format!("{n} object(s)"), t);
    }
    s.push(
        "time per scene",
        format!(
            "{:.1} ms in the detector ({} threads), {:.2} s wall for all",
            report.overall.ms_per_scene.unwrap_or(0.0),
            report.threads,
            wall_s
        ),
    );
    s.push("matching", format!("greedy by box IoU >= {MIN_IOU}"));
    s.push(
        "output",
        format!("{} (overview.png, report.json)", opts.out.display()),
    );
    s.push(
        "total time",
        format!("{:.1} s", start.elapsed().as_secs_f64()),
    );
    if opts.json {
        s.raw = Some(json);
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::parse_bar;

    #[test]
    fn bars_are_q16_cosines() {
        assert_eq!(parse_bar("0.95"), Ok(62_259));
        assert_eq!(parse_bar("0"), Ok(0));
        assert_eq!(parse_bar("1"), Ok(u32::MAX));
        assert_eq!(parse_bar("2.5"), Ok(u32::MAX));
        assert!(parse_bar("-0.1").is_err());
        assert!(parse_bar("NaN").is_err());
        assert!(parse_bar("high").is_err());
    }
}
