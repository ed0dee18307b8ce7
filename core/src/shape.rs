//! Shape feature vectors (paper section 3.5): the 720-element centroidal
//! profile of a binary object mask.
//!
//! The stage is three steps, each callable alone:
//!
//! 1. [`centroid`]: the mean pixel position, from exact integer sums,
//!    rounded to Q8 (1/256 px). Pixel `(x, y)` sits at the point `(x, y)`.
//! 2. [`radial_profile`]: every contour pixel (see below) in polar
//!    coordinates about the centroid; per 1° bin the largest and the smallest
//!    radius (Q8 px); empty bins filled by circular linear interpolation.
//! 3. [`normalise`]: the 720-vector (360 max radii, then 360 min radii),
//!    z-normalised into [`ShapeElem`] (`I4F12`).
//!
//! [`shape_vector`] runs all three.
//!
//! **Contour pixels.** An object pixel (non-zero) is a contour pixel when one
//! of its 4-neighbours is background (zero) or outside the image; an object
//! touching the border is closed by the border. The paper follows the
//! perimeter; we scan. The result is the same because the profile keeps only
//! the largest and smallest radius per bin, which depend on the *set* of
//! contour pixels, not on their order, and this set is exactly the union of
//! the pixels that 8-connected boundary following (Moore tracing, or Suzuki
//! and Abe's border following) visits on the outer border and on every hole
//! border: those are the object pixels 4-adjacent to a background pixel,
//! with the outside of the image counted as background. A mask with several
//! components contributes every component's contours (the segment stage
//! hands over one object).
//!
//! **Angles.** Images have y growing downwards. The angle of a pixel at
//! `(dx, dy)` from the centroid is `atan2(-dy, dx)`: counter-clockwise as
//! seen on screen, 0° pointing right, 90° up, -90° down, ±180° left. Bin `b`
//! (0..360) holds angles in `[b - 180°, b - 179°)`, so bin 0 is
//! `[-180°, -179°)` and a pixel straight left of the centroid (180° = -180°)
//! falls into bin 0. The bin is decided in integers by [`angle_bin`]:
//! quarter turns, an octant reflection, and a binary search in a table of
//! `tan(k°)` in Q32. A contour pixel exactly at the centroid has no angle
//! and is skipped.
//!
//! **Empty bins.** A bin without contour pixels (small objects, thin parts)
//! takes, for the max and the min profile separately, the linear
//! interpolation between the nearest non-empty bins before and after it,
//! circularly, rounded to Q8. With one non-empty bin every bin takes its
//! value. With none (a one-pixel object, whose only pixel is the centroid)
//! the profile is all zero.
//!
//! **Normalisation.** `s^N = (s - mean) / σ` with the population standard
//! deviation (divide by 720), computed from exact integer sums; each element
//! is rounded once to `I4F12` (LSB 1/4096) and saturates to
//! `[-8, 8 - 1/4096]`. A profile with zero variance (every element equal:
//! a one-, two- or 2x2-pixel object, for instance) has no normalised form and
//! returns [`ShapeError::ZeroVariance`].
//!
//! ```
//! use protogist::image::ImageView;
//! use protogist::shape::*;
//! // A 7x5 mask holding a 5x3 rectangle.
//! let mut px = [0u8; 35];
//! for y in 1..4 { for x in 1..6 { px[y * 7 + x] = 1; } }
//! let mask = ImageView::packed(&px, 7, 5).unwrap();
//! let mut profile = RadialProfile::new();
//! let mut v: ShapeVector = [ShapeElem::ZERO; SHAPE_LEN];
//! let report = shape_vector(&mask, &mut profile, &mut v).unwrap();
//! assert_eq!((report.centroid.x_q8, report.centroid.y_q8), (3 * 256, 2 * 256));
//! // Straight right (0°, bin 180) the outline is 2 px away, straight up
//! // (90°, bin 270) 1 px: the first is above the mean, the second below.
//! assert_eq!(profile.max()[180], 2 * 256);
//! assert_eq!(profile.max()[270], 256);
//! assert!(v[180] > ShapeElem::ZERO && v[270] < ShapeElem::ZERO);
//! ```

