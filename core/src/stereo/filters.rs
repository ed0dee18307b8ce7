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

use super::MAX_CARRIERS;
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

/// One row of the ↓2 pyramid step: binomial `[1 4 6 4 1]` in x (at the
/// kept columns `2i`) and y, over five source rows (already clamped to the
/// image: rows `2j − 2 ..= 2j + 2`), normalised by 256. Exact sums,
/// rounded once to `U8F8`.
///
/// Separable and running: the vertical sums `v(x)` (≤ 16·65535) of the
/// columns `2i + 1`, `2i + 2` are computed once and the three before them
/// carried over, so each output is `v(2i − 2) + 4v(2i − 1) + 6v(2i) +
/// 4v(2i + 1) + v(2i + 2)` (≤ 256·65535 < 2^24), the same integer as the
/// 25-tap sum. The columns are clamped to the row only at the two ends.
pub fn pyramid_row(rows: [&[u16]; 5], out: &mut [u16]) {
    let [r0, r1, r2, r3, r4] = rows;
    let last = r0.len().saturating_sub(1);
    let vert = |a: u16, b: u16, c: u16, d: u16, e: u16| {
        u32::from(a) + 4 * (u32::from(b) + u32::from(d)) + 6 * u32::from(c) + u32::from(e)
    };
    let at = |r: &[u16], x: usize| r.get(x.min(last)).copied().unwrap_or(0);
    let v = |x: usize| vert(at(r0, x), at(r1, x), at(r2, x), at(r3, x), at(r4, x));
    let round = |acc: u32| ((acc + 128) >> 8) as u16;
    // Vertical sums at 2i − 2, 2i − 1, 2i.
    let mut p = [v(0); 3];
    // Interior: 2i + 2 ≤ last, the pairs (2i + 1, 2i + 2) of each row.
    fn pairs(r: &[u16]) -> impl Iterator<Item = [u16; 2]> + '_ {
        let pairs = r.get(1..).unwrap_or(&[]).chunks_exact(2);
        pairs.filter_map(|p| <[u16; 2]>::try_from(p).ok())
    }
    let interior = pairs(r0)
        .zip(pairs(r1))
        .zip(pairs(r2))
        .zip(pairs(r3))
        .zip(pairs(r4));
    let mut done = 0;
    for (o, ((((a, b), c), d), e)) in out.iter_mut().zip(interior) {
        let n1 = vert(a[0], b[0], c[0], d[0], e[0]);
        let n2 = vert(a[1], b[1], c[1], d[1], e[1]);
        *o = round(p[0] + 4 * (p[1] + n1) + 6 * p[2] + n2);
        p = [p[2], n1, n2];
        done += 1;
    }
    for (i, o) in out.iter_mut().enumerate().skip(done) {
        let (n1, n2) = (v(2 * i + 1), v(2 * i + 2));
        *o = round(p[0] + 4 * (p[1] + n1) + 6 * p[2] + n2);
        p = [p[2], n1, n2];
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
/// ky_im (odd)]`, and its DC term.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Halves {
    kx: [[i32; 2]; MAX_RADIUS + 1],
    ky: [[i32; 2]; MAX_RADIUS + 1],
    dc: [i64; 2],
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
/// ([`finish`]) is applied to them unchanged. Formats: the y sums are
/// exact in `i32` with pre-added pixels (`|g·(v ± v')| ≤ 2^14·131070 <
/// 2^31` and every partial sum is at most `65535·Σ|g|`); a pre-added pair
/// of y sums needs `Σ|ky| ≤ 2^14` (checked: `2·65535·2^14 < 2^31`; the
/// envelope has `Σ = 2^14`, all taps ≥ 0); the x sums stay exact in `i64`.
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
                dc: g.dc,
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
                b: hb.map(|h| h.dc).zip(take(u.b)),
                e: he.zip(take(u.e)),
            };
            macro_rules! by_radius {
                ($($r:literal)*) => {
                    match r {
                        $($r => x.run::<$r>(col),)*
                        _ => {}
                    }
                };
            }
            by_radius!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15);
        }
    }
}

