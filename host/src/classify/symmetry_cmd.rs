//! The per-class symmetry of a model (blob version 2,
//! docs/MODEL_FORMAT.md): derived by `protogist train` and `quantize`
//! after quantisation from the class's clean training silhouettes, and by
//! `protogist model-symmetry` for an existing model without retraining.

use super::dataset::{load_dataset, Sample};
use super::model::{bad_model, parse_sidecar};
use super::model_cmd::sidecar_path;
use super::quant::{mirror_agreement, model_error, with_symmetry, SYMMETRY_MIN_AGREEMENT};
use crate::error::{HostError, Result};
use crate::summary::Summary;
use protogist::mlp::{Model, Symmetry};
use protogist::shape::Mirror;
use std::collections::HashSet;
use std::path::PathBuf;

/// `blob` with the symmetry bytes derived from `samples` (clean
/// silhouettes with their labels), and each class's agreement per mirror
/// ([`Mirror::ALL`] order).
///
/// # Errors
/// A blob that does not parse; a class without sample; a model that does
/// not take shape vectors.
pub fn add_symmetry(blob: &[u8], samples: &[&Sample]) -> Result<(Vec<u8>, Vec<[f64; 2]>)> {
    let model = Model::parse(blob).map_err(super::ClassifyError::from)?;
    let inputs: Vec<Vec<i16>> = samples.iter().map(|s| s.shape.clone()).collect();
    let labels: Vec<usize> = samples.iter().map(|s| s.label).collect();
    let rates = mirror_agreement(&model, &inputs, &labels)?;
    let flags: Vec<u8> = rates.iter().map(|r| flags_of(r).bits()).collect();
    Ok((with_symmetry(blob, &flags)?, rates))
}

/// The symmetry of one class's agreements.
pub fn flags_of(rates: &[f64; 2]) -> Symmetry {
    Mirror::ALL
        .into_iter()
        .zip(rates)
        .filter(|&(_, &r)| r >= SYMMETRY_MIN_AGREEMENT)
        .fold(Symmetry::NONE, |s, (m, _)| s.with(m))
}

/// One summary value: `V H` flags and the agreements of every class.
pub fn describe(model: &Model<'_>, rates: &[[f64; 2]]) -> String {
    rates
        .iter()
        .enumerate()
        .map(|(c, r)| {
            let s = flags_of(r);
            let name = model.class_name(c).unwrap_or("?");
            format!(
                "{name} {}{} ({:.1}/{:.1} %)",
                if s.has(Mirror::Vertical) { "V" } else { "-" },
                if s.has(Mirror::Horizontal) { "H" } else { "-" },
                100.0 * r[0],
                100.0 * r[1]
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Options of `protogist model-symmetry`.
#[derive(Clone, Debug, PartialEq, Eq, clap::Args)]
pub struct ModelSymmetryOptions {
    /// The int8 model blob (version 1 or 2).
    #[arg(long)]
    pub model: PathBuf,
    /// The dataset of clean silhouettes it was trained on (its classes in
    /// the model's order); with the model's float sidecar (`<model>.json`)
    /// beside it, only its training split is used.
    #[arg(long)]
    pub dataset: PathBuf,
    /// The version-2 blob to write.
    #[arg(long)]
    pub out: PathBuf,
}

/// `protogist model-symmetry`: the model with symmetry bytes derived as
/// `train` derives them, without retraining.
///
/// # Errors
/// A malformed model, a dataset whose classes are not the model's, I/O.
pub fn run_model_symmetry(opts: &ModelSymmetryOptions) -> Result<Summary> {
    let blob = std::fs::read(&opts.model).map_err(|e| HostError::io(&opts.model, e))?;
    let model = Model::parse(&blob).map_err(|e| bad_model(&opts.model, model_error(e)))?;
    let ds = load_dataset(&opts.dataset)?;
    let names: Vec<String> = (0..model.classes())
        .map(|c| model.class_name(c).unwrap_or("").to_string())
        .collect();
    if ds.classes != names {
        return Err(HostError::Dataset {
            path: opts.dataset.clone(),
            reason: "its classes are not the model's".into(),
        });
    }
    let sidecar = sidecar_path(&opts.model);
    let train: Option<HashSet<String>> = match std::fs::read(&sidecar) {
        Ok(bytes) => Some(parse_sidecar(&bytes, &sidecar)?.train.into_iter().collect()),
        Err(_) => None,
    };
    let samples: Vec<&Sample> = ds
        .samples
        .iter()
        .filter(|s| train.as_ref().is_none_or(|t| t.contains(&s.key)))
        .collect();
    let (out, rates) = add_symmetry(&blob, &samples)?;
    if let Some(parent) = opts.out.parent().filter(|p| !p.as_os_str().is_empty()) {
        crate::output::ensure_dir(parent)?;
    }
    let mut files = crate::output::Output::files();
    files.add(&opts.out, out.clone());
    files.commit()?;
    let mut s = Summary::new(format!(
        "protogist model-symmetry: {}",
        opts.model.display()
    ));
    s.push(
        "silhouettes",
        format!(
            "{} ({})",
            samples.len(),
            if train.is_some() {
                "the sidecar's training split"
            } else {
                "the whole dataset: no sidecar"
            }
        ),
    );
    s.push(
        "symmetry (V, H: named as the class when mirrored)",
        describe(&model, &rates),
    );
    s.push("wrote", format!("{} ({} B)", opts.out.display(), out.len()));
    Ok(s)
}
