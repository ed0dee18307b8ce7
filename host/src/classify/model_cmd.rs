//! `protogist train` (module [`super::train_cmd`], re-exported here) and
//! `protogist eval`: the float network on an image-folder dataset, its
//! quantised model blob and JSON float sidecar, and the section 5.1
//! measures on the held-out split, float and int8 side by side.
//!
//! **Files.** `train --out model.bin` writes two files: `model.bin`, the
//! int8 `PGML` blob the core runs (docs/MODEL_FORMAT.md), and
//! `model.bin.json` ([`sidecar_path`]), the float network with its class
//! names, training parameters and split. `eval` reads both.

use super::dataset::load_dataset;
use super::eval_set::{eval_set, outputs as eval_outputs};
use super::metrics::{cmc, Det};
use super::model::{bad_model, ModelFile};
use super::plots::{add_plot, cmc_points, Curve, PlotKind, ORANGE, SHAPE_BLUE};
use super::quant::{int_outputs, int_scores, model_error, score_sets};
use super::rules::{evaluate, ranked, Evaluation};
use crate::error::{HostError, Result};
use crate::summary::Summary;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

pub use super::train_cmd::{
    run_train, run_train_with, train_meta, Features, TrainCommand, TrainOptions,
};

/// The float sidecar of a model blob: `<blob>.json`.
pub fn sidecar_path(blob: &std::path::Path) -> PathBuf {
    let mut s = blob.as_os_str().to_owned();
    s.push(".json");
    PathBuf::from(s)
}

/// Options of `protogist eval`.
#[derive(Clone, Debug, PartialEq, Eq, clap::Args)]
pub struct EvalOptions {
    /// Model blob written by `protogist train` (its float sidecar
    /// `<model>.json` must be beside it).
    #[arg(long)]
    pub model: PathBuf,
    /// The dataset the model was trained on.
    #[arg(long)]
    pub dataset: PathBuf,
    /// Output directory for the plots and metrics.json.
    #[arg(long)]
    pub out: PathBuf,
    /// Print the metrics as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The measures `protogist eval` reports (rates in `[0, 1]`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EvalMetrics {
    /// Classes.
    pub classes: usize,
    /// Training images (templates) and test probes.
    pub train: usize,
    /// Test probes.
    pub test: usize,
    /// Rank-one recognition rate.
    pub ror: f64,
    /// CMC at ranks 1..=min(10, N).
    pub cmc: Vec<f64>,
    /// Equal error rate.
    pub eer: f64,
    /// Minimal half total error rate.
    pub hter_min: f64,
    /// Area under the ROC.
    pub auc: f64,
    /// Verification rate at FAR 1 %.
    pub vr_far_1: f64,
    /// Verification rate at FAR 0.1 %.
    pub vr_far_01: f64,
}

impl EvalMetrics {
    /// The measures of one evaluation.
    ///
    /// # Errors
    /// [`ClassifyError`](super::ClassifyError) for empty score sets.
    pub fn of(ev: &Evaluation, train: usize) -> Result<(Self, Vec<f64>, Det)> {
        let n = ev.classes;
        let rates = cmc(&ev.ranks, n)?;
        let det = Det::sweep(&ev.genuine, &ev.impostor)?;
        let m = Self {
            classes: n,
            train,
            test: ev.ranks.len(),
            ror: rates[0],
            cmc: rates.iter().take(10).copied().collect(),
            eer: det.eer(),
            hter_min: det.hter_min().0,
            auc: det.auc(),
            vr_far_1: det.verification_rate_at(0.01)?,
            vr_far_01: det.verification_rate_at(0.001)?,
        };
        Ok((m, rates, det))
    }
}

/// What `protogist eval --json` prints and writes to `metrics.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EvalReport {
    /// The float network.
    pub float: EvalMetrics,
    /// The int8 blob, run by the core.
    pub int8: EvalMetrics,
    /// Fraction of test probes whose rank-1 class is the same for both.
    pub top1_agreement: f64,
    /// Bytes of the blob.
    pub model_bytes: usize,
    /// Integer inferences (`mlp::forward`) per second on one host thread,
    /// over the test probes for at least 0.3 s.
    pub int8_inferences_per_s: f64,
}

