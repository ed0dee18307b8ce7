//! The per-class symmetry of a model (blob version 2,
//! docs/MODEL_FORMAT.md): derived by `protogist train` and `quantize`
//! after quantisation from the class's clean held-out silhouettes (the
//! split `train` kept out; [`symmetry_samples`]), and by
//! `protogist model-symmetry` for an existing model without retraining.

use super::dataset::{load_dataset, Sample};
use super::model::{bad_model, parse_sidecar};
use super::model_cmd::sidecar_path;
use super::quant::model_error;
use super::symmetry::{mirror_agreement, with_symmetry, Agreement, SYMMETRY_MIN_RATIO};
use crate::error::{HostError, Result};
use crate::summary::Summary;
use protogist::mlp::Model;
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
    let model = Model::parse(blob).map_err(super::ClassifyError::from)?;
    let inputs: Vec<Vec<i16>> = samples.iter().map(|s| s.shape.clone()).collect();
    let labels: Vec<usize> = samples.iter().map(|s| s.label).collect();
    let rates = mirror_agreement(&model, &inputs, &labels)?;
    let flags: Vec<u8> = rates.iter().map(|a| a.symmetry().bits()).collect();
    Ok((with_symmetry(blob, &flags)?, rates))
}

/// Where the silhouettes of [`symmetry_samples`] come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SymmetrySource {
    /// The held-out split: silhouettes the network was not trained on.
    HeldOut,
    /// The training split (the held-out one misses a class).
    Training,
    /// Every silhouette of the dataset (no split known).
    All,
}

impl SymmetrySource {
    /// For summaries.
    #[must_use]
    pub const fn describe(self) -> &'static str {
        match self {
            Self::HeldOut => "held out",
            Self::Training => "the training split: the held-out split misses a class",
            Self::All => "the whole dataset: no split known",
        }
    }
}

/// The silhouettes the symmetry is measured on: the held-out ones when
/// every one of the `classes` classes has one, else the training ones.
///
/// Held-out first because the network has memorised its training
/// silhouettes but not their mirror images, which it never saw: on the
/// shipped model's training split it names circles right 80.2 % of the
/// time and their mirror images 64.8 / 62.6 % (V / H), on the held-out
/// split 68 % all three (docs/CLASSIFY.md, "The mirror check").
pub fn symmetry_samples<'a>(
    held_out: Vec<&'a Sample>,
    training: Vec<&'a Sample>,
    classes: usize,
) -> (Vec<&'a Sample>, SymmetrySource) {
    let mut seen = vec![false; classes];
    for s in &held_out {
        if let Some(v) = seen.get_mut(s.label) {
            *v = true;
        }
    }
    if classes > 0 && seen.iter().all(|&v| v) {
        (held_out, SymmetrySource::HeldOut)
    } else {
        (training, SymmetrySource::Training)
    }
}

/// One summary value: `V H` flags and the rates of every class:
/// unmirrored, mirrored V, mirrored H.
pub fn describe(model: &Model<'_>, rates: &[Agreement]) -> String {
    let names: Vec<String> = (0..rates.len())
        .map(|c| model.class_name(c).unwrap_or("?").to_string())
        .collect();
    describe_rates(&names, rates)
}

/// [`describe`] with the class names given (`?` past their end).
pub fn describe_rates(names: &[String], rates: &[Agreement]) -> String {
    rates
        .iter()
        .enumerate()
        .map(|(c, a)| {
            let s = a.symmetry();
            let name = names.get(c).map_or("?", String::as_str);
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
    /// beside it, its held-out split (or, when that misses a class, its
    /// training split), as `train` chooses.
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
    // With the float sidecar beside the model, its split: the held-out
    // silhouettes first (`symmetry_samples`).
    let sidecar = sidecar_path(&opts.model);
    let split = match std::fs::read(&sidecar) {
        Ok(bytes) => {
            let f = parse_sidecar(&bytes, &sidecar)?;
            let keys = |k: Vec<String>| k.into_iter().collect::<HashSet<String>>();
            Some((keys(f.test), keys(f.train)))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
        Err(e) => return Err(HostError::io(&sidecar, e)),
    };
    let (samples, source) = match &split {
        Some((test, train)) => {
            let of = |keys: &HashSet<String>| -> Vec<&Sample> {
                ds.samples
                    .iter()
                    .filter(|s| keys.contains(&s.key))
                    .collect()
            };
            symmetry_samples(of(test), of(train), ds.classes.len())
        }
        None => (ds.samples.iter().collect(), SymmetrySource::All),
    };
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
        format!("{} ({})", samples.len(), source.describe()),
    );
    s.push(
        format!(
            "symmetry (named as the class: unmirrored: mirrored V/H; V, H when ≥ {SYMMETRY_MIN_RATIO} × unmirrored)"
        ),
        describe(&model, &rates),
    );
    s.push("wrote", format!("{} ({} B)", opts.out.display(), out.len()));
    Ok(s)
}
