//! The RGB-D Object Dataset (Lai et al. 2011), its cropped release, and the
//! paper's experiment on it (sections 4.2 to 5: Table 1 and Fig. 8).
//!
//! * [`loader`]: the dataset's layout, its sampling (every 5th video frame)
//!   and split (per category, the first instance tests, the others train);
//! * [`gen`]: `protogist gen-rgbd`, a synthetic stand-in in the same layout;
//! * [`features`]: the pre-processing of section 4.3 and the seven input
//!   conditions of section 4.4;
//! * [`experiment`]: `protogist experiment`, one network per condition,
//!   float and int8, the table and the figures;
//! * [`fig8`]: the seven-curve CMC, DET and ROC plots;
//! * [`render`]: the ray caster behind `gen-rgbd`;
//! * [`speed`]: `protogist train-speed`, GFLOP/s of the training products.

pub mod experiment;
pub mod features;
pub mod fig8;
pub mod gen;
pub mod loader;
pub mod render;
pub mod speed;

use std::path::PathBuf;

/// Why an RGB-D dataset cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RgbdError {
    /// The folder is not laid out as `<category>/<instance>/<instance>_<video>_<frame>_crop.png`.
    #[error("{}: not the RGB-D Object Dataset layout: {reason}", path.display())]
    NotDataset {
        /// The folder or file that does not fit.
        path: PathBuf,
        /// What does not fit (one line).
        reason: String,
    },
    /// A category folder without any usable frame.
    #[error("category {category}: no instance holds a sampled frame")]
    EmptyCategory {
        /// The category's folder name.
        category: String,
    },
    /// A crop whose depth or mask file is missing.
    #[error("{}: its {kind} file {} is missing", crop.display(), missing.display())]
    MissingCompanion {
        /// The RGB crop.
        crop: PathBuf,
        /// `depth` or `mask`.
        kind: &'static str,
        /// The missing file.
        missing: PathBuf,
    },
    /// The depth or mask image is not the size of its RGB crop.
    #[error("{}: {kind} is {got:?}, the RGB crop is {crop_size:?}", path.display())]
    SizeMismatch {
        /// The depth or mask file.
        path: PathBuf,
        /// `depth` or `mask`.
        kind: &'static str,
        /// The crop's `(width, height)`.
        crop_size: (u32, u32),
        /// The other file's `(width, height)`.
        got: (u32, u32),
    },
    /// A depth file that is not a readable 16-bit grey PNG.
    #[error("{}: not a readable 16-bit depth PNG: {reason}", path.display())]
    BadDepth {
        /// The depth file.
        path: PathBuf,
        /// Why (one line).
        reason: String,
    },
    /// An RGB crop or mask that cannot be decoded.
    #[error("cannot decode {}: {reason}", path.display())]
    Decode {
        /// The file.
        path: PathBuf,
        /// The decoder's message.
        reason: String,
    },
    /// A frame whose depth has no valid (non-zero) value.
    #[error("{}: no valid depth value", path.display())]
    NoDepth {
        /// The depth file.
        path: PathBuf,
    },
}
