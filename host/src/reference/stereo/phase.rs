//! f32 reference of the full-resolution phase refinement
//! (`protogist::stereo::phase`): the last step of the coarse-to-fine model
//! of Chen & Qian 2004 (dem-spec §5, alternative \[B\]).
//!
//! A coarse map gives each frame pixel a disparity `d` (the half-size
//! level's map spread over its 2x2 blocks). The position shift is set to
//! `s = round(d)`, and the remainder is read from the phase of phase-shift
//! cells of the frame's own resolution: with the 0° responses `z_L`, `z_R`
//! of the two grey images ([`grey8`]; the zero-DC complex Gabor
//! `e(t)·(cos kt − dc) + i·e(t)·sin kt` along the rows,
//! `k = 2π/λ`, envelope `e` of σ = σ/λ·λ with Σ = 1, `dc = Σ e cos kt`),
//!
//! ```text
//! P(x) = Σ_{|j| ≤ pool} z_L(x + j) · conj(z_R(x + j − s))
//! d'   = clamp(s + arg P(x) · λ / 2π, 0, max_disp)
//! ```
//!
//! since a correlation with `e^{ikt}` gives `z(x) ∝ e^{−ikx}` on a grating,
//! and `z_L(x) = z_R(x − d)` then gives `arg P = 2π (d − s) / λ`. The
//! argument is the peak of the phase-shift energy population
//! `|z_L + e^{iΔφ} z_R(x − s)|²` over `Δφ` (the energy model's phase-shift
//! cells, read out in closed form), pooled over `2·pool + 1` pixels of the
//! row. Columns are clamped to the image (replicated borders, as the
//! model's filters). OFF pixels stay OFF; a pixel with both components of `P` below
//! [`P_LSB`] keeps `d`.

use super::filters::{Complex, Plane, Response};
use super::StereoError;
use protogist::disparity::{Disparity, DisparityCell};
use protogist::image::{ImageView, Rgb8};

/// Core's LSB of `P`, grey levels²: a smaller `P` has no phase (core's
/// integer `P` is then 0).
pub const P_LSB: f32 = 1.0 / 256.0;

/// Largest `|arg P|` used, turns (core's `MAX_TURN`): beyond it the
/// remainder is ambiguous and the pixel keeps `d`.
pub const MAX_TURNS: f32 = 0.375;

/// The refinement's parameters (`protogist::stereo::phase::PhaseParams`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseParams {
    /// Wavelength of the 0° carrier, px. Default 4 (the model's level 0).
    pub wavelength: f32,
    /// Envelope σ / λ. Default 0.4.
    pub sigma_per_wavelength: f32,
    /// Radius of the x kernel, taps `−r..=r`. Default 2.
    pub radius: u8,
    /// Pooling half width along the row, px. Default 1 (3 px).
    pub pool: u8,
}

impl From<protogist::stereo::phase::PhaseParams> for PhaseParams {
    /// The reference's parameters for core's.
    fn from(p: protogist::stereo::phase::PhaseParams) -> Self {
        Self {
            wavelength: p.wavelength,
            sigma_per_wavelength: p.sigma_per_wavelength,
            radius: p.radius,
            pool: p.pool,
        }
    }
}

impl PhaseParams {
    /// λ 4, σ/λ 0.4, radius 2, pool 1 (core's defaults).
    pub const DEFAULT: Self = Self {
        wavelength: 4.0,
        sigma_per_wavelength: 0.4,
        radius: 2,
        pool: 1,
    };
}