use crate::fixed::{div_round_i64, isqrt_floor_u128, isqrt_round_u64};
use crate::image::{ImageError, ImageView};
use crate::segment::BitView;
use core::fmt;
use core::num::NonZeroU64;

pub use fixed::types::I4F12;

/// Angle bins: 1° each, from -180° to 179°.
pub const BINS: usize = 360;

/// Elements of a shape vector: [`BINS`] max radii, then [`BINS`] min radii.
pub const SHAPE_LEN: usize = 2 * BINS;

/// One element of a normalised shape vector: `I4F12`, LSB 1/4096, range
/// `[-8, 8)`; values beyond saturate.
pub type ShapeElem = I4F12;

/// A normalised shape vector (1440 bytes).
pub type ShapeVector = [ShapeElem; SHAPE_LEN];

/// Fraction bits of the centroid and of radii (Q8: 1/256 px).
pub const FRAC_BITS: u32 = 8;

/// Largest error of a profile element (a max or min radius, interpolated or
/// not) of [`radial_profile`] against the exact value on the same contour
/// pixels in the same bins, px: the centroid rounded to Q8 moves every radius
/// by at most `√2/512`, the radius is rounded once (`1/512`), an interpolated
/// bin is rounded once more (`1/512`). Derived in `docs/ERROR_BOUNDS.md`,
/// section 6.
pub const MAX_ERR_PROFILE_PX: f32 = 0.0067;

/// Relative error of the f32 reference's radii (offset, squares, sum and
/// square root: 2.5 · 2^-24; interpolation: 4 · 2^-24 of the largest
/// radius; rounded up to 7 · 2^-24), to add as
/// `MAX_ERR_PROFILE_REL_F32 · r_max` to [`MAX_ERR_PROFILE_PX`] when comparing
/// against it.
pub const MAX_ERR_PROFILE_REL_F32: f32 = 4.2e-7;

/// Largest error of [`normalise`] against the z-score of the same profile
/// computed in f64 and rounded to f32, in output LSBs: one rounding (0.5),
/// the floor of the standard deviation in Q16, which makes every |z| at most
/// 5.7e-7 relative too large (0.019 LSB at |z| = 8), and the f32 rounding of
/// the reference (0.002 LSB at |z| = 8).
pub const MAX_ERR_NORM_LSB: f32 = 0.53;

/// Errors of the shape stage.
///
/// Buffer sizes are carried by the types ([`RadialProfile`],
/// [`ShapeVector`]); a mask buffer that cannot be viewed as an image is an
/// [`ImageError`], wrapped here so a caller can build the view with `?`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ShapeError {
    /// The mask buffer cannot be viewed as an image.
    Image(ImageError),
    /// The mask has no object pixel.
    EmptyMask,
    /// Every element of the profile is the same (for instance a one-pixel,
    /// two-pixel or 2x2 object): no standard deviation to divide by.
    ZeroVariance,
}

impl fmt::Display for ShapeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Image(e) => write!(f, "shape mask: {e}"),
            Self::EmptyMask => write!(f, "the mask has no object pixel"),
            Self::ZeroVariance => write!(
                f,
                "the shape profile has zero variance and cannot be normalised"
            ),
        }
    }
}

impl core::error::Error for ShapeError {}

impl From<ImageError> for ShapeError {
    fn from(e: ImageError) -> Self {
        Self::Image(e)
    }
}

/// The centroid of a mask in Q8 pixel coordinates, and its area.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Centroid {
    /// Column, Q8 (1/256 px), rounded.
    pub x_q8: i32,
    /// Row, Q8, rounded.
    pub y_q8: i32,
    /// Object pixels.
    pub area: u32,
}

