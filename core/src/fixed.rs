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
//!
//! **Rounding rule.** Every requantisation in core rounds to nearest, ties
//! toward +∞: add half an LSB of the target, then shift or divide with floor
//! ([`round_shift`], [`div_round`]). The float references do not round; the
//! half-LSB this costs is part of every stage's error bound.

pub use fixed::types::{I10F6, U10F6};

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

/// `round(sqrt(x))` exactly, ties (never reached for integers) toward +∞.
///
/// Integer only: an initial guess from the bit length, then Newton steps from
/// above, which decrease monotonically to `floor(sqrt(x))`.
#[inline]
pub const fn isqrt_round(x: u32) -> u32 {
    if x == 0 {
        return 0;
    }
    let bits = 32 - x.leading_zeros();
    // 2^ceil(bits/2) >= sqrt(x).
    let mut y = 1u32 << bits.div_ceil(2);
    loop {
        let next = (y + x / y) / 2;
        if next >= y {
            break;
        }
        y = next;
    }
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
    fn rounding_ties_go_up() {
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
