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
//! instead of 3, which is what made the portable cell spill. The cell's
//! row is one assembly loop (`pg_snn_row`, about 108 instructions a cell
//! against 130 for the same code in Rust, which spilled): the sums of the
//! kept pixels unpack the word with `SXTAH` and an `ASR`-shifted add; the
//! mean rounds as core's `div5_round` does (`UDIV` of `2 s + 5 + 5 · 2^16`
//! by 10). The result is core's
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

// The smoothing cell's row: r0, r1, r2 = the cell's up, middle and down
// rows at `x` (pixels `x..x + 3`), r3 = `out[x]`, [sp] (on entry) = the
// end of `out`. Per cell: the centre (r4 = L* | u* << 16, r5 = v*), the
// sums (r6..r8) started with it, then per pair (m, p) both distances
// (`SSUB16`, `SMUAD`, `SUB`, `MLA`), the nearer member loaded again
// (`ITTEE`; `m` on a tie) and added; then each mean of 5 rounded as
// core's `div5_round` (r12 = 327 685, lr = 10).
macro_rules! snn_row_asm {
    ($(($mlu:literal, $mv:literal, $plu:literal, $pv:literal)),*) => {
        core::arch::global_asm!(
            ".syntax unified",
            ".section .text.pg_snn_row,\"ax\",%progbits",
            ".global pg_snn_row",
            ".type pg_snn_row,%function",
            ".thumb_func",
            "pg_snn_row:",
            "push {{r4-r11, lr}}",
            "movw r12, #5",
            "movt r12, #5",
            "mov lr, #10",
            "1:",
            "ldr r4, [r1, #6]",
            "ldrsh r5, [r1, #10]",
            "sxth r6, r4",
            "asr r7, r4, #16",
            "mov r8, r5",
            $(
                concat!("ldr r9, ", $mlu),
                "ssub16 r9, r4, r9",
                "smuad r9, r9, r9",
                concat!("ldrsh r10, ", $mv),
                "sub r10, r5, r10",
                "mla r9, r10, r10, r9",
                concat!("ldr r10, ", $plu),
                "ssub16 r10, r4, r10",
                "smuad r10, r10, r10",
                concat!("ldrsh r11, ", $pv),
                "sub r11, r5, r11",
                "mla r10, r11, r11, r10",
                "cmp r9, r10",
                "ittee ls",
                concat!("ldrls r9, ", $mlu),
                concat!("ldrshls r10, ", $mv),
                concat!("ldrhi r9, ", $plu),
                concat!("ldrshhi r10, ", $pv),
                "sxtah r6, r6, r9",
                "add r7, r7, r9, asr #16",
                "add r8, r8, r10",
            )*
            "add r6, r12, r6, lsl #1",
            "udiv r6, r6, lr",
            "sub r6, r6, #32768",
            "add r7, r12, r7, lsl #1",
            "udiv r7, r7, lr",
            "sub r7, r7, #32768",
            "add r8, r12, r8, lsl #1",
            "udiv r8, r8, lr",
            "sub r8, r8, #32768",
            "strh r6, [r3]",
            "strh r7, [r3, #2]",
            "strh r8, [r3, #4]",
            "adds r0, #6",
            "adds r1, #6",
            "adds r2, #6",
            "adds r3, #6",
            "ldr r9, [sp, #36]",
            "cmp r3, r9",
            "blo 1b",
            "pop {{r4-r11, pc}}",
            ".size pg_snn_row, . - pg_snn_row",
        );
    };
}

// The pairs of `snn_row`, in its order: (b0, b2), (a0, c2), (a1, c1),
// (a2, c0), with a = up (r0), b = middle (r1), c = down (r2).
snn_row_asm!(
    ("[r1]", "[r1, #4]", "[r1, #12]", "[r1, #16]"),
    ("[r0]", "[r0, #4]", "[r2, #12]", "[r2, #16]"),
    ("[r0, #6]", "[r0, #10]", "[r2, #6]", "[r2, #10]"),
    ("[r0, #12]", "[r0, #16]", "[r2]", "[r2, #4]")
);

extern "C" {
    /// The smoothing cell for `out..end` (at least one cell), reading 3
    /// pixels from `x` of each row for cell `x`; see `snn_row_asm`.
    fn pg_snn_row(
        prev: *const Luv,
        cur: *const Luv,
        next: *const Luv,
        out: *mut Luv,
        end: *mut Luv,
    );
}

impl ColourKernel for PhaseAsm {
    fn snn_row(prev: &[Luv], cur: &[Luv], next: &[Luv], out: &mut [Luv]) {
        let n = prev
            .len()
            .min(cur.len())
            .min(next.len())
            .saturating_sub(2)
            .min(out.len());
        if n == 0 {
            return;
        }
        let start = out.as_mut_ptr();
        // SAFETY: `Luv` is `repr(C)` of three `i16` (see `px`); the kernel
        // writes `out[..n]` and reads pixels `..n + 2` of each row, all
        // within the slices (`n + 2 <= len`), with unaligned word loads
        // (allowed on v7-M) and halfword loads and stores at 2-aligned
        // addresses; registers r4..r11 and lr are saved.
        unsafe {
            pg_snn_row(
                prev.as_ptr(),
                cur.as_ptr(),
                next.as_ptr(),
                start,
                start.add(n),
            );
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