/// The mean position of the object (non-zero) pixels, rounded to Q8.
///
/// Sums are exact (`u64`); the division rounds to nearest, ties toward +∞.
/// Translating the mask by whole pixels translates the result exactly.
///
/// # Errors
/// [`ShapeError::EmptyMask`] when no pixel is set.
pub fn centroid(mask: &ImageView<'_, u8>) -> Result<Centroid, ShapeError> {
    centroid_of_rows(mask.rows().map(|row| {
        let xs = row.iter().enumerate().filter(|(_, &p)| p != 0);
        xs.fold((0, 0), |(n, sx), (x, _)| (n + 1, sx + x as u64))
    }))
}

/// The centroid from `(pixels, sum of x)` per row, top row first.
fn centroid_of_rows(rows: impl Iterator<Item = (u64, u64)>) -> Result<Centroid, ShapeError> {
    let (mut n, mut sx, mut sy) = (0u64, 0u64, 0u64);
    for (y, (rn, rsx)) in rows.enumerate() {
        n += rn;
        sx += rsx;
        sy += rn * y as u64;
    }
    // At most 2^26 pixels, so `2n` is 0 only for an empty mask.
    let Some(two_n) = NonZeroU64::new(2 * n) else {
        return Err(ShapeError::EmptyMask);
    };
    // Coordinates below 2^13: 2^48 after the shift.
    let q8 = |s: u64| ((2 * (s << FRAC_BITS) + n) / two_n) as i32;
    Ok(Centroid {
        x_q8: q8(sx),
        y_q8: q8(sy),
        area: n as u32,
    })
}

/// Calls `f(x, y)` for every contour pixel, row by row: an object pixel with
/// a 4-neighbour that is background or outside the image.
pub fn for_each_contour_pixel(mask: &ImageView<'_, u8>, mut f: impl FnMut(usize, usize)) {
    let bg = |r: Option<&[u8]>, i: usize| !matches!(r.and_then(|r| r.get(i)), Some(&v) if v != 0);
    for (y, row) in mask.rows().enumerate() {
        let up = y.checked_sub(1).and_then(|u| mask.row(u));
        let down = mask.row(y + 1);
        for (x, _) in row.iter().enumerate().filter(|(_, &p)| p != 0) {
            let edge = bg(Some(row), x.wrapping_sub(1))
                || bg(Some(row), x + 1)
                || bg(up, x)
                || bg(down, x);
            if edge {
                f(x, y);
            }
        }
    }
}

/// `round(tan(k°) · 2^32)` for k in 0..45 (from mpmath at 120 bits; a unit
/// test checks them against `libm`).
const TAN_Q32: [u64; 45] = [
    0, 74968933, 149983563, 225089698, 300333370, 375760949, 451419253, 527355674, 603618289,
    680255991, 757318616, 834857071, 912923481, 991571331, 1070855618, 1150833018, 1231562054,
    1313103278, 1395519469, 1478875838, 1563240253, 1648683477, 1735279427, 1823105454, 1912242643,
    2002776142, 2094795517, 2188395142, 2283674620, 2380739248, 2479700525, 2580676708, 2683793431,
    2789184375, 2896992021, 3007368477, 3120476397, 3236490001, 3355596215, 3477995939, 3603905474,
    3733558110, 3867205923, 4005121798, 4147601706,
];

/// `floor(atan(b / a))` in degrees for `0 <= b < a < 2^30`: the largest k
/// with `tan(k°) <= b / a`, by the table.
fn octant_floor(a: u64, b: u64) -> usize {
    // TAN_Q32 < 2^32 and a < 2^30: no product overflows.
    let count = TAN_Q32.partition_point(|&t| t * a <= b << 32);
    count.saturating_sub(1)
}

