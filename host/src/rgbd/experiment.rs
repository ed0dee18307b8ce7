//! `protogist experiment`: the paper's experiment (sections 4.2 to 5) on an
//! RGB-D Object Dataset folder, real or made by `gen-rgbd`.
//!
//! One network per input condition ([`Condition`]), each trained as in
//! section 4.4 (two layers, log-sigmoid, Rprop, `MSE_REG` with γ = 0.2; the
//! paper's 2000 hidden units and 1000 epochs are the defaults) on the
//! training instances, then evaluated on the test instances with the
//! rules of section 4.1 (class templates from the training outputs, cosine
//! scores): ROR, EER, AUC, HTER_min and the verification rates at FAR 1 %
//! and 0.1 %, for the float network and for its int8 blob run by the core.
//!
//! Writes to `--out`: `table1.md` and `table1.json` (Table 1's layout,
//! float and int8), `fig8_cmc`, `fig8_det` and `fig8_roc` (PNG and SVG,
//! all conditions' curves, [`super::fig8`]), and `models/<condition>.bin`
//! (the int8 blobs).

use super::features::{item_features, Condition, Features, ShapeSource};
use super::fig8::{write_fig8, Fig8Curves};
use super::loader::scan;
use crate::classify::metrics::Det;
use crate::classify::mlp::{Mlp, GAMMA};
use crate::classify::model_cmd::EvalMetrics;
use crate::classify::quant::{int_outputs, int_scores, model_error, quantize_as, score_sets};
use crate::classify::rules::{evaluate, Templates};
use crate::classify::train::{train, TrainParams};
use crate::error::{HostError, Result};
use crate::output::{ensure_dir, write_atomic};
use crate::summary::Summary;
use indicatif::{ProgressBar, ProgressStyle};
use ndarray::Array2;
use rayon::prelude::*;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// Options of `protogist experiment`.
#[derive(Clone, Debug, PartialEq, clap::Args)]
pub struct ExperimentOptions {
    /// The dataset: the `rgbd-dataset` folder or its parent.
    #[arg(long)]
    pub dataset: PathBuf,
    /// Output folder for the table, the figures and the models.
    #[arg(long)]
    pub out: PathBuf,
    /// Hidden units (the paper: 2000).
    #[arg(long, default_value_t = 2000)]
    pub hidden: usize,
    /// Rprop epochs (the paper: 1000).
    #[arg(long, default_value_t = 1000)]
    pub epochs: usize,
    /// Conditions, comma-separated (default: the paper's seven).
    #[arg(long, alias = "features", value_enum, value_delimiter = ',')]
    pub conditions: Vec<Condition>,
    /// Weight of the MSE in MSE_REG (the paper: 0.2).
    #[arg(long, default_value_t = GAMMA)]
    pub gamma: f64,
    /// Seed of the initial weights.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print the table as JSON.
    #[arg(long)]
    pub json: bool,
}

/// One condition's results.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConditionResult {
    /// The `--conditions` name.
    pub condition: String,
    /// Table 1's row label.
    pub label: String,
    /// Input length.
    pub inputs: usize,
    /// The float network.
    pub float: EvalMetrics,
    /// The int8 blob, run by the core.
    pub int8: EvalMetrics,
    /// `MSE_REG` after training.
    pub final_perf: f64,
    /// Training time, s.
    pub train_s: f64,
    /// Seconds per epoch.
    pub epoch_s: f64,
}

/// `table1.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table1 {
    /// Categories.
    pub classes: usize,
    /// Training images.
    pub train: usize,
    /// Test images.
    pub test: usize,
    /// Shape vectors from figure-ground, from the dataset mask, and none.
    pub shape_sources: [usize; 3],
    /// Mean intersection over union of the figure-ground masks with the
    /// dataset's masks (0 for a frame without figure-ground mask).
    pub mask_iou: f64,
    /// Hidden units.
    pub hidden: usize,
    /// Epochs.
    pub epochs: usize,
    /// γ.
    pub gamma: f64,
    /// One entry per condition, in the order run.
    pub conditions: Vec<ConditionResult>,
}

