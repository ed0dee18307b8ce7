//! Stereo cameras in the sensor's format: a rectified RGB565 pair captured
//! into caller memory (embedded-hal style, like [`crate::camera`]).
//!
//! DVP sensors (OV7670, OV2640, … behind the STM32's DCMI) deliver RGB565:
//! one `u16` per pixel, red in bits 15..11, green in 10..5, blue in 4..0.
//! A pair at 160x120 is 75 KB this way, against 113 KB as [`Rgb8`].
//!
//! - [`StereoCamera`] captures a pair into one caller buffer of
//!   [`pair_len`] `u16`s and says where each eye is ([`PairLayout`]).
//! - [`SideBySide`] adapts the single frame that stereo camera modules
//!   deliver (left half | right half of each row) without copying: the two
//!   eyes are views into the same rows, with a stride of two widths.
//! - [`SimStereoCamera`] renders the demo scene's pair
//!   ([`SceneSpec::demo`]); [`SimSideBySideSensor`] renders it as a
//!   side-by-side module would deliver it.
//! - [`Rgb565View`] gives the pipeline an eye as RGB rows
//!   ([`RgbRows`]), expanding each pixel to [`Rgb8`] by bit replication
//!   ([`expand_rgb565`]).

use crate::camera::{CameraError, CameraErrorKind};
use crate::pg::conspicuity::Luv;
use crate::pg::image::{ImageError, ImageView, Rgb8};
use crate::pg::pipeline::RgbRows;
use crate::pg::synth::SceneSpec;

/// `u16`s of a captured `width` x `height` pair (both eyes).
pub const fn pair_len(width: usize, height: usize) -> usize {
    2 * width * height
}

pub use crate::rgb565::{expand_rgb565, pack_rgb565};

/// CIELUV of every RGB565 value, `LUV_TABLES.convert(expand_rgb565(v))`
/// at index `v`, made by the build script (`build.rs`) with core's own
/// conversion: 384 KB of flash for about 130 instructions a pixel.
static LUV565: [Luv; 1 << 16] = {
    const BYTES: &[u8; 6 << 16] = include_bytes!(concat!(env!("OUT_DIR"), "/luv565.bin"));
    let mut t = [Luv::from_bits(0, 0, 0); 1 << 16];
    let mut i = 0;
    while i < t.len() {
        let b = 6 * i;
        t[i] = Luv::from_bits(
            i16::from_le_bytes([BYTES[b], BYTES[b + 1]]),
            i16::from_le_bytes([BYTES[b + 2], BYTES[b + 3]]),
            i16::from_le_bytes([BYTES[b + 4], BYTES[b + 5]]),
        );
        i += 1;
    }
    t
};

/// CIELUV of an RGB565 pixel: core's
/// [`LUV_TABLES`](crate::pg::conspicuity::LUV_TABLES)`.convert` of
/// [`expand_rgb565`]`(v)`, bit for bit, from a table.
#[inline]
pub fn luv_of_rgb565(v: u16) -> Luv {
    LUV565
        .get(usize::from(v))
        .copied()
        .unwrap_or(Luv::from_bits(0, 0, 0))
}

// `GREY565_R`, `GREY565_G`, `GREY565_B`: see `grey8_of_rgb565`.
include!(concat!(env!("OUT_DIR"), "/grey565.rs"));

/// The phase step's grey of an RGB565 pixel: core's
/// [`grey8`](crate::pg::stereo::phase::grey8) of [`expand_rgb565`]`(v)`,
/// as the sum of one table entry per channel (made by the build script
/// with `grey8` itself; `grey8` is a sum of one product per channel).
#[inline]
pub fn grey8_of_rgb565(v: u16) -> i32 {
    GREY565_R[usize::from(v >> 11) & 31]
        + GREY565_G[usize::from(v >> 5) & 63]
        + GREY565_B[usize::from(v) & 31]
}

