//! The monocular front end in fixed point: grey and
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

use super::MAX_CARRIERS;
use crate::fixed::round_shift;
use crate::image::Rgb8;

mod kernels;

use kernels::{y_sym, XUnit};

/// Fraction bits of the kernel taps (`I2F14`).
pub const KERNEL_FRAC: u32 = 14;
/// Fraction bits of the grey input (`U8F8`).
pub const GREY_FRAC: u32 = 8;
/// Fraction bits of a response (`I10F6`).
pub const Z_FRAC: u32 = 6;
/// Largest kernel radius core supports (sizes the kernel arrays): the
/// design's ⌈3σ⌉ at λ = 4 px, σ = 0.56λ (docs/STEREO.md); longer
/// wavelengths come from the pyramid, not from wider kernels. Every kernel
/// array, and every copy of the set-up stereo engine on a board's stack,
/// is sized by it (15 took 8 KB more of the product's stack).
pub const MAX_RADIUS: usize = 7;
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
        // Largest-remainder rounding by mirrored pairs: Σ env = 2^14
        // exactly, every tap within 1 LSB of its value, and the envelope
        // even, which the bank's fast path needs (a single remainder to
        // one tap of a pair would break it). The centre takes one LSB when
        // the deficit is odd, each pair two, largest remainders first; the
        // deficit is below `taps`, so the `r` pairs always suffice.
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
        let mut left = (1i32 << KERNEL_FRAC) - sum;
        if left % 2 == 1 {
            if let Some(c) = env.get_mut(r) {
                *c += 1;
            }
            left -= 1;
        }
        while left >= 2 {
            let mut best = 0;
            for i in 1..r {
                if rem.get(i) > rem.get(best) {
                    best = i;
                }
            }
            if rem.get(best).is_none_or(|&v| v < 0.0) {
                break;
            }
            for i in [best, taps - 1 - best] {
                if let (Some(e), Some(q)) = (env.get_mut(i), rem.get_mut(i)) {
                    *e += 1;
                    *q = -1.0;
                }
            }
            left -= 2;
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
        *o = finish([re, im], bl >> KERNEL_FRAC, g.dc);
    }
}

/// The zero-DC correction and the one rounding of the x pass: `z = s −
/// dc·b` with `b = bl >> 14` (`bl` is Q36, `b` Q22, exact on flat input;
/// `dc·b` is Q50), rounded to `I10F6` and saturated to `i16`.
#[inline(always)]
fn finish(s: [i64; 2], b: i64, dc: [i64; 2]) -> Z {
    let shift = GREY_FRAC + 2 * KERNEL_FRAC - Z_FRAC;
    let q = |v: i64| round_shift(v, shift).clamp(-32768, 32767) as i16;
    [
        q(s[0] - ((dc[0] * b) >> KERNEL_FRAC)),
        q(s[1] - ((dc[1] * b) >> KERNEL_FRAC)),
    ]
}

/// Taps `t = −r..=0` of an exactly even or odd kernel, `h[i] = g(i − r)`;
/// tap `s > 0` is `h[r − s]` (even) or `−h[r − s]` (odd). A correlation
/// with it pre-adds (even) or pre-subtracts (odd) the pixel pair `x ∓ s`:
/// `g(−s)·I(x − s) + g(s)·I(x + s) = h[r − s]·(I(x − s) ± I(x + s))`.
type Half = [i32; MAX_RADIUS + 1];

/// `g`'s half (taps `0..taps` of a kernel stored `−r..=r`) if `g` is
/// exactly even (`odd` false) or odd (then its centre tap is 0).
fn half(g: impl Fn(usize) -> i32, taps: usize, odd: bool) -> Option<Half> {
    let mut h = [0; MAX_RADIUS + 1];
    for (i, o) in h.iter_mut().enumerate().take(taps / 2 + 1) {
        let (a, b) = (g(i), g(taps - 1 - i));
        if b != if odd { -a } else { a } {
            return None;
        }
        *o = a;
    }
    Some(h)
}

/// Whether `Σ|g| ≤ 2^14` over `taps`: then a y sum is at most
/// `65535·2^14` in magnitude, so a pair of them (the x pass pre-adds) and
/// every pre-added y product `g·(v ± v')` fit `i32` (`2·65535·2^14 < 2^31`).
fn fits(g: impl Fn(usize) -> i32, taps: usize) -> bool {
    (0..taps).map(|i| i64::from(g(i)).abs()).sum::<i64>() <= 1 << KERNEL_FRAC
}

/// One carrier's halves: `[kx_re (even), kx_im (odd)]`, `[ky_re (even),
/// ky_im (odd)]`, and its DC term (which the bank needs to fit `i32`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Halves {
    kx: [[i32; 2]; MAX_RADIUS + 1],
    ky: [[i32; 2]; MAX_RADIUS + 1],
    dc32: [i32; 2],
}

