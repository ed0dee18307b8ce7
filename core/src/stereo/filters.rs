//! The monocular front end in fixed point: grey, the ↓2 binomial pyramid and
//! the separable complex Gabor bank with zero-DC correction.
//!
//! | quantity | format | range |
//! |---|---|---|
//! | grey (Rec. 601 luma) | `U8F8` in `u16` | 0..=255 |
//! | Gabor taps `kx`, `ky`, envelope | `I2F14` in `i32` | \|k\| ≤ 1 |
//! | DC term `Σkx·Σky` | `I36F28` in `i64` | \|dc\| ≤ 1 |
//! | y-pass sums | `I10F22` in `i32`, exact | \|·\| ≤ 2^30 |
//! | x-pass sums | `I28F36` in `i64`, exact | \|·\| ≤ 2^46 |
//! | response `z` | `I10F6` in `i16`, rounded once | \|z\| ≤ 257 |
//!
//! Every filter is a correlation `z(x) = Σ_t g(t)·I(x + t)` with replicated
//! borders, as in the f32 reference (`host/src/reference/stereo/filters.rs`).
//! The envelope is quantised with Σ = 2^14 exactly and the DC term is the
//! exact product of the quantised 1-D sums, so the quantised 2-D kernel
//! sums to 0 exactly: a flat image gives `z = 0` exactly.

use crate::fixed::round_shift;
use crate::image::Rgb8;

/// Fraction bits of the kernel taps (`I2F14`).
pub const KERNEL_FRAC: u32 = 14;
/// Fraction bits of the grey input (`U8F8`).
pub const GREY_FRAC: u32 = 8;
/// Fraction bits of a response (`I10F6`).
pub const Z_FRAC: u32 = 6;
/// Largest kernel radius core supports (sizes the kernel arrays).
pub const MAX_RADIUS: usize = 15;
/// Largest number of taps.
pub const MAX_TAPS: usize = 2 * MAX_RADIUS + 1;

/// A complex response `[re, im]` in `I10F6`.
pub type Z = [i16; 2];

/// Rec. 601 luma of one pixel in `U8F8`: `(299 r + 587 g + 114 b) / 1000`
/// rounded to 1/256 (½ LSB at most).
#[inline(always)]
pub fn grey(p: Rgb8) -> u16 {
    let s = 299 * u32::from(p.r) + 587 * u32::from(p.g) + 114 * u32::from(p.b);
    // s · 256 / 1000 = 64 s / 250, rounded half up; at most 65280.
    ((64 * s + 125) / 250) as u16
}

/// The grey of one RGB row.
pub fn grey_row(rgb: &[Rgb8], out: &mut [u16]) {
    for (o, &p) in out.iter_mut().zip(rgb) {
        *o = grey(p);
    }
}

/// The binomial `[1 4 6 4 1]`.
const BINOMIAL: [u32; 5] = [1, 4, 6, 4, 1];

/// One row of the ↓2 pyramid step: binomial `[1 4 6 4 1]/16` in x (at the
/// kept columns `2i`) and y, over five source rows (already clamped to the
/// image: rows `2j − 2 ..= 2j + 2`). Exact sums, rounded once to `U8F8`.
pub fn pyramid_row(rows: [&[u16]; 5], out: &mut [u16]) {
    let w = rows[0].len();
    for (i, o) in out.iter_mut().enumerate() {
        let mut acc = 0u32;
        for (row, by) in rows.iter().zip(BINOMIAL) {
            let mut xs = 0u32;
            for (t, bx) in BINOMIAL.iter().enumerate() {
                let x = (2 * i + t).saturating_sub(2).min(w.saturating_sub(1));
                xs += bx * u32::from(row.get(x).copied().unwrap_or(0));
            }
            acc += by * xs;
        }
        // acc ≤ 256 · 65535 < 2^24.
        *o = ((acc + 128) >> 8) as u16;
    }
}

/// Size of a pyramid level: `ceil(n / 2^level)`.
pub const fn level_size(n: usize, level: usize) -> usize {
    n.div_ceil(1 << level)
}

/// Carrier direction `k` of `n`, degrees from horizontal: evenly spread
/// over (−90°, 90°) around 0, e.g. −45, 0, 45 for 3. Setup only.
#[allow(clippy::float_arithmetic, clippy::cast_precision_loss)]
pub fn carrier_deg(k: usize, n: usize) -> f32 {
    (k as f32 - (n as f32 - 1.0) / 2.0) * 180.0 / (n as f32 + 1.0)
}

/// One separable complex Gabor kernel in fixed point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Gabor {
    /// Taps, `2r + 1`.
    pub taps: usize,
    /// x kernel `[re, im]`, `I2F14`, taps `−r..=r`.
    pub kx: [[i32; 2]; MAX_TAPS],
    /// y kernel.
    pub ky: [[i32; 2]; MAX_TAPS],
    /// 1-D envelope, `I2F14`, Σ = 2^14 exactly.
    pub env: [i32; MAX_TAPS],
    /// `Σkx · Σky`, `Q28` (exact product of the quantised sums).
    pub dc: [i64; 2],
}

