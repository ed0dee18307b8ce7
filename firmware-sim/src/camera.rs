//! Camera abstraction (embedded-hal style) and a simulated camera.
//!
//! embedded-hal 1.0 has no camera trait, so this follows its conventions: an
//! error type with a `kind()` that maps driver errors onto a small common enum.

use crate::pg::image::{ImageError, ImageViewMut, Rgb8};
use crate::pg::synth::{self, SceneSpec, SynthError};

/// Driver-independent camera error categories.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[non_exhaustive]
pub enum CameraErrorKind {
    /// The caller's buffer cannot hold a frame of the requested size.
    BufferTooSmall,
    /// The sensor cannot deliver the requested resolution.
    UnsupportedResolution,
    /// No frame arrived in time.
    Timeout,
    /// Sensor bus (SCCB/I2C, DCMI, SPI) failure.
    Bus,
    /// Anything else.
    Other,
}

impl core::fmt::Display for CameraErrorKind {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::BufferTooSmall => "frame buffer too small",
            Self::UnsupportedResolution => "unsupported resolution",
            Self::Timeout => "capture timed out",
            Self::Bus => "sensor bus error",
            Self::Other => "camera error",
        })
    }
}

/// Camera error: any driver error that can say which [`CameraErrorKind`] it is.
pub trait CameraError: core::fmt::Debug {
    /// The generic category of this error.
    fn kind(&self) -> CameraErrorKind;
}

impl CameraError for CameraErrorKind {
    fn kind(&self) -> CameraErrorKind {
        *self
    }
}

/// A camera that captures one RGB frame at a time into caller memory.
pub trait Camera {
    /// Driver error type.
    type Error: CameraError;

    /// Capture one `width` x `height` frame into `frame` (row-major, stride = width).
    fn capture(
        &mut self,
        frame: &mut [Rgb8],
        width: usize,
        height: usize,
    ) -> Result<(), Self::Error>;
}

/// Renders the core's deterministic synthetic scene (left view) as its "sensor".
#[derive(Clone, Debug)]
pub struct SimCamera {
    seed: Option<u64>,
    frames: u32,
}

/// Errors from [`SimCamera`]. Only `Debug` is derived, so the core's error types
/// need nothing more.
#[derive(Debug)]
pub enum SimCameraError {
    /// The buffer does not describe a valid image of the requested size.
    Buffer(ImageError),
    /// The scene renderer rejected the request.
    Render(SynthError),
}

impl CameraError for SimCameraError {
    fn kind(&self) -> CameraErrorKind {
        match self {
            Self::Buffer(_) => CameraErrorKind::BufferTooSmall,
            Self::Render(_) => CameraErrorKind::UnsupportedResolution,
        }
    }
}

impl SimCamera {
    /// The demo scene, exactly as `SceneSpec::demo` defines it.
    pub const fn new() -> Self {
        Self {
            seed: None,
            frames: 0,
        }
    }

    /// The demo scene layout with another seed (a different image).
    pub const fn with_seed(seed: u64) -> Self {
        Self {
            seed: Some(seed),
            frames: 0,
        }
    }

    /// Frames captured so far.
    pub const fn frames(&self) -> u32 {
        self.frames
    }
}

impl Default for SimCamera {
    fn default() -> Self {
        Self::new()
    }
}

impl Camera for SimCamera {
    type Error = SimCameraError;

    fn capture(
        &mut self,
        frame: &mut [Rgb8],
        width: usize,
        height: usize,
    ) -> Result<(), Self::Error> {
        let mut view =
            ImageViewMut::new(frame, width, height, width).map_err(SimCameraError::Buffer)?;
        let mut spec = SceneSpec::demo(width, height);
        if let Some(seed) = self.seed {
            spec.seed = seed;
        }
        synth::render_left(&spec, &mut view).map_err(SimCameraError::Render)?;
        self.frames = self.frames.wrapping_add(1);
        Ok(())
    }
}
