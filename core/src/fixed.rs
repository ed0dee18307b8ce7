//! Fixed-point formats and the one rounding rule.
//!
//! Formats are named as in the [`fixed`] crate: `I10F6` is a signed 16-bit
//! number with 10 integer bits (sign included) and 6 fraction bits, so one
//! LSB is 1/64. Core stores values in the `fixed` types and computes on their
//! raw bits ([`fixed::FixedI16::to_bits`]) in the per-pixel loops.
//!
//! | quantity | format | LSB | range |
//! |---|---|---|---|
//! | CIELUV L*, u*, v* | [`I10F6`] | 1/64 | ±512 |
//! | conspicuity C~ (CIELUV distance) | [`U10F6`] | 1/64 | 0..1024 |
//! | disparity, px | [`U8F8`] | 1/256 | 0..256 |
//!
//! **Rounding rule.** Every requantisation in core rounds to nearest, ties
//! toward +∞: add half an LSB of the target, then shift or divide with floor
//! ([`round_shift`], [`div_round`]). The float references do not round; the
//! half-LSB this costs is part of every stage's error bound.

pub use fixed::types::{I10F6, U10F6, U8F8};

use core::num::NonZeroU32;

/// `x / 2^n` rounded to nearest, ties toward +∞. `n` must be in `1..=62`.
#[inline(always)]
pub const fn round_shift(x: i64, n: u32) -> i64 {
    (x + (1 << (n - 1))) >> n
}

/// `x / d` rounded to nearest, ties toward +∞, for `d > 0`.
#[inline(always)]
pub const fn div_round(x: i32, d: i32) -> i32 {
    (2 * x + d).div_euclid(2 * d)
}

/// `x / d` rounded to nearest, ties toward +∞, for `d > 0`: [`div_round`]
/// in `i64`.
#[inline(always)]
pub const fn div_round_i64(x: i64, d: i64) -> i64 {
    (2 * x + d).div_euclid(2 * d)
}

/// Digit-by-digit floor square root: no division, one bit pair per step.
macro_rules! isqrt_floor_digits {
    ($name:ident, $t:ty, $doc:literal) => {
        #[doc = $doc]
        pub const fn $name(x: $t) -> $t {
            let mut rem = x;
            let mut root: $t = 0;
            let mut bit: $t = 1 << (<$t>::BITS - 2);
            while bit > x {
                bit >>= 2;
            }
            while bit != 0 {
                if rem >= root + bit {
                    rem -= root + bit;
                    root = (root >> 1) + bit;
                } else {
                    root >>= 1;
                }
                bit >>= 2;
            }
            root
        }
    };
}

isqrt_floor_digits!(
    isqrt_floor_u64,
    u64,
    "`floor(sqrt(x))` for `u64` (32 steps)."
);
isqrt_floor_digits!(
    isqrt_floor_u128,
    u128,
    "`floor(sqrt(x))` for `u128` (64 steps)."
);

/// `round(sqrt(x))` for `u64`; [`isqrt_round`] when `x` fits in `u32`.
#[inline]
pub fn isqrt_round_u64(x: u64) -> u64 {
    if let Ok(small) = u32::try_from(x) {
        return u64::from(isqrt_round(small));
    }
    let y = isqrt_floor_u64(x);
    // x >= (y + 1/2)^2 = y^2 + y + 1/4 rounds up.
    if x - y * y > y {
        y + 1
    } else {
        y
    }
}

/// `floor(16 · sqrt(t))` for `t` in 0..256: the first guess of [`isqrt_round`].
// Evaluated at compile time: an index out of bounds would fail the build.
#[allow(clippy::indexing_slicing)]
const SQRT_SEED: [u8; 256] = {
    let mut t = [0u8; 256];
    let mut i = 0;
    while i < 256 {
        // floor(sqrt(256 i)), by counting up: at most 255 steps, const only.
        let mut r = 0u32;
        while (r + 1) * (r + 1) <= 256 * i as u32 {
            r += 1;
        }
        t[i] = if r > 255 { 255 } else { r as u8 };
        i += 1;
    }
    t
};