/// [`expand_rgb565`]'s 8-bit value of each 5-bit (red, blue) and 6-bit
/// (green) channel value.
const EXPAND5: [u16; 32] = {
    let mut t = [0; 32];
    let mut i = 0;
    while i < 32 {
        t[i] = expand_rgb565((i as u16) << 11).r as u16;
        i += 1;
    }
    t
};
const EXPAND6: [u16; 64] = {
    let mut t = [0; 64];
    let mut i = 0;
    while i < 64 {
        t[i] = expand_rgb565((i as u16) << 5).g as u16;
        i += 1;
    }
    t
};

/// The rounded mean of 4 RGB565 pixels, expanded ([`expand_rgb565`]),
/// per channel: core's [`mean_2x2_row`](crate::pg::image::mean_2x2_row) of
/// their expansions.
#[inline]
pub fn mean_rgb565(p: [u16; 4]) -> Rgb8 {
    let sum = |t: &[u16], shift: u32, mask: usize| -> u8 {
        let s: u16 = p
            .iter()
            .map(|&v| t.get(usize::from(v >> shift) & mask).copied().unwrap_or(0))
            .sum();
        ((s + 2) >> 2) as u8
    };
    Rgb8::new(
        sum(&EXPAND5, 11, 31),
        sum(&EXPAND6, 5, 63),
        sum(&EXPAND5, 0, 31),
    )
}

/// One eye of a pair as RGB rows for the pipeline.
#[derive(Clone, Copy, Debug)]
pub struct Rgb565View<'a>(ImageView<'a, u16>);

impl<'a> Rgb565View<'a> {
    /// Views RGB565 pixels (any stride).
    pub const fn new(view: ImageView<'a, u16>) -> Self {
        Self(view)
    }

    /// The pixels.
    pub const fn pixels(&self) -> &ImageView<'a, u16> {
        &self.0
    }
}

impl RgbRows for Rgb565View<'_> {
    fn size(&self) -> (usize, usize) {
        self.0.size()
    }

    fn rgb_row(&self, y: usize, out: &mut [Rgb8]) {
        if let Some(row) = self.0.row(y) {
            for (o, &p) in out.iter_mut().zip(row) {
                *o = expand_rgb565(p);
            }
        }
    }

    /// Only the pixels `xs`: the same bits as [`Self::rgb_row`] there.
    fn rgb_part(&self, y: usize, xs: core::ops::Range<usize>, out: &mut [Rgb8]) {
        let Some(row) = self.0.row(y) else {
            return;
        };
        if let (Some(o), Some(r)) = (out.get_mut(xs.clone()), row.get(xs)) {
            for (o, &p) in o.iter_mut().zip(r) {
                *o = expand_rgb565(p);
            }
        }
    }

    /// From the RGB565 pixels ([`mean_rgb565`]): the default's values.
    fn half_row(&self, j: usize, out: &mut [Rgb8], _scratch: &mut [Rgb8]) {
        let (Some(a), Some(b)) = (self.0.row(2 * j), self.0.row(2 * j + 1)) else {
            return;
        };
        for ((o, a), b) in out.iter_mut().zip(a.chunks_exact(2)).zip(b.chunks_exact(2)) {
            if let (&[a0, a1], &[b0, b1]) = (a, b) {
                *o = mean_rgb565([a0, a1, b0, b1]);
            }
        }
    }

    /// By tables ([`grey8_of_rgb565`]): the default's values.
    fn grey8_row(&self, y: usize, _rgb: &mut [Rgb8], out: &mut [i32]) {
        if let Some(row) = self.0.row(y) {
            for (o, &p) in out.iter_mut().zip(row) {
                *o = grey8_of_rgb565(p);
            }
        }
    }

    /// By table ([`luv_of_rgb565`]): the bits of the default conversion.
    fn luv_row(&self, y: usize, _rgb: &mut [Rgb8], out: &mut [Luv]) {
        if let Some(row) = self.0.row(y) {
            for (o, &p) in out.iter_mut().zip(row) {
                *o = luv_of_rgb565(p);
            }
        }
    }
}

