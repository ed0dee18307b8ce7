//! The colour stage's Cortex-M4 kernel ([`ColourKernel`] for [`PhaseAsm`]):
//! squared CIELUV distances with the DSP pair instructions, for the
//! smoothing cell and C~.
//!
//! A [`Luv`] is three `i16` (L*, u*, v*, `repr(C)`), so its first word is
//! L* | u* << 16; the M4 loads it with one `LDR` from the 2-aligned
//! address (unaligned word loads are allowed on v7-M). Per distance:
//!
//! ```text
//! ssub16 d, a_lu, b_lu     ; dL | du << 16, each exact: |dL|, |du| <= 32 766
//! smuad  s, d, d           ; dL² + du² <= 2 · 32 766² < 2^31: no overflow
//! sub    t, a_v, b_v
//! mla    s, t, t, s        ; + dv² < 2^30: the sum < 3 · 2^30 < 2^32
//! ```
//!
//! 4 instructions and 4 loads (2 per pixel) where the portable code has
//! 6 loads and 6 arithmetic instructions, and a pixel held in 2 registers
//! instead of 3, which is what made the portable cell spill. The sums of
//! the kept pixels unpack the word with `SXTAH` and an `ASR`-shifted add;
//! the mean rounds as core's `div5_round` does. The result is core's
//! portable [`snn_row`](firmware_sim::pg::conspicuity::snn_row) and
//! [`pair_dist2`](firmware_sim::pg::conspicuity::pair_dist2), bit for bit:
//! `cargo xtask product` compares the QEMU product (this kernel) with the
//! host's (the portable one), the smoothed colour reaching the objects
//! through the completion.

#![allow(unsafe_code)]

use crate::dsp::PhaseAsm;
use firmware_sim::pg::conspicuity::{ColourKernel, Luv};

/// A pixel as the kernel holds it: L* | u* << 16, and v*.
#[derive(Clone, Copy)]
struct Px {
    lu: u32,
    v: i32,
}

#[inline(always)]
fn px(p: &Luv) -> Px {
    let [_, _, v] = p.to_bits();
    // SAFETY: `Luv` is `repr(C)` of three `i16` (6 bytes, `bytemuck::Pod`),
    // so its first 4 bytes are L* and u*, little-endian; `read_unaligned`
    // takes the 2-aligned address.
    let lu = unsafe { core::ptr::read_unaligned(core::ptr::from_ref(p).cast::<u32>()) };
    Px {
        lu,
        v: i32::from(v),
    }
}

/// Squared distance, Q12: the portable `dist2`'s value (see the module
/// docs for the ranges).
#[inline(always)]
fn d2(a: Px, b: Px) -> u32 {
    let s: u32;
    // SAFETY: registers only (SMUAD may set the sticky Q flag; it cannot
    // overflow here).
    unsafe {
        core::arch::asm!(
            "ssub16 {d}, {a}, {b}",
            "smuad {s}, {d}, {d}",
            a = in(reg) a.lu,
            b = in(reg) b.lu,
            d = out(reg) _,
            s = lateout(reg) s,
            options(pure, nomem, nostack),
        );
    }
    let dv = a.v - b.v;
    s.wrapping_add((dv * dv) as u32)
}

/// core's `div5_round`: `round(s / 5)`, ties toward +∞, for
/// `|s| <= 5 · 2^15`.
#[inline(always)]
fn div5_round(s: i32) -> i16 {
    let biased = (2 * s + 5 + 327_680) as u32;
    ((biased / 10) as i32 - 32_768) as i16
}

impl ColourKernel for PhaseAsm {
    fn snn_row(prev: &[Luv], cur: &[Luv], next: &[Luv], out: &mut [Luv]) {
        let cells = prev.windows(3).zip(cur.windows(3)).zip(next.windows(3));
        for (((up, mid), down), o) in cells.zip(out.iter_mut()) {
            let ([a0, a1, a2], [b0, b1, b2], [c0, c1, c2]) = (up, mid, down) else {
                continue;
            };
            let c = px(b1);
            let (mut l, mut u, mut v) = (i32::from(c.lu as i16), (c.lu as i32) >> 16, c.v);
            for (m, p) in [(b0, b2), (a0, c2), (a1, c1), (a2, c0)] {
                let (m, p) = (px(m), px(p));
                // The `p - δ` member on a tie, as the portable cell.
                let k = if d2(c, m) <= d2(c, p) { m } else { p };
                l += i32::from(k.lu as i16);
                u += (k.lu as i32) >> 16;
                v += k.v;
            }
            // SAFETY: as in `px`; the mean of 5 pixels within the `Luv`
            // limit is within it.
            unsafe {
                core::ptr::write_unaligned(
                    core::ptr::from_mut(o).cast::<[i16; 3]>(),
                    [div5_round(l), div5_round(u), div5_round(v)],
                );
            }
        }
    }

    fn pair_dist2(up: &[Luv], mid: &[Luv], down: &[Luv]) -> u32 {
        let ([a0, a1, a2], [b0, _, b2], [c0, c1, c2]) = (up, mid, down) else {
            return 0;
        };
        d2(px(b0), px(b2))
            .max(d2(px(a0), px(c2)))
            .max(d2(px(a1), px(c1)))
            .max(d2(px(a2), px(c0)))
    }
}
