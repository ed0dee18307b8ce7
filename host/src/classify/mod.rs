//! Object categorisation, host side (paper sections 4.1, 4.3 and 5.1):
//! the classification rules over generic output vectors, the performance
//! measures, their plots and a generator of development silhouettes.
//!
//! * [`rules`]: class templates (mean output per class), cosine
//!   similarity, verification (`cos(v, v_c) >= Δ`), identification (argmax,
//!   or the unknown class `U_{N+1}` below `Δ`), ranked lists, and the score
//!   sets that the metrics take.
//! * [`metrics`]: ROR and CMC, the FAR/FRR sweep over `Δ` (DET), EER,
//!   HTER_min, verification rate at a FAR, ROC and AUC; [`probit`] is the
//!   inverse normal CDF for DET axes.
//! * [`plots`]: CMC, DET and ROC curves like the paper's Fig. 8, as PNG and
//!   SVG.
//! * [`shapes`]: seeded parametric binary silhouettes in an image-folder
//!   layout (`protogist gen-shapes`), of the [`families`].
//!
//! * [`mlp`], [`train`]: the float network of section 4.4 (two layers,
//!   log-sigmoid, `MSE_REG`) and its full-batch Rprop− training.
//! * [`dataset`]: image-folder datasets of silhouettes, their shape vectors
//!   and a seeded stratified split; [`model_cmd`]: `protogist train`
//!   ([`train_cmd`]) and `protogist eval`; [`model`]: the JSON model file;
//!   [`pipeline_data`]: training masks as core's pipeline segments them
//!   (`train --through-pipeline`).
//!
//! The rules take any output vectors (`&[Vec<f32>]`), so the 720-element
//! shape vectors themselves can also stand in for a network output (an
//! identity "network") as a baseline.
//!
//! Rates are fractions in `[0, 1]` throughout; the paper prints them in %.

pub mod dataset;
pub mod eval_set;
pub mod families;
pub mod metrics;
pub mod mirror;
pub mod mirror_images;
pub mod mlp;
pub mod model;
pub mod model_cmd;
pub mod pipeline_data;
mod plot_style;
mod plot_text;
pub mod plots;
pub mod probit;
pub mod quant;
pub mod quant_cmd;
pub mod rules;
pub mod shapes;
pub mod shipped;
pub mod symmetry;
pub mod symmetry_cmd;
pub mod train;
pub mod train_cmd;

/// Why a classification rule or a metric rejected its input.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ClassifyError {
    /// No classes (N = 0).
    #[error("there must be at least one class")]
    ZeroClasses,
    /// An input that must not be empty is.
    #[error("no {what} given")]
    Empty {
        /// What is missing (outputs, genuine scores, ...).
        what: &'static str,
    },
    /// A vector of another length than the first one (or the templates').
    #[error("vector {index} has {got} elements, expected {expected}")]
    DimensionMismatch {
        /// Position of the offending vector.
        index: usize,
        /// The expected length.
        expected: usize,
        /// Its length.
        got: usize,
    },
    /// Outputs and labels of different counts.
    #[error("{outputs} output vectors but {labels} labels")]
    LabelCount {
        /// Output vectors.
        outputs: usize,
        /// Labels.
        labels: usize,
    },
    /// A class label (or claim) not below the number of classes.
    #[error("class {label} out of range for {classes} classes")]
    LabelOutOfRange {
        /// The label.
        label: usize,
        /// Number of classes.
        classes: usize,
    },
    /// A class without any training vector: no template.
    #[error("class {class} has no training vector")]
    EmptyClass {
        /// The class.
        class: usize,
    },
    /// A NaN or infinite value.
    #[error("{what} holds a NaN or infinite value")]
    NonFinite {
        /// Where.
        what: &'static str,
    },
    /// A vector whose elements are all equal cannot be z-normalised.
    #[error("the vector has zero variance and cannot be normalised")]
    ZeroVariance,
    /// The integer network rejected its input.
    #[error("integer network: {0}")]
    Mlp(#[from] protogist::mlp::MlpError),
    /// A model blob does not parse.
    #[error("model blob: {0}")]
    Model(#[from] protogist::mlp::ModelError),
    /// A rate (FAR target, ...) outside `[0, 1]`.
    #[error("rate {0} is outside [0, 1]")]
    BadRate(f64),
}
