//! What `protogist eval` scores: the probes of a dataset folder and the
//! float templates they are scored against.
//!
//! * **The training dataset** (the folder holds every image the model was
//!   trained and tested on, by `class/file` key): the held-out split, with
//!   templates from the training split's outputs, as `train` made them.
//! * **Any other labelled folder** (the usual separate `test/` beside
//!   `train/`, the same class subfolders): every usable image is a probe.
//!   Its class folders are mapped to the model's classes by name (a subset
//!   is fine; a folder the model does not know is
//!   [`HostError::UnknownClass`]) and scored against the templates stored
//!   in the float sidecar.

use super::dataset::Dataset;
use super::mlp::Mlp;
use super::model::{bad_model, ModelFile};
use super::rules::Templates;
use crate::error::{HostError, Result};
use ndarray::Array2;
use protogist::shape::SHAPE_LEN;
use std::collections::HashSet;
use std::path::Path;

/// Probes and templates of one evaluation.
#[derive(Clone, Debug)]
pub struct EvalSet {
    /// Indices of the probes in the dataset's samples.
    pub probes: Vec<usize>,
    /// The probes' classes, as indices of the model's classes.
    pub labels: Vec<usize>,
    /// The float templates, one per model class.
    pub templates: Templates,
    /// Training images behind the templates.
    pub train: usize,
    /// Whether the folder is the training dataset (the held-out split).
    pub held_out: bool,
}

/// Float outputs of `net` for the samples `rows` of `ds`.
pub fn outputs(net: &Mlp, ds: &Dataset, rows: &[usize]) -> Vec<Vec<f32>> {
    let mut x = Array2::zeros((rows.len(), SHAPE_LEN));
    for (r, &i) in rows.iter().enumerate() {
        for (j, &v) in ds.samples[i].x.iter().enumerate() {
            x[[r, j]] = f64::from(v);
        }
    }
    net.predict(x.view())
        .rows()
        .into_iter()
        .map(|r| r.iter().map(|&o| o as f32).collect())
        .collect()
}

/// The evaluation of `model` (its network `net`, its sidecar at `side`)
/// on the dataset `ds` loaded from `path`.
///
/// # Errors
/// [`HostError::UnknownClass`] for a class folder the model does not know;
/// [`HostError::InvalidArgument`] when the training dataset has no
/// held-out image; [`HostError::BadModel`] when a separate folder is given
/// and the sidecar has no templates; [`HostError::Classify`].
pub fn eval_set(
    ds: &Dataset,
    model: &ModelFile,
    net: &Mlp,
    path: &Path,
    side: &Path,
) -> Result<EvalSet> {
    let keys: HashSet<&str> = ds.samples.iter().map(|s| s.key.as_str()).collect();
    let is_training = ds.classes == model.classes
        && model
            .train
            .iter()
            .chain(&model.test)
            .all(|k| keys.contains(k.as_str()));
    if is_training {
        let pick = |set: &[String]| -> Vec<usize> {
            let set: HashSet<&str> = set.iter().map(String::as_str).collect();
            (0..ds.samples.len())
                .filter(|&i| set.contains(ds.samples[i].key.as_str()))
                .collect()
        };
        let (train, test) = (pick(&model.train), pick(&model.test));
        if test.is_empty() {
            return Err(HostError::InvalidArgument {
                name: "dataset",
                reason: "it is the model's training dataset and the model holds out no image \
                         (trained with --test-fraction 0): give a separate test folder"
                    .into(),
            });
        }
        let label = |rows: &[usize]| rows.iter().map(|&i| ds.samples[i].label).collect();
        let train_y: Vec<usize> = label(&train);
        let templates =
            Templates::from_outputs(&outputs(net, ds, &train), &train_y, model.classes.len())?;
        return Ok(EvalSet {
            labels: label(&test),
            probes: test,
            templates,
            train: train.len(),
            held_out: true,
        });
    }
    // A separate folder: its classes by name.
    let mut map = Vec::with_capacity(ds.classes.len());
    for class in &ds.classes {
        let c = model
            .classes
            .iter()
            .position(|m| m == class)
            .ok_or_else(|| HostError::UnknownClass {
                path: path.join(class),
                class: class.clone(),
                known: model.classes.join(", "),
            })?;
        map.push(c);
    }
    let stored = model.templates.as_ref().ok_or_else(|| {
        bad_model(
            side,
            "it holds no class templates (written by an older `train`): evaluate on the \
             training dataset, or train again",
        )
    })?;
    if stored.len() != model.classes.len() {
        return Err(bad_model(
            side,
            format!(
                "{} templates for {} classes",
                stored.len(),
                model.classes.len()
            ),
        ));
    }
    let probes: Vec<usize> = (0..ds.samples.len()).collect();
    let labels = ds.samples.iter().map(|s| map[s.label]).collect();
    Ok(EvalSet {
        probes,
        labels,
        templates: Templates::new(stored.clone())?,
        train: model.train.len(),
        held_out: false,
    })
}
