//! Edge conspicuity (paper section 3.2): colour smoothing, CIELUV, the
//! largest colour distance over 4 symmetric pixel pairs, a 10 % threshold.
//!
//! The stage is four steps, each callable alone so every intermediate map can
//! be observed:
//!
//! 1. [`rgb_to_luv`]: sRGB to CIELUV ([`Luv`], channels in `I10F6`).
//! 2. [`smooth`]: the edge-preserving symmetric-nearest-neighbour cell, in place.
//! 3. [`conspicuity`]: C~(x, y), the largest CIELUV distance between the
//!    pixels at `p - δ` and `p + δ` for δ in (1,0), (1,1), (0,1), (-1,1),
//!    rounded to [`Conspicuity`] (`U10F6`). Returns max C~.
//! 4. [`threshold`]: C = C~ where C~ > 10 % of max C~, else OFF, in place.
//!
//! [`edge_conspicuity`] runs all four on caller-provided [`EdgeBuffers`].
//! The paper smooths the colour image and then converts; we convert first,
//! because the smoothing cell decides by CIELUV distance.
//!
//! ```
//! use protogist::conspicuity::*;
//! use protogist::image::{ImageView, Rgb8};
//! // A 4x3 image: black left half, white right half.
//! let px: [Rgb8; 12] = core::array::from_fn(|i| {
//!     if i % 4 < 2 { Rgb8::new(0, 0, 0) } else { Rgb8::new(255, 255, 255) }
//! });
//! let rgb = ImageView::packed(&px, 4, 3).unwrap();
//! let (mut luv, mut sm, mut rows, mut c) = (
//!     [Luv::default(); 12], [Luv::default(); 12],
//!     [Luv::default(); row_scratch_len(4)], [EdgeCell::OFF; 12],
//! );
//! let mut bufs = EdgeBuffers::new(4, 3, &mut luv, &mut sm, &mut rows, &mut c).unwrap();
//! let report = edge_conspicuity(&LuvTables::new(), &EdgeParams::default(), &rgb, &mut bufs).unwrap();
//! let edges = bufs.conspicuity();
//! // Only the two columns at the step are edges: |ΔL*| = 100.
//! let on: Vec<bool> = edges.row(1).unwrap().iter().map(|c| c.is_on()).collect();
//! assert_eq!(on, [false, true, true, false]);
//! assert_eq!(report.max.to_num::<u32>(), 100);
//! ```

mod kernel;
mod luv;
mod luv_table;
mod ring;
mod smooth;
mod stream;

pub use kernel::ColourKernel;
pub use luv::{
    lightness, srgb_to_linear, Luv, LuvTables, CIE_EPSILON, CIE_KAPPA, LUV_LIMIT_BITS, LUV_TABLES,
    MAX_ERR_L, MAX_ERR_U, MAX_ERR_V, SRGB_TO_XYZ, WHITE_U, WHITE_V,
};
pub use ring::row_scratch_len;
pub use smooth::{smooth, smooth_step, snn_row, SmoothParams, MAX_ERR_SMOOTH_STEP_LSB};
pub use stream::{stream, stream_scratch_len, stream_with};

use crate::checksum::Fnv1a;
use crate::fixed::{isqrt_round, U10F6};
use crate::image::{ImageError, ImageView, ImageViewMut, Rgb8};
use crate::off::{MaybeOff, OffValue};
use core::fmt;
use ring::Ring;
use smooth::{bits, dist2};

/// A conspicuity value: a CIELUV distance in `U10F6` (LSB 1/64).
pub type Conspicuity = U10F6;

/// One cell of a conspicuity map: a value or OFF.
pub type EdgeCell = MaybeOff<Conspicuity>;

impl OffValue for U10F6 {
    /// `U10F6::MAX`; real distances stay below 300, values saturate at
    /// `MAX - 1 LSB`.
    const OFF: Self = U10F6::MAX;
}

/// Largest ON conspicuity value (one LSB below the OFF value).
pub const CONSPICUITY_SATURATED: Conspicuity = U10F6::from_bits(u16::MAX - 1);

/// Largest error of [`conspicuity`] against its f32 reference given the same
/// input, in output LSBs: the exact integer distance is rounded once.
pub const MAX_ERR_CONSPICUITY_LSB: f32 = 0.51;