/// Refines `cells` (left-referenced, `w x h` row-major as `left`) in
/// place, writing at most `max_disp`; returns the number of pixels
/// refined (ON, with `P` above [`P_LSB`] and `|arg P|` within
/// [`MAX_TURNS`]).
///
/// # Errors
/// [`StereoError::SizeMismatch`] for eyes of different sizes,
/// [`StereoError::BadParams`] for a map of another size or bad parameters.
pub fn refine(
    params: &PhaseParams,
    max_disp: u8,
    left: &ImageView<'_, Rgb8>,
    right: &ImageView<'_, Rgb8>,
    cells: &mut [DisparityCell],
) -> Result<usize, StereoError> {
    if left.size() != right.size() {
        return Err(StereoError::SizeMismatch {
            left: left.size(),
            right: right.size(),
        });
    }
    let (w, h) = left.size();
    if cells.len() != w * h {
        return Err(StereoError::BadParams("the map must be the frame's size"));
    }
    let ok = (2.0..=64.0).contains(&params.wavelength)
        && params.sigma_per_wavelength > 0.0
        && params.sigma_per_wavelength <= 4.0
        && (1..=5).contains(&params.radius)
        && params.pool <= 4;
    if !ok {
        return Err(StereoError::BadParams("bad phase refinement parameters"));
    }
    let (zl, zr) = (
        respond(params, &grey8(left)),
        respond(params, &grey8(right)),
    );
    let last = w as isize - 1;
    let pool = isize::from(params.pool);
    let max = f32::from(max_disp);
    let mut refined = 0;
    for (y, row) in cells.chunks_exact_mut(w.max(1)).enumerate() {
        for (x, cell) in row.iter_mut().enumerate() {
            let Some(d) = cell.get() else { continue };
            let d: f32 = d.to_num();
            let s = d.round().min(max);
            let mut p: Complex = [0.0, 0.0];
            for j in -pool..=pool {
                let xl = (x as isize + j).clamp(0, last);
                let xr = (x as isize + j - s as isize).clamp(0, last);
                let (a, b) = (zl.at(0, xl, y), zr.at(0, xr, y));
                // a · conj(b)
                p[0] += a[0] * b[0] + a[1] * b[1];
                p[1] += a[1] * b[0] - a[0] * b[1];
            }
            // Below one LSB of core's `P` (2^-8 grey²): no phase.
            if p[0].abs() < P_LSB && p[1].abs() < P_LSB {
                continue;
            }
            // arg P in (−π, π]: a −0 imaginary part is +0 (core's tie).
            let im = if p[1] == 0.0 { 0.0 } else { p[1] };
            let turns = im.atan2(p[0]) / core::f32::consts::TAU;
            // Beyond ±3/8 turn the remainder is ambiguous: keep `d`.
            if turns.abs() > MAX_TURNS {
                continue;
            }
            let r = turns * params.wavelength;
            let v = (s + r).clamp(0.0, max);
            *cell = DisparityCell::from_raw(Disparity::from_num(v));
            refined += 1;
        }
    }
    Ok(refined)
}

/// Grey with core's 8-bit weights (`protogist::stereo::phase::grey8`):
/// `(77 R + 150 G + 29 B) / 256`, 0..255.
pub fn grey8(img: &ImageView<'_, Rgb8>) -> Plane {
    let (width, height) = img.size();
    let data = img
        .pixels()
        .map(|p| (77.0 * f32::from(p.r) + 150.0 * f32::from(p.g) + 29.0 * f32::from(p.b)) / 256.0)
        .collect();
    Plane {
        width,
        height,
        data,
    }
}

/// The 0° response of `img`: the zero-DC complex Gabor along each row
/// (clamped columns).
pub fn respond(params: &PhaseParams, img: &Plane) -> Response {
    let (w, h) = (img.width, img.height);
    let (c, s) = kernel(params);
    let r = (c.len() / 2) as isize;
    let mut z = vec![[0.0f32; 2]; w * h];
    for y in 0..h {
        let yi = y as isize;
        let v: Vec<f32> = (0..w as isize).map(|x| img.at(x, yi)).collect();
        for x in 0..w {
            let mut acc = [0.0f32; 2];
            for t in -r..=r {
                let p = v[(x as isize + t).clamp(0, w as isize - 1) as usize];
                acc[0] += c[(t + r) as usize] * p;
                acc[1] += s[(t + r) as usize] * p;
            }
            z[y * w + x] = acc;
        }
    }
    Response {
        width: w,
        height: h,
        channels: 1,
        z,
    }
}

/// The x kernel: `e·(cos kt − dc)` (Σ = 0) and `e·sin kt`, envelope Σ = 1.
pub fn kernel(params: &PhaseParams) -> (Vec<f32>, Vec<f32>) {
    let r = i32::from(params.radius);
    let sigma = params.sigma_per_wavelength * params.wavelength;
    let k = core::f32::consts::TAU / params.wavelength;
    let raw: Vec<f32> = (-r..=r)
        .map(|t| (-(t * t) as f32 / (2.0 * sigma * sigma)).exp())
        .collect();
    let total: f32 = raw.iter().sum();
    let env: Vec<f32> = raw.iter().map(|e| e / total).collect();
    let dc: f32 = (-r..=r)
        .zip(&env)
        .map(|(t, e)| e * (k * t as f32).cos())
        .sum();
    let c = (-r..=r)
        .zip(&env)
        .map(|(t, e)| e * ((k * t as f32).cos() - dc))
        .collect();
    let s = (-r..=r)
        .zip(&env)
        .map(|(t, e)| e * (k * t as f32).sin())
        .collect();
    (c, s)
}
