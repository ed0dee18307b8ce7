//! `protogist train`: the float network on an image-folder dataset (clean
//! silhouettes, or the masks the pipeline segments from them, module
//! [`super::pipeline_data`]), its quantised model blob and JSON float
//! sidecar (`model_cmd`'s module docs say what they hold).

use super::dataset::{load_dataset, stratified_split, Sample};
use super::mirror_images::{add_mirror_images, MirrorImages};
use super::mlp::{Mlp, GAMMA};
use super::model::{bad_model, ModelFile, MODEL_FORMAT};
use super::model_cmd::sidecar_path;
use super::pipeline_data::{harvest_split, int8_top1, training_samples, PipelineTraining};
use super::quant::{model_error, quantize};
use super::rules::Templates;
use super::train::{train, TrainParams};
use crate::error::{HostError, Result};
use crate::output::ensure_dir;
use crate::summary::Summary;
use ndarray::Array2;
use protogist::shape::SHAPE_LEN;
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
    /// Model blob to write (int8, PGML); the float network goes to
    /// `<out>.json` beside it.
    #[arg(long)]
    pub out: PathBuf,
    /// Input features: the 720-element shape vector (the only kind).
    #[arg(long, value_enum, default_value_t = Features::Shape)]
    pub features: Features,
    /// Fraction of each class held out for testing.
    #[arg(long, default_value_t = 0.5)]
    pub test_fraction: f64,
    /// Seed of the split and of the initial weights.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Weight of the MSE in MSE_REG = γ·MSE + (1 − γ)·MSW (msereg's ratio).
    #[arg(long, default_value_t = GAMMA)]
    pub gamma: f64,
    /// Also train on the mirror images of every training vector of a class
    /// with a mirror symmetry (measured on the clean silhouettes by their
    /// nearest others, before training; module
    /// [`super::mirror_images`]).
    #[arg(long)]
    pub mirror_images: bool,
}

/// `protogist train`'s command line: [`TrainOptions`] and the pipeline
/// options.
#[derive(Clone, Debug, PartialEq, clap::Args)]
pub struct TrainCommand {
    /// Dataset, network and split.
    #[command(flatten)]
    pub train: TrainOptions,
    /// Training on the pipeline's masks.
    #[command(flatten)]
    pub pipeline: PipelineTraining,
}

/// Input features of the network.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Features {
    /// The centroidal profile of section 3.5 (720 values).
    #[default]
    Shape,
}

fn inputs(samples: &[Sample]) -> (Array2<f64>, Vec<usize>) {
    let mut x = Array2::zeros((samples.len(), SHAPE_LEN));
    let mut labels = vec![];
    for (r, s) in samples.iter().enumerate() {
        for (j, &v) in s.x.iter().enumerate() {
            x[[r, j]] = f64::from(v);
        }
        labels.push(s.label);
    }
    (x, labels)
}

/// `protogist train` on clean silhouettes.
///
/// # Errors
/// Bad arguments, dataset and I/O errors, all typed.
pub fn run_train(opts: &TrainOptions) -> Result<Summary> {
    run_train_with(opts, &PipelineTraining::default())
}