/// Errors of the conspicuity stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ConspicuityError {
    /// A buffer cannot be viewed as an image of the working size.
    Image(ImageError),
    /// Input and buffers differ in size.
    SizeMismatch {
        /// The buffers' `(width, height)`.
        expected: (usize, usize),
        /// The input's `(width, height)`.
        got: (usize, usize),
    },
    /// The row scratch is too short.
    ScratchTooSmall {
        /// Elements needed.
        needed: usize,
        /// Elements given.
        got: usize,
    },
    /// The threshold percentage is above 100.
    BadThreshold(u8),
}

impl fmt::Display for ConspicuityError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Image(e) => write!(f, "conspicuity buffer: {e}"),
            Self::SizeMismatch { expected, got } => write!(
                f,
                "input is {}x{}, buffers are {}x{}",
                got.0, got.1, expected.0, expected.1
            ),
            Self::ScratchTooSmall { needed, got } => {
                write!(f, "row scratch holds {got} pixels, needs {needed}")
            }
            Self::BadThreshold(p) => write!(f, "threshold {p} % is above 100 %"),
        }
    }
}

impl core::error::Error for ConspicuityError {}

impl From<ImageError> for ConspicuityError {
    fn from(e: ImageError) -> Self {
        Self::Image(e)
    }
}

fn check_size(expected: (usize, usize), got: (usize, usize)) -> Result<(), ConspicuityError> {
    if expected == got {
        Ok(())
    } else {
        Err(ConspicuityError::SizeMismatch { expected, got })
    }
}

/// Converts an sRGB image to CIELUV.
///
/// # Errors
/// [`ConspicuityError::SizeMismatch`] when `src` and `dst` differ in size.
pub fn rgb_to_luv(
    tables: &LuvTables,
    src: &ImageView<'_, Rgb8>,
    dst: &mut ImageViewMut<'_, Luv>,
) -> Result<(), ConspicuityError> {
    check_size(dst.size(), src.size())?;
    for (s, d) in src.rows().zip(dst.rows_mut()) {
        for (p, o) in s.iter().zip(d.iter_mut()) {
            *o = tables.convert(*p);
        }
    }
    Ok(())
}

/// Computes C~ into `dst` (every cell ON) and returns max C~.
///
/// # Errors
/// [`ConspicuityError::SizeMismatch`] or [`ConspicuityError::ScratchTooSmall`].
pub fn conspicuity(
    src: &ImageView<'_, Luv>,
    dst: &mut ImageViewMut<'_, EdgeCell>,
    rows: &mut [Luv],
) -> Result<Conspicuity, ConspicuityError> {
    check_size(dst.size(), src.size())?;
    let h = src.height();
    let mut ring = Ring::new(rows, src.width())?;
    ring.start(src.row(0).unwrap_or(&[]));
    let mut max = 0u16;
    for (y, out) in dst.rows_mut().enumerate() {
        ring.load_next(src.row((y + 1).min(h - 1)).unwrap_or(&[]));
        max = max.max(conspicuity_row(ring.prev, ring.cur, ring.next, out));
        ring.advance();
    }
    Ok(U10F6::from_bits(max))
}

fn conspicuity_row(prev: &[Luv], cur: &[Luv], next: &[Luv], out: &mut [EdgeCell]) -> u16 {
    let mut max = 0;
    let cells = prev.windows(3).zip(cur.windows(3)).zip(next.windows(3));
    for (((up, mid), down), o) in cells.zip(out.iter_mut()) {
        let c = to_conspicuity(pair_dist2(up, mid, down));
        *o = MaybeOff::from_raw(U10F6::from_bits(c));
        max = max.max(c);
    }
    max
}

/// The largest squared CIELUV distance (Q12) over the 4 pairs of a 3x3
/// window given as its three rows (3 pixels each; 0 for shorter slices).
#[inline(always)]
pub fn pair_dist2(up: &[Luv], mid: &[Luv], down: &[Luv]) -> u32 {
    let (&[a0, a1, a2], &[b0, _, b2], &[c0, c1, c2]) = (up, mid, down) else {
        return 0;
    };
    dist2(bits(b0), bits(b2))
        .max(dist2(bits(a0), bits(c2)))
        .max(dist2(bits(a1), bits(c1)))
        .max(dist2(bits(a2), bits(c0)))
}

/// Q12 squared distance -> Q6 distance; below 2^16 - 1 = OFF.
#[inline(always)]
fn to_conspicuity(d: u32) -> u16 {
    isqrt_round(d).min(u32::from(u16::MAX - 1)) as u16
}

