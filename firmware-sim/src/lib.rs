//! protogist firmware, written against embedded-hal 1.0 traits.
//!
//! The product ([`product`], the crate's default binary `src/main.rs`)
//! runs core's pipeline on a stereo pair from a [`stereo_camera`] on a
//! Cortex-M under QEMU and on the desktop, printing the same objects.
//! The bench firmware (`src/bin/bench/`, the stage harnesses of
//! [`bench`](mod@bench)) measures the stages one by one; the panic probe
//! (`src/bin/panic-probe.rs`, [`probe`]) exists to be linked.
#![no_std]
#![forbid(unsafe_code)]

pub mod bench;
pub mod camera;
pub mod display;
pub mod probe;
pub mod product;
mod rgb565;
pub mod stereo_camera;
pub mod ticks;

pub use protogist as pg;

pub use camera::{Camera, CameraError, CameraErrorKind, SimCamera, SimCameraError};
pub use ticks::{write_ipp, NoTicks, Ticks};
