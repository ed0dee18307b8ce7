//! Full-resolution phase refinement of a coarse disparity map: the last
//! step of the coarse-to-fine energy model of Chen & Qian 2004 (dem-spec
//! §5, alternative \[B\]: "set a constant position shift equal to the
//! coarse estimate, refine the remainder with phase-shift cells at the
//! finer scale"). It turns the half-size map of the coarse-to-fine engine
//! ([`super::c2f::C2fParams::finest`] 1) into a map of the frame's own
//! resolution for about 160 instructions per pixel on the M4 with the
//! firmware's assembly phase step ([`PhaseKernel`]; the named points
//! `fast` against `half`, docs/STEREO.md, "Operating points").
//!
//! For each ON pixel with disparity `d`, the position shift is `s =
//! min(round(d), max_disp)` and, with the 0° complex Gabor responses `z_L`,
//! `z_R` of the two frames' grey,
//!
//! ```text
//! P(x) = Σ_{|j| ≤ pool} z_L(x + j) · conj(z_R(x + j − s))
//! d'   = clamp(s + arg P · λ / 2π, 0, max_disp)
//! ```
//!
//! A correlation with `e^{ikt}` gives `z(x) ∝ e^{−ikx}` on a grating, so
//! `z_L(x) = z_R(x − d)` makes `arg P = k (d − s)`. `arg P` is where the
//! energy `|z_L + e^{iΔφ} z_R(x − s)|²` of the phase-shift cells peaks over
//! `Δφ`, read out in closed form and pooled over `2·pool + 1` pixels of the
//! row. The filter is 1-D, the zero-DC complex Gabor of λ, σ and radius
//! `r` along the row of [`grey8`] (no y pass: dropping the `[1 2 1]/4` one
//! cost nothing on the held-out pair, docs/STEREO.md). Columns are clamped
//! to the frame (replicated borders, as the filters). OFF pixels stay OFF; a pixel with
//! `P = 0`, or with `|arg P|` above [`MAX_TURN`] (3/8 turn: at half a turn
//! either sign fits, so the remainder is ambiguous), keeps `d`. The
//! f32 reference is `protogist_host::reference::stereo::phase` (same
//! names).
//!
//! **Formats.**
//!
//! | quantity | format | range |
//! |---|---|---|
//! | grey ([`grey8`], exact) | `U8F8` in `i32` | 0..=255 |
//! | x taps `c_x = e·(cos kt − dc)` (Σ = 0 exactly), `s_x = e·sin kt` (odd) | `I2F14` in `i32` | Σ\|c\|, Σ\|s\| ≤ 2^15 (checked) |
//! | response `z`, rounded once | `I12F4` in `i16` | \|z\| ≤ 2^15·255/2^14 < 2^13 |
//! | pooled product `P` | `Q8` grey² in `i32`, exact | \|P\| ≤ 9·2·2^26 < 2^31 |
//! | phase | turns, `Q16` in `i32` | ±2^15 |
//! | disparity | `U8F8` | 0..=max_disp |
//!
//! `c_x` is the zero-DC real part (`dc = Σ e cos kt`, the envelope `e`
//! normalised to Σ = 1), quantised with its sum kept at 0 exactly, so flat
//! input gives `z = 0` exactly, as the model's filters do.
//!
//! **Error bound** against the f32 reference, per pixel (ERROR_BOUNDS.md
//! section 7b): with `δ ≤ 0.1` grey levels the bound on each component of
//! `z_core − z_ref` (`2^-15` per tap with the taps' sums exact, and the
//! response's rounding; the grey is exact), `|ΔP| ≤ Σ_j (|z_L||Δz_R| + |z_R||Δz_L| +
//! |Δz_L||Δz_R|)` with `|Δz| ≤ √2·δ`, and `|d'_core − d'_ref| ≤ λ/2π ·
//! (asin(min(1, |ΔP|/|P|)) + 0.0039) + 2^-8` px: the arc tangent's
//! polynomial is within 0.0038 rad and the quotient's truncation within
//! 2^-15. Pixels with a strong pooled response are within a few
//! hundredths of a pixel; only weak ones (|P| near |ΔP|) can differ more.

use super::{param, StereoError};
use crate::disparity::DisparityCell;
use crate::image::RgbRows;
use crate::image::{ImageViewMut, Rgb8};
use core::marker::PhantomData;

mod kernels;

pub use kernels::{atan2_turns, grey8, phase_row3, x_pass5, PhaseKernel, SafePhase};
use kernels::{grey_row, phase_row_at, x_pass};

