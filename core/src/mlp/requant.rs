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
//! The doubling high multiply rounds halves up (gemmlowp's nudge and
//! truncation, see [`doubling_high_mul`]); the division by a power of two
//! rounds half away from zero. One difference from the C:
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

/// gemmlowp's `SaturatingRoundingDoublingHighMul`: `a · b / 2^31` rounded
/// to nearest, `i32::MAX` for the one overflowing case `a = b = i32::MIN`.
///
/// gemmlowp adds a nudge of `2^30` (`1 − 2^30` when `a · b < 0`) and divides
/// by `2^31` truncating toward zero. For `p = a · b < 0` that is
/// `ceil((p + 1 − 2^30) / 2^31) = floor((p + 2^30) / 2^31)`, the same
/// expression as for `p >= 0`; so halves round up (toward +∞), and one
/// add and one arithmetic shift compute it (`smull`, `adds`, `adc` and two
/// shifts on the Cortex-M4). `|p + 2^30| < 2^62`, and the quotient fits
/// `i32` except in the case handled first. The test module keeps gemmlowp's
/// form and checks the two agree.
#[inline]
pub const fn doubling_high_mul(a: i32, b: i32) -> i32 {
    if a == i32::MIN && b == i32::MIN {
        return i32::MAX;
    }
    ((a as i64 * b as i64 + (1i64 << 30)) >> 31) as i32
}

/// `x / 2^exponent` rounded to nearest, halves away from zero
/// (gemmlowp's `RoundingDivideByPOT`); `exponent` is clamped to `0..=31`.
///
/// gemmlowp compares the remainder `r = x mod 2^e` with the threshold
/// `2^(e−1) − 1 + [x < 0]`; `r > threshold` exactly when
/// `r + 2^(e−1) − [x < 0] >= 2^e`, so the result is
/// `floor((x + 2^(e−1) − [x < 0]) / 2^e)`: one add and one arithmetic
/// shift in `i64` (no overflow). The test module checks it against
/// gemmlowp's form.
#[inline]
pub const fn rounding_divide_by_pot(x: i32, exponent: i32) -> i32 {
    let e = if exponent < 0 {
        0
    } else if exponent > 31 {
        31
    } else {
        exponent
    };
    if e == 0 {
        return x;
    }
    let neg = if x < 0 { 1i64 } else { 0 };
    ((x as i64 + (1i64 << (e - 1)) - neg) >> e) as i32
}

/// TFLM's `MultiplyByQuantizedMultiplier(x, multiplier, shift)`: `x` times
/// `multiplier · 2^(shift − 31)`, integer only. `shift` is clamped to
/// `−31..=30`; the left shift saturates.
#[inline]
pub const fn requantize(x: i32, multiplier: i32, shift: i32) -> i32 {
    // Models written by `protogist quantize` have `shift <= 0`: no
    // multiply before the high multiply.
    let scaled = if shift > 0 {
        x.saturating_mul(1 << if shift > 30 { 30 } else { shift })
    } else {
        x
    };
    let right = if shift < 0 { -shift } else { 0 };
    rounding_divide_by_pot(doubling_high_mul(scaled, multiplier), right)
}