/// Carriers computed from one y pass: `a` from its own (`ky_a`), `b`
/// whose y kernel is `conj(ky_a)` and whose x kernel is `kx_a` exactly, and
/// `e` whose y kernel is the envelope (its y sums are `E`, which every
/// unit computes for the zero-DC term). A unit with only `e` runs the
/// envelope's y pass alone (when no unit before it has).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Unit {
    a: Option<usize>,
    b: Option<usize>,
    e: Option<usize>,
}

/// The Gabor bank of one level, organised so that the shared and
/// symmetric work is done once, with the same result bit for bit as
/// [`y_pass`] and [`x_pass`] per carrier (which stay the reference).
///
/// **Exact reorganisation.** Checked once in [`Bank::new`] on the quantised
/// taps (else every row falls back to `y_pass` + `x_pass` per carrier):
/// - the envelope and every `kx_re`, `ky_re` are even and every `kx_im`,
///   `ky_im` odd, so each 1-D correlation pre-adds or pre-subtracts the
///   pixel pair `±s` (half the multiplies);
/// - carriers at ±θ have `ky_b = conj(ky_a)` and `kx_b = kx_a`: with
///   `Y = Yr + i·Yi` the y pass of `a` and `A = Σkx_re·Yr`, `B =
///   Σkx_im·Yi`, `C = Σkx_re·Yi`, `D = Σkx_im·Yr`, `z_a = (A − B) + i(C +
///   D)` and `z_b = (A + B) + i(D − C)`: one y pass and four real x
///   correlations for two carriers instead of two and eight;
/// - a carrier whose `ky` is the envelope (0° when the rounding agrees)
///   reuses the envelope's y sums `E`, which every carrier needs for its
///   zero-DC term anyway.
///
/// The sums are the same integers as the reference's (exact integer
/// identities, no intermediate rounding), and the one rounding
/// (`finish`) is applied to them unchanged. Formats: the y sums are
/// exact in `i32` with pre-added pixels (`|g·(v ± v')| ≤ 2^14·131070 <
/// 2^31` and every partial sum is at most `65535·Σ|g|`); a pre-added pair
/// of y sums needs `Σ|ky| ≤ 2^14` (checked: `2·65535·2^14 < 2^31`; the
/// envelope has `Σ = 2^14`, all taps ≥ 0); the x sums stay exact in `i64`
/// (every `|kx| ≤ 2^14` and `dc` in `i32`, checked: see `finish1`).
#[derive(Clone, Copy, Debug)]
pub struct Bank<'k> {
    kernels: &'k [Gabor],
    taps: usize,
    env: Half,
    halves: [Halves; MAX_CARRIERS],
    units: [Unit; MAX_CARRIERS],
    n_units: usize,
    fast: bool,
}

impl<'k> Bank<'k> {
    /// The bank of `kernels` (at most [`MAX_CARRIERS`] are used).
    pub fn new(kernels: &'k [Gabor]) -> Self {
        let kernels = kernels.get(..MAX_CARRIERS).unwrap_or(kernels);
        let taps = kernels.iter().map(|g| g.taps).max().unwrap_or(1);
        let mut bank = Self {
            kernels,
            taps,
            env: [0; MAX_RADIUS + 1],
            halves: [Halves::default(); MAX_CARRIERS],
            units: [Unit::default(); MAX_CARRIERS],
            n_units: 0,
            fast: false,
        };
        bank.fast = bank.plan().is_some();
        bank
    }