/// Largest kernel radius.
pub const MAX_RADIUS: usize = 5;
/// Largest pooling half width.
pub const MAX_POOL: usize = 4;
/// Fraction bits of the taps (`I2F14`).
pub const TAP_FRAC: u32 = 14;
/// Fraction bits of a response (`I12F4`).
pub const Z_FRAC: u32 = 4;
/// Largest `|arg P|` used, turns in `Q16` (3/8 turn, 135°: a remainder of
/// at most 3λ/8); a larger one keeps the cell.
pub const MAX_TURN: i32 = 3 << 13;

/// The refinement's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseParams {
    /// Wavelength of the 0° carrier, px (2..=64). Default 4, the model's
    /// finest level.
    pub wavelength: f32,
    /// Envelope σ / λ (isotropic). Default 0.4.
    pub sigma_per_wavelength: f32,
    /// Radius of the x kernel, taps `−r..=r` (1..=[`MAX_RADIUS`]).
    /// Default 2.
    pub radius: u8,
    /// Pooling half width along the row (0..=[`MAX_POOL`]). Default 1
    /// (3 px).
    pub pool: u8,
}

impl PhaseParams {
    /// λ 4, σ/λ 0.4, radius 2, pool 1: chosen on the held-out Motorcycle
    /// pair (docs/STEREO.md, "How the parameters were chosen").
    pub const DEFAULT: Self = Self {
        wavelength: 4.0,
        sigma_per_wavelength: 0.4,
        radius: 2,
        pool: 1,
    };

    /// Taps, `2r + 1`.
    pub const fn taps(&self) -> usize {
        2 * self.radius as usize + 1
    }
}

impl Default for PhaseParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// `i32` elements of the grey row, padded by `r` on each side.
pub const fn v_len(w: usize, p: &PhaseParams) -> usize {
    w + 2 * p.radius as usize
}

/// `[i16; 2]` elements of the two response rows: the left padded by
/// `pool` on each side, the right by `pool + max_disp` on the left and
/// `pool` on the right.
pub const fn z_len(w: usize, p: &PhaseParams, max_disp: u8) -> usize {
    2 * (w + 2 * p.pool as usize) + max_disp as usize
}

/// Scratch bytes of a refinement at width `w` (the map row buffer of the
/// streaming form included).
pub const fn scratch_bytes(w: usize, p: &PhaseParams, max_disp: u8) -> usize {
    3 * w + 4 * v_len(w, p) + 4 * z_len(w, p, max_disp) + 2 * w
}

/// Caller-provided scratch, sized by the `const fn`s of this module.
pub struct PhaseBuffers<'a> {
    /// One RGB row (`w`).
    pub rgb: &'a mut [Rgb8],
    /// Grey row ([`v_len`]).
    pub v: &'a mut [i32],
    /// Response rows ([`z_len`]).
    pub z: &'a mut [[i16; 2]],
    /// One map row (`w`), for [`Refiner::push`].
    pub row: &'a mut [DisparityCell],
}

/// The set-up refinement: checked parameters and quantised taps.
#[derive(Clone, Debug, PartialEq)]
pub struct Phase {
    /// The parameters.
    pub params: PhaseParams,
    /// Largest disparity written.
    pub max_disp: u8,
    /// `c_x` at taps `0..=r` (even: tap `−t` is tap `t`; Σ over
    /// `−r..=r` is 0 exactly).
    pub c_half: Half,
    /// `s_x` at taps `0..=r` (odd: tap `−t` is minus tap `t`; tap 0 is 0).
    pub s_half: Half,
    /// λ in `U8F8` units (`λ·256`, rounded).
    pub lambda_q8: i32,
}

/// Taps `0..=r` of an even or odd kernel.
pub type Half = [i32; MAX_RADIUS + 1];