/// The 1° bin (0..360) of the direction `(dx, dy)` in image coordinates (y
/// down), at any common scale: the bin of `atan2(-dy, dx)` in degrees, bin
/// `b` holding `[b - 180°, b - 179°)`. `None` for `(0, 0)`.
///
/// Integer only. The decision is exact on the axes and diagonals; elsewhere
/// it can differ from the real-number bin only when `tan` of the angle's
/// octant part is within the Q32 table's rounding (2^-33) of `tan(k°)`.
pub fn angle_bin(dx: i32, dy: i32) -> Option<usize> {
    let (mut x, mut y) = (i64::from(dx), -i64::from(dy));
    if x == 0 && y == 0 {
        return None;
    }
    // Turn clockwise by quarter turns into Q0 = {x > 0, y >= 0}, the
    // half-open quadrant [0°, 90°); each half-open quadrant maps onto the
    // next exactly, so floor(angle) = floor(angle in Q0) + 90 q.
    let mut q = 0;
    while !(x > 0 && y >= 0) {
        (x, y) = (y, -x);
        q += 1;
    }
    let (x, y) = (x.unsigned_abs(), y.unsigned_abs());
    let deg = match y.cmp(&x) {
        core::cmp::Ordering::Equal => 45,
        core::cmp::Ordering::Less => octant_floor(x, y),
        // 90° - atan(x / y), and atan(x / y) in (0°, 45°) is never a whole
        // degree (tan k° is irrational for 0 < k < 45).
        core::cmp::Ordering::Greater => 89 - octant_floor(y, x),
    };
    Some((deg + 90 * q + 180) % BINS)
}

/// Marks an empty bin while the profile is collected.
const EMPTY: u32 = u32::MAX;

/// Per-bin max and min radius, Q8 px: the scratch of the stage (2880 bytes,
/// [`scratch_bytes`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RadialProfile {
    max: [u32; BINS],
    min: [u32; BINS],
}

impl Default for RadialProfile {
    fn default() -> Self {
        Self::new()
    }
}

impl RadialProfile {
    /// An empty profile.
    pub const fn new() -> Self {
        Self {
            max: [0; BINS],
            min: [EMPTY; BINS],
        }
    }

    /// Largest radius per bin, Q8 px (bin `b` is `[b - 180°, b - 179°)`).
    pub const fn max(&self) -> &[u32; BINS] {
        &self.max
    }

    /// Smallest radius per bin, Q8 px.
    pub const fn min(&self) -> &[u32; BINS] {
        &self.min
    }

    /// The 720 profile values: max radii, then min radii.
    pub fn values(&self) -> impl Iterator<Item = u32> + '_ {
        self.max.iter().chain(self.min.iter()).copied()
    }
}

/// Bytes of the stage's scratch ([`RadialProfile`]).
pub const fn scratch_bytes() -> usize {
    core::mem::size_of::<RadialProfile>()
}

/// What [`radial_profile`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ProfileReport {
    /// Contour pixels binned (the one at the centroid, if any, excluded).
    pub contour_pixels: u32,
    /// Bins that had no contour pixel and were interpolated.
    pub empty_bins: u16,
}

/// Radius of `(dx, dy)` given in Q8, rounded to Q8.
fn radius_q8(dx: i32, dy: i32) -> u32 {
    let (x, y) = (i64::from(dx), i64::from(dy));
    // |dx|, |dy| < 2^22: the sum is below 2^45, the root below 2^23.
    isqrt_round_u64((x * x + y * y).unsigned_abs()) as u32
}

/// Fills the max and min radius of every bin from the contour pixels of
/// `mask` about `c`, then interpolates the empty bins (module docs).
pub fn radial_profile(
    mask: &ImageView<'_, u8>,
    c: &Centroid,
    profile: &mut RadialProfile,
) -> ProfileReport {
    profile_from(c, profile, |f| for_each_contour_pixel(mask, f))
}

/// [`radial_profile`] over the contour pixels `contour` calls its argument
/// with.
fn profile_from(
    c: &Centroid,
    profile: &mut RadialProfile,
    contour: impl FnOnce(&mut dyn FnMut(usize, usize)),
) -> ProfileReport {
    *profile = RadialProfile::new();
    let mut contour_pixels = 0u32;
    contour(&mut |x, y| {
        // x, y < 2^13: Q8 fits i32.
        let dx = ((x as i32) << FRAC_BITS) - c.x_q8;
        let dy = ((y as i32) << FRAC_BITS) - c.y_q8;
        let Some(b) = angle_bin(dx, dy) else {
            return;
        };
        let r = radius_q8(dx, dy);
        if let (Some(hi), Some(lo)) = (profile.max.get_mut(b), profile.min.get_mut(b)) {
            *hi = (*hi).max(r);
            *lo = (*lo).min(r);
            contour_pixels += 1;
        }
    });
    let empty = profile.min.iter().filter(|&&v| v == EMPTY).count();
    if empty == BINS {
        profile.max = [0; BINS];
        profile.min = [0; BINS];
    } else {
        let filled = profile.min.map(|v| v != EMPTY);
        interpolate(&mut profile.max, &filled);
        interpolate(&mut profile.min, &filled);
    }
    ProfileReport {
        contour_pixels,
        empty_bins: empty as u16,
    }
}