/// [`requantize`] of 16-bit values with one `(multiplier, shift)`, its
/// loop-invariant parts computed once (the input layer: 720 values, one
/// pair). Bit-identical to [`requantize`] for every `i16` (tested
/// exhaustively). With `shift <= 0` and `|x| <= 2^15` the high multiply
/// cannot saturate and `|d| <= 2^15`, so the rounding division runs in
/// `i32` as `(d + 2^(e−1) − [d < 0]) >> e` (see [`rounding_divide_by_pot`]);
/// a positive shift takes the general path.
#[inline(always)]
pub fn requantize_i16(multiplier: i32, shift: i32) -> impl Fn(i16) -> i32 {
    let e = if shift < -31 {
        31
    } else if shift < 0 {
        -shift
    } else {
        0
    };
    let half = if e == 0 { 0 } else { 1i32 << (e - 1) };
    // −[d < 0] is `d >> 31`; masked off when e = 0 (no rounding).
    let neg_mask = if e == 0 { 0 } else { -1 };
    move |x| {
        if shift > 0 {
            return requantize(i32::from(x), multiplier, shift);
        }
        let d = ((i64::from(x) * i64::from(multiplier) + (1i64 << 30)) >> 31) as i32;
        (d + half + ((d >> 31) & neg_mask)) >> e
    }
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

    /// gemmlowp's `SaturatingRoundingDoublingHighMul`, as written there.
    fn gemmlowp_srdhm(a: i32, b: i32) -> i32 {
        if a == i32::MIN && b == i32::MIN {
            return i32::MAX;
        }
        let ab = a as i64 * b as i64;
        let nudge = if ab >= 0 {
            1i64 << 30
        } else {
            1 - (1i64 << 30)
        };
        ((ab + nudge) / (1i64 << 31)) as i32
    }

    /// gemmlowp's `RoundingDivideByPOT`, as written there.
    fn gemmlowp_rdbp(x: i32, exponent: i32) -> i32 {
        let e = exponent.clamp(0, 31);
        let mask = ((1i64 << e) - 1) as i32;
        let remainder = x & mask;
        let threshold = (mask >> 1) + i32::from(x < 0);
        (x >> e) + i32::from(remainder > threshold)
    }

    /// Values that sit on rounding boundaries and at the ends of `i32`.
    fn edges() -> impl Iterator<Item = i32> {
        let pow = (0..31).flat_map(|k| {
            let p = 1i32 << k;
            [p, p - 1, p + 1, -p, -p - 1, -p + 1, p / 2 * 3]
        });
        pow.chain([0, 1, -1, i32::MAX, i32::MIN, i32::MIN + 1, i32::MAX - 1])
    }

    #[test]
    fn requantize_i16_equals_requantize_for_every_i16() {
        let mut rng = crate::rng::SplitMix64::new(16);
        let mut pairs = [(0i32, 0i32); 96];
        for (k, p) in pairs.iter_mut().enumerate() {
            let m = match k % 4 {
                0 => i32::MAX,
                1 => 1 << 30,
                _ => (1 << 30) + (rng.next_u64() % (1 << 30)) as i32,
            };
            // Every shift in -33..=32 once or more, the rest at random.
            let s = if k < 66 {
                k as i32 - 33
            } else {
                (rng.next_u64() % 40) as i32 - 35
            };
            *p = (m, s);
        }
        pairs[95] = (0, -7);
        for (m, s) in pairs {
            let f = requantize_i16(m, s);
            for x in i16::MIN..=i16::MAX {
                assert_eq!(f(x), requantize(i32::from(x), m, s), "x {x} m {m} s {s}");
            }
        }
    }

    #[test]
    fn fast_forms_equal_gemmlowp_on_edges_and_random_values() {
        let mut rng = crate::rng::SplitMix64::new(5);
        let edges: [i32; 224] = {
            let mut e = [0; 224];
            e.iter_mut().zip(edges()).for_each(|(d, s)| *d = s);
            e
        };
        for &a in &edges {
            for &b in &edges {
                assert_eq!(doubling_high_mul(a, b), gemmlowp_srdhm(a, b), "{a} {b}");
            }
            for e in -2..34 {
                assert_eq!(rounding_divide_by_pot(a, e), gemmlowp_rdbp(a, e), "{a} {e}");
            }
        }
        for _ in 0..200_000 {
            let (a, b) = (rng.next_u64() as i32, rng.next_u64() as i32);
            assert_eq!(doubling_high_mul(a, b), gemmlowp_srdhm(a, b), "{a} {b}");
            let e = (rng.next_u64() % 36) as i32 - 2;
            assert_eq!(rounding_divide_by_pot(a, e), gemmlowp_rdbp(a, e), "{a} {e}");
            // Small values, where every rounding boundary is hit often.
            let (s, e) = (
                (rng.next_u64() % 4096) as i32 - 2048,
                (rng.next_u64() % 12) as i32,
            );
            assert_eq!(rounding_divide_by_pot(s, e), gemmlowp_rdbp(s, e), "{s} {e}");
        }
    }

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
