//! The per-class symmetry of a model (blob version 2,
//! docs/MODEL_FORMAT.md): derived by `protogist train` and `quantize`
//! after quantisation from the class's clean training silhouettes, and by
//! `protogist model-symmetry` for an existing model without retraining.

use super::dataset::{load_dataset, Sample};
use super::model::{bad_model, parse_sidecar};
use super::model_cmd::sidecar_path;
use super::quant::{mirror_agreement, model_error, with_symmetry, Agreement, SYMMETRY_MIN_RATIO};
use crate::error::{HostError, Result};
use crate::summary::Summary;
use protogist::mlp::{Model, Symmetry};
use protogist::shape::Mirror;
use std::collections::HashSet;
use std::path::PathBuf;

/// `blob` with the symmetry bytes derived from `samples` (clean
/// silhouettes with their labels) under the rule with
/// [`SYMMETRY_MIN_RATIO`], and each class's identification rates.
///
/// # Errors
/// A blob that does not parse; a class without sample; a model that does
/// not take shape vectors.
pub fn add_symmetry(blob: &[u8], samples: &[&Sample]) -> Result<(Vec<u8>, Vec<Agreement>)> {
    add_symmetry_with(blob, samples, SYMMETRY_MIN_RATIO)
}

/// [`add_symmetry`] with the rule's ratio `min_ratio`
/// ([`Agreement::symmetry`]).
///
/// # Errors
/// As [`add_symmetry`].
pub fn add_symmetry_with(
    blob: &[u8],
    samples: &[&Sample],
    min_ratio: f64,
) -> Result<(Vec<u8>, Vec<Agreement>)> {
    let model = Model::parse(blob).map_err(super::ClassifyError::from)?;
    let inputs: Vec<Vec<i16>> = samples.iter().map(|s| s.shape.clone()).collect();
    let labels: Vec<usize> = samples.iter().map(|s| s.label).collect();
    let rates = mirror_agreement(&model, &inputs, &labels)?;
    let flags: Vec<u8> = rates.iter().map(|a| a.symmetry(min_ratio).bits()).collect();
    Ok((with_symmetry(blob, &flags)?, rates))
}

/// The symmetry of one class's rates under the rule with
/// [`SYMMETRY_MIN_RATIO`].
pub fn flags_of(a: &Agreement) -> Symmetry {
    a.symmetry(SYMMETRY_MIN_RATIO)
}

/// One summary value: `V H` flags (rule ratio `min_ratio`) and the rates
/// of every class: unmirrored, mirrored V, mirrored H.
pub fn describe(model: &Model<'_>, rates: &[Agreement], min_ratio: f64) -> String {
    rates
        .iter()
        .enumerate()
        .map(|(c, a)| {
            let s = a.symmetry(min_ratio);
            let name = model.class_name(c).unwrap_or("?");
            format!(
                "{name} {}{} ({:.1}: {:.1}/{:.1} %)",
                if s.has(Mirror::Vertical) { "V" } else { "-" },
                if s.has(Mirror::Horizontal) { "H" } else { "-" },
                100.0 * a.plain,
                100.0 * a.mirrored[0],
                100.0 * a.mirrored[1]
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Options of `protogist model-symmetry`.
#[derive(Clone, Debug, PartialEq, clap::Args)]
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
    /// A mirror is flagged when the class's mirrored silhouettes are
    /// named as the class at least this many times as often as its
    /// unmirrored ones.
    #[arg(long, default_value_t = SYMMETRY_MIN_RATIO)]
    pub min_ratio: f64,
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
    let (out, rates) = add_symmetry_with(&blob, &samples, opts.min_ratio)?;
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
        format!(
            "symmetry (named as the class: unmirrored: mirrored V/H; V, H when ≥ {} × unmirrored)",
            opts.min_ratio
        ),
        describe(&model, &rates, opts.min_ratio),
    );
    s.push("wrote", format!("{} ({} B)", opts.out.display(), out.len()));
    Ok(s)
}