fn bar(len: usize, what: &str) -> ProgressBar {
    let b = ProgressBar::new(len as u64);
    b.set_style(
        ProgressStyle::with_template(&format!(
            "{what} {{bar:40}} {{pos}}/{{len}} [{{elapsed}}<{{eta}}]"
        ))
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    b
}

fn matrix(rows: &[Vec<i16>]) -> Array2<f64> {
    let d = rows.first().map_or(0, Vec::len);
    let mut x = Array2::zeros((rows.len(), d));
    x.axis_iter_mut(ndarray::Axis(0))
        .into_par_iter()
        .zip(rows)
        .for_each(|(mut row, r)| {
            for (o, &v) in row.iter_mut().zip(r) {
                *o = f64::from(v) / 4096.0;
            }
        });
    x
}

fn outputs(net: &Mlp, x: &Array2<f64>) -> Vec<Vec<f32>> {
    net.predict_blocked(x.view())
        .rows()
        .into_iter()
        .map(|r| r.iter().map(|&v| v as f32).collect())
        .collect()
}

/// Curves of one evaluation: CMC rates, DET.
type Curves = (Vec<f64>, Det);

/// Trains and evaluates one condition.
#[allow(clippy::too_many_arguments)]
fn run_condition(
    c: Condition,
    feats: &[Features],
    train_idx: &[usize],
    test_idx: &[usize],
    labels: &[usize],
    names: &[String],
    opts: &ExperimentOptions,
) -> Result<(ConditionResult, Curves, Curves, Vec<u8>)> {
    let n = names.len();
    let raw = |idx: &[usize]| -> Vec<Vec<i16>> { idx.iter().map(|&i| feats[i].input(c)).collect() };
    let (train_raw, test_raw) = (raw(train_idx), raw(test_idx));
    let (train_y, test_y): (Vec<usize>, Vec<usize>) = (
        train_idx.iter().map(|&i| labels[i]).collect(),
        test_idx.iter().map(|&i| labels[i]).collect(),
    );
    let x = matrix(&train_raw);
    let mut t = Array2::zeros((train_y.len(), n));
    for (r, &k) in train_y.iter().enumerate() {
        t[[r, k]] = 1.0;
    }
    let mut net = Mlp::new(c.input_len(), opts.hidden, n, opts.seed);
    let start = Instant::now();
    eprintln!(
        "{}: {} inputs, {} training images",
        c.name(),
        c.input_len(),
        train_y.len()
    );
    let report = train(
        &mut net,
        x.view(),
        t.view(),
        &TrainParams {
            epochs: opts.epochs,
            gamma: opts.gamma,
            ..TrainParams::default()
        },
    );
    let train_s = start.elapsed().as_secs_f64();
    let train_out = outputs(&net, &x);
    drop(x);
    let test_out = outputs(&net, &matrix(&test_raw));
    let templates = Templates::from_outputs(&train_out, &train_y, n)?;
    let ev = evaluate(&templates, &test_out, &test_y)?;
    let (fm, f_rates, f_det) = EvalMetrics::of(&ev, train_out.len())?;
    let meta = format!(
        "protogist experiment --conditions {} --hidden {} --epochs {} --gamma {} --seed {}",
        c.name(),
        opts.hidden,
        report.epochs_run,
        opts.gamma,
        opts.seed
    );
    let blob = quantize_as(&net, &train_raw, &train_y, names, &meta, c.kind())?;
    let bad = |reason: String| HostError::BadModel {
        path: opts.out.join("models"),
        reason,
    };
    let qm = protogist::mlp::Model::parse(&blob).map_err(|e| bad(model_error(e)))?;
    qm.expect_input(c.kind())
        .map_err(crate::classify::ClassifyError::from)?;
    let iev = score_sets(&int_scores(&qm, &int_outputs(&qm, &test_raw)?)?, &test_y);
    let (im, i_rates, i_det) = EvalMetrics::of(&iev, train_out.len())?;
    let r = ConditionResult {
        condition: c.name().into(),
        label: c.label().into(),
        inputs: c.input_len(),
        float: fm,
        int8: im,
        final_perf: *report.perf.last().unwrap_or(&f64::NAN),
        train_s,
        epoch_s: train_s / report.epochs_run.max(1) as f64,
    };
    Ok((r, (f_rates, f_det), (i_rates, i_det), blob))
}

/// `protogist experiment`.
///
/// # Errors
/// Bad arguments, dataset errors ([`super::RgbdError`]), I/O.
pub fn run_experiment(opts: &ExperimentOptions) -> Result<Summary> {
    let start = Instant::now();
    if opts.hidden == 0 {
        return Err(HostError::ZeroDimension { name: "hidden" });
    }
    if opts.epochs == 0 {
        return Err(HostError::ZeroDimension { name: "epochs" });
    }
    if !(opts.gamma > 0.0 && opts.gamma <= 1.0) {
        return Err(HostError::InvalidArgument {
            name: "gamma",
            reason: format!("{} is outside (0, 1]", opts.gamma),
        });
    }
    let conditions: Vec<Condition> = if opts.conditions.is_empty() {
        Condition::PAPER.to_vec()
    } else {
        let mut v = opts.conditions.clone();
        v.dedup();
        v
    };
    let index = scan(&opts.dataset)?;
    let (n_train, n_test) = index.counts();
    if n_train == 0 || n_test == 0 {
        return Err(HostError::Dataset {
            path: opts.dataset.clone(),
            reason: "needs at least two instances per category (one tests, the others train)"
                .into(),
        });
    }
    eprintln!(
        "{} categories, {} sampled frames of {}: {n_train} train, {n_test} test",
        index.categories.len(),
        index.items.len(),
        index.frames_seen
    );
    let colour3 = conditions.contains(&Condition::Colour3);
    let b = bar(index.items.len(), "features");
    let feats: Vec<Features> = index
        .items
        .par_iter()
        .map(|item| {
            let f = item_features(item, colour3);
            b.inc(1);
            f
        })
        .collect::<Result<_>>()?;
    b.finish_and_clear();
    let mut sources = [0usize; 3];
    for f in &feats {
        sources[match f.shape_source {
            ShapeSource::FigureGround => 0,
            ShapeSource::DatasetMask => 1,
            ShapeSource::None => 2,
        }] += 1;
    }
    let labels: Vec<usize> = index.items.iter().map(|i| i.category).collect();
    let train_idx: Vec<usize> = (0..feats.len()).filter(|&i| !index.items[i].test).collect();
    let test_idx: Vec<usize> = (0..feats.len()).filter(|&i| index.items[i].test).collect();
    ensure_dir(&opts.out.join("models"))?;
    let mut results = vec![];
    let mut curves = Fig8Curves::default();
    for &c in &conditions {
        let (r, fc, ic, blob) = run_condition(
            c,
            &feats,
            &train_idx,
            &test_idx,
            &labels,
            &index.categories,
            opts,
        )?;
        write_atomic(&opts.out.join(format!("models/{}.bin", c.name())), &blob)?;
        curves.float.push((c, fc.0, fc.1));
        curves.int8.push((c, ic.0, ic.1));
        results.push(r);
    }
    let table = Table1 {
        classes: index.categories.len(),
        train: n_train,
        test: n_test,
        shape_sources: sources,
        mask_iou: feats.iter().map(|f| f64::from(f.mask_iou)).sum::<f64>()
            / feats.len().max(1) as f64,
        hidden: opts.hidden,
        epochs: opts.epochs,
        gamma: opts.gamma,
        conditions: results,
    };
    let json = serde_json::to_string_pretty(&table).map_err(|e| HostError::InvalidArgument {
        name: "json",
        reason: e.to_string(),
    })?;
    write_atomic(&opts.out.join("table1.json"), json.as_bytes())?;
    write_atomic(
        &opts.out.join("table1.md"),
        table1_markdown(&table).as_bytes(),
    )?;
    write_fig8(&opts.out, &curves)?;
    let mut s = Summary::new(format!("protogist experiment: {}", index.root.display()));
    s.push("categories", table.classes);
    s.push("images", format!("{n_train} train, {n_test} test"));
    s.push(
        "shape vectors",
        format!(
            "{} figure-ground (mean IoU with the dataset mask {:.2}), {} dataset mask, {} none",
            sources[0], table.mask_iou, sources[1], sources[2]
        ),
    );
    for r in &table.conditions {
        s.push(
            r.condition.clone(),
            format!(
                "ROR {:.1} % | {:.1} % int8, EER {:.1} %, {:.2} s/epoch",
                100.0 * r.float.ror,
                100.0 * r.int8.ror,
                100.0 * r.float.eer,
                r.epoch_s
            ),
        );
    }
    s.push("out", opts.out.display());
    s.push("time", format!("{:.1} s", start.elapsed().as_secs_f64()));
    if opts.json {
        s.raw = Some(json);
    }
    Ok(s)
}

/// Table 1 as Markdown: one table for the float networks and one for the
/// int8 blobs, each in the paper's layout, the best value of each column
/// in bold.
pub fn table1_markdown(t: &Table1) -> String {
    let mut s = format!(
        "# Table 1: {} categories, {} training and {} test images\n\n\
         Networks: 2 layers, log-sigmoid, {} hidden units, Rprop, {} epochs, MSE_REG γ = {}.\n\
         Shape vectors: {} from figure-ground (mean IoU with the dataset's mask {:.2}), {} from the dataset's mask, {} none.\n",
        t.classes,
        t.train,
        t.test,
        t.hidden,
        t.epochs,
        t.gamma,
        t.shape_sources[0],
        t.mask_iou,
        t.shape_sources[1],
        t.shape_sources[2]
    );
    type Pick = fn(&EvalMetrics) -> f64;
    let cols: [(Pick, bool); 6] = [
        (|m| m.ror, true),
        (|m| m.eer, false),
        (|m| m.auc, true),
        (|m| m.hter_min, false),
        (|m| m.vr_far_1, true),
        (|m| m.vr_far_01, true),
    ];
    for (title, pick) in [
        (
            "Float network",
            (|r: &ConditionResult| &r.float) as fn(&ConditionResult) -> &EvalMetrics,
        ),
        ("int8 network (core)", |r: &ConditionResult| &r.int8),
    ] {
        s.push_str(&format!(
            "\n## {title}\n\n| Data type | ROR % | EER % | AUC % | HTER_min % | FAR 1 % | FAR 0.1 % |\n|---|---|---|---|---|---|---|\n"
        ));
        let best: Vec<f64> = cols
            .iter()
            .map(|&(f, high)| {
                let v = t.conditions.iter().map(|r| f(pick(r)));
                if high {
                    v.fold(f64::NEG_INFINITY, f64::max)
                } else {
                    v.fold(f64::INFINITY, f64::min)
                }
            })
            .collect();
        for r in &t.conditions {
            s.push_str(&format!("| {} |", r.label));
            for (&(f, _), &b) in cols.iter().zip(&best) {
                let v = f(pick(r));
                let cell = format!("{:.1}", 100.0 * v);
                if t.conditions.len() > 1 && (v - b).abs() < 1e-12 {
                    s.push_str(&format!(" **{cell}** |"));
                } else {
                    s.push_str(&format!(" {cell} |"));
                }
            }
            s.push('\n');
        }
    }
    s
}
