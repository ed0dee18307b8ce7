//! `protogist train` and `protogist eval`: the float network on an
//! image-folder dataset, its JSON model file, and the section 5.1
//! measures on the held-out split.

use super::dataset::{load_dataset, stratified_split, Dataset};
use super::metrics::{cmc, Det};
use super::mlp::{Mlp, GAMMA};
use super::model::{bad_model, ModelFile, MODEL_FORMAT};
use super::plots::{cmc_points, write_plot, Curve, PlotKind, SHAPE_BLUE};
use super::rules::{evaluate, Templates};
use super::train::{train, TrainParams};
use crate::error::{HostError, Result};
use crate::io::{ensure_dir, write_atomic};
use crate::summary::Summary;
use ndarray::Array2;
use protogist::shape::SHAPE_LEN;
use serde::Serialize;
use std::collections::HashSet;
use std::path::PathBuf;
use std::time::Instant;

/// Options of `protogist train`.
#[derive(Clone, Debug, PartialEq, clap::Args)]
pub struct TrainOptions {
    /// Image-folder dataset: one subfolder per class.
    #[arg(long)]
    pub dataset: PathBuf,
    /// Hidden units (the paper: 2000).
    #[arg(long, default_value_t = 2000)]
    pub hidden: usize,
    /// Maximum epochs (the paper: 1000).
    #[arg(long, default_value_t = 1000)]
    pub epochs: usize,
    /// Model file to write (JSON).
    #[arg(long)]
    pub out: PathBuf,
    /// Fraction of each class held out for testing.
    #[arg(long, default_value_t = 0.5)]
    pub test_fraction: f64,
    /// Seed of the split and of the initial weights.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Weight of the MSE in MSE_REG = γ·MSE + (1 − γ)·MSW (msereg's ratio).
    #[arg(long, default_value_t = GAMMA)]
    pub gamma: f64,
}