/// `protogist train`, on the pipeline's masks with
/// `pipeline.through_pipeline` (module [`super::pipeline_data`]).
///
/// # Errors
/// Bad arguments, dataset and I/O errors, a class of which no pipeline
/// mask was kept, all typed.
pub fn run_train_with(opts: &TrainOptions, pipeline: &PipelineTraining) -> Result<Summary> {
    let start = Instant::now();
    let arg = |name, reason: String| HostError::InvalidArgument { name, reason };
    if opts.hidden == 0 {
        return Err(HostError::ZeroDimension { name: "hidden" });
    }
    crate::limits::check_hidden(opts.hidden)?;
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
    let record = pipeline.record();
    if let Some(r) = &record {
        if !(1..=super::pipeline_data::MAX_VIEWS).contains(&r.views) {
            return Err(arg(
                "views",
                format!(
                    "{} is outside 1..={}",
                    r.views,
                    super::pipeline_data::MAX_VIEWS
                ),
            ));
        }
    }
    let ds = load_dataset(&opts.dataset)?;
    let labels: Vec<usize> = ds.samples.iter().map(|s| s.label).collect();
    let n = ds.classes.len();
    let is_test = stratified_split(&labels, n, opts.test_fraction, opts.seed);
    let clean_split = |test: bool| -> Vec<Sample> {
        ds.samples
            .iter()
            .zip(&is_test)
            .filter(|(_, &t)| t == test)
            .map(|(s, _)| s.clone())
            .collect()
    };
    let (clean_train, clean_test) = (clean_split(false), clean_split(true));
    let (train_set, harvests) = match &record {
        Some(r) => {
            let (set, h) = training_samples(&opts.dataset, &ds, &is_test, r, opts.seed, true)?;
            let held = harvest_split(&opts.dataset, &ds, &is_test, true, r, opts.seed, true)?;
            (set, Some((h, held)))
        }
        None => (clean_train.clone(), None),
    };
    // The mirror images of the classes with a mirror symmetry, measured
    // before training on the clean silhouettes (module
    // `super::mirror_images`).
    let (train_set, mirrored) = if opts.mirror_images {
        let (with, what) = add_mirror_images(&ds.samples, &train_set, n)?;
        (with, Some(what))
    } else {
        (train_set, None)
    };
    let (x, y) = inputs(&train_set);
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
        blob_crc32: None,
        templates: Some(train_templates(&out, &y, n)?),
        pipeline: record,
        mirror_images: opts.mirror_images,
    };
    if let Some(parent) = opts.out.parent().filter(|p| !p.as_os_str().is_empty()) {
        ensure_dir(parent)?;
    }
    let calib: Vec<Vec<i16>> = train_set.iter().map(|s| s.shape.clone()).collect();
    let blob = quantize(
        &net,
        &calib,
        &y,
        &ds.classes,
        &train_meta(&model, &opts.dataset),
    )?;
    // The symmetry of each class, from the quantised model and the class's
    // clean held-out silhouettes (docs/MODEL_FORMAT.md, version 2).
    let (sym_samples, sym_source) = super::symmetry_cmd::symmetry_samples(
        clean_test.iter().collect(),
        clean_train.iter().collect(),
        n,
    );
    let (blob, symmetry) = super::symmetry_cmd::add_symmetry(&blob, &sym_samples)?;
    let model = ModelFile {
        blob_crc32: Some(protogist::mlp::blob::crc32(&blob)),
        ..model
    };
    let json = serde_json::to_vec(&model).map_err(|e| bad_model(&opts.out, e.to_string()))?;
    // The blob and its sidecar are one result: both or neither.
    let mut files = crate::output::Output::files();
    files.add(&opts.out, blob.clone());
    files.add(sidecar_path(&opts.out), json);
    files.commit()?;
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
    if let (Some(r), Some((h, held))) = (&record, &harvests) {
        s.push(
            "pipeline masks",
            format!(
                "{} of {} training scenes ({} views per silhouette, silhouette placed in {}), {} of {} held-out scenes; trained on {} vectors{}",
                h.samples.len(),
                h.scenes,
                r.views,
                h.placed,
                held.samples.len(),
                held.scenes,
                train_set.len(),
                if r.with_clean { " with the clean silhouettes" } else { "" }
            ),
        );
    }
    if let Some(MirrorImages { rates, added }) = &mirrored {
        s.push(
            "mirror images",
            format!(
                "{added} vectors added; per class, how often the nearest other of the {} clean silhouettes is of the class, unmirrored: mirrored V/H: {}",
                ds.samples.len(),
                super::symmetry_cmd::describe_rates(&ds.classes, rates)
            ),
        );
    }
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
    let pc = |r: Option<f64>| r.map_or_else(|| "n/a".into(), |v| format!("{:.1} %", 100.0 * v));
    let qm =
        protogist::mlp::Model::parse(&blob).map_err(|e| bad_model(&opts.out, model_error(e)))?;
    s.push(
        "held-out top-1 (int8), clean silhouettes",
        pc(int8_top1(&qm, &clean_test)?),
    );
    if let Some((_, held)) = &harvests {
        s.push(
            "held-out top-1 (int8), their pipeline masks",
            pc(int8_top1(&qm, held.samples.iter().map(|(_, s)| s))?),
        );
    }
    s.push(
        format!(
            "symmetry ({} {} silhouettes named as the class: unmirrored: mirrored V/H)",
            sym_samples.len(),
            sym_source.describe()
        ),
        super::symmetry_cmd::describe(&qm, &symmetry),
    );
    s.push(
        "model",
        format!(
            "{} ({} B int8), {}",
            opts.out.display(),
            blob.len(),
            sidecar_path(&opts.out).display()
        ),
    );
    s.push("time", format!("{:.1} s", start.elapsed().as_secs_f64()));
    Ok(s)
}

/// The float templates of `train`'s sidecar: each class's mean output
/// over the training split (`outputs`, one row per image of class
/// `labels[i]`).
///
/// # Errors
/// [`ClassifyError`](super::ClassifyError) for a class without images.
fn train_templates(outputs: &Array2<f64>, labels: &[usize], n: usize) -> Result<Vec<Vec<f32>>> {
    let rows: Vec<Vec<f32>> = outputs
        .rows()
        .into_iter()
        .map(|r| r.iter().map(|&o| o as f32).collect())
        .collect();
    let t = Templates::from_outputs(&rows, labels, n)?;
    Ok((0..n)
        .map(|c| t.template(c).map(<[f32]>::to_vec).unwrap_or_default())
        .collect())
}

/// The metadata string a blob records: how `train` made it (the dataset
/// folder's name and the sidecar's parameters; `epochs` is the number run).
pub fn train_meta(model: &ModelFile, dataset: &std::path::Path) -> String {
    let name = dataset
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let through = model.pipeline.map_or_else(String::new, |p| {
        format!(
            " --through-pipeline --views {}{}",
            p.views,
            if p.with_clean { " --with-clean" } else { "" }
        )
    });
    format!(
        "protogist train --dataset {name} --features shape --hidden {} --epochs {} --test-fraction {} --seed {} --gamma {}{through}{}",
        model.hidden,
        model.epochs,
        model.test_fraction,
        model.seed,
        model.gamma,
        if model.mirror_images { " --mirror-images" } else { "" }
    )
}
