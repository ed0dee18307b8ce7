//! sRGB (8 bit) to CIELUV (D65) in fixed point, by tables built once.
//!
//! Per pixel, integer only:
//! 1. linear light from a 256-entry table, in Q20;
//! 2. XYZ = M · linear with M in Q20, accumulated in `u64`, rounded to Q24;
//! 3. L* by linear interpolation in a 1025-interval table over Y (Q9 entries);
//! 4. u′ and v′ as exact floors in Q18 by a two-step 32-bit long division on
//!    a normalised denominator (no 64-bit division, which a Cortex-M4 lacks);
//! 5. u* = 13 L* (u′ − u′ₙ), v* likewise, rounded once to [`I10F6`].
//!
//! The derivation of the error bounds against the f32 reference is in
//! `docs/ERROR_BOUNDS.md`; the constants [`MAX_ERR_L`], [`MAX_ERR_U`] and
//! [`MAX_ERR_V`] state them, in CIELUV units.

use crate::fixed::{round_shift, I10F6};
use crate::image::Rgb8;

/// D65 sRGB to XYZ, rows X, Y, Z (IEC 61966-2-1, four digits).
pub const SRGB_TO_XYZ: [[f64; 3]; 3] = [
    [0.4124, 0.3576, 0.1805],
    [0.2126, 0.7152, 0.0722],
    [0.0193, 0.1192, 0.9505],
];
/// u′ of the D65 white point.
pub const WHITE_U: f64 = 0.19784;
/// v′ of the D65 white point.
pub const WHITE_V: f64 = 0.46834;
/// CIE ε: below this Y, L* is linear.
pub const CIE_EPSILON: f64 = 0.008856;
/// CIE κ: the slope of L* below ε.
pub const CIE_KAPPA: f64 = 903.3;

/// Largest |L*| error against the f32 reference, CIELUV units (1.22 LSB).
pub const MAX_ERR_L: f32 = 0.019;
/// Largest |u*| error against the f32 reference, CIELUV units (4.0 LSB).
pub const MAX_ERR_U: f32 = 0.063;
/// Largest |v*| error against the f32 reference, CIELUV units (4.8 LSB).
pub const MAX_ERR_V: f32 = 0.075;

/// Intervals of the L* table over Y in [0, 1].
const L_INTERVALS: usize = 1024;
const LIN_FRAC: u32 = 20;
const M_FRAC: u32 = 20;
const XYZ_FRAC: u32 = 24;
const L_TABLE_FRAC: u32 = 9;
/// Bits of Y below the L* table index.
const L_INDEX_SHIFT: u32 = XYZ_FRAC - 10;
const UV_FRAC: u32 = 18;

/// Largest |raw Q6 value| a [`Luv`] channel holds: ±255.98 CIELUV units.
/// Real CIELUV of sRGB stays within L* 0..100, u* −83..175, v* −134..107
/// (±11 200 LSB), so conversion never reaches it. The bound keeps every
/// channel difference below 2^15, so squared distances are exact in `u32`.
pub const LUV_LIMIT_BITS: i16 = 16_383;

/// A CIELUV pixel, each channel in [`I10F6`] within ±[`LUV_LIMIT_BITS`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Luv {
    l: I10F6,
    u: I10F6,
    v: I10F6,
}

impl Luv {
    /// A pixel from raw Q6 bits, each clamped to ±[`LUV_LIMIT_BITS`].
    pub const fn from_bits(l: i16, u: i16, v: i16) -> Self {
        Self::in_range(clamp_bits(l), clamp_bits(u), clamp_bits(v))
    }

    /// A pixel from bits the caller has proven to lie within the limit
    /// (conversion output, means of valid pixels).
    #[inline(always)]
    pub(crate) const fn in_range(l: i16, u: i16, v: i16) -> Self {
        Self {
            l: I10F6::from_bits(l),
            u: I10F6::from_bits(u),
            v: I10F6::from_bits(v),
        }
    }