/// [`centroid`] of a bit mask ([`BitView`]).
///
/// # Errors
/// [`ShapeError::EmptyMask`] when no pixel is set.
pub fn centroid_bits(mask: &BitView<'_>) -> Result<Centroid, ShapeError> {
    let (w, _) = mask.size();
    // Bit i of word k sits at x = 32 k + i: the sum of x over a word is
    // 32 k · ones + Σ 2^j · ones(word & M_j), M_j the bits whose index has
    // bit j set.
    const M: [u32; 5] = [
        0xAAAA_AAAA,
        0xCCCC_CCCC,
        0xF0F0_F0F0,
        0xFF00_FF00,
        0xFFFF_0000,
    ];
    centroid_of_rows(mask.words().chunks_exact(w.div_ceil(32).max(1)).map(|row| {
        let words = row.iter().enumerate().filter(|(_, &v)| v != 0);
        words.fold((0, 0), |(n, sx), (k, &v)| {
            let ones = u64::from(v.count_ones());
            let bits = M.iter().enumerate();
            let within = bits.fold(0, |a, (j, m)| a + (u64::from((v & m).count_ones()) << j));
            (n + ones, sx + 32 * k as u64 * ones + within)
        })
    }))
}

/// [`for_each_contour_pixel`] of a bit mask: the object pixels with a
/// background or outside 4-neighbour, row by row.
pub fn for_each_contour_bit(mask: &BitView<'_>, mut f: impl FnMut(usize, usize)) {
    let (w, h) = mask.size();
    let stride = w.div_ceil(32).max(1);
    let words = mask.words();
    let row = |y: usize| words.get(y * stride..(y + 1) * stride);
    for y in 0..h {
        let (Some(cur), up, down) = (row(y), y.checked_sub(1).and_then(row), row(y + 1)) else {
            continue;
        };
        let at = |r: Option<&[u32]>, i: usize| r.and_then(|r| r.get(i)).copied().unwrap_or(0);
        for (i, &c) in cur.iter().enumerate() {
            if c == 0 {
                continue;
            }
            let left = c << 1 | i.checked_sub(1).map_or(0, |j| at(Some(cur), j) >> 31);
            let right = c >> 1 | at(Some(cur), i + 1) << 31;
            // Interior: all four neighbours set (outside counts as unset).
            let interior = left & right & at(up, i) & at(down, i);
            let mut edge = c & !interior;
            while edge != 0 {
                f(i * 32 + edge.trailing_zeros() as usize, y);
                edge &= edge - 1;
            }
        }
    }
}

/// [`shape_vector`] of a bit mask (as [`segment`](crate::segment) leaves
/// it in [`SegmentBuffers::mask`](crate::segment::SegmentBuffers::mask)):
/// the same result as on the mask's bytes.
///
/// # Errors
/// [`ShapeError::EmptyMask`] or [`ShapeError::ZeroVariance`].
pub fn shape_vector_bits(
    mask: &BitView<'_>,
    profile: &mut RadialProfile,
    out: &mut ShapeVector,
) -> Result<ShapeReport, ShapeError> {
    let c = centroid_bits(mask)?;
    let report = profile_from(&c, profile, |f| for_each_contour_bit(mask, f));
    let saturated = normalise(profile, out)?;
    Ok(ShapeReport {
        centroid: c,
        profile: report,
        saturated,
    })
}