/// The symmetric y pass: `col[x] = [E, Yr, Yi]` (`Σ env·v`, `Σ ky_re·v`,
/// `Σ ky_im·v` over the rows, exact in `i32`, see [`Bank`]); with `ky`
/// `None`, only `E` (the rest is left as it was).
fn y_sym(
    rows: &[&[u16]],
    env: &Half,
    ky: Option<&[[i32; 2]; MAX_RADIUS + 1]>,
    col: &mut [[i32; 3]],
) {
    let r = rows.len() / 2;
    let Some((lo, rest)) = rows.split_at_checked(r) else {
        return;
    };
    let Some((centre, hi)) = rest.split_first() else {
        return;
    };
    let ec = env.get(r).copied().unwrap_or(0);
    let pairs = lo.iter().zip(hi.iter().rev());
    if let Some(ky) = ky {
        let kc = ky.get(r).map_or(0, |k| k[0]);
        for (o, &v) in col.iter_mut().zip(*centre) {
            let v = i32::from(v);
            *o = [ec * v, kc * v, 0];
        }
        for ((a, b), (&e, k)) in pairs.zip(env.iter().zip(ky)) {
            for ((o, &va), &vb) in col.iter_mut().zip(*a).zip(*b) {
                let (va, vb) = (i32::from(va), i32::from(vb));
                let (p, m) = (va + vb, va - vb);
                o[0] += e * p;
                o[1] += k[0] * p;
                o[2] += k[1] * m;
            }
        }
    } else {
        for (o, &v) in col.iter_mut().zip(*centre) {
            o[0] = ec * i32::from(v);
        }
        for ((a, b), &e) in pairs.zip(env) {
            for ((o, &va), &vb) in col.iter_mut().zip(*a).zip(*b) {
                o[0] += e * (i32::from(va) + i32::from(vb));
            }
        }
    }
}

/// Calls `px` on the `taps`-wide window of `col` centred on each column
/// in turn, borders replicated (copied into a local window).
#[inline(always)]
fn for_windows(col: &[[i32; 3]], taps: usize, mut px: impl FnMut(&[[i32; 3]])) {
    let w = col.len();
    let r = taps / 2;
    let border = |x: usize, px: &mut dyn FnMut(&[[i32; 3]])| {
        let mut win = [[0i32; 3]; MAX_TAPS];
        for (t, v) in win.iter_mut().enumerate().take(taps) {
            let xi = (x + t).saturating_sub(r).min(w.saturating_sub(1));
            *v = col.get(xi).copied().unwrap_or([0; 3]);
        }
        px(win.get(..taps).unwrap_or(&[]));
    };
    if w < taps {
        (0..w).for_each(|x| border(x, &mut px));
        return;
    }
    (0..r).for_each(|x| border(x, &mut px));
    for win in col.windows(taps) {
        px(win);
    }
    (w - r..w).for_each(|x| border(x, &mut px));
}