    /// The raw Q6 bits `[l, u, v]`.
    pub const fn to_bits(self) -> [i16; 3] {
        [self.l.to_bits(), self.u.to_bits(), self.v.to_bits()]
    }

    /// Lightness L*, 0..100.
    pub const fn l(self) -> I10F6 {
        self.l
    }

    /// Red–green u*.
    pub const fn u(self) -> I10F6 {
        self.u
    }

    /// Yellow–blue v*.
    pub const fn v(self) -> I10F6 {
        self.v
    }
}

const fn clamp_bits(x: i16) -> i16 {
    if x > LUV_LIMIT_BITS {
        LUV_LIMIT_BITS
    } else if x < -LUV_LIMIT_BITS {
        -LUV_LIMIT_BITS
    } else {
        x
    }
}

/// The tables of the conversion: 3 KB, built once by [`LuvTables::new`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LuvTables {
    /// sRGB code to linear light, Q20.
    lin: [u32; 256],
    /// Rows of [`SRGB_TO_XYZ`] in Q20.
    m: [[u32; 3]; 3],
    /// L*(i / 1024) in Q9, for i in 0..=1025 (the last entry only pads the
    /// interpolation at Y = 1).
    l: [u16; L_INTERVALS + 2],
    /// u′ₙ, v′ₙ in Q18.
    white: [i32; 2],
}

/// sRGB decoding, `c` in [0, 1].
#[allow(clippy::float_arithmetic)]
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        libm::pow((c + 0.055) / 1.055, 2.4)
    }
}

/// L* of luminance `y` (white = 1).
#[allow(clippy::float_arithmetic)]
pub fn lightness(y: f64) -> f64 {
    if y > CIE_EPSILON {
        116.0 * libm::cbrt(y) - 16.0
    } else {
        CIE_KAPPA * y
    }
}

#[allow(
    clippy::float_arithmetic,
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss
)]
fn quantise(x: f64, frac: u32) -> u32 {
    libm::round(x * f64::from(1u32 << frac)) as u32
}

/// The tables of [`LuvTables::new`], as constants: in flash on a board,
/// so that a holder of the stage's tables (the pipeline) carries a
/// reference, not 3 KB of RAM that moves with it. Equal to
/// [`LuvTables::new`]'s (the test `the_static_tables_are_their_definition`).
pub static LUV_TABLES: LuvTables = LuvTables {
    lin: super::luv_table::LIN,
    m: super::luv_table::M,
    l: super::luv_table::L,
    white: super::luv_table::WHITE,
};

impl Default for LuvTables {
    fn default() -> Self {
        Self::new()
    }
}

impl LuvTables {
    /// Builds the tables. One-time setup: the only floats of the stage.
    #[allow(clippy::float_arithmetic, clippy::cast_possible_truncation)]
    pub fn new() -> Self {
        let lin = core::array::from_fn(|i| {
            quantise(srgb_to_linear(f64::from(i as u8) / 255.0), LIN_FRAC)
        });
        let m = SRGB_TO_XYZ.map(|row| row.map(|c| quantise(c, M_FRAC)));
        let l = core::array::from_fn(|i| {
            quantise(lightness(i as f64 / L_INTERVALS as f64), L_TABLE_FRAC) as u16
        });
        let white = [WHITE_U, WHITE_V].map(|w| quantise(w, UV_FRAC) as i32);
        Self { lin, m, l, white }
    }