/// Circular linear interpolation of the bins not `filled`; at least one is.
fn interpolate(v: &mut [u32; BINS], filled: &[bool; BINS]) {
    let Some(first) = filled.iter().position(|&f| f) else {
        return;
    };
    let at = |v: &[u32; BINS], i: usize| v.get(i % BINS).copied().unwrap_or(0);
    let mut last = first;
    // Walk one full turn from `first`, back to it.
    for step in 1..=BINS {
        let i = first + step;
        if !filled.get(i % BINS).copied().unwrap_or(true) {
            continue;
        }
        let gap = i - last;
        let (a, b) = (i64::from(at(v, last)), i64::from(at(v, i)));
        for t in 1..gap {
            let value = a + div_round_small((b - a) * t as i64, gap as i64);
            if let Some(cell) = v.get_mut((last + t) % BINS) {
                // Between two u32 values: fits.
                *cell = value as u32;
            }
        }
        last = i;
    }
}

/// [`div_round_i64`], in 32-bit arithmetic (the Cortex-M4 divides those in
/// hardware) when the operands fit, as they do for every interpolation.
fn div_round_small(x: i64, d: i64) -> i64 {
    match (i32::try_from(2 * x + d), i32::try_from(2 * d)) {
        (Ok(n), Ok(dd)) if dd > 0 => i64::from(n.div_euclid(dd)),
        _ => div_round_i64(x, d),
    }
}

/// `floor(n / d)` for `d > 0` and `|n| < 2^62` whose quotient is below
/// 2^16 in magnitude, or `None` when it is not (the caller saturates):
/// `inv = floor(2^64 / d)` gives a quotient estimate at most 1 short
/// (`|n| · (2^64 / d − inv) / 2^64 < 1/4`), corrected with one product.
fn div_floor_small(n: i64, d: u64, inv: u64) -> Option<i64> {
    let a = n.unsigned_abs();
    if a >> 16 >= d {
        return None;
    }
    let mut q = ((u128::from(a) * u128::from(inv)) >> 64) as u64;
    // q <= a / d < 2^16 and d < 2^62 / 2^13: no overflow.
    let mut rem = a - q * d;
    if rem >= d {
        q += 1;
        rem -= d;
    }
    let q = q as i64;
    Some(if n >= 0 { q } else { -q - i64::from(rem != 0) })
}

/// Fraction bits of the scaled standard deviation in [`normalise`].
const SIGMA_FRAC_BITS: u32 = 16;

/// z-normalises the profile into `out` (max radii, then min radii) and
/// returns how many elements saturated.
///
/// With `d_i = 720 s_i - Σs` (exact) and `S = Σ d_i²` (exact, `u128`),
/// `z_i = d_i / sqrt(S / 720)`; the root is taken in Q16, then each element
/// is divided and rounded once.
///
/// # Errors
/// [`ShapeError::ZeroVariance`] when all 720 values are equal.
pub fn normalise(profile: &RadialProfile, out: &mut ShapeVector) -> Result<u16, ShapeError> {
    const N: i64 = SHAPE_LEN as i64;
    // Radii are below 2^22 (Q8 of 8192·√2): sums below 2^32.
    let sum: i64 = profile.values().map(i64::from).sum();
    let dev = |s: u32| N * i64::from(s) - sum;
    // |d| < 2^32: each square fits u64.
    let s2: u128 = profile
        .values()
        .map(|s| {
            let d = dev(s).unsigned_abs();
            u128::from(d.wrapping_mul(d))
        })
        .sum();
    if s2 == 0 {
        return Err(ShapeError::ZeroVariance);
    }
    // |d| < 720 · 2^22 < 2^32 so S < 2^74; S · 2^32 < 2^106. R = floor(2^16 sqrt(S / 720)),
    // at least 2^16 · sqrt(719) since S >= 720 · 719 for unequal integers.
    let r = isqrt_floor_u128((s2 << (2 * SIGMA_FRAC_BITS)) / SHAPE_LEN as u128);
    // R < 2^16 · sqrt(2^74 / 720) < 2^48: i64 holds 2R and 2 · d · 2^28 + R.
    let r = i64::try_from(r).unwrap_or(i64::MAX >> 2);
    let d2 = (2 * r).unsigned_abs().max(1);
    let inv = u64::try_from((1u128 << 64) / u128::from(d2)).unwrap_or(u64::MAX);
    let (lo, hi) = (i64::from(i16::MIN), i64::from(i16::MAX));
    let mut saturated = 0u16;
    for (o, s) in out.iter_mut().zip(profile.values()) {
        // z in Q12: d · 2^(12 + 16) / R, rounded; |d · 2^28| < 2^60.
        let num = dev(s) << (ShapeElem::FRAC_NBITS + SIGMA_FRAC_BITS);
        let n = 2 * num + r;
        // Beyond 2^16 in magnitude z saturates either way.
        let z = div_floor_small(n, d2, inv).unwrap_or(if n < 0 { lo - 1 } else { hi + 1 });
        if z < lo || z > hi {
            saturated += 1;
        }
        *o = ShapeElem::from_bits(z.clamp(lo, hi) as i16);
    }
    Ok(saturated)
}

