//! f32 reference of [`protogist::shape`].
//!
//! Same step names and argument order as core. The centroid is the exact
//! mean (integer sums divided in f64); offsets from it are rounded to f32,
//! and angles and radii come from f32 `atan2` and `sqrt`. The 720 sums of the
//! normalisation are accumulated in f64 (an f32 sum of 720 radii would lose
//! more than the fixed-point path does). The contour rule, the bins, the
//! empty-bin interpolation and the population standard deviation are
//! core's.
//!
//! The bin of a contour pixel is discontinuous in its angle: a pixel within
//! f32 rounding of a whole degree can land in the neighbouring bin here and
//! in core. [`Binning::SameAsCore`] makes the reference take core's integer
//! bin decision (on core's Q8 centroid) while keeping its own f32 radii,
//! which is what the stated error bound compares.

use protogist::image::ImageView;
use protogist::shape::{self as fx, ShapeError, BINS, SHAPE_LEN};

/// A normalised shape vector in f32 (not saturated).
pub type ShapeVectorF = [f32; SHAPE_LEN];

/// How contour pixels are assigned to bins.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Binning {
    /// `floor` of the f32 `atan2` in degrees.
    Float,
    /// Core's integer [`protogist::shape::angle_bin`] on core's Q8 centroid.
    SameAsCore,
}

/// Per-bin max and min radius, px.
#[derive(Clone, Debug, PartialEq)]
pub struct RadialProfileF {
    /// Largest radius per bin.
    pub max: [f32; BINS],
    /// Smallest radius per bin.
    pub min: [f32; BINS],
}

impl Default for RadialProfileF {
    fn default() -> Self {
        Self {
            max: [0.0; BINS],
            min: [f32::INFINITY; BINS],
        }
    }
}

impl RadialProfileF {
    /// The 720 values: max radii, then min radii.
    pub fn values(&self) -> impl Iterator<Item = f32> + '_ {
        self.max.iter().chain(self.min.iter()).copied()
    }
}

/// The exact centroid `(x, y)`, px.
///
/// # Errors
/// [`ShapeError::EmptyMask`].
pub fn centroid(mask: &ImageView<'_, u8>) -> Result<(f64, f64), ShapeError> {
    let (mut n, mut sx, mut sy) = (0u64, 0u64, 0u64);
    for (y, row) in mask.rows().enumerate() {
        for (x, &p) in row.iter().enumerate() {
            if p != 0 {
                n += 1;
                sx += x as u64;
                sy += y as u64;
            }
        }
    }
    if n == 0 {
        return Err(ShapeError::EmptyMask);
    }
    Ok((sx as f64 / n as f64, sy as f64 / n as f64))
}

/// Contour pixels: object pixels with a 4-neighbour that is background or
/// outside the image.
pub fn contour_pixels(mask: &ImageView<'_, u8>) -> Vec<(usize, usize)> {
    let on = |x: isize, y: isize| {
        x >= 0 && y >= 0 && mask.get(x as usize, y as usize).is_some_and(|p| p != 0)
    };
    let mut out = Vec::new();
    for y in 0..mask.height() as isize {
        for x in 0..mask.width() as isize {
            if on(x, y) && !(on(x - 1, y) && on(x + 1, y) && on(x, y - 1) && on(x, y + 1)) {
                out.push((x as usize, y as usize));
            }
        }
    }
    out
}

/// The bin of `atan2(-dy, dx)` in f32 degrees; `None` for `(0, 0)`.
pub fn angle_bin(dx: f32, dy: f32) -> Option<usize> {
    if dx == 0.0 && dy == 0.0 {
        return None;
    }
    let deg = (-dy).atan2(dx).to_degrees();
    Some((deg.floor() as i64 + 180).rem_euclid(BINS as i64) as usize)
}