/// Keeps C~ where `100 · C~ > percent · max`, and turns the rest OFF, in
/// place. Returns the number of ON cells. With `max == 0` (a flat image)
/// every cell turns OFF.
///
/// # Errors
/// [`ConspicuityError::BadThreshold`] when `percent > 100`.
pub fn threshold(
    map: &mut ImageViewMut<'_, EdgeCell>,
    max: Conspicuity,
    percent: u8,
) -> Result<u32, ConspicuityError> {
    if percent > 100 {
        return Err(ConspicuityError::BadThreshold(percent));
    }
    let limit = u32::from(percent) * u32::from(max.to_bits());
    let mut on = 0;
    for row in map.rows_mut() {
        for cell in row.iter_mut() {
            let keep = cell
                .get()
                .is_some_and(|c| 100 * u32::from(c.to_bits()) > limit);
            if keep {
                on += 1;
            } else {
                *cell = EdgeCell::OFF;
            }
        }
    }
    Ok(on)
}

/// Parameters of the whole stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeParams {
    /// The smoothing cell.
    pub smooth: SmoothParams,
    /// Edge threshold, percent of max C~ (the paper's 10).
    pub threshold_percent: u8,
}

impl EdgeParams {
    /// One smoothing pass and the paper's 10 % threshold.
    pub const DEFAULT: Self = Self {
        smooth: SmoothParams { iterations: 1 },
        threshold_percent: 10,
    };
}

impl Default for EdgeParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What [`edge_conspicuity`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeReport {
    /// max C~ over the image.
    pub max: Conspicuity,
    /// Cells left ON by the threshold.
    pub on_count: u32,
}

/// Full-frame CIELUV pixels the stage needs per buffer.
pub const fn luv_len(width: usize, height: usize) -> usize {
    width * height
}

/// Bytes of all buffers of [`EdgeBuffers`] at this size: two CIELUV maps,
/// the row scratch and the conspicuity map.
pub const fn scratch_bytes(width: usize, height: usize) -> usize {
    let luv = core::mem::size_of::<Luv>();
    2 * luv_len(width, height) * luv
        + row_scratch_len(width) * luv
        + width * height * core::mem::size_of::<EdgeCell>()
}

/// The caller-provided buffers of the stage, validated once.
#[derive(Debug)]
pub struct EdgeBuffers<'a> {
    luv: ImageViewMut<'a, Luv>,
    smoothed: ImageViewMut<'a, Luv>,
    rows: &'a mut [Luv],
    conspicuity: ImageViewMut<'a, EdgeCell>,
}

impl<'a> EdgeBuffers<'a> {
    /// Checks every buffer against the `width` x `height` working size.
    ///
    /// # Errors
    /// [`ConspicuityError::Image`] for a zero or too-large size or a short
    /// map buffer, [`ConspicuityError::ScratchTooSmall`] for short rows.
    pub fn new(
        width: usize,
        height: usize,
        luv: &'a mut [Luv],
        smoothed: &'a mut [Luv],
        rows: &'a mut [Luv],
        conspicuity: &'a mut [EdgeCell],
    ) -> Result<Self, ConspicuityError> {
        let needed = row_scratch_len(width);
        if rows.len() < needed {
            return Err(ConspicuityError::ScratchTooSmall {
                needed,
                got: rows.len(),
            });
        }
        Ok(Self {
            luv: ImageViewMut::packed(luv, width, height)?,
            smoothed: ImageViewMut::packed(smoothed, width, height)?,
            rows,
            conspicuity: ImageViewMut::packed(conspicuity, width, height)?,
        })
    }

    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        self.luv.size()
    }

    /// The CIELUV map of the input.
    pub fn luv(&self) -> ImageView<'_, Luv> {
        self.luv.as_view()
    }

    /// The smoothed CIELUV map.
    pub fn smoothed(&self) -> ImageView<'_, Luv> {
        self.smoothed.as_view()
    }

    /// The conspicuity map: C after [`edge_conspicuity`].
    pub fn conspicuity(&self) -> ImageView<'_, EdgeCell> {
        self.conspicuity.as_view()
    }

    /// FNV-1a 32 over the raw little-endian bits of the CIELUV, smoothed and
    /// conspicuity maps, in that order.
    pub fn checksum(&self) -> u32 {
        let mut h = Fnv1a::new();
        for map in [self.luv(), self.smoothed()] {
            map.pixels()
                .for_each(|p| p.to_bits().iter().for_each(|b| h.write(&b.to_le_bytes())));
        }
        self.conspicuity()
            .pixels()
            .for_each(|c| h.write(&c.raw().to_bits().to_le_bytes()));
        h.finish()
    }
}