/// Where the two eyes of a captured pair are in its buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PairLayout {
    /// Width of one eye, px.
    pub width: usize,
    /// Height, px.
    pub height: usize,
    /// Elements from one row of an eye to its next.
    pub stride: usize,
    /// Offset of the left eye's first pixel.
    pub left: usize,
    /// Offset of the right eye's first pixel.
    pub right: usize,
}

impl PairLayout {
    /// Left frame, then right frame, each packed.
    pub const fn stacked(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            stride: width,
            left: 0,
            right: width * height,
        }
    }

    /// One frame of `2 * width` columns: left half | right half.
    pub const fn side_by_side(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            stride: 2 * width,
            left: 0,
            right: width,
        }
    }

    /// The two eyes of `frame`.
    ///
    /// # Errors
    /// [`ImageError`] when `frame` cannot hold the layout.
    pub fn views<'a>(
        &self,
        frame: &'a [u16],
    ) -> Result<(Rgb565View<'a>, Rgb565View<'a>), ImageError> {
        let eye = |offset: usize| {
            let data = frame.get(offset..).unwrap_or(&[]);
            ImageView::new(data, self.width, self.height, self.stride).map(Rgb565View)
        };
        Ok((eye(self.left)?, eye(self.right)?))
    }
}

/// A stereo camera: captures a rectified RGB565 pair into caller memory.
pub trait StereoCamera {
    /// Driver error type.
    type Error: CameraError;

    /// Captures one `width` x `height` pair into `frame` (at least
    /// [`pair_len`] long) and says where each eye is.
    fn capture_pair(
        &mut self,
        frame: &mut [u16],
        width: usize,
        height: usize,
    ) -> Result<PairLayout, Self::Error>;
}

/// A single sensor delivering RGB565 frames (a DVP sensor on DCMI).
pub trait Rgb565Camera {
    /// Driver error type.
    type Error: CameraError;

    /// Captures one `width` x `height` frame into `frame` (row-major,
    /// stride = width).
    fn capture(
        &mut self,
        frame: &mut [u16],
        width: usize,
        height: usize,
    ) -> Result<(), Self::Error>;
}

/// A stereo module that delivers both eyes in one frame, left half | right
/// half: the pair is that frame, read with [`PairLayout::side_by_side`].
#[derive(Clone, Debug)]
pub struct SideBySide<C>(C);

impl<C> SideBySide<C> {
    /// Wraps the module's sensor.
    pub const fn new(sensor: C) -> Self {
        Self(sensor)
    }

    /// Gives the sensor back.
    pub fn release(self) -> C {
        self.0
    }
}

/// Errors of [`SideBySide`].
#[derive(Debug)]
pub enum SideBySideError<E> {
    /// Twice the requested width does not fit a `usize`.
    TooWide,
    /// The sensor failed.
    Sensor(E),
}

impl<E: CameraError> CameraError for SideBySideError<E> {
    fn kind(&self) -> CameraErrorKind {
        match self {
            Self::TooWide => CameraErrorKind::UnsupportedResolution,
            Self::Sensor(e) => e.kind(),
        }
    }
}

impl<C: Rgb565Camera> StereoCamera for SideBySide<C> {
    type Error = SideBySideError<C::Error>;

    fn capture_pair(
        &mut self,
        frame: &mut [u16],
        width: usize,
        height: usize,
    ) -> Result<PairLayout, Self::Error> {
        let full = width.checked_mul(2).ok_or(SideBySideError::TooWide)?;
        self.0
            .capture(frame, full, height)
            .map_err(SideBySideError::Sensor)?;
        Ok(PairLayout::side_by_side(width, height))
    }
}