/// Reads and parses a model blob and its float sidecar.
///
/// # Errors
/// I/O errors, a malformed blob or sidecar.
pub fn load_models(path: &std::path::Path) -> Result<(Vec<u8>, ModelFile)> {
    let blob = std::fs::read(path).map_err(|e| HostError::io(path, e))?;
    let kind = super::model::ModelKind::of(&blob);
    if kind != super::model::ModelKind::Blob {
        return Err(bad_model(
            path,
            format!(
                "is {}, not a protogist model blob (--model takes the int8 PGML blob written by `protogist train`, its JSON float sidecar beside it)",
                kind.describe()
            ),
        ));
    }
    protogist::mlp::Model::parse(&blob).map_err(|e| bad_model(path, model_error(e)))?;
    let side = sidecar_path(path);
    let text = std::fs::read(&side).map_err(|e| HostError::io(&side, e))?;
    let model: ModelFile = super::model::parse_sidecar(&text, &side)?;
    if let Some(crc) = model.blob_crc32 {
        let got = protogist::mlp::blob::crc32(&blob);
        if got != crc {
            return Err(bad_model(
                path,
                format!(
                    "the blob (CRC-32 {got:#010x}) is not the one its sidecar {} was written with ({crc:#010x}): the two files come from different runs",
                    side.display()
                ),
            ));
        }
    }
    Ok((blob, model))
}

/// `protogist eval`.
///
/// # Errors
/// A missing or malformed model, a dataset that does not match it, I/O.
pub fn run_eval(opts: &EvalOptions) -> Result<Summary> {
    let (report, json) = evaluate_model(opts)?;
    Ok(eval_summary(opts, &report, json))
}

/// The work of `protogist eval`: the report (also written, with the plots,
/// to `--out`) and its JSON.
///
/// # Errors
/// As [`run_eval`].
pub fn evaluate_model(opts: &EvalOptions) -> Result<(EvalReport, String)> {
    let (blob, model) = load_models(&opts.model)?;
    let side = sidecar_path(&opts.model);
    let net = model.network(&side)?;
    let qm =
        protogist::mlp::Model::parse(&blob).map_err(|e| bad_model(&opts.model, model_error(e)))?;
    // `eval` reads image-folder datasets of shape vectors: a model of another
    // input kind (an `experiment` blob) is refused.
    qm.expect_input(protogist::mlp::InputKind::Shape)
        .map_err(super::ClassifyError::from)?;
    let names: Vec<&str> = (0..qm.classes()).filter_map(|c| qm.class_name(c)).collect();
    if names != model.classes || qm.hidden() != model.hidden {
        return Err(bad_model(
            &opts.model,
            format!(
                "the blob does not match its float sidecar {}",
                side.display()
            ),
        ));
    }
    let ds = load_dataset(&opts.dataset)?;
    let set = eval_set(&ds, &model, &net, &opts.dataset, &side)?;
    let n = model.classes.len();
    let test_out = eval_outputs(&net, &ds, &set.probes);
    let test_y = set.labels.clone();
    let templates = set.templates.clone();
    let ev = evaluate(&templates, &test_out, &test_y)?;
    let (fm, f_rates, f_det) = EvalMetrics::of(&ev, set.train)?;
    // The int8 network on the same probes, with the blob's templates.
    let test_raw: Vec<Vec<i16>> = set
        .probes
        .iter()
        .map(|&i| ds.samples[i].shape.clone())
        .collect();
    let int_s = int_scores(&qm, &int_outputs(&qm, &test_raw)?)?;
    let iev = score_sets(&int_s, &test_y);
    let (im, i_rates, i_det) = EvalMetrics::of(&iev, set.train)?;
    let agree = test_out
        .iter()
        .zip(&int_s)
        .filter(|(f, i)| {
            let fs = templates.scores(f).unwrap_or_default();
            let is: Vec<f64> = i.iter().map(|&v| f64::from(v)).collect();
            ranked(&fs).first() == ranked(&is).first()
        })
        .count();
    let report = EvalReport {
        float: fm,
        int8: im,
        top1_agreement: agree as f64 / test_out.len() as f64,
        model_bytes: blob.len(),
        int8_inferences_per_s: inferences_per_s(&qm, &test_raw)?,
    };
    let curves = |f: Vec<(f64, f64)>, i: Vec<(f64, f64)>| {
        vec![
            Curve {
                label: "float model".into(),
                points: f,
                colour: SHAPE_BLUE,
                dashed: false,
            },
            Curve {
                label: "int8 model".into(),
                points: i,
                colour: ORANGE,
                dashed: true,
            },
        ]
    };
    let det_pts = |d: &Det| d.points().iter().map(|p| (p.far, p.frr)).collect();
    let mut files = crate::output::Output::dir(&opts.out);
    for (name, kind, c) in [
        (
            "cmc",
            PlotKind::Cmc { classes: n },
            curves(cmc_points(&f_rates), cmc_points(&i_rates)),
        ),
        (
            "det",
            PlotKind::Det,
            curves(det_pts(&f_det), det_pts(&i_det)),
        ),
        ("roc", PlotKind::Roc, curves(f_det.roc(), i_det.roc())),
    ] {
        add_plot(&mut files, name, kind, &c, (480, 360))?;
    }
    let json =
        serde_json::to_string_pretty(&report).map_err(|e| bad_model(&opts.model, e.to_string()))?;
    files.add("metrics.json", json.clone().into_bytes());
    // Plots and metrics are one result: all or nothing.
    files.commit()?;
    Ok((report, json))
}

