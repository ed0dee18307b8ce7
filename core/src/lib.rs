//! # protogist
//!
//! Proto-object detection for microcontroller camera boards: which kinds of
//! objects are about where, from low-level features, in fixed point, with no
//! allocation and no `unsafe`.
//!
//! The crate follows the stages of Martins et al., "proto-object
//! categorisation from low-level features" (sections 3 to 5):
//!
//! ```text
//!  left RGB ──► conspicuity ─────────────┐
//!   │           (CIELUV, smoothing, C~)  ├─► segment ─► shape ─► mlp
//!  right RGB ─► stereo (disparity) ──────┘
//! ```
//!
//! This release has [`conspicuity`], [`segment`] and [`shape`]; `stereo` and
//! `mlp` follow. Every stage works on [`image::ImageView`]s over caller-provided
//! buffers whose sizes come from `const fn`s, returns a typed error for bad
//! input, and has an f32 reference of the same name in `protogist-host`.
//! Per-pixel work is integer-only ([`fixed`] names the formats); floats
//! appear only in one-time setup such as [`conspicuity::LuvTables::new`].
//!
//! With the cargo feature `draw`, `protogist::draw` outlines objects and
//! writes their categories and captions onto any `embedded-graphics`
//! `DrawTarget`: a PNG on the desktop or a frame buffer on the board.
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::float_arithmetic,
        clippy::indexing_slicing
    )
)]

pub mod checksum;
pub mod complete;
pub mod conspicuity;
pub mod disparity;
#[cfg(feature = "draw")]
pub mod draw;
pub mod fixed;
pub mod image;
pub mod mlp;
mod named;
pub mod off;
pub mod pipeline;
pub mod rng;
pub mod segment;
pub mod shape;
pub mod stereo;
pub mod synth;