/// Options of `protogist eval`.
#[derive(Clone, Debug, PartialEq, Eq, clap::Args)]
pub struct EvalOptions {
    /// Model file written by `protogist train`.
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

fn inputs(ds: &Dataset, pick: impl Fn(usize) -> bool) -> (Array2<f64>, Vec<usize>) {
    let rows: Vec<usize> = (0..ds.samples.len()).filter(|&i| pick(i)).collect();
    let mut x = Array2::zeros((rows.len(), SHAPE_LEN));
    let mut labels = vec![];
    for (r, &i) in rows.iter().enumerate() {
        for (j, &v) in ds.samples[i].x.iter().enumerate() {
            x[[r, j]] = f64::from(v);
        }
        labels.push(ds.samples[i].label);
    }
    (x, labels)
}

/// `protogist train`.
///
/// # Errors
/// Bad arguments, dataset and I/O errors, all typed.
pub fn run_train(opts: &TrainOptions) -> Result<Summary> {
    let start = Instant::now();
    let arg = |name, reason: String| HostError::InvalidArgument { name, reason };
    if opts.hidden == 0 {
        return Err(HostError::ZeroDimension { name: "hidden" });
    }
    if opts.epochs == 0 {
        return Err(HostError::ZeroDimension { name: "epochs" });
    }
    if !(0.0..1.0).contains(&opts.test_fraction) {
        return Err(arg(
            "test-fraction",
            format!("{} is outside [0, 1)", opts.test_fraction),
        ));
    }
    if !(0.0..=1.0).contains(&opts.gamma) || opts.gamma == 0.0 {
        return Err(arg("gamma", format!("{} is outside (0, 1]", opts.gamma)));
    }
    let ds = load_dataset(&opts.dataset)?;
    let labels: Vec<usize> = ds.samples.iter().map(|s| s.label).collect();
    let n = ds.classes.len();
    let is_test = stratified_split(&labels, n, opts.test_fraction, opts.seed);
    let (x, y) = inputs(&ds, |i| !is_test[i]);
    let mut t = Array2::zeros((y.len(), n));
    for (r, &c) in y.iter().enumerate() {
        t[[r, c]] = 1.0;
    }
    let mut net = Mlp::new(SHAPE_LEN, opts.hidden, n, opts.seed);
    let params = TrainParams {
        epochs: opts.epochs,
        gamma: opts.gamma,
        ..TrainParams::default()
    };
    let report = train(&mut net, x.view(), t.view(), &params);
    let out = net.predict(x.view());
    let correct = out
        .rows()
        .into_iter()
        .zip(&y)
        .filter(|(row, &c)| (0..n).max_by(|&a, &b| row[a].total_cmp(&row[b])) == Some(c))
        .count();
    let keys = |test: bool| -> Vec<String> {
        ds.samples
            .iter()
            .zip(&is_test)
            .filter(|(_, &t)| t == test)
            .map(|(s, _)| s.key.clone())
            .collect()
    };
    let final_perf = *report.perf.last().unwrap_or(&f64::NAN);
    let model = ModelFile {
        format: MODEL_FORMAT.into(),
        classes: ds.classes.clone(),
        inputs: SHAPE_LEN,
        hidden: opts.hidden,
        gamma: opts.gamma,
        seed: opts.seed,
        test_fraction: opts.test_fraction,
        epochs: report.epochs_run,
        final_perf,
        final_mse: report.final_mse,
        train: keys(false),
        test: keys(true),
        w1: net.w1.iter().copied().collect(),
        b1: net.b1.to_vec(),
        w2: net.w2.iter().copied().collect(),
        b2: net.b2.to_vec(),
    };
    if let Some(parent) = opts.out.parent().filter(|p| !p.as_os_str().is_empty()) {
        ensure_dir(parent)?;
    }
    let json = serde_json::to_vec(&model).map_err(|e| bad_model(&opts.out, e.to_string()))?;
    write_atomic(&opts.out, &json)?;
    let mut s = Summary::new(format!("protogist train: {}", opts.dataset.display()));
    s.push("classes", n);
    s.push(
        "images",
        format!(
            "{} usable, {} skipped (empty or degenerate mask)",
            ds.samples.len(),
            ds.skipped
        ),
    );
    s.push(
        "split",
        format!(
            "{} train, {} test (seed {})",
            model.train.len(),
            model.test.len(),
            opts.seed
        ),
    );
    s.push(
        "network",
        format!(
            "{SHAPE_LEN}-{}-{n}, log-sigmoid, γ {}",
            opts.hidden, opts.gamma
        ),
    );
    s.push("epochs", report.epochs_run);
    s.push(
        "MSE_REG",
        format!("{:.4e} -> {final_perf:.4e}", report.initial_perf),
    );
    s.push("MSE", format!("{:.4e}", report.final_mse));
    s.push(
        "train accuracy (argmax)",
        format!("{:.1} %", 100.0 * correct as f64 / y.len().max(1) as f64),
    );
    s.push("model", opts.out.display());
    s.push("time", format!("{:.1} s", start.elapsed().as_secs_f64()));
    Ok(s)
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

/// `protogist eval`.
///
/// # Errors
/// A missing or malformed model, a dataset that does not match it, I/O.
pub fn run_eval(opts: &EvalOptions) -> Result<Summary> {
    let text = std::fs::read(&opts.model).map_err(|e| HostError::io(&opts.model, e))?;
    let model: ModelFile =
        serde_json::from_slice(&text).map_err(|e| bad_model(&opts.model, e.to_string()))?;
    let net = model.network(&opts.model)?;
    let ds = load_dataset(&opts.dataset)?;
    if ds.classes != model.classes {
        return Err(HostError::Dataset {
            path: opts.dataset.clone(),
            reason: format!(
                "its {} classes are not the model's {}",
                ds.classes.len(),
                model.classes.len()
            ),
        });
    }
    let train_set: HashSet<&str> = model.train.iter().map(String::as_str).collect();
    let test_set: HashSet<&str> = model.test.iter().map(String::as_str).collect();
    let outputs = |pick: &HashSet<&str>| {
        let (x, labels) = inputs(&ds, |i| pick.contains(ds.samples[i].key.as_str()));
        let y = net.predict(x.view());
        let v: Vec<Vec<f32>> = y
            .rows()
            .into_iter()
            .map(|r| r.iter().map(|&o| o as f32).collect())
            .collect();
        (v, labels)
    };
    let (train_out, train_y) = outputs(&train_set);
    let (test_out, test_y) = outputs(&test_set);
    if test_out.is_empty() {
        return Err(HostError::InvalidArgument {
            name: "dataset",
            reason: "none of the model's test images is in it (trained with --test-fraction 0?)"
                .into(),
        });
    }
    let n = ds.classes.len();
    let templates = Templates::from_outputs(&train_out, &train_y, n)?;
    let ev = evaluate(&templates, &test_out, &test_y)?;
    let rates = cmc(&ev.ranks, n)?;
    let det = Det::sweep(&ev.genuine, &ev.impostor)?;
    let m = EvalMetrics {
        classes: n,
        train: train_out.len(),
        test: test_out.len(),
        ror: rates[0],
        cmc: rates.iter().take(10).copied().collect(),
        eer: det.eer(),
        hter_min: det.hter_min().0,
        auc: det.auc(),
        vr_far_1: det.verification_rate_at(0.01)?,
        vr_far_01: det.verification_rate_at(0.001)?,
    };
    let curve = |points| Curve {
        points,
        colour: SHAPE_BLUE,
        dashed: false,
    };
    let det_pts = det.points().iter().map(|p| (p.far, p.frr)).collect();
    for (name, kind, c) in [
        (
            "cmc",
            PlotKind::Cmc { classes: n },
            curve(cmc_points(&rates)),
        ),
        ("det", PlotKind::Det, curve(det_pts)),
        ("roc", PlotKind::Roc, curve(det.roc())),
    ] {
        write_plot(&opts.out, name, kind, &[c], (480, 360))?;
    }
    let json =
        serde_json::to_string_pretty(&m).map_err(|e| bad_model(&opts.model, e.to_string()))?;
    write_atomic(&opts.out.join("metrics.json"), json.as_bytes())?;
    let pc = |r: f64| format!("{:.1} %", 100.0 * r);
    let mut s = Summary::new(format!(
        "protogist eval: {} on {}",
        opts.model.display(),
        opts.dataset.display()
    ));
    s.push("classes", n);
    s.push(
        "probes",
        format!(
            "{} test, templates from {} training images",
            m.test, m.train
        ),
    );
    s.push("ROR", pc(m.ror));
    s.push(
        "CMC 1..",
        m.cmc
            .iter()
            .map(|&r| format!("{:.1}", 100.0 * r))
            .collect::<Vec<_>>()
            .join(" "),
    );
    s.push("EER", pc(m.eer));
    s.push("HTER_min", pc(m.hter_min));
    s.push("AUC", pc(m.auc));
    s.push("VR @ FAR 1 %", pc(m.vr_far_1));
    s.push("VR @ FAR 0.1 %", pc(m.vr_far_01));
    s.push("plots", opts.out.display());
    if opts.json {
        s.raw = Some(json);
    }
    Ok(s)
}