/// `round(sqrt(x))` exactly, ties (never reached for integers) toward +∞.
///
/// Integer only: an 8-bit first guess from a table of the top bits, one
/// Newton step (which lands at or above the root), then Newton steps from
/// above, which decrease monotonically to `floor(sqrt(x))`; usually one.
#[inline]
pub fn isqrt_round(x: u32) -> u32 {
    if x == 0 {
        return 0;
    }
    // Scale x by an even power of 4^k into t in [64, 256), so that
    // sqrt(x) = sqrt(t) * 2^k with sqrt(t) in [8, 16).
    let bits = 32 - x.leading_zeros();
    let k = (bits as i32 - 7) / 2;
    let t = if k >= 0 { x >> (2 * k) } else { x << (-2 * k) };
    let seed = u32::from(*SQRT_SEED.get(t as usize & 0xff).unwrap_or(&255));
    // seed / 16 * 2^k, rounded up to at least 1.
    let y = if k >= 4 {
        seed << (k - 4)
    } else {
        (seed >> (4 - k)).max(1)
    };
    // One step from anywhere lands at or above the root (AM-GM). `y` is at
    // least 1 here and stays so (`next` is 0 only if `y` were): held as
    // `NonZeroU32`, so that the divisions have no panic path.
    let Some(y) = NonZeroU32::new(y) else {
        return 0;
    };
    let first = (y.get() + x / y).div_ceil(2);
    let Some(mut y) = NonZeroU32::new(first) else {
        return 0;
    };
    loop {
        match NonZeroU32::new((y.get() + x / y) / 2) {
            Some(next) if next < y => y = next,
            _ => break,
        }
    }
    let y = y.get();
    // y = floor(sqrt(x)); round up when x >= (y + 1/2)^2 = y^2 + y + 1/4.
    if x - y * y > y {
        y + 1
    } else {
        y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isqrt_round_is_exact() {
        for x in (0u32..200_000).chain((0..2000).map(|k| u32::MAX / 2 - k * 7919)) {
            let exact = libm::sqrt(f64::from(x));
            let r = isqrt_round(x);
            assert!(
                (f64::from(r) - exact).abs() <= 0.5,
                "x={x} r={r} exact={exact}"
            );
        }
    }

    #[test]
    fn isqrt_u64_is_exact() {
        let xs = (0u64..5000)
            .chain((0..5000).map(|k| u64::MAX - k * 1_000_003))
            .chain((1u64..2_000_000).map(|r| r * r))
            .chain((1u64..2_000_000).map(|r| r * r + r))
            .chain((1u64..2_000_000).map(|r| r * r + r + 1));
        for x in xs {
            let f = isqrt_floor_u64(x);
            assert!(u128::from(f) * u128::from(f) <= u128::from(x), "x={x}");
            assert!(
                u128::from(f + 1) * u128::from(f + 1) > u128::from(x),
                "x={x}"
            );
            let r = isqrt_round_u64(x);
            // (r - 1/2)^2 <= x < (r + 1/2)^2, times 4.
            let (x4, r) = (4 * u128::from(x), u128::from(r));
            assert!(r == 0 || (2 * r - 1) * (2 * r - 1) <= x4, "x={x}");
            assert!(x4 < (2 * r + 1) * (2 * r + 1), "x={x}");
        }
    }

    #[test]
    fn isqrt_u128_is_exact() {
        let big = [
            u128::MAX,
            u128::MAX - 1,
            1 << 100,
            (1 << 100) - 1,
            u128::from(u64::MAX),
        ];
        let roots = (1u128..3000).map(|r| r * r * 1_000_003);
        for x in (0u128..3000).chain(big).chain(roots) {
            let f = isqrt_floor_u128(x);
            assert!(f.checked_mul(f).is_some_and(|f2| f2 <= x), "x={x}");
            assert!((f + 1).checked_mul(f + 1).is_none_or(|g| g > x), "x={x}");
        }
    }

    #[test]
    fn rounding_ties_go_up() {
        assert_eq!(div_round_i64(5, 2), 3);
        assert_eq!(div_round_i64(-5, 2), -2);
        assert_eq!(div_round_i64(-8, 5), -2);
        assert_eq!(round_shift(3, 1), 2); // 1.5 -> 2
        assert_eq!(round_shift(-3, 1), -1); // -1.5 -> -1
        assert_eq!(round_shift(5, 2), 1); // 1.25 -> 1
        assert_eq!(div_round(7, 5), 1);
        assert_eq!(div_round(-7, 5), -1);
        assert_eq!(div_round(5, 2), 3); // 2.5 -> 3
        assert_eq!(div_round(-5, 2), -2); // -2.5 -> -2
        assert_eq!(div_round(-8, 5), -2);
    }
}