/// Errors of the simulated cameras.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimStereoError {
    /// The buffer holds fewer than the `needed` pixels.
    BufferTooSmall {
        /// `u16`s needed.
        needed: usize,
        /// `u16`s given.
        got: usize,
    },
    /// A side of the frame is zero or beyond the scene's coordinates.
    BadSize,
}

impl CameraError for SimStereoError {
    fn kind(&self) -> CameraErrorKind {
        match self {
            Self::BufferTooSmall { .. } => CameraErrorKind::BufferTooSmall,
            Self::BadSize => CameraErrorKind::UnsupportedResolution,
        }
    }
}

/// Checks a frame of `frames` images of `width` x `height` against the
/// scene's `i32` coordinates and the buffer.
fn check(frame: &[u16], width: usize, height: usize, frames: usize) -> Result<(), SimStereoError> {
    let needed = width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(frames))
        .ok_or(SimStereoError::BadSize)?;
    if width == 0 || height == 0 || i32::try_from(width.max(height)).is_err() {
        return Err(SimStereoError::BadSize);
    }
    if frame.len() < needed {
        return Err(SimStereoError::BufferTooSmall {
            needed,
            got: frame.len(),
        });
    }
    Ok(())
}

/// Writes the `right` (or left) eye of `spec`, `width` x `height`, into
/// `rows`, whose rows are `stride` apart.
fn render_eye(
    rows: &mut [u16],
    spec: &SceneSpec,
    right: bool,
    stride: usize,
    size: (usize, usize),
) {
    let (width, height) = size;
    for (y, row) in (0i32..).zip(rows.chunks_mut(stride.max(1)).take(height)) {
        for (x, p) in (0i32..).zip(row.iter_mut().take(width)) {
            *p = pack_rgb565(spec.colour(right, x, y));
        }
    }
}

/// Renders the demo scene's rectified pair ([`SceneSpec::demo`]) as RGB565,
/// [`PairLayout::stacked`].
#[derive(Clone, Debug, Default)]
pub struct SimStereoCamera {
    frames: u32,
}

impl SimStereoCamera {
    /// A camera on the demo scene.
    pub const fn new() -> Self {
        Self { frames: 0 }
    }

    /// Pairs captured so far.
    pub const fn frames(&self) -> u32 {
        self.frames
    }
}

impl StereoCamera for SimStereoCamera {
    type Error = SimStereoError;

    fn capture_pair(
        &mut self,
        frame: &mut [u16],
        width: usize,
        height: usize,
    ) -> Result<PairLayout, Self::Error> {
        check(frame, width, height, 2)?;
        let spec = SceneSpec::demo(width, height);
        let (left, right) = frame
            .split_at_mut_checked(width * height)
            .ok_or(SimStereoError::BadSize)?;
        render_eye(left, &spec, false, width, (width, height));
        render_eye(right, &spec, true, width, (width, height));
        self.frames = self.frames.wrapping_add(1);
        Ok(PairLayout::stacked(width, height))
    }
}

/// The demo scene as a side-by-side stereo module delivers it: one frame of
/// twice the eye's width, left eye in the left half. Wrap it in
/// [`SideBySide`] for a [`StereoCamera`].
#[derive(Clone, Debug, Default)]
pub struct SimSideBySideSensor;

impl Rgb565Camera for SimSideBySideSensor {
    type Error = SimStereoError;

    fn capture(
        &mut self,
        frame: &mut [u16],
        width: usize,
        height: usize,
    ) -> Result<(), Self::Error> {
        check(frame, width, height, 1)?;
        if width % 2 != 0 {
            return Err(SimStereoError::BadSize);
        }
        let eye = width / 2;
        let spec = SceneSpec::demo(eye, height);
        render_eye(frame, &spec, false, width, (eye, height));
        if let Some(right) = frame.get_mut(eye..) {
            render_eye(right, &spec, true, width, (eye, height));
        }
        Ok(())
    }
}