/// The x pass of one [`Unit`] (see [`Bank`]): the envelope's halves, and
/// for each carrier of the unit its halves (its DC term for `b`) and its
/// output row.
struct XUnit<'h, 'o> {
    env: &'h Half,
    a: Option<(&'h Halves, &'o mut [Z])>,
    b: Option<([i64; 2], &'o mut [Z])>,
    e: Option<(&'h Halves, &'o mut [Z])>,
}

/// `f(i, m, p)` for the window's pairs: tap `i − R` (`i < R`) at `m` and
/// its mirror at `p` (constant indices once `R` is known).
#[inline(always)]
fn mirror<const R: usize>(win: &[[i32; 3]], mut f: impl FnMut(usize, &[i32; 3], &[i32; 3])) {
    for i in 0..R {
        if let (Some(m), Some(p)) = (win.get(i), win.get(2 * R - i)) {
            f(i, m, p);
        }
    }
}

/// Tap `i` of a half, `[re, im]`.
#[inline(always)]
fn tap(h: &[[i32; 2]; MAX_RADIUS + 1], i: usize) -> [i64; 2] {
    h.get(i)
        .map_or([0; 2], |k| [i64::from(k[0]), i64::from(k[1])])
}

impl XUnit<'_, '_> {
    /// Runs over the row with radius `R` (the bank's), the sums in groups
    /// of at most three 64-bit accumulators (they stay in registers).
    fn run<const R: usize>(self, col: &[[i32; 3]]) {
        let env = self.env;
        let ec = i64::from(env.get(R).copied().unwrap_or(0));
        let et = |i: usize| i64::from(env.get(i).copied().unwrap_or(0));
        let mut a = self.a.map(|(h, o)| (h, o.iter_mut()));
        let mut b = self.b.map(|(dc, o)| (dc, o.iter_mut()));
        let mut e = self.e.map(|(h, o)| (h, o.iter_mut()));
        for_windows(col, 2 * R + 1, |win| {
            let Some(c) = win.get(..2 * R + 1).and_then(|w| w.get(R)) else {
                return;
            };
            let (ca, cr, ci) = (i64::from(c[0]), i64::from(c[1]), i64::from(c[2]));
            // bl = Σ env·E, with the rider's [re, im] = Σ kx·E.
            let mut bl = ec * ca;
            if let Some((h, o)) = &mut e {
                let mut re = tap(&h.kx, R)[0] * ca;
                mirror::<R>(win, |i, m, p| {
                    let pe = i64::from(m[0] + p[0]);
                    bl += et(i) * pe;
                    re += tap(&h.kx, i)[0] * pe;
                });
                let mut im = 0;
                mirror::<R>(win, |i, m, p| {
                    im += tap(&h.kx, i)[1] * i64::from(m[0] - p[0])
                });
                if let Some(o) = o.next() {
                    *o = finish([re, im], bl >> KERNEL_FRAC, h.dc);
                }
            } else {
                mirror::<R>(win, |i, m, p| bl += et(i) * i64::from(m[0] + p[0]));
            }
            let Some((h, oa)) = &mut a else {
                return;
            };
            // A = Σ kx_re·Yr, C = Σ kx_re·Yi; B = Σ kx_im·Yi, D = Σ kx_im·Yr.
            let k = tap(&h.kx, R)[0];
            let (mut sa, mut sc) = (k * cr, k * ci);
            mirror::<R>(win, |i, m, p| {
                let k = tap(&h.kx, i)[0];
                sa += k * i64::from(m[1] + p[1]);
                sc += k * i64::from(m[2] + p[2]);
            });
            let (mut sb, mut sd) = (0, 0);
            mirror::<R>(win, |i, m, p| {
                let k = tap(&h.kx, i)[1];
                sb += k * i64::from(m[2] - p[2]);
                sd += k * i64::from(m[1] - p[1]);
            });
            let bl = bl >> KERNEL_FRAC;
            if let Some(o) = oa.next() {
                *o = finish([sa - sb, sc + sd], bl, h.dc);
            }
            if let Some((dc, ob)) = &mut b {
                if let Some(o) = ob.next() {
                    *o = finish([sa + sb, sd - sc], bl, *dc);
                }
            }
        });
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
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    const W: usize = 40;

    /// `Bank::row` against `y_pass` + `x_pass` per carrier on random rows
    /// (with the extremes 0 and 65535 often), every width up to `W`.
    fn check(kernels: &[Gabor], rng: &mut SplitMix64) -> bool {
        let bank = Bank::new(kernels);
        let taps = bank.taps();
        for w in [1, 2, 3, taps - 1, taps, taps + 1, 2 * taps + 3, W] {
            let w = w.clamp(1, W);
            let mut grey = [[0u16; W]; MAX_TAPS];
            for v in grey.iter_mut().flatten() {
                *v = match rng.below(4) {
                    0 => 0,
                    1 => 65535,
                    _ => rng.below(65536) as u16,
                };
            }
            let rows: [&[u16]; MAX_TAPS] = core::array::from_fn(|t| &grey[t][..w]);
            let mut col = [[0i32; 3]; W];
            let mut fast = [[0i16; 2]; MAX_CARRIERS * W];
            bank.row(&rows[..taps], &mut col[..w], &mut fast[..kernels.len() * w]);
            for (c, g) in kernels.iter().enumerate() {
                let skip = taps / 2 - g.radius();
                let mut slow = [[0i16; 2]; W];
                y_pass(g, rows[skip..].iter().copied(), &mut col[..w]);
                x_pass(g, &col[..w], &mut slow[..w]);
                assert_eq!(
                    &fast[c * w..(c + 1) * w],
                    &slow[..w],
                    "carrier {c} width {w}"
                );
            }
        }
        bank.is_fast()
    }

    #[test]
    fn the_bank_gives_the_reference_bits() {
        let mut rng = SplitMix64::new(3);
        let (mut fast, mut all) = (0, 0);
        for n in 1..=MAX_CARRIERS {
            for radius in [1u8, 2, 3, 7, 11, 15] {
                for lambda in [2.5f32, 4.0, 7.0, 13.0] {
                    for sigma in [0.3f32, 0.56, 1.2] {
                        let kernels: [Gabor; MAX_CARRIERS] = core::array::from_fn(|k| {
                            Gabor::new(lambda, sigma, radius, carrier_deg(k.min(n - 1), n))
                        });
                        fast += usize::from(check(&kernels[..n], &mut rng));
                        all += 1;
                    }
                }
            }
        }
        // Every setting was checked above; the defaults take the fast path
        // (the others fall back where the largest-remainder envelope is not
        // symmetric or Σ|ky| > 2^14).
        let d: [Gabor; 3] = core::array::from_fn(|k| Gabor::new(4.0, 0.56, 7, carrier_deg(k, 3)));
        assert!(Bank::new(&d).is_fast());
        assert!(
            fast > 0 && fast < all,
            "fast path for {fast} of {all} settings"
        );
    }

    #[test]
    fn the_default_bank_shares_the_y_passes() {
        let d: [Gabor; 3] = core::array::from_fn(|k| Gabor::new(4.0, 0.56, 7, carrier_deg(k, 3)));
        let bank = Bank::new(&d);
        let units = &bank.units[..bank.n_units];
        assert_eq!(
            units,
            [Unit {
                a: Some(0),
                b: Some(2),
                e: Some(1)
            }]
        );
    }

    /// The pyramid row as the direct 25-tap sum with a clamp per tap.
    fn pyramid_direct(rows: [&[u16]; 5], out: &mut [u16]) {
        const B: [u32; 5] = [1, 4, 6, 4, 1];
        let w = rows[0].len();
        for (i, o) in out.iter_mut().enumerate() {
            let mut acc = 0u32;
            for (row, by) in rows.iter().zip(B) {
                for (t, bx) in B.iter().enumerate() {
                    let x = (2 * i + t).saturating_sub(2).min(w.saturating_sub(1));
                    acc += by * bx * u32::from(row.get(x).copied().unwrap_or(0));
                }
            }
            *o = ((acc + 128) >> 8) as u16;
        }
    }

    #[test]
    fn the_running_pyramid_is_the_direct_sum() {
        let mut rng = SplitMix64::new(9);
        for w in 0..=W {
            for _ in 0..20 {
                let mut grey = [[0u16; W]; 5];
                for v in grey.iter_mut().flatten() {
                    *v = if rng.below(3) == 0 {
                        65535
                    } else {
                        rng.below(65536) as u16
                    };
                }
                let rows: [&[u16]; 5] = core::array::from_fn(|t| &grey[t][..w]);
                let (mut a, mut b) = ([1u16; W], [2u16; W]);
                let lw = level_size(w, 1);
                pyramid_row(rows, &mut a[..lw]);
                pyramid_direct(rows, &mut b[..lw]);
                assert_eq!(a[..lw], b[..lw], "width {w}");
            }
        }
    }

    #[test]
    fn mixed_radii_fall_back_to_the_reference() {
        let mut rng = SplitMix64::new(5);
        let k = [
            Gabor::new(4.0, 0.56, 7, -45.0),
            Gabor::new(4.0, 0.56, 4, 0.0),
        ];
        assert!(!check(&k, &mut rng));
    }
}
