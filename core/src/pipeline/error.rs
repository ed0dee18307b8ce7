//! Why a pipeline could not be set up or run.

use crate::complete::CompleteError;
use crate::conspicuity::ConspicuityError;
use crate::image::ImageError;
use crate::mlp::{MlpError, ModelError};
use crate::segment::SegmentError;
use crate::shape::ShapeError;
use crate::stereo::{StereoError, TableError};
use core::fmt;

/// The two parts of a split workspace ([`Pipeline::run_split`](super::Pipeline::run_split)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Region {
    /// The maps kept for the result ([`kept_words`](super::kept_words)).
    Kept,
    /// The region the stages share ([`shared_words`](super::shared_words)).
    Shared,
}

impl fmt::Display for Region {
    /// The part's name in messages: `kept maps` or `shared region`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Kept => "kept maps",
            Self::Shared => "shared region",
        })
    }
}

/// Why a pipeline could not be set up or run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum PipelineError {
    /// A parameter is out of range; what is wrong.
    BadParams(&'static str),
    /// The decoder tables are not one per stereo level.
    TableCount {
        /// Tables the operating point needs.
        expected: usize,
        /// Tables given.
        got: usize,
    },
    /// A decoder table is corrupt.
    Table(TableError),
    /// The model blob is corrupt.
    Model(ModelError),
    /// The model does not fit the pipeline: its inputs are not the shape
    /// vector's, or it is larger than [`PipelineParams::model`](super::PipelineParams::model).
    ModelMismatch {
        /// What does not fit: `"inputs"`, `"hidden"` or `"classes"`.
        what: &'static str,
        /// The largest (or, for inputs, the only) value the pipeline takes.
        expected: usize,
        /// The model's.
        got: usize,
    },
    /// The workspace is smaller than [`workspace_bytes`](super::workspace_bytes).
    WorkspaceTooSmall {
        /// Bytes needed.
        needed: usize,
        /// Bytes given.
        got: usize,
    },
    /// One part of a split workspace is smaller than it needs
    /// ([`kept_words`](super::kept_words), [`shared_words`](super::shared_words)).
    RegionTooSmall {
        /// The part.
        region: Region,
        /// Bytes needed.
        needed: usize,
        /// Bytes given.
        got: usize,
    },
    /// A workspace buffer could not be typed (not expected with a `u64`
    /// workspace).
    WorkspaceAlignment,
    /// A frame buffer is invalid.
    Image(ImageError),
    /// The stereo stage: frames of different sizes, too small for the
    /// engine, or a table of another layout.
    Stereo(StereoError),
    /// The conspicuity stage.
    Conspicuity(ConspicuityError),
    /// The disparity completion.
    Complete(CompleteError),
    /// Figure-ground segregation.
    Segment(SegmentError),
    /// The shape stage (other than an empty or degenerate mask, which
    /// drops the object).
    Shape(ShapeError),
    /// The classifier.
    Mlp(MlpError),
}

impl fmt::Display for PipelineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BadParams(what) => write!(f, "pipeline parameters: {what}"),
            Self::TableCount { expected, got } => write!(
                f,
                "the stereo point needs {expected} decoder tables (one per level), got {got}"
            ),
            Self::Table(e) => write!(f, "decoder table: {e}"),
            Self::Model(e) => write!(f, "model blob: {e}"),
            Self::ModelMismatch {
                what: "inputs",
                expected,
                got,
            } => write!(
                f,
                "the model takes {got} inputs; the pipeline gives it the {expected}-element shape vector"
            ),
            Self::ModelMismatch {
                what,
                expected,
                got,
            } => write!(
                f,
                "the model has {got} {what}; the workspace is laid out for at most {expected}"
            ),
            Self::WorkspaceTooSmall { needed, got } => write!(
                f,
                "workspace of {got} bytes is too small: the run needs {needed}"
            ),
            Self::RegionTooSmall {
                region,
                needed,
                got,
            } => write!(
                f,
                "workspace part '{region}' of {got} bytes is too small: the run needs {needed}"
            ),
            Self::WorkspaceAlignment => f.write_str("workspace buffer could not be typed"),
            Self::Image(e) => write!(f, "frame: {e}"),
            Self::Stereo(e) => write!(f, "stereo: {e}"),
            Self::Conspicuity(e) => write!(f, "conspicuity: {e}"),
            Self::Complete(e) => write!(f, "{e}"),
            Self::Segment(e) => write!(f, "figure-ground: {e}"),
            Self::Shape(e) => write!(f, "shape: {e}"),
            Self::Mlp(e) => write!(f, "classifier: {e}"),
        }
    }
}

impl core::error::Error for PipelineError {}

macro_rules! from_stage {
    ($($t:ty => $v:ident),*) => {$(
        impl From<$t> for PipelineError {
            fn from(e: $t) -> Self {
                Self::$v(e)
            }
        }
    )*};
}

from_stage!(
    TableError => Table, ModelError => Model, ImageError => Image,
    StereoError => Stereo, ConspicuityError => Conspicuity,
    CompleteError => Complete, SegmentError => Segment, ShapeError => Shape,
    MlpError => Mlp
);
