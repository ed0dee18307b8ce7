//! The JSON model file of `protogist train`: the float network, its class
//! names, its training parameters and its split.
//!
//! Weights are `f64` and read back bit-exact (`serde_json` is built with
//! `float_roundtrip`; its default parser may be off by one ulp).

use super::mlp::Mlp;
use crate::error::{HostError, Result};
use ndarray::Array2;
use protogist::shape::SHAPE_LEN;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The `format` field of a model file.
pub const MODEL_FORMAT: &str = "protogist-mlp-f64";

/// The model file: the float network, its class names and its split.
/// Weights are row-major: `w1` is `hidden × inputs`, `w2` is
/// `classes × hidden`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelFile {
    /// [`MODEL_FORMAT`].
    pub format: String,
    /// Class folder names; output `c` is class `classes[c]`.
    pub classes: Vec<String>,
    /// Input length (720).
    pub inputs: usize,
    /// Hidden units.
    pub hidden: usize,
    /// γ of MSE_REG.
    pub gamma: f64,
    /// Seed of split and initialisation.
    pub seed: u64,
    /// Held-out fraction.
    pub test_fraction: f64,
    /// Epochs run.
    pub epochs: usize,
    /// Final MSE_REG and MSE on the training split.
    pub final_perf: f64,
    /// Final MSE on the training split.
    pub final_mse: f64,
    /// Training images (`class/file`).
    pub train: Vec<String>,
    /// Test images (`class/file`).
    pub test: Vec<String>,
    /// Hidden weights.
    pub w1: Vec<f64>,
    /// Hidden biases.
    pub b1: Vec<f64>,
    /// Output weights.
    pub w2: Vec<f64>,
    /// Output biases.
    pub b2: Vec<f64>,
    /// CRC-32 of the blob written with this sidecar, so that a blob and a
    /// sidecar of different runs are told apart (absent in older files).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blob_crc32: Option<u32>,
    /// The float class templates (each class's mean network output over
    /// the training split), so that `eval` can score a folder that does not
    /// hold the training images (absent in older files).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub templates: Option<Vec<Vec<f32>>>,
    /// How the training masks were made through the pipeline (`train
    /// --through-pipeline`); absent for clean silhouettes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pipeline: Option<super::pipeline_data::PipelineRecord>,
    /// Whether the training vectors of the classes with a mirror symmetry
    /// were also trained on mirrored (`train --mirror-images`); absent
    /// when not.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub mirror_images: bool,
}

pub(crate) fn bad_model(path: &Path, reason: impl Into<String>) -> HostError {
    HostError::BadModel {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// What a model file holds, told by its content (never by its name).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelKind {
    /// An int8 model blob (`PGML` magic, docs/MODEL_FORMAT.md).
    Blob,
    /// A JSON object: a float sidecar, or meant to be one.
    Sidecar,
    /// An empty file.
    Empty,
    /// Neither.
    Other,
}

impl ModelKind {
    /// The kind of `bytes`.
    pub fn of(bytes: &[u8]) -> Self {
        if bytes.starts_with(&protogist::mlp::blob::MAGIC) {
            return Self::Blob;
        }
        match bytes.iter().find(|b| !b.is_ascii_whitespace()) {
            None if bytes.is_empty() => Self::Empty,
            Some(b'{') => Self::Sidecar,
            _ => Self::Other,
        }
    }

    /// What the file is, for a message.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Blob => "an int8 PGML model blob",
            Self::Sidecar => "a JSON file",
            Self::Empty => "empty",
            Self::Other => "neither a PGML model blob nor a JSON float sidecar",
        }
    }
}

