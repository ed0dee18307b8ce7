//! The host error type: every way the CLI and the demo can fail.
//!
//! Each variant's message is one line, so `main` can print
//! `error: {err}` and exit non-zero.

use crate::reference::stereo::table::TableError;
use crate::reference::stereo::StereoError;
use protogist::conspicuity::ConspicuityError;
use protogist::image::ImageError;
use protogist::synth::SynthError;
use std::path::PathBuf;

/// Why a host command failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum HostError {
    /// A working width or height of zero.
    #[error("--{name} must be at least 1, got 0")]
    ZeroDimension {
        /// The option's name, `width` or `height`.
        name: &'static str,
    },
    /// A frame size the core rejects (zero, or above its limit).
    #[error("invalid frame size: {0}")]
    Image(#[from] ImageError),
    /// The conspicuity stage rejected its input or buffers.
    #[error("conspicuity stage: {0}")]
    Conspicuity(#[from] ConspicuityError),
    /// The synthetic scene generator failed.
    #[error("{0}")]
    Synth(#[from] SynthError),
    /// The segmentation stage rejected its input.
    #[error("segmentation stage: {0}")]
    Segment(#[from] protogist::segment::SegmentError),
    /// The shape stage rejected its mask.
    #[error("shape stage: {0}")]
    Shape(#[from] protogist::shape::ShapeError),
    /// Core's pipeline rejected its inputs.
    #[error("pipeline: {0}")]
    Pipeline(protogist::pipeline::PipelineError),
    /// The disparity completion stage rejected its input.
    #[error("disparity completion: {0}")]
    Complete(#[from] protogist::complete::CompleteError),
    /// A file or directory could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// An input image could not be decoded (corrupt, truncated, unsupported).
    #[error("cannot decode {}: {source}", path.display())]
    Decode {
        /// The input file.
        path: PathBuf,
        /// The decoder's error.
        source: image::ImageError,
    },
    /// A truncated or corrupt JPEG (found by the strict decoder).
    #[error("{} is damaged (truncated or corrupt JPEG): {reason}", path.display())]
    DamagedImage {
        /// The input file.
        path: PathBuf,
        /// The strict decoder's message.
        reason: String,
    },
    /// An input image above [`crate::io::MAX_INPUT_PIXELS`].
    #[error("{} is {width}x{height}, over the limit of {limit} pixels", path.display())]
    ImageTooLarge {
        /// The input file.
        path: PathBuf,
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
        /// The limit, pixels.
        limit: u64,
    },
    /// A panel could not be encoded as PNG.
    #[error("cannot encode panel {name}: {source}")]
    Encode {
        /// The panel's name.
        name: String,
        /// The encoder's error.
        source: image::ImageError,
    },
    /// The stereo stage rejected its input or parameters.
    #[error("stereo: {0}")]
    Stereo(#[from] StereoError),
    /// The fixed-point stereo engine (`protogist stereo --engine core`)
    /// rejected its input, parameters or buffers.
    #[error("stereo engine (core): {0}")]
    Engine(#[from] protogist::stereo::StereoError),
    /// A decoder table that cannot be used.
    #[error("{}: {source}", path.display())]
    Table {
        /// The table file.
        path: PathBuf,
        /// What is wrong with it.
        source: TableError,
    },
    /// A ground-truth file that cannot be used.
    #[error("ground truth {}: {reason}", path.display())]
    BadGroundTruth {
        /// The GT file.
        path: PathBuf,
        /// What is wrong with it (one line).
        reason: String,
    },
    /// Ground truth of another size than the left image.
    #[error("ground truth {} is {}x{}, the left image {}x{}", path.display(), got.0, got.1, expected.0, expected.1)]
    GroundTruthSize {
        /// The GT file.
        path: PathBuf,
        /// The left image's size.
        expected: (usize, usize),
        /// The GT's size.
        got: (usize, usize),
    },
    /// An argument out of its accepted range.
    #[error("--{name}: {reason}")]
    InvalidArgument {
        /// The option's name.
        name: &'static str,
        /// What is wrong (one line).
        reason: String,
    },
    /// A classification rule or metric rejected its input.
    #[error("classify: {0}")]
    Classify(#[from] crate::classify::ClassifyError),
    /// An image-folder dataset that cannot be used.
    #[error("dataset {}: {reason}", path.display())]
    Dataset {
        /// The dataset or class folder.
        path: PathBuf,
        /// What is wrong with it (one line).
        reason: String,
    },
    /// A class folder of an evaluation dataset that the model does not
    /// know.
    #[error("{}: class {class:?} is not one of the model's classes ({known})", path.display())]
    UnknownClass {
        /// The class folder.
        path: PathBuf,
        /// Its name.
        class: String,
        /// The model's class names, comma-separated.
        known: String,
    },
    /// A model file that cannot be used.
    #[error("model {}: {reason}", path.display())]
    BadModel {
        /// The model file.
        path: PathBuf,
        /// What is wrong with it (one line).
        reason: String,
    },
    /// A scene set (`gen-scenes`) that cannot be used.
    #[error("{0}")]
    Scene(#[from] SceneError),
    /// A run that would need more memory than the limit.
    #[error("{what} needs about {need_mib} MiB, over the limit of {limit_mib} MiB (raise it with --max-memory MIB)")]
    TooMuchMemory {
        /// What would need it.
        what: String,
        /// The estimate, MiB.
        need_mib: u64,
        /// The limit, MiB.
        limit_mib: u64,
    },
    /// A concurrent writer holds the lock of an output.
    #[error("another protogist run is writing this output (lock file {} held for over {waited} s; remove it if no run is writing)", path.display())]
    Locked {
        /// The lock file.
        path: PathBuf,
        /// Seconds waited.
        waited: u64,
    },
    /// A value that could not be serialised for output.
    #[error("cannot serialise {what}: {reason}")]
    Serialize {
        /// What was being written.
        what: String,
        /// The serialiser's message.
        reason: String,
    },
    /// An RGB-D Object Dataset that cannot be used.
    #[error("RGB-D dataset: {0}")]
    Rgbd(#[from] crate::rgbd::RgbdError),
    /// An output path exists and is not a directory.
    #[error("{} exists and is not a directory", .0.display())]
    NotADirectory(PathBuf),
}

impl HostError {
    /// An [`HostError::Io`] for `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }
}

/// Result of host operations.
pub type Result<T, E = HostError> = std::result::Result<T, E>;

/// Why a scene set cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// `index.json` unreadable as an index, or of another format.
    #[error("scene index {}: {reason}", path.display())]
    Index {
        /// The index file.
        path: PathBuf,
        /// What is wrong (one line).
        reason: String,
    },
    /// A scene file that disagrees with the truth or the index.
    #[error("scene {}: {reason}", path.display())]
    Truth {
        /// The file at fault.
        path: PathBuf,
        /// What is wrong (one line).
        reason: String,
    },
    /// A class of the scenes that the model does not know.
    #[error("model {} has no class {class:?} of the scenes ({})", model.display(), index.display())]
    ModelClasses {
        /// The model file.
        model: PathBuf,
        /// The scenes' index.
        index: PathBuf,
        /// The first class missing from the model.
        class: String,
    },
}
