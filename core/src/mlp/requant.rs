//! Integer requantisation and the log-sigmoid table.
//!
//! **Requantisation** is TFLM's `MultiplyByQuantizedMultiplier` (the
//! default, double-rounding variant; CMSIS-NN's `arm_nn_requantize` without
//! `CMSIS_NN_USE_SINGLE_ROUNDING` computes the same): a real factor
//! `m = M · 2^(shift − 31)` with `M` in `[2^30, 2^31)` (or 0) is applied as
//!
//! ```text
//! RoundingDivideByPOT(SaturatingRoundingDoublingHighMul(x · 2^max(shift, 0), M), max(−shift, 0))
//! ```
//!
//! The doubling high multiply rounds half away from zero, the division by a
//! power of two rounds half away from zero too. One difference from the C:
//! `x · 2^left` saturates instead of overflowing (undefined in C); models
//! written by `protogist quantize` only use `shift <= 0`, where it does not
//! arise.
//!
//! **Log-sigmoid.** [`logsig_q12`] maps a pre-activation `z` in Q12
//! (`z / 4096`) to `round(65535 · σ(z / 4096))` within 1 LSB, for every
//! `i32`: a table of `σ` at every 1/64 on `[0, 12]` in Q8 above the output
//! LSB, linear interpolation, and `σ(−z) = 1 − σ(z)`. Error budget, in
//! output LSB: interpolation `max|σ''| / 8 · (1/64)² · 65535 = 0.19`, table
//! rounding `1/512`, final rounding 0.5; beyond 12, `65535 · (1 − σ(12))
//! = 0.40`. The host test `logsig_lut_within_one_lsb` checks every `z` in
//! `[−2^16, 2^16]` (σ is monotone and the table saturates beyond).
//! [`logsig_u8`] narrows to `round(255 · σ)` (`65535 = 255 · 257`) within
//! 0.504 LSB of the exact `255 · σ`.

use super::logsig_table::LOGSIG_Q8;

/// `round(a · b / 2^31)`, halves away from zero; `i32::MAX` for the one
/// overflowing case `a = b = i32::MIN` (gemmlowp's
/// `SaturatingRoundingDoublingHighMul`).
#[inline]
pub const fn doubling_high_mul(a: i32, b: i32) -> i32 {
    if a == i32::MIN && b == i32::MIN {
        return i32::MAX;
    }
    let ab = a as i64 * b as i64;
    let nudge = if ab >= 0 {
        1i64 << 30
    } else {
        1 - (1i64 << 30)
    };
    // |ab| <= 2^62 - 2^31 + ..., so the sum does not overflow, and the
    // quotient fits i32 except for the case handled above.
    ((ab + nudge) / (1i64 << 31)) as i32
}

/// `x / 2^exponent` rounded to nearest, halves away from zero
/// (gemmlowp's `RoundingDivideByPOT`); `exponent` is clamped to `0..=31`.
#[inline]
pub const fn rounding_divide_by_pot(x: i32, exponent: i32) -> i32 {
    let e = if exponent < 0 {
        0
    } else if exponent > 31 {
        31
    } else {
        exponent
    };
    let mask = ((1i64 << e) - 1) as i32;
    let remainder = x & mask;
    let threshold = (mask >> 1) + if x < 0 { 1 } else { 0 };
    (x >> e) + if remainder > threshold { 1 } else { 0 }
}

/// TFLM's `MultiplyByQuantizedMultiplier(x, multiplier, shift)`: `x` times
/// `multiplier · 2^(shift − 31)`, integer only. `shift` is clamped to
/// `−31..=30`; the left shift saturates.
#[inline]
pub const fn requantize(x: i32, multiplier: i32, shift: i32) -> i32 {
    let left = if shift > 0 {
        if shift > 30 {
            30
        } else {
            shift
        }
    } else {
        0
    };
    let right = if shift < 0 { -shift } else { 0 };
    rounding_divide_by_pot(
        doubling_high_mul(x.saturating_mul(1 << left), multiplier),
        right,
    )
}

/// Table nodes per unit of `z` (`2^6`): node `i` is `z = i / 64`.
const NODE_BITS: u32 = 6;
/// Fraction bits of `z` ([`logsig_q12`] takes Q12).
pub const Z_FRAC_BITS: u32 = 12;
/// `Z_FRAC_BITS − NODE_BITS`: Q12 steps between two nodes is `2^6`.
const STEP_BITS: u32 = Z_FRAC_BITS - NODE_BITS;

/// `round(65535 · σ(z / 4096))` within 1 LSB (see the module doc).
#[inline]
pub fn logsig_q12(z: i32) -> u16 {
    let a = z.unsigned_abs();
    let i = (a >> STEP_BITS) as usize;
    let f = a & ((1 << STEP_BITS) - 1);
    let v = match (LOGSIG_Q8.get(i), LOGSIG_Q8.get(i.wrapping_add(1))) {
        (Some(&t0), Some(&t1)) => {
            // t <= 65535 · 256 < 2^24 and the weights sum to 2^6: < 2^30.
            let s = t0 * ((1 << STEP_BITS) - f) + t1 * f;
            (s + (1 << (STEP_BITS + 8 - 1))) >> (STEP_BITS + 8)
        }
        _ => 65535,
    };
    let v = if v > 65535 { 65535 } else { v as u16 };
    if z < 0 {
        65535 - v
    } else {
        v
    }
}

/// `round(255 · σ(z / 4096))`: [`logsig_q12`] divided by 257, rounded.
#[inline]
pub fn logsig_u8(z: i32) -> u8 {
    let s = u32::from(logsig_q12(z));
    // (65535 + 128) / 257 = 255.
    ((s + 128) / 257) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_by_hand() {
        assert_eq!(rounding_divide_by_pot(5, 1), 3); // 2.5 -> 3
        assert_eq!(rounding_divide_by_pot(-5, 1), -3); // -2.5 -> -3
        assert_eq!(rounding_divide_by_pot(-6, 2), -2); // -1.5 -> -2
        assert_eq!(rounding_divide_by_pot(7, 0), 7);
        assert_eq!(doubling_high_mul(i32::MIN, i32::MIN), i32::MAX);
        // 0.5 in Q31 times 100: 50.
        assert_eq!(doubling_high_mul(100, 1 << 30), 50);
        // m = 0.75 = (3 << 29) · 2^(0 − 31); 0.75 · 10 = 7.5 -> 8.
        assert_eq!(requantize(10, 3 << 29, 0), 8);
        // m = 0.75 · 2^-2: 0.1875 · 100 = 18.75 -> 19.
        assert_eq!(requantize(100, 3 << 29, -2), 19);
        // m = 0.75 · 2^3 = 6: 6 · 7 = 42.
        assert_eq!(requantize(7, 3 << 29, 3), 42);
        // The left shift saturates at i32::MAX; (2^31 - 1)^2 / 2^31 rounds to 2^31 - 2.
        assert_eq!(requantize(i32::MAX, i32::MAX, 30), i32::MAX - 1);
    }

    #[test]
    fn logsig_ends_and_symmetry() {
        assert_eq!(logsig_q12(i32::MAX), 65535);
        assert_eq!(logsig_q12(i32::MIN), 0);
        for z in [-100_000, -4096, -1, 1, 333, 4096, 49_000] {
            assert_eq!(
                u32::from(logsig_q12(z)) + u32::from(logsig_q12(-z)),
                65535,
                "{z}"
            );
        }
        assert_eq!(logsig_u8(i32::MAX), 255);
        assert_eq!(logsig_u8(i32::MIN), 0);
    }
}