impl Phase {
    /// Checks `params` and quantises the taps (one-time setup, floats via
    /// `libm`).
    ///
    /// # Errors
    /// [`StereoError::BadParams`].
    #[allow(
        clippy::float_arithmetic,
        clippy::cast_possible_truncation,
        clippy::cast_precision_loss
    )]
    pub fn new(params: &PhaseParams, max_disp: u8) -> Result<Self, StereoError> {
        param(
            params.wavelength >= 2.0 && params.wavelength <= 64.0,
            "the phase wavelength must be in 2..=64 px",
        )?;
        param(
            params.sigma_per_wavelength > 0.0 && params.sigma_per_wavelength <= 4.0,
            "the phase envelope must be in (0, 4] wavelengths",
        )?;
        param(
            (1..=MAX_RADIUS).contains(&usize::from(params.radius)),
            "the phase radius must be 1..=5",
        )?;
        param(
            usize::from(params.pool) <= MAX_POOL,
            "the phase pooling must be 0..=4",
        )?;
        let r = usize::from(params.radius);
        let lambda = f64::from(params.wavelength);
        let sigma = f64::from(params.sigma_per_wavelength) * lambda;
        // The envelope at taps 0..=r, normalised to Σ = 1 over −r..=r.
        let mut env = [0.0f64; MAX_RADIUS + 1];
        for (t, e) in env.iter_mut().enumerate().take(r + 1) {
            let t = t as f64;
            *e = libm::exp(-(t * t) / (2.0 * sigma * sigma));
        }
        let total: f64 = 2.0 * env.iter().sum::<f64>() - env[0];
        env.iter_mut().for_each(|e| *e /= total);
        let one = f64::from(1u32 << TAP_FRAC);
        let k = core::f64::consts::TAU / lambda;
        let dc: f64 = 2.0
            * env
                .iter()
                .enumerate()
                .map(|(t, &e)| e * libm::cos(k * t as f64))
                .sum::<f64>()
            - env[0];
        let (mut c_half, mut s_half) = ([0i32; MAX_RADIUS + 1], [0i32; MAX_RADIUS + 1]);
        for (t, ((c, s), &e)) in c_half
            .iter_mut()
            .zip(&mut s_half)
            .zip(&env)
            .enumerate()
            .skip(1)
        {
            let t = t as f64;
            *c = libm::round(e * (libm::cos(k * t) - dc) * one) as i32;
            *s = libm::round(e * libm::sin(k * t) * one) as i32;
        }
        // Σ c_x = 0 exactly over −r..=r: the centre tap takes the rounding.
        c_half[0] = -2 * c_half.iter().skip(1).sum::<i32>();
        // Σ|k| over −r..=r.
        let abs_sum = |h: &Half| 2 * h.iter().map(|v| v.abs()).sum::<i32>() - h[0].abs();
        param(
            abs_sum(&c_half) <= 1 << 15 && abs_sum(&s_half) <= 1 << 15,
            "the phase kernel is too large for its format",
        )?;
        Ok(Self {
            params: *params,
            max_disp,
            c_half,
            s_half,
            lambda_q8: libm::round(lambda * 256.0) as i32,
        })
    }
}

/// The first `n` elements of `buf` (the passes size themselves by their
/// buffers), or [`StereoError::Buffer`].
fn take<'b, T>(buf: &'b mut [T], n: usize, what: &'static str) -> Result<&'b mut [T], StereoError> {
    let got = buf.len();
    buf.get_mut(..n).ok_or(StereoError::Buffer {
        what,
        needed: n,
        got,
    })
}

/// The refinement of a map row by row (rows in any order: each reads its
/// own frame row of both eyes), the phase step by kernel `K`
/// ([`PhaseKernel`]; [`Refiner::new`] gives the portable [`SafePhase`],
/// [`Refiner::with_kernel`] a target's own).
pub struct Refiner<'p, 'b, S: RgbRows, K = SafePhase> {
    phase: &'p Phase,
    eyes: [&'p S; 2],
    w: usize,
    h: usize,
    rgb: &'b mut [Rgb8],
    v: &'b mut [i32],
    z: &'b mut [[i16; 2]],
    row: &'b mut [DisparityCell],
    /// Pixels refined so far.
    refined: usize,
    kernel: PhantomData<fn() -> K>,
}

impl<'p, 'b, S: RgbRows> Refiner<'p, 'b, S> {
    /// Checks sizes and buffers; the phase step is [`SafePhase`].
    ///
    /// # Errors
    /// [`StereoError::SizeMismatch`], [`StereoError::TooSmall`] for an
    /// empty frame, [`StereoError::Buffer`] for short buffers.
    pub fn new(
        phase: &'p Phase,
        left: &'p S,
        right: &'p S,
        bufs: PhaseBuffers<'b>,
    ) -> Result<Self, StereoError> {
        Self::with_kernel(phase, left, right, bufs)
    }
}

impl<'p, 'b, S: RgbRows, K: PhaseKernel> Refiner<'p, 'b, S, K> {
    /// [`Refiner::new`] with the phase step of kernel `K`.
    ///
    /// # Errors
    /// As [`Refiner::new`].
    pub fn with_kernel(
        phase: &'p Phase,
        left: &'p S,
        right: &'p S,
        bufs: PhaseBuffers<'b>,
    ) -> Result<Self, StereoError> {
        let (l, r) = (left.size(), right.size());
        if l != r {
            return Err(StereoError::SizeMismatch { left: l, right: r });
        }
        let (w, h) = l;
        if w == 0 || h == 0 {
            return Err(StereoError::TooSmall { min: 1, got: l });
        }
        let p = &phase.params;
        Ok(Self {
            phase,
            eyes: [left, right],
            w,
            h,
            rgb: take(bufs.rgb, w, "phase rgb")?,
            v: take(bufs.v, v_len(w, p), "phase v")?,
            z: take(bufs.z, z_len(w, p, phase.max_disp), "phase z")?,
            row: take(bufs.row, w, "phase row")?,
            refined: 0,
            kernel: PhantomData,
        })
    }

