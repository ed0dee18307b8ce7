//! The bench firmware's stage harnesses (`src/bin/bench/`), none of which
//! the product uses: the conspicuity [`app`] on a mono camera frame after
//! frame, figure-ground and shape on the scene's **ground-truth**
//! disparity ([`objects`]), the stereo engine at its named operating
//! points ([`stereo_run`]), and the classifier with the seeded benchmark
//! networks ([`mlp_run`]).

pub mod app;
pub mod costs_check;
pub mod mlp_run;
pub mod objects;
pub mod stereo_run;

pub use app::{App, AppError, Buffers, FrameResult, StepTicks};

/// Frame sizes the bench's conspicuity app runs, smallest first. The last
/// one sizes the buffers.
pub const FRAME_SIZES: [(usize, usize); 2] = [(64, 48), (160, 120)];
/// Largest frame width in [`FRAME_SIZES`].
pub const MAX_WIDTH: usize = 160;
/// Largest frame height in [`FRAME_SIZES`].
pub const MAX_HEIGHT: usize = 120;