    /// Fills the halves and the units; `None` if a kernel breaks a
    /// condition of the fast path.
    fn plan(&mut self) -> Option<()> {
        let (first, taps) = (self.kernels.first()?, self.taps);
        let at = |k: &[i32; MAX_TAPS], i: usize| k.get(i).copied().unwrap_or(0);
        let re = |k: &[[i32; 2]; MAX_TAPS], i: usize| k.get(i).map_or(0, |k| k[0]);
        let im = |k: &[[i32; 2]; MAX_TAPS], i: usize| k.get(i).map_or(0, |k| k[1]);
        if !(3..=MAX_TAPS).contains(&taps) || !fits(|i| at(&first.env, i), taps) {
            return None;
        }
        self.env = half(|i| at(&first.env, i), taps, false)?;
        let zip = |a: Half, b: Half| {
            let mut z = [[0; 2]; MAX_RADIUS + 1];
            for ((z, x), y) in z.iter_mut().zip(a).zip(b) {
                *z = [x, y];
            }
            z
        };
        for (g, h) in self.kernels.iter().zip(&mut self.halves) {
            let ok = g.taps == taps
                && g.env == first.env
                && g.kx.iter().flatten().all(|k| k.abs() <= 1 << KERNEL_FRAC)
                && fits(|i| re(&g.ky, i), taps)
                && fits(|i| im(&g.ky, i), taps);
            if !ok {
                return None;
            }
            *h = Halves {
                kx: zip(
                    half(|i| re(&g.kx, i), taps, false)?,
                    half(|i| im(&g.kx, i), taps, true)?,
                ),
                ky: zip(
                    half(|i| re(&g.ky, i), taps, false)?,
                    half(|i| im(&g.ky, i), taps, true)?,
                ),
                dc32: [i32::try_from(g.dc[0]).ok()?, i32::try_from(g.dc[1]).ok()?],
            };
        }
        // Units: conjugate pairs and own y passes first, then the carriers
        // on the envelope's y sums ride along (they reuse `E` and `bl`).
        let n = self.kernels.len();
        let is_env = |g: &Gabor| {
            g.ky.iter()
                .zip(&g.env)
                .all(|(k, &e)| k[0] == e && k[1] == 0)
        };
        let conj = |g: &Gabor, h: &Gabor| {
            h.kx == g.kx
                && h.ky
                    .iter()
                    .zip(&g.ky)
                    .all(|(p, q)| p[0] == q[0] && p[1] == -q[1])
        };
        let mut done = [false; MAX_CARRIERS];
        let mut units = [Unit::default(); MAX_CARRIERS];
        let mut k = 0;
        for (a, g) in self.kernels.iter().enumerate() {
            if is_env(g) || done.get(a).copied().unwrap_or(true) {
                continue;
            }
            let b = (a + 1..n).find(|&b| {
                !done.get(b).copied().unwrap_or(true)
                    && self
                        .kernels
                        .get(b)
                        .is_some_and(|h| !is_env(h) && conj(g, h))
            });
            for c in core::iter::once(a).chain(b) {
                if let Some(d) = done.get_mut(c) {
                    *d = true;
                }
            }
            if let Some(u) = units.get_mut(k) {
                *u = Unit {
                    a: Some(a),
                    b,
                    e: None,
                };
                k += 1;
            }
        }
        for (e, g) in self.kernels.iter().enumerate() {
            if !is_env(g) {
                continue;
            }
            if let Some(u) = units.iter_mut().take(k).find(|u| u.e.is_none()) {
                u.e = Some(e);
            } else if let Some(u) = units.get_mut(k) {
                *u = Unit {
                    a: None,
                    b: None,
                    e: Some(e),
                };
                k += 1;
            }
        }
        self.units = units;
        self.n_units = k;
        Some(())
    }

    /// Taps of the y pass: [`Bank::row`] takes this many source rows,
    /// `j − r ..= j + r` clamped to the level.
    pub const fn taps(&self) -> usize {
        self.taps
    }

    /// Whether the exact fast path is in use (else `y_pass` + `x_pass`).
    pub const fn is_fast(&self) -> bool {
        self.fast
    }

    /// One response row of every carrier: `rows` are the [`Bank::taps`]
    /// source rows, `col` the y-pass scratch (its length is the row
    /// width `w`), `out` the carriers' rows one after the other (carrier
    /// `c` at `c·w..(c + 1)·w`). The same bits as `y_pass` + `x_pass`.
    pub fn row(&self, rows: &[&[u16]], col: &mut [[i32; 3]], out: &mut [Z]) {
        let w = col.len();
        let r = self.taps / 2;
        let Some(rows) = rows.get(..self.taps).filter(|_| w > 0) else {
            return;
        };
        if !self.fast {
            for (g, dst) in self.kernels.iter().zip(out.chunks_exact_mut(w)) {
                let skip = r.saturating_sub(g.radius());
                y_pass(g, rows.iter().skip(skip).copied(), col);
                x_pass(g, col, dst);
            }
            return;
        }
        let mut chunks: [Option<&mut [Z]>; MAX_CARRIERS] = Default::default();
        for (slot, c) in chunks.iter_mut().zip(out.chunks_exact_mut(w)) {
            *slot = Some(c);
        }
        let mut take = |c: Option<usize>| c.and_then(|c| chunks.get_mut(c)?.take());
        let mut have_e = false;
        for u in self.units.iter().take(self.n_units) {
            let half = |c: Option<usize>| c.and_then(|c| self.halves.get(c));
            let (ha, hb, he) = (half(u.a), half(u.b), half(u.e));
            if let Some(ha) = ha {
                y_sym(rows, &self.env, Some(&ha.ky), col);
            } else if !have_e {
                y_sym(rows, &self.env, None, col);
            }
            have_e = true;
            let x = XUnit {
                env: &self.env,
                a: ha.zip(take(u.a)),
                b: hb.map(|h| h.dc32).zip(take(u.b)),
                e: he.zip(take(u.e)),
            };
            macro_rules! by_radius {
                ($($r:literal $t:literal)*) => {
                    match r {
                        $($r => x.run::<$r, $t>(col),)*
                        _ => {}
                    }
                };
            }
            by_radius!(1 3 2 5 3 7 4 9 5 11 6 13 7 15 8 17 9 19 10 21 11 23 12 25 13 27 14 29 15 31);
        }
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

#[cfg(test)]
mod tests;