/// Runs the whole stage: CIELUV, smoothing, C~ and the threshold.
///
/// # Errors
/// [`ConspicuityError::SizeMismatch`] when `rgb` is not the buffers' size;
/// [`ConspicuityError::BadThreshold`] for a threshold above 100 %.
pub fn edge_conspicuity(
    tables: &LuvTables,
    params: &EdgeParams,
    rgb: &ImageView<'_, Rgb8>,
    bufs: &mut EdgeBuffers<'_>,
) -> Result<EdgeReport, ConspicuityError> {
    rgb_to_luv(tables, rgb, &mut bufs.luv)?;
    bufs.smoothed.copy_from(&bufs.luv.as_view())?;
    smooth(&params.smooth, &mut bufs.smoothed, bufs.rows)?;
    let max = conspicuity(&bufs.smoothed.as_view(), &mut bufs.conspicuity, bufs.rows)?;
    let on_count = threshold(&mut bufs.conspicuity, max, params.threshold_percent)?;
    Ok(EdgeReport { max, on_count })
}

#[cfg(test)]
mod tests {
    use super::*;

    const W: usize = 5;
    const H: usize = 4;

    type Storage = (
        [Luv; W * H],
        [Luv; W * H],
        [Luv; row_scratch_len(W)],
        [EdgeCell; W * H],
    );

    fn storage() -> Storage {
        (
            [Luv::default(); W * H],
            [Luv::default(); W * H],
            [Luv::default(); row_scratch_len(W)],
            [EdgeCell::OFF; W * H],
        )
    }

    fn grey(v: u8) -> [Rgb8; W * H] {
        [Rgb8::new(v, v, v); W * H]
    }

    #[test]
    fn buffers_of_the_wrong_size_are_typed_errors() {
        let (mut a, mut b, mut r, mut c) = storage();
        let short = EdgeBuffers::new(W, H + 1, &mut a, &mut b, &mut r, &mut c).err();
        assert_eq!(
            short,
            Some(ConspicuityError::Image(ImageError::BufferTooSmall {
                needed: 25,
                got: 20
            }))
        );
        let zero = EdgeBuffers::new(0, H, &mut a, &mut b, &mut r, &mut c).err();
        assert_eq!(zero, Some(ConspicuityError::Image(ImageError::ZeroSize)));
        let rows = EdgeBuffers::new(W, H, &mut a, &mut b, &mut r[..10], &mut c).err();
        assert_eq!(
            rows,
            Some(ConspicuityError::ScratchTooSmall {
                needed: 21,
                got: 10
            })
        );
    }

    #[test]
    fn input_of_another_size_and_bad_threshold_are_typed_errors() {
        let (mut a, mut b, mut r, mut c) = storage();
        let mut bufs = EdgeBuffers::new(W, H, &mut a, &mut b, &mut r, &mut c).unwrap();
        let px = grey(9);
        let rgb = ImageView::packed(&px, H, W).unwrap();
        let t = LuvTables::new();
        assert_eq!(
            edge_conspicuity(&t, &EdgeParams::default(), &rgb, &mut bufs),
            Err(ConspicuityError::SizeMismatch {
                expected: (W, H),
                got: (H, W)
            })
        );
        let rgb = ImageView::packed(&px, W, H).unwrap();
        let params = EdgeParams {
            threshold_percent: 101,
            ..EdgeParams::default()
        };
        assert_eq!(
            edge_conspicuity(&t, &params, &rgb, &mut bufs),
            Err(ConspicuityError::BadThreshold(101))
        );
    }

    #[test]
    fn a_flat_image_has_no_edges() {
        let (mut a, mut b, mut r, mut c) = storage();
        let mut bufs = EdgeBuffers::new(W, H, &mut a, &mut b, &mut r, &mut c).unwrap();
        let px = grey(200);
        let rgb = ImageView::packed(&px, W, H).unwrap();
        let report =
            edge_conspicuity(&LuvTables::new(), &EdgeParams::default(), &rgb, &mut bufs).unwrap();
        assert_eq!(
            report,
            EdgeReport {
                max: U10F6::ZERO,
                on_count: 0
            }
        );
        assert!(bufs.conspicuity().pixels().all(EdgeCell::is_off));
    }

    #[test]
    fn out_of_range_luv_is_clamped_at_construction() {
        let p = Luv::from_bits(i16::MAX, i16::MIN, 5);
        assert_eq!(p.to_bits(), [LUV_LIMIT_BITS, -LUV_LIMIT_BITS, 5]);
    }
}
