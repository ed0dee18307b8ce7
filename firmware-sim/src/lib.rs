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

pub mod assets;
pub mod bench;
pub mod camera;
pub mod display;
pub mod probe;
pub mod product;
mod rgb565;
pub mod stereo_camera;
pub mod ticks;

pub use protogist as pg;

/// Bytes at a 4-byte-aligned address: a model blob's weight rows are then
/// word-aligned (docs/MODEL_FORMAT.md), which the `SMLAD` kernel's `ldrd`
/// needs, and a decoder table's biases halfword-aligned, which the
/// read-out's cost kernel needs. The kernels check, and fall back to the
/// portable code on other addresses.
#[repr(C, align(4))]
pub struct Aligned<T: ?Sized>(pub T);

pub use camera::{Camera, CameraError, CameraErrorKind, SimCamera, SimCameraError};
pub use ticks::{write_ipp, NoTicks, Ticks};