    /// Pixels refined so far (ON pixels with `P ≠ 0` and `|arg P|` within
    /// [`MAX_TURN`]).
    pub const fn refined(&self) -> usize {
        self.refined
    }

    /// Takes the cells of the map in row-major order (the coarse-to-fine
    /// engine's sink order); at the end of each row, refines it and passes
    /// its cells on to `sink` ([`Refiner::flush`]).
    pub fn push(
        &mut self,
        x: usize,
        y: usize,
        cell: DisparityCell,
        sink: &mut impl FnMut(usize, usize, DisparityCell),
    ) {
        if let Some(c) = self.row.get_mut(x) {
            *c = cell;
        }
        if x + 1 == self.w {
            self.flush(y, sink);
        }
    }

    /// The map row that [`Refiner::flush`] refines (`w` cells), to fill
    /// directly instead of by [`Refiner::push`].
    pub fn row_mut(&mut self) -> &mut [DisparityCell] {
        self.row
    }

    /// Refines the row of [`Refiner::row_mut`] as map row `y` and passes
    /// its cells on to `sink`.
    pub fn flush(&mut self, y: usize, sink: &mut impl FnMut(usize, usize, DisparityCell)) {
        let row = core::mem::take(&mut self.row);
        self.refine_row(y, row);
        for (x, &c) in row.iter().enumerate() {
            sink(x, y, c);
        }
        self.row = row;
    }

    /// Refines map row `y` (`cells`, at least `w` long) in place.
    pub fn refine_row(&mut self, y: usize, cells: &mut [DisparityCell]) {
        if y >= self.h {
            return;
        }
        match self.phase.params.taps() {
            3 => self.row_n::<3>(y, cells),
            5 => self.row_n::<5>(y, cells),
            7 => self.row_n::<7>(y, cells),
            9 => self.row_n::<9>(y, cells),
            _ => self.row_n::<11>(y, cells),
        }
    }

    /// [`Refiner::refine_row`] with `N = 2r + 1` taps known.
    fn row_n<const N: usize>(&mut self, y: usize, cells: &mut [DisparityCell]) {
        let w = self.w;
        let r = N / 2;
        let pool = usize::from(self.phase.params.pool);
        let md = usize::from(self.phase.max_disp);
        // The buffers were cut to their lengths in `new`; a split that does
        // not fit cannot happen, and leaves the row as it is.
        let Some((zl, zr)) = self.z.split_at_mut_checked(w + 2 * pool) else {
            return;
        };
        for ((eye, z), pad) in self
            .eyes
            .iter()
            .zip([&mut *zl, &mut *zr])
            .zip([pool, pool + md])
        {
            grey_row(*eye, y, self.rgb, self.v, r);
            let Some(zrow) = z.get_mut(pad..pad + w) else {
                return;
            };
            let (ch, sh) = (&self.phase.c_half, &self.phase.s_half);
            if N == 5 {
                K::x_pass5(self.v, ch, sh, zrow);
            } else {
                x_pass::<N>(self.v, ch, sh, zrow);
            }
            let (first, last) = (
                zrow.first().copied().unwrap_or([0; 2]),
                zrow.last().copied().unwrap_or([0; 2]),
            );
            z.iter_mut().take(pad).for_each(|v| *v = first);
            z.iter_mut().skip(pad + w).for_each(|v| *v = last);
        }
        let (zl, zr) = (&*zl, &*zr);
        let (md, lambda) = (self.phase.max_disp, self.phase.lambda_q8);
        let refined = match pool {
            0 => phase_row_at::<1>(md, lambda, zl, zr, cells),
            1 => K::phase_row3(md, lambda, zl, zr, cells),
            2 => phase_row_at::<5>(md, lambda, zl, zr, cells),
            3 => phase_row_at::<7>(md, lambda, zl, zr, cells),
            _ => phase_row_at::<9>(md, lambda, zl, zr, cells),
        };
        self.refined += refined;
    }
}

/// Refines a whole map in place, rows top to bottom; returns the number of
/// pixels refined.
///
/// # Errors
/// As [`Refiner::new`], and [`StereoError::Buffer`] for a map of another
/// size.
pub fn refine<S: RgbRows>(
    phase: &Phase,
    left: &S,
    right: &S,
    map: &mut ImageViewMut<'_, DisparityCell>,
    bufs: PhaseBuffers<'_>,
) -> Result<usize, StereoError> {
    let mut refiner = Refiner::new(phase, left, right, bufs)?;
    if map.size() != left.size() {
        return Err(StereoError::Buffer {
            what: "phase map",
            needed: refiner.w * refiner.h,
            got: map.size().0 * map.size().1,
        });
    }
    for (y, row) in map.rows_mut().enumerate() {
        refiner.refine_row(y, row);
    }
    Ok(refiner.refined)
}

#[cfg(test)]
mod tests;