    /// Converts one pixel.
    #[inline]
    pub fn convert(&self, p: Rgb8) -> Luv {
        let lin = |c: u8| u64::from(*self.lin.get(usize::from(c)).unwrap_or(&0));
        let (r, g, b) = (lin(p.r), lin(p.g), lin(p.b));
        let dot = |row: &[u32; 3]| {
            let [a, b2, c] = row.map(u64::from);
            let acc = a * r + b2 * g + c * b;
            // < 1.09 * 2^40, so Q24 fits u32 after the shift.
            round_shift(acc as i64, LIN_FRAC + M_FRAC - XYZ_FRAC) as u32
        };
        let [mx, my, mz] = &self.m;
        let (x, y, z) = (dot(mx), dot(my), dot(mz));

        // L* in Q23 by interpolation; Y <= 2^24 so the index is <= 1024.
        let idx = (y >> L_INDEX_SHIFT) as usize;
        let frac = y & ((1 << L_INDEX_SHIFT) - 1);
        let l0 = u32::from(*self.l.get(idx).unwrap_or(&0));
        let l1 = u32::from(*self.l.get(idx + 1).unwrap_or(&0));
        let l_q23 = (l0 << L_INDEX_SHIFT) + l1.saturating_sub(l0) * frac;
        let l_bits = round_shift(i64::from(l_q23), L_TABLE_FRAC + L_INDEX_SHIFT - 6) as i16;

        let denom = x + 15 * y + 3 * z;
        if denom == 0 {
            return Luv::in_range(l_bits, 0, 0);
        }
        let (d, nu, nv) = normalise(denom, 4 * x, 9 * y);
        let [wu, wv] = self.white;
        let chroma = |n: u32, white: i32| {
            // |13 * diff| < 2^24 fits i32, so the product is one 32x32->64
            // multiply: L(Q23) * 13 diff(Q18) < 2^54; back to Q6.
            let diff13 = 13 * (div_q18(n, d) as i32 - white);
            let q = i64::from(l_q23) * i64::from(diff13);
            round_shift(q, L_TABLE_FRAC + L_INDEX_SHIFT + UV_FRAC - 6) as i16
        };
        // In range: |L*| <= 100, |u*|, |v*| <= 175 units (module docs).
        Luv::in_range(l_bits, chroma(nu, wu), chroma(nv, wv))
    }
}

/// Shifts `d` (and the numerators with it) into [2^20, 2^21). Numerators are
/// at most 4·d, so they stay below 2^23.
#[inline(always)]
fn normalise(d: u32, n1: u32, n2: u32) -> (u32, u32, u32) {
    let bits = 32 - d.leading_zeros();
    if bits > 21 {
        let s = bits - 21;
        (d >> s, n1 >> s, n2 >> s)
    } else {
        let s = 21 - bits;
        (d << s, n1 << s, n2 << s)
    }
}

/// `floor(n / d * 2^18)` for `d` in [2^20, 2^21) and `n < 2^23`, with two
/// 32-bit divisions (8 then 10 fraction bits).
#[inline(always)]
fn div_q18(n: u32, d: u32) -> u32 {
    // `d` is already in [2^20, 2^21), so this changes nothing; it lets the
    // compiler see that `d` is not 0, and drop the division's panic path.
    let d = d | (1 << 20);
    let a = n << 8;
    let qa = a / d;
    let ra = a - qa * d;
    let qb = (ra << 10) / d;
    (qa << 10) + qb
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_division_is_the_exact_floor() {
        for (n, d) in [
            (0u32, 1u32 << 20),
            (1, 1 << 20),
            ((1 << 23) - 1, 1 << 20),
            (777_777, 2_000_001),
        ] {
            let exact = (u64::from(n) << 18) / u64::from(d);
            assert_eq!(u64::from(div_q18(n, d)), exact, "{n}/{d}");
        }
    }

    #[test]
    fn the_static_tables_are_their_definition() {
        assert_eq!(LUV_TABLES, LuvTables::new());
    }

    #[test]
    fn white_and_black_are_exact() {
        let t = LuvTables::new();
        let w = t.convert(Rgb8::new(255, 255, 255)).to_bits();
        assert_eq!(w[0], 100 * 64);
        // The 4-digit matrix maps white to v′ = 0.468323, 1.7e-5 below v′ₙ:
        // v* = -0.022 (-1.4 LSB), not 0.
        assert!(w[1].abs() <= 1 && (-3..=0).contains(&w[2]), "{w:?}");
        assert_eq!(t.convert(Rgb8::new(0, 0, 0)).to_bits(), [0, 0, 0]);
    }
}