/// Fills the profile from the contour pixels about `c`, then interpolates
/// the empty bins as core does. Returns the number of empty bins.
pub fn radial_profile(
    mask: &ImageView<'_, u8>,
    c: (f64, f64),
    binning: Binning,
    profile: &mut RadialProfileF,
) -> usize {
    *profile = RadialProfileF::default();
    let core_c = fx::centroid(mask).ok();
    for (x, y) in contour_pixels(mask) {
        let dx = (x as f64 - c.0) as f32;
        let dy = (y as f64 - c.1) as f32;
        let bin = match (binning, core_c) {
            (Binning::Float, _) => angle_bin(dx, dy),
            (Binning::SameAsCore, Some(cc)) => fx::angle_bin(
                ((x as i32) << fx::FRAC_BITS) - cc.x_q8,
                ((y as i32) << fx::FRAC_BITS) - cc.y_q8,
            ),
            (Binning::SameAsCore, None) => None,
        };
        let Some(b) = bin else { continue };
        let r = (dx * dx + dy * dy).sqrt();
        profile.max[b] = profile.max[b].max(r);
        profile.min[b] = profile.min[b].min(r);
    }
    let filled: Vec<bool> = profile.min.iter().map(|m| m.is_finite()).collect();
    let empty = filled.iter().filter(|f| !**f).count();
    if empty == BINS {
        profile.max = [0.0; BINS];
        profile.min = [0.0; BINS];
    } else {
        interpolate(&mut profile.max, &filled);
        interpolate(&mut profile.min, &filled);
    }
    empty
}

fn interpolate(v: &mut [f32; BINS], filled: &[bool]) {
    let Some(first) = filled.iter().position(|&f| f) else {
        return;
    };
    let mut last = first;
    for i in first + 1..=first + BINS {
        if !filled[i % BINS] {
            continue;
        }
        let gap = i - last;
        let (a, b) = (v[last % BINS], v[i % BINS]);
        for t in 1..gap {
            v[(last + t) % BINS] = a + (b - a) * t as f32 / gap as f32;
        }
        last = i;
    }
}

/// Population mean and standard deviation of the 720 values, f64 sums.
pub fn mean_sigma(profile: &RadialProfileF) -> (f64, f64) {
    let n = SHAPE_LEN as f64;
    let mean = profile.values().map(f64::from).sum::<f64>() / n;
    let var = profile
        .values()
        .map(|s| (f64::from(s) - mean).powi(2))
        .sum::<f64>()
        / n;
    (mean, var.sqrt())
}

/// z-normalises the profile into `out`.
///
/// # Errors
/// [`ShapeError::ZeroVariance`] when the standard deviation is zero.
pub fn normalise(profile: &RadialProfileF, out: &mut ShapeVectorF) -> Result<(), ShapeError> {
    let (mean, sigma) = mean_sigma(profile);
    if sigma == 0.0 {
        return Err(ShapeError::ZeroVariance);
    }
    for (o, s) in out.iter_mut().zip(profile.values()) {
        *o = ((f64::from(s) - mean) / sigma) as f32;
    }
    Ok(())
}

/// The whole stage with f32 binning.
///
/// # Errors
/// [`ShapeError::EmptyMask`] or [`ShapeError::ZeroVariance`].
pub fn shape_vector(
    mask: &ImageView<'_, u8>,
    profile: &mut RadialProfileF,
    out: &mut ShapeVectorF,
) -> Result<(), ShapeError> {
    shape_vector_binned(mask, Binning::Float, profile, out)
}

/// The whole stage with the given binning.
///
/// # Errors
/// [`ShapeError::EmptyMask`] or [`ShapeError::ZeroVariance`].
pub fn shape_vector_binned(
    mask: &ImageView<'_, u8>,
    binning: Binning,
    profile: &mut RadialProfileF,
    out: &mut ShapeVectorF,
) -> Result<(), ShapeError> {
    let c = centroid(mask)?;
    radial_profile(mask, c, binning, profile);
    normalise(profile, out)
}
