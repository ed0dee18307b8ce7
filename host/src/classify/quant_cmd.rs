//! `protogist quantize`: the int8 blob of a float model, and optionally a
//! Rust source file holding it as a `static` byte array for firmware.
//!
//! `--model` is either a float model (the JSON sidecar `train` writes, with
//! `--dataset` for calibration, templates and Δ on its training split) or
//! an existing blob (checked, then re-emitted as is). From the sidecar and
//! the same dataset it rebuilds the blob `train` wrote, bit for bit (for a
//! model trained `--through-pipeline`, by rendering and segmenting the
//! training silhouettes' scenes again).

use super::dataset::load_dataset;
use super::model::{bad_model, parse_sidecar, ModelKind};
use super::quant::{emit_rust, model_error, quantize};
use crate::error::{HostError, Result};
use crate::output::ensure_dir;
use crate::output::Output;
use crate::summary::Summary;
use protogist::mlp::Model;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// Options of `protogist quantize`.
#[derive(Clone, Debug, PartialEq, Eq, clap::Args)]
pub struct QuantizeOptions {
    /// A float model (`model.bin.json`) or an int8 blob (`model.bin`).
    #[arg(long)]
    pub model: PathBuf,
    /// The dataset the float model was trained on (calibration, templates,
    /// Δ); not needed for a blob.
    #[arg(long)]
    pub dataset: Option<PathBuf>,
    /// Blob to write.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Rust source to write: `pub static MODEL: [u8; N]`.
    #[arg(long)]
    pub emit_rust: Option<PathBuf>,
}

/// Adds `bytes` as `path` to `out`, creating its folder.
fn add_file(out: &mut Output, path: &Path, bytes: Vec<u8>) -> Result<()> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        ensure_dir(parent)?;
    }
    out.add(path, bytes);
    Ok(())
}

/// `protogist quantize`.
///
/// # Errors
/// Neither `--out` nor `--emit-rust`; a malformed model; a float model
/// without `--dataset`; dataset and I/O errors.
pub fn run_quantize(opts: &QuantizeOptions) -> Result<Summary> {
    if opts.out.is_none() && opts.emit_rust.is_none() {
        return Err(HostError::InvalidArgument {
            name: "out",
            reason: "give --out, --emit-rust or both".into(),
        });
    }
    let bytes = std::fs::read(&opts.model).map_err(|e| HostError::io(&opts.model, e))?;
    let kind = ModelKind::of(&bytes);
    let blob = if kind == ModelKind::Blob {
        Model::parse(&bytes).map_err(|e| bad_model(&opts.model, model_error(e)))?;
        bytes
    } else if kind == ModelKind::Sidecar {
        let file = parse_sidecar(&bytes, &opts.model)?;
        let net = file.network(&opts.model)?;
        let dir = opts.dataset.as_ref().ok_or(HostError::InvalidArgument {
            name: "dataset",
            reason: "a float model needs its training dataset".into(),
        })?;
        let ds = load_dataset(dir)?;
        if ds.classes != file.classes {
            return Err(HostError::Dataset {
                path: dir.clone(),
                reason: "its classes are not the model's".into(),
            });
        }
        let train: HashSet<&str> = file.train.iter().map(String::as_str).collect();
        let calib: Vec<super::dataset::Sample> = match &file.pipeline {
            // Trained on pipeline masks: the same scenes again.
            Some(rec) => {
                let is_test: Vec<bool> = ds
                    .samples
                    .iter()
                    .map(|s| !train.contains(s.key.as_str()))
                    .collect();
                super::pipeline_data::training_samples(dir, &ds, &is_test, rec, file.seed, true)?.0
            }
            None => ds
                .samples
                .iter()
                .filter(|s| train.contains(s.key.as_str()))
                .cloned()
                .collect(),
        };
        // As `train`: the mirror images too, when it trained on them.
        let calib = if file.mirror_images {
            super::mirror_images::add_mirror_images(&ds.samples, &calib, ds.classes.len())?.0
        } else {
            calib
        };
        let (calib, labels): (Vec<Vec<i16>>, Vec<usize>) =
            calib.into_iter().map(|s| (s.shape, s.label)).unzip();
        let meta = super::model_cmd::train_meta(&file, dir);
        let blob = quantize(&net, &calib, &labels, &file.classes, &meta)?;
        // As `train`: the symmetry from the clean held-out silhouettes.
        let test: HashSet<&str> = file.test.iter().map(String::as_str).collect();
        let of = |keys: &HashSet<&str>| -> Vec<&super::dataset::Sample> {
            ds.samples
                .iter()
                .filter(|s| keys.contains(s.key.as_str()))
                .collect()
        };
        let (clean, _) =
            super::symmetry_cmd::symmetry_samples(of(&test), of(&train), ds.classes.len());
        super::symmetry_cmd::add_symmetry(&blob, &clean)?.0
    } else {
        return Err(bad_model(
            &opts.model,
            format!(
                "is {}; --model takes an int8 PGML blob (model.bin) or its JSON float sidecar (model.bin.json)",
                kind.describe()
            ),
        ));
    };
    let model = Model::parse(&blob).map_err(|e| bad_model(&opts.model, model_error(e)))?;
    let mut s = Summary::new(format!("protogist quantize: {}", opts.model.display()));
    s.push(
        "network",
        format!(
            "{}-{}-{} int8, {} classes",
            model.inputs(),
            model.hidden(),
            model.classes(),
            model.classes()
        ),
    );
    s.push("blob", format!("{} B", blob.len()));
    // The blob and the Rust source are one result: both or neither.
    let mut files = Output::files();
    if let Some(out) = &opts.out {
        add_file(&mut files, out, blob.clone())?;
        s.push("wrote", out.display());
    }
    if let Some(rs) = &opts.emit_rust {
        let what = format!("{} ({})", opts.model.display(), model.meta());
        add_file(&mut files, rs, emit_rust(&blob, &what).into_bytes())?;
        s.push("wrote", rs.display());
    }
    files.commit()?;
    Ok(s)
}
