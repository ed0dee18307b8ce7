//! The JSON model file of `protogist train`: the float network, its class
//! names, its training parameters and its split.

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
}

pub(crate) fn bad_model(path: &Path, reason: impl Into<String>) -> HostError {
    HostError::BadModel {
        path: path.to_path_buf(),
        reason: reason.into(),
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