/// Single-thread `mlp::forward` rate over `inputs` (repeated for at least
/// 0.3 s).
fn inferences_per_s(model: &protogist::mlp::Model<'_>, inputs: &[Vec<i16>]) -> Result<f64> {
    use protogist::mlp::{forward, hidden_len, output_len, packed_len, Scratch};
    let (d, h, k) = (model.inputs(), model.hidden(), model.classes());
    let elems: Vec<_> = inputs
        .iter()
        .map(|r| super::quant::shape_elems(r))
        .collect();
    let (mut xi, mut hi, mut yo) = (
        vec![0u32; packed_len(d, h)],
        vec![0u8; hidden_len(h)],
        vec![0u16; output_len(k)],
    );
    let start = Instant::now();
    let mut runs = 0u64;
    while runs == 0 || start.elapsed().as_secs_f64() < 0.3 {
        for e in &elems {
            let mut s = Scratch {
                input: &mut xi,
                hidden: &mut hi,
                output: &mut yo,
            };
            std::hint::black_box(forward(model, e, &mut s).map_err(super::ClassifyError::from)?);
            runs += 1;
        }
        if elems.is_empty() {
            break;
        }
    }
    Ok(runs as f64 / start.elapsed().as_secs_f64().max(1e-9))
}

fn eval_summary(opts: &EvalOptions, r: &EvalReport, json: String) -> Summary {
    let pc = |r: f64| format!("{:.1} %", 100.0 * r);
    let both = |f: f64, i: f64| format!("{:>7} | {:>7}", pc(f), pc(i));
    let (f, i) = (&r.float, &r.int8);
    let mut s = Summary::new(format!(
        "protogist eval: {} on {}",
        opts.model.display(),
        opts.dataset.display()
    ));
    s.push("classes", f.classes);
    s.push(
        "probes",
        format!(
            "{} test, templates from {} training images",
            f.test, f.train
        ),
    );
    s.push("measure", format!("{:>7} | {:>7}", "float", "int8"));
    s.push("ROR", both(f.ror, i.ror));
    let cmc = |m: &EvalMetrics| {
        m.cmc
            .iter()
            .map(|&r| format!("{:.1}", 100.0 * r))
            .collect::<Vec<_>>()
            .join(" ")
    };
    s.push("CMC 1.. float", cmc(f));
    s.push("CMC 1.. int8", cmc(i));
    s.push("EER", both(f.eer, i.eer));
    s.push("HTER_min", both(f.hter_min, i.hter_min));
    s.push("AUC", both(f.auc, i.auc));
    s.push("VR @ FAR 1 %", both(f.vr_far_1, i.vr_far_1));
    s.push("VR @ FAR 0.1 %", both(f.vr_far_01, i.vr_far_01));
    s.push("top-1 agreement", pc(r.top1_agreement));
    s.push("model", format!("{} B int8", r.model_bytes));
    s.push(
        "int8 inferences/s",
        format!("{:.0} (one thread)", r.int8_inferences_per_s),
    );
    s.push("plots", opts.out.display());
    if opts.json {
        s.raw = Some(json);
    }
    s
}