/// What [`shape_vector`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShapeReport {
    /// The centroid.
    pub centroid: Centroid,
    /// Contour pixels and empty bins.
    pub profile: ProfileReport,
    /// Elements that saturated at ±8.
    pub saturated: u16,
}

/// Runs the stage: [`centroid`], [`radial_profile`] into `profile`, and
/// [`normalise`] into `out`.
///
/// # Errors
/// [`ShapeError::EmptyMask`] or [`ShapeError::ZeroVariance`].
pub fn shape_vector(
    mask: &ImageView<'_, u8>,
    profile: &mut RadialProfile,
    out: &mut ShapeVector,
) -> Result<ShapeReport, ShapeError> {
    let c = centroid(mask)?;
    let report = radial_profile(mask, &c, profile);
    let saturated = normalise(profile, out)?;
    Ok(ShapeReport {
        centroid: c,
        profile: report,
        saturated,
    })
}

/// A reflection of the object, as a permutation of its shape vector.
///
/// Bin `b` holds the angles `[b − 180°, b − 179°)`. A mirror about the
/// vertical axis (`x → −x`) sends the angle `θ` to `180° − θ`, so bin `b`
/// to bin `179 − b` (mod 360); a mirror about the horizontal axis
/// (`y → −y`) sends `θ` to `−θ`, bin `b` to `359 − b`. The max and the
/// min half are permuted alike. A permutation keeps the mean and the
/// standard deviation, so the mirrored vector is the exact `I4F12` vector
/// of the mirrored profile: no renormalisation, no rounding. (The vector of
/// a really mirrored mask can differ a little: a contour pixel exactly on a
/// bin boundary falls into the half-open bin on the other side.)
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mirror {
    /// About the vertical axis through the centroid (left and right swap).
    Vertical,
    /// About the horizontal axis through the centroid (top and bottom swap).
    Horizontal,
}

impl Mirror {
    /// Both mirrors.
    pub const ALL: [Self; 2] = [Self::Vertical, Self::Horizontal];

    /// The element of the original vector that lands at element `i` of the
    /// mirrored one (`i` in `0..SHAPE_LEN`; the map is its own inverse).
    pub const fn source(self, i: usize) -> usize {
        let half = i / BINS * BINS;
        let b = i % BINS;
        let k = match self {
            Self::Vertical => BINS / 2 - 1,
            Self::Horizontal => BINS - 1,
        };
        // (k − b) mod 360 with b < 360, k < 360.
        half + (k + BINS - b) % BINS
    }

    /// Writes the mirrored `src` into `dst`: `dst[i] = src[source(i)]`.
    pub fn apply(self, src: &ShapeVector, dst: &mut ShapeVector) {
        for (i, d) in dst.iter_mut().enumerate() {
            *d = src.get(self.source(i)).copied().unwrap_or(ShapeElem::ZERO);
        }
    }
}

#[cfg(test)]
mod tests;
