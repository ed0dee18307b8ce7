//! protogist firmware application, written against embedded-hal 1.0 traits.
//!
//! The same [`App`] runs on a Cortex-M (under QEMU, see `src/main.rs`) and on the
//! desktop, fed by a [`SimCamera`] that renders the core's deterministic synthetic
//! scene, so both print bit-identical checksums.
#![no_std]
#![forbid(unsafe_code)]

pub mod app;
pub mod camera;
pub mod display;
pub mod mlp_run;
pub mod objects;
pub mod probe;
pub mod product;
pub mod stereo_camera;
pub mod stereo_run;

pub use protogist as pg;

pub use app::{App, AppError, Buffers, FrameResult, NoTicks, StepTicks, Ticks};
pub use camera::{Camera, CameraError, CameraErrorKind, SimCamera, SimCameraError};

/// Frame sizes the firmware runs, smallest first. The last one sizes the buffers.
pub const FRAME_SIZES: [(usize, usize); 2] = [(64, 48), (160, 120)];
/// Largest frame width in [`FRAME_SIZES`].
pub const MAX_WIDTH: usize = 160;
/// Largest frame height in [`FRAME_SIZES`].
pub const MAX_HEIGHT: usize = 120;