/// Parses a float sidecar, after telling by its content that it is one.
///
/// # Errors
/// [`HostError::BadModel`] saying what the file is instead (a blob, empty,
/// something else) and that the JSON float sidecar written by `protogist
/// train` was expected, or where the JSON is malformed.
pub fn parse_sidecar(bytes: &[u8], path: &Path) -> Result<ModelFile> {
    match ModelKind::of(bytes) {
        ModelKind::Sidecar => serde_json::from_slice(bytes)
            .map_err(|e| bad_model(path, format!("malformed JSON float sidecar: {e}"))),
        kind => Err(bad_model(
            path,
            format!(
                "is {}; expected the JSON float sidecar written by `protogist train` (model.bin.json)",
                kind.describe()
            ),
        )),
    }
}

impl ModelFile {
    /// The network, after checking every shape.
    ///
    /// # Errors
    /// [`HostError::BadModel`] naming the first inconsistency.
    pub fn network(&self, path: &Path) -> Result<Mlp> {
        let (d, h, n) = (self.inputs, self.hidden, self.classes.len());
        if self.format != MODEL_FORMAT {
            return Err(bad_model(
                path,
                format!("format {:?}, expected {MODEL_FORMAT:?}", self.format),
            ));
        }
        if d != SHAPE_LEN || h == 0 || n == 0 {
            return Err(bad_model(path, format!("{d} inputs, {h} hidden, {n} classes; expected {SHAPE_LEN} inputs and at least 1 of each")));
        }
        for (name, v, len) in [
            ("w1", &self.w1, h * d),
            ("b1", &self.b1, h),
            ("w2", &self.w2, n * h),
            ("b2", &self.b2, n),
        ] {
            if v.len() != len {
                return Err(bad_model(
                    path,
                    format!("{name} has {} values, expected {len}", v.len()),
                ));
            }
            if v.iter().any(|x| !x.is_finite()) {
                return Err(bad_model(
                    path,
                    format!("{name} holds a NaN or infinite value"),
                ));
            }
        }
        let arr = |v: &[f64], r, c| {
            Array2::from_shape_vec((r, c), v.to_vec()).map_err(|e| bad_model(path, e.to_string()))
        };
        Ok(Mlp {
            w1: arr(&self.w1, h, d)?,
            b1: self.b1.clone().into(),
            w2: arr(&self.w2, n, h)?,
            b2: self.b2.clone().into(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(net: &Mlp) -> ModelFile {
        ModelFile {
            format: MODEL_FORMAT.into(),
            classes: (0..net.outputs()).map(|c| format!("c{c}")).collect(),
            inputs: net.inputs(),
            hidden: net.hidden(),
            gamma: 0.2,
            seed: 1,
            test_fraction: 0.5,
            epochs: 0,
            final_perf: 0.0,
            final_mse: 0.0,
            train: vec![],
            test: vec![],
            w1: net.w1.iter().copied().collect(),
            b1: net.b1.to_vec(),
            w2: net.w2.iter().copied().collect(),
            b2: net.b2.to_vec(),
            blob_crc32: None,
            templates: None,
            pipeline: None,
            mirror_images: false,
        }
    }

    #[test]
    fn json_round_trip_and_shape_checks() {
        let net = Mlp::new(SHAPE_LEN, 3, 2, 5);
        let f = file(&net);
        let back: ModelFile = serde_json::from_str(&serde_json::to_string(&f).unwrap()).unwrap();
        let p = Path::new("m.json");
        assert_eq!(back.network(p).unwrap(), net);
        let reason = |f: &ModelFile| match f.network(p) {
            Err(HostError::BadModel { reason, .. }) => reason,
            other => panic!("{other:?}"),
        };
        let mut bad = f.clone();
        bad.w1.pop();
        assert_eq!(reason(&bad), "w1 has 2159 values, expected 2160");
        let mut bad = f.clone();
        bad.b1[0] = f64::NAN;
        assert_eq!(reason(&bad), "b1 holds a NaN or infinite value");
        let mut bad = f.clone();
        bad.inputs = 10;
        assert!(reason(&bad).starts_with("10 inputs"));
        let mut bad = f;
        bad.format = "other".into();
        assert!(reason(&bad).starts_with("format \"other\""));
    }
}