#[allow(
    clippy::float_arithmetic,
    clippy::cast_possible_truncation,
    clippy::indexing_slicing
)]
impl Gabor {
    /// The kernel of carrier `theta_deg` for wavelength `lambda`, envelope
    /// σ = `sigma_per_wavelength`·λ and `radius` (at most [`MAX_RADIUS`];
    /// larger values are clamped). One-time setup with `libm`.
    pub fn new(lambda: f32, sigma_per_wavelength: f32, radius: u8, theta_deg: f32) -> Self {
        let r = usize::from(radius).clamp(1, MAX_RADIUS);
        let taps = 2 * r + 1;
        let lambda = f64::from(lambda);
        let sigma = f64::from(sigma_per_wavelength) * lambda;
        let mut envf = [0.0f64; MAX_TAPS];
        let mut total = 0.0;
        for (i, e) in envf.iter_mut().take(taps).enumerate() {
            let t = i as f64 - r as f64;
            *e = libm::exp(-(t * t) / (2.0 * sigma * sigma));
            total += *e;
        }
        // Largest-remainder rounding: Σ env = 2^14 exactly, every tap
        // within 1 LSB of its value.
        let one = f64::from(1u32 << KERNEL_FRAC);
        let mut env = [0i32; MAX_TAPS];
        let mut rem = [-1.0f64; MAX_TAPS];
        let mut sum = 0i32;
        for i in 0..taps {
            let v = envf[i] / total * one;
            env[i] = libm::floor(v) as i32;
            rem[i] = v - libm::floor(v);
            sum += env[i];
        }
        while sum < 1 << KERNEL_FRAC {
            let mut best = 0;
            for i in 0..taps {
                if rem[i] > rem[best] {
                    best = i;
                }
            }
            env[best] += 1;
            rem[best] = -1.0;
            sum += 1;
        }
        let th = f64::from(theta_deg).to_radians();
        let (fx, fy) = (
            core::f64::consts::TAU * libm::cos(th) / lambda,
            core::f64::consts::TAU * libm::sin(th) / lambda,
        );
        let modulate = |f: f64| {
            let mut k = [[0i32; 2]; MAX_TAPS];
            for (i, k) in k.iter_mut().take(taps).enumerate() {
                let t = i as f64 - r as f64;
                let e = envf[i] / total;
                *k = [
                    libm::round(e * libm::cos(f * t) * one) as i32,
                    libm::round(e * libm::sin(f * t) * one) as i32,
                ];
            }
            k
        };
        let (kx, ky) = (modulate(fx), modulate(fy));
        let sum = |k: &[[i32; 2]; MAX_TAPS]| {
            k.iter().fold([0i64; 2], |a, c| {
                [a[0] + i64::from(c[0]), a[1] + i64::from(c[1])]
            })
        };
        let (sx, sy) = (sum(&kx), sum(&ky));
        Self {
            taps,
            kx,
            ky,
            env,
            dc: [sx[0] * sy[0] - sx[1] * sy[1], sx[0] * sy[1] + sx[1] * sy[0]],
        }
    }

    /// The radius `r`.
    pub const fn radius(&self) -> usize {
        self.taps / 2
    }
}

/// The y pass of one output row: for every column, `[Σ ky_re·v, Σ ky_im·v,
/// Σ env·v]` over the `2r + 1` source rows in `rows` (already clamped), in
/// `I10F22`, exact: |Σ| ≤ 65535·(2^14 + 16) < 2^31 for r ≤ 15.
pub fn y_pass<'r>(g: &Gabor, rows: impl Iterator<Item = &'r [u16]>, col: &mut [[i32; 3]]) {
    col.iter_mut().for_each(|c| *c = [0; 3]);
    for ((row, k), &e) in rows.zip(&g.ky).zip(&g.env).take(g.taps) {
        for (c, &v) in col.iter_mut().zip(row) {
            let v = i32::from(v);
            c[0] += k[0] * v;
            c[1] += k[1] * v;
            c[2] += e * v;
        }
    }
}

/// The x pass of one row on the y-pass columns, with the zero-DC
/// correction `z = Σ kx·col − dc·(Σ env·col_env)`, rounded once to `I10F6`
/// (saturated to `i16`, which no input reaches: |z| ≤ 128·(1 + |dc|) + 1).
pub fn x_pass(g: &Gabor, col: &[[i32; 3]], out: &mut [Z]) {
    let w = col.len();
    let r = g.radius();
    let last = w.saturating_sub(1);
    for (x, o) in out.iter_mut().enumerate().take(w) {
        let (mut re, mut im, mut bl) = (0i64, 0i64, 0i64);
        for (t, (k, &e)) in g.kx.iter().zip(&g.env).enumerate().take(g.taps) {
            let xi = (x + t).saturating_sub(r).min(last);
            let c = col.get(xi).copied().unwrap_or([0; 3]);
            let (kr, ki) = (i64::from(k[0]), i64::from(k[1]));
            let (cr, ci) = (i64::from(c[0]), i64::from(c[1]));
            re += kr * cr - ki * ci;
            im += kr * ci + ki * cr;
            bl += i64::from(e) * i64::from(c[2]);
        }
        // bl is Q36; bl >> 14 is Q22 (exact on flat input); dc·b is Q50.
        let b = bl >> KERNEL_FRAC;
        let zr = re - ((g.dc[0] * b) >> KERNEL_FRAC);
        let zi = im - ((g.dc[1] * b) >> KERNEL_FRAC);
        let shift = GREY_FRAC + 2 * KERNEL_FRAC - Z_FRAC;
        let q = |v: i64| round_shift(v, shift).clamp(-32768, 32767) as i16;
        *o = [q(zr), q(zi)];
    }
}

/// Binocular energies of one pixel from `z_L` and `z_R(x − s)` (`None`
/// outside the image, read as 0): `[A, X_r, X_i]` in `Q12` grey², exact.
#[inline(always)]
pub fn energy(l: Z, r: Option<Z>) -> [i64; 3] {
    let (lr, li) = (i64::from(l[0]), i64::from(l[1]));
    let (rr, ri) = r.map_or((0, 0), |r| (i64::from(r[0]), i64::from(r[1])));
    [
        lr * lr + li * li + rr * rr + ri * ri,
        lr * rr + li * ri,
        li * rr - lr * ri,
    ]
}
