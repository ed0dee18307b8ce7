//! The Cortex-M4 assembly kernels: the phase step of the stereo stage's
//! refinement ([`PhaseAsm`], at the end of this file) and the dot-product
//! kernel of the classifier (issue 5 §10), described here:
//! `SMLAD`, two 16x16 multiply-accumulates per instruction, which safe
//! Rust cannot ask for (core forbids `unsafe`, and LLVM does not form
//! `SMLAD` from byte weights). Core exposes the hook
//! ([`protogist::mlp::MacKernel`], CMSIS-NN style); this module is the only
//! `unsafe` of the classifier, and its result is bit-identical to the
//! portable kernel's (the `checksum mlp` lines, compared by xtask between
//! this build and the desktop one, show it on every CI run).
//!
//! **Inner loop** (`pg_rows_smlad`): three rows at a time share the
//! inputs, which core packs as `x0 | x2 << 16`, `x1 | x3 << 16` per group of
//! four; weights are excess-128 bytes, row-major as in the blob. Per eight
//! inputs:
//!
//! ```text
//! ldm    x!, {x02a, x13a, x02b, x13b}   ; 8 inputs, once for 3 rows
//! per row:
//!   ldrd   w0, w1, [row], #8           ; 8 weight bytes
//!   uxtb16 t, w0                       ; u0 | u2 << 16
//!   uxtb16 w0, w0, ror #8              ; u1 | u3 << 16
//!   smlad  acc, t, x02a, acc           ; += u0·x0 + u2·x2
//!   smlad  acc, w0, x13a, acc          ; += u1·x1 + u3·x3
//!   (the same four for w1 with x02b, x13b)
//! ```
//!
//! 28 instructions per 24 multiply-accumulates; unrolled to 16 inputs with
//! a 3-instruction loop test, 59 per 48 = 1.23 instructions/MAC. Rows left
//! over (fewer than three) go one at a time (23 per 16). Fourteen registers
//! are live in the loop (three row pointers, three accumulators, four
//! inputs, two weight words, a temporary and the input pointer), so the
//! loop end lives on the stack. Sums wrap modulo 2^32 as the portable
//! kernel's do (`SMLAD` wraps; it only sets the Q flag), and addition
//! modulo 2^32 does not depend on order: the result is the same bits.
//!
//! `ldrd` and `ldm` need word-aligned addresses: the wrapper takes this
//! path only for an aligned weight block with a stride that is a multiple
//! of 4 and a row length that is a multiple of 16 (the firmware keeps its
//! model blobs 4-byte aligned, and the blob's weight sections start at a
//! multiple of 4 when `d` is one; docs/MODEL_FORMAT.md), and falls back to
//! the portable kernel otherwise.

#![allow(unsafe_code)]

use firmware_sim::pg::disparity::DisparityCell;
use firmware_sim::pg::mlp::{safe_dot_rows, MacKernel};
use firmware_sim::pg::stereo::phase::{phase_row3, PhaseKernel};

/// One row, eight inputs: `acc += w·x` for the eight weight bytes at
/// `[ptr]`, post-incremented.
macro_rules! row8 {
    ($acc:literal, $ptr:literal) => {
        concat!(
            "ldrd r11, r12, [",
            $ptr,
            "], #8\n",
            "uxtb16 lr, r11\n",
            "uxtb16 r11, r11, ror #8\n",
            "smlad ",
            $acc,
            ", lr, r7, ",
            $acc,
            "\n",
            "smlad ",
            $acc,
            ", r11, r8, ",
            $acc,
            "\n",
            "uxtb16 lr, r12\n",
            "uxtb16 r12, r12, ror #8\n",
            "smlad ",
            $acc,
            ", lr, r9, ",
            $acc,
            "\n",
            "smlad ",
            $acc,
            ", r12, r10, ",
            $acc,
            "\n",
        )
    };
}

// r0 = &mut Args (see `Args` for the offsets).
core::arch::global_asm!(
    ".syntax unified",
    ".section .text.pg_rows_smlad,\"ax\",%progbits",
    ".global pg_rows_smlad",
    ".type pg_rows_smlad,%function",
    ".thumb_func",
    "pg_rows_smlad:",
    "push {{r4-r11, lr}}",
    "sub sp, #8",
    // [sp] = args, [sp + 4] = end of the inputs.
    "str r0, [sp]",
    "ldr r1, [r0, #12]",
    "ldr r2, [r0, #8]",
    "add r1, r1, r2, lsl #5",
    "str r1, [sp, #4]",
    // Blocks of three rows.
    "3:",
    "ldr r0, [sp]",
    "ldr r1, [r0, #20]",
    "cmp r1, #3",
    "blo 5f",
    "subs r1, #3",
    "str r1, [r0, #20]",
    "ldr r3, [r0, #12]",
    "ldr r2, [r0, #4]",
    "ldr r0, [r0, #0]",
    "add r1, r0, r2",
    "add r2, r1, r2",
    "movs r4, #0",
    "movs r5, #0",
    "movs r6, #0",
    "4:",
    "ldm r3!, {{r7-r10}}",
    row8!("r4", "r0"),
    row8!("r5", "r1"),
    row8!("r6", "r2"),
    "ldm r3!, {{r7-r10}}",
    row8!("r4", "r0"),
    row8!("r5", "r1"),
    row8!("r6", "r2"),
    "ldr lr, [sp, #4]",
    "cmp r3, lr",
    "bne 4b",
    // Store the three sums, advance the rows by 3 · stride.
    "ldr r0, [sp]",
    "ldr r1, [r0, #16]",
    "stm r1!, {{r4-r6}}",
    "str r1, [r0, #16]",
    "ldr r1, [r0, #0]",
    "ldr r2, [r0, #4]",
    "add r2, r2, r2, lsl #1",
    "add r1, r1, r2",
    "str r1, [r0, #0]",
    "b 3b",
    // Single rows (r0 = args, r1 = rows left).
    "5:",
    "cmp r1, #0",
    "beq 7f",
    "subs r1, #1",
    "str r1, [r0, #20]",
    "ldr r3, [r0, #12]",
    "ldr r1, [r0, #0]",
    "movs r4, #0",
    "6:",
    "ldm r3!, {{r7-r10}}",
    row8!("r4", "r1"),
    "ldm r3!, {{r7-r10}}",
    row8!("r4", "r1"),
    "ldr lr, [sp, #4]",
    "cmp r3, lr",
    "bne 6b",
    "ldr r1, [r0, #16]",
    "str r4, [r1], #4",
    "str r1, [r0, #16]",
    "ldr r1, [r0, #0]",
    "ldr r2, [r0, #4]",
    "add r1, r1, r2",
    "str r1, [r0, #0]",
    "ldr r1, [r0, #20]",
    "b 5b",
    "7:",
    "add sp, #8",
    "pop {{r4-r11, pc}}",
    ".size pg_rows_smlad, . - pg_rows_smlad",
);

/// The kernel's arguments (offsets in bytes: 0, 4, 8, 12, 16, 20); it
/// advances `w`, `out` and `rows` as it goes.
#[repr(C)]
struct Args {
    /// First weight byte of the next row (word-aligned).
    w: *const u8,
    /// Bytes from one row to the next (a multiple of 4).
    stride: usize,
    /// Inputs per row / 16 (at least 1).
    iters: usize,
    /// The packed inputs (`8 · iters` words).
    x: *const u32,
    /// The next sum.
    out: *mut i32,
    /// Rows left.
    rows: usize,
}

extern "C" {
    /// `out[r] = Σ_i w[r · stride + i] · x[i]` (wrapping), `i < 16 · iters`,
    /// for every row; see [`Args`].
    fn pg_rows_smlad(args: *mut Args);
}

/// The `SMLAD` kernel. Blocks it cannot take (unaligned, or a row length
/// that is not a multiple of 16) go to the portable kernel.
#[derive(Clone, Copy, Debug, Default)]
pub struct SmladKernel;

impl MacKernel for SmladKernel {
    #[inline]
    fn dot_rows(w: &[u8], stride: usize, len: usize, x: &[u32], acc: &mut [i32]) {
        let rows = acc.len();
        let fits = rows
            .checked_sub(1)
            .and_then(|last| last.checked_mul(stride))
            .and_then(|start| start.checked_add(len))
            .is_some_and(|end| end <= w.len());
        let aligned = (w.as_ptr() as usize) % 4 == 0 && stride % 4 == 0;
        if !(fits && aligned && len >= 16 && len % 16 == 0 && x.len() >= len / 2) {
            safe_dot_rows(w, stride, len, x, acc);
            return;
        }
        let mut args = Args {
            w: w.as_ptr(),
            stride,
            iters: len / 16,
            x: x.as_ptr(),
            out: acc.as_mut_ptr(),
            rows,
        };
        // SAFETY: the kernel reads bytes `w[r · stride..][..len]` for
        // `r < rows`, all inside `w` (checked: `(rows − 1) · stride + len
        // <= w.len()`), with `ldrd` on word-aligned addresses (checked:
        // `w` aligned, `stride` a multiple of 4, and it steps by 8); it
        // reads `len / 2` words of `x` (checked) with `ldm`, and writes
        // `rows` words of `acc`. It keeps the AAPCS (saves r4-r11, restores
        // sp) and touches no other memory.
        unsafe { pg_rows_smlad(&mut args) };
    }
}

// The phase step of the full-resolution refinement (pool 1), bit for bit
// the portable `phase_row3`; r0 = &mut PhaseArgs (offsets 0..28). Per ON
// cell: the shift, two `ldm` of three responses, `SMUAD`/`SMLAD` for
// Re P and `SMUSDX`/`SMLSDX` for Im P, the arc tangent in turns
// (octant, one `udiv`, the same polynomial), the 3/8-turn test, the
// remainder and the clamp.
core::arch::global_asm!(
    ".syntax unified",
    ".section .text.pg_phase_row3,\"ax\",%progbits",
    ".global pg_phase_row3",
    ".type pg_phase_row3,%function",
    ".thumb_func",
    "pg_phase_row3:",
    "push {{r4-r11, lr}}",
    "sub sp, #4",
    "str r0, [sp]",
    "ldr r1, [r0, #4]",
    "ldr r2, [r0, #8]",
    "ldr r3, [r0, #12]",
    "movs r5, #0",
    "ldr r0, [r0, #0]",
    "b 2f",
    // Next cell: r0 cells, r2 left window, r3 right column x + max_disp.
    "1:",
    "adds r0, #2",
    "adds r2, #4",
    "adds r3, #4",
    "2:",
    "cmp r0, r1",
    "bhs 9f",
    "ldrh r4, [r0]",
    // OFF (0xffff) stays.
    "add r6, r4, #1",
    "cmp r6, #65536",
    "beq 1b",
    // s = min((d + 128) >> 8, max_disp).
    "adds r4, #128",
    "lsrs r4, r4, #8",
    "ldr r6, [sp]",
    "ldr r7, [r6, #16]",
    "cmp r4, r7",
    "it hi",
    "movhi r4, r7",
    "sub r12, r3, r4, lsl #2",
    "ldm r2, {{r6, r7, r8}}",
    "ldm r12, {{r9, r10, r11}}",
    // Re P = Σ ar br + ai bi; Im P = Σ br ai − bi ar.
    "smuad r12, r6, r9",
    "smlad r12, r7, r10, r12",
    "smlad r12, r8, r11, r12",
    "smusdx lr, r9, r6",
    "smlsdx lr, r10, r7, lr",
    "smlsdx lr, r11, r8, lr",
    // r6 = |Re|, r7 = |Im|; r8 = min, r9 = max.
    "eor r6, r12, r12, asr #31",
    "sub r6, r6, r12, asr #31",
    "eor r7, lr, lr, asr #31",
    "sub r7, r7, lr, asr #31",
    "cmp r7, r6",
    "ittee hi",
    "movhi r9, r7",
    "movhi r8, r6",
    "movls r9, r6",
    "movls r8, r7",
    // P = 0: no phase, the cell stays.
    "cmp r9, #0",
    "beq 1b",
    // Both below 2^16, then t = (min << 15) / max.
    "clz r10, r9",
    "rsbs r10, r10, #16",
    "it mi",
    "movmi r10, #0",
    "lsr r8, r8, r10",
    "lsr r9, r9, r10",
    "lsl r8, r8, #15",
    "udiv r8, r8, r9",
    // a = t/4 + (2847 · (t (32768 − t) >> 15)) >> 15.
    "rsb r10, r8, #32768",
    "mul r10, r10, r8",
    "asr r10, r10, #15",
    "movw r11, #2847",
    "mul r10, r10, r11",
    "asr r10, r10, #15",
    "add r10, r10, r8, asr #2",
    "cmp r7, r6",
    "it hi",
    "rsbhi r10, r10, #16384",
    "cmp r12, #0",
    "it lt",
    "rsblt r10, r10, #32768",
    "cmp lr, #0",
    "it lt",
    "rsblt r10, r10, #0",
    // Beyond 3/8 turn the cell stays.
    "eor r11, r10, r10, asr #31",
    "sub r11, r11, r10, asr #31",
    "cmp r11, #24576",
    "bhi 1b",
    // v = clamp((s << 8) + (turns · λ + 2^15) >> 16, 0, top).
    "ldr r6, [sp]",
    "ldr r7, [r6, #20]",
    "mul r10, r10, r7",
    "add r10, r10, #32768",
    "asr r10, r10, #16",
    "add r10, r10, r4, lsl #8",
    "bic r10, r10, r10, asr #31",
    "ldr r7, [r6, #24]",
    "cmp r10, r7",
    "it gt",
    "movgt r10, r7",
    "strh r10, [r0]",
    "adds r5, #1",
    "b 1b",
    "9:",
    "ldr r0, [sp]",
    "str r5, [r0, #28]",
    "add sp, #4",
    "pop {{r4-r11, pc}}",
    ".size pg_phase_row3, . - pg_phase_row3",
);

/// The phase kernel's arguments (offsets in bytes: 0, 4, ..., 28).
#[repr(C)]
struct PhaseArgs {
    /// The row's cells (`u16` bits).
    cells: *mut u16,
    /// One past the last cell.
    end: *const u16,
    /// Left responses from column −1 (word-aligned).
    zl: *const [i16; 2],
    /// Right responses from column `−1` (that is, `zr + max_disp`;
    /// word-aligned).
    zrq: *const [i16; 2],
    /// `max_disp`.
    md: u32,
    /// λ in `U8F8`.
    lambda: i32,
    /// `max_disp · 256`.
    top: i32,
    /// Cells refined (out).
    refined: u32,
}

extern "C" {
    /// The phase step of one row; see [`PhaseArgs`].
    fn pg_phase_row3(args: *mut PhaseArgs);
}

/// The phase step in assembly. Rows it cannot take (unaligned or short
/// responses, λ out of range) go to the portable step.
#[derive(Clone, Copy, Debug, Default)]
pub struct PhaseAsm;

impl PhaseKernel for PhaseAsm {
    #[inline]
    fn phase_row3(
        max_disp: u8,
        lambda_q8: i32,
        zl: &[[i16; 2]],
        zr: &[[i16; 2]],
        cells: &mut [DisparityCell],
    ) -> usize {
        let (w, md) = (cells.len(), usize::from(max_disp));
        let fits = zl.len() >= w + 2 && zr.len() >= w + 2 + md;
        let aligned = (zl.as_ptr() as usize) % 4 == 0 && (zr.as_ptr() as usize) % 4 == 0;
        if !(fits && aligned && (0..=64 * 256).contains(&lambda_q8)) {
            return phase_row3(max_disp, lambda_q8, zl, zr, cells);
        }
        let range = cells.as_mut_ptr_range();
        let mut args = PhaseArgs {
            cells: range.start.cast::<u16>(),
            end: range.end.cast::<u16>(),
            zl: zl.as_ptr(),
            zrq: zr.as_ptr().wrapping_add(md),
            md: u32::from(max_disp),
            lambda: lambda_q8,
            top: i32::from(max_disp) << 8,
            refined: 0,
        };
        // SAFETY: `DisparityCell` is `repr(transparent)` over `u16`; the
        // kernel reads and writes the `w` cells in `cells..end`. For cell
        // `x` it reads three words of `zl` from `x` (at most `w + 1 <
        // zl.len()`, checked) and three of `zr` from `x + md − s` with `s
        // <= md` (at most `w + 1 + md < zr.len()`, checked), with `ldm` on
        // word-aligned addresses (checked; both step by 4). It keeps the
        // AAPCS (saves r4-r11, restores sp) and touches no other memory.
        unsafe { pg_phase_row3(&mut args) };
        args.refined as usize
    }

    /// The SGM path step for windows of 5 in 16-bit lanes ([`sgm_lanes`]).
    #[inline(always)]
    fn sgm_step5(
        c: &[u16; 5],
        p: &[u16; 5],
        pad: u32,
        (p1, p2): (u32, u32),
        acc: &mut [u32; 5],
    ) -> [u16; 5] {
        let (l01, l23, l4) = sgm_lanes(c, p, pad.min(0xffff), p1 | p1 << 16, p2 | p2 << 16);
        sgm_settle(l01, l23, l4, acc)
    }

    /// The SGM path step for 9 candidates in 16-bit lanes, as
    /// [`sgm_lanes`] and [`sgm_settle`] with the lane operations one by
    /// one ([`min16`], [`uqadd16`], [`uadd16`], [`usub16`]), the words
    /// packed and unpacked by the compiler.
    #[inline(always)]
    fn sgm_step9(
        c: &[u16; 9],
        p: &[u16; 9],
        pad: u32,
        (p1, p2): (u32, u32),
        acc: &mut [u32; 9],
    ) -> [u16; 9] {
        let pad16 = pad.min(0xffff);
        let (p1x2, p2x2) = (p1 | p1 << 16, p2 | p2 << 16);
        // Candidates 2i and 2i + 1 per word; the 10th is the pad.
        let word = |v: &[u16; 9], i: usize, none: u32| {
            let at = |j: usize| v.get(j).map_or(none, |&x| u32::from(x));
            at(2 * i) | at(2 * i + 1) << 16
        };
        let h: [u32; 5] = core::array::from_fn(|i| word(p, i, pad16));
        let l: [u32; 5] = core::array::from_fn(|i| {
            let hi = h.get(i).copied().unwrap_or(0);
            let prev = i
                .checked_sub(1)
                .and_then(|j| h.get(j))
                .map_or(pad16 << 16, |&v| v);
            let next = h.get(i + 1).map_or(pad16, |&v| v);
            // (h(2i − 1), h(2i)) and (h(2i + 1), h(2i + 2)).
            let below = prev >> 16 | hi << 16;
            let above = hi >> 16 | next << 16;
            let t = uqadd16(min16(below, above), p1x2);
            uadd16(min16(min16(t, hi), p2x2), word(c, i, 0))
        });
        for (i, &v) in l.iter().enumerate() {
            if let Some(a) = acc.get_mut(2 * i) {
                *a += v & 0xffff;
            }
            if let Some(a) = acc.get_mut(2 * i + 1) {
                *a += v >> 16;
            }
        }
        // The minimum of the nine in both halves (the 10th lane left out).
        let last = l.get(4).map_or(u32::MAX, |&v| v | 0xffff_0000);
        let m = l.iter().take(4).fold(last, |m, &v| min16(m, v));
        let m = min16(m, m.rotate_right(16));
        let s = l.map(|v| usub16(v, m));
        core::array::from_fn(|d| {
            let v = s.get(d / 2).copied().unwrap_or(0);
            (if d % 2 == 0 { v } else { v >> 16 }) as u16
        })
    }
}

/// The lane-wise minimum of two pairs of `u16` (`USUB16` sets GE where
/// `a >= b`, `SEL` then takes `b`).
#[inline(always)]
fn min16(a: u32, b: u32) -> u32 {
    let r: u32;
    // SAFETY: registers only.
    unsafe {
        core::arch::asm!(
            "usub16 {t}, {a}, {b}",
            "sel {r}, {b}, {a}",
            a = in(reg) a,
            b = in(reg) b,
            t = out(reg) _,
            r = lateout(reg) r,
            options(pure, nomem, nostack),
        );
    }
    r
}

/// Lane-wise `a + b`, saturating at 65535.
#[inline(always)]
fn uqadd16(a: u32, b: u32) -> u32 {
    let r: u32;
    // SAFETY: registers only.
    unsafe {
        core::arch::asm!("uqadd16 {r}, {a}, {b}", a = in(reg) a, b = in(reg) b, r = lateout(reg) r,
            options(pure, nomem, nostack, preserves_flags));
    }
    r
}

/// Lane-wise `a + b` modulo 2^16.
#[inline(always)]
fn uadd16(a: u32, b: u32) -> u32 {
    let r: u32;
    // SAFETY: registers only (GE flags only).
    unsafe {
        core::arch::asm!("uadd16 {r}, {a}, {b}", a = in(reg) a, b = in(reg) b, r = lateout(reg) r,
            options(pure, nomem, nostack));
    }
    r
}

/// Lane-wise `a − b` modulo 2^16.
#[inline(always)]
fn usub16(a: u32, b: u32) -> u32 {
    let r: u32;
    // SAFETY: registers only (GE flags only).
    unsafe {
        core::arch::asm!("usub16 {r}, {a}, {b}", a = in(reg) a, b = in(reg) b, r = lateout(reg) r,
            options(pure, nomem, nostack));
    }
    r
}

/// `L` of one SGM path step for 5 candidates, two per word: `d = 0, 1` in
/// the first (candidate `2i` in the low half), `2, 3` in the second, 4 in
/// the low half of the third. With `h` the predecessor's state `p` and
/// `pad` for the candidates outside it (`h(−1) = h(5) = pad16`),
/// `L(d) = c(d) + min(P2, h(d), min(h(d − 1), h(d + 1)) + P1)`: the
/// neighbours are the words shifted by a half (`lsl`/`lsr`/`orr`), the
/// minima `USUB16` + `SEL` (GE set where the first is not below the
/// second), `+ P1` saturating (`UQADD16`), `+ c` plain (`UADD16`).
///
/// The same integers as the portable step under the kernel contract
/// ([`PhaseKernel::sgm_step5`]): every lane value is at most 65535; a
/// sum `min(..) + P1` above 65535 saturates to 65535, which is not below
/// `P2` (at most 65535), so the minimum with `P2` is `P2` either way;
/// `pad16 = min(pad, 65535)` (the portable pad is 0 or `2^30`) acts as
/// the portable pad for the same reason; `c(d) + min(..) <= c(d) + P2 <=
/// 65535` does not wrap. The third word's high lane is don't-care.
#[inline(always)]
fn sgm_lanes(c: &[u16; 5], p: &[u16; 5], pad16: u32, p1x2: u32, p2x2: u32) -> (u32, u32, u32) {
    let (b0, b1, b2): (u32, u32, u32);
    // SAFETY: reads the 10 bytes of `p` and of `c` (two words, possibly
    // unaligned, which the Cortex-M4 allows for `ldr`, and a halfword
    // each); registers only otherwise; no stack, flags clobbered.
    unsafe {
        core::arch::asm!(
            "ldr {h1}, [{pp}, #4]",
            "ldrh {h2}, [{pp}, #8]",
            "ldr {h0}, [{pp}]",
            // B0 = (pad, h0), B1 = (h1, h2), min(B0, B1): d = 0, 1.
            "lsl {b0}, {h0}, #16",
            "orr {b0}, {b0}, {pad}",
            "lsr {b1}, {h0}, #16",
            "orr {b1}, {b1}, {h1}, lsl #16",
            "usub16 {pp}, {b0}, {b1}",
            "sel {b0}, {b1}, {b0}",
            // B2 = (h3, ·), min(B2, pad): d = 4.
            "lsr {b2}, {h1}, #16",
            "usub16 {pp}, {b2}, {pad}",
            "sel {b2}, {pad}, {b2}",
            // A1 = (h3, h4), min(B1, A1): d = 2, 3.
            "lsr {pad}, {h1}, #16",
            "orr {pad}, {pad}, {h2}, lsl #16",
            "usub16 {pp}, {b1}, {pad}",
            "sel {b1}, {pad}, {b1}",
            // + P1, saturating.
            "uqadd16 {b0}, {b0}, {p1}",
            "uqadd16 {b1}, {b1}, {p1}",
            "uqadd16 {b2}, {b2}, {p1}",
            // min with h.
            "usub16 {pp}, {b0}, {h0}",
            "sel {b0}, {h0}, {b0}",
            "usub16 {pp}, {b1}, {h1}",
            "sel {b1}, {h1}, {b1}",
            "usub16 {pp}, {b2}, {h2}",
            "sel {b2}, {h2}, {b2}",
            // min with P2.
            "usub16 {pp}, {b0}, {p2}",
            "sel {b0}, {p2}, {b0}",
            "usub16 {pp}, {b1}, {p2}",
            "sel {b1}, {p2}, {b1}",
            "usub16 {pp}, {b2}, {p2}",
            "sel {b2}, {p2}, {b2}",
            // + c.
            "ldr {h0}, [{cp}]",
            "ldr {h1}, [{cp}, #4]",
            "ldrh {h2}, [{cp}, #8]",
            "uadd16 {b0}, {b0}, {h0}",
            "uadd16 {b1}, {b1}, {h1}",
            "uadd16 {b2}, {b2}, {h2}",
            pp = inout(reg) p.as_ptr() => _,
            cp = in(reg) c.as_ptr(),
            pad = inout(reg) pad16 => _,
            p1 = in(reg) p1x2,
            p2 = in(reg) p2x2,
            h0 = out(reg) _,
            h1 = out(reg) _,
            h2 = out(reg) _,
            b0 = out(reg) b0,
            b1 = out(reg) b1,
            b2 = out(reg) b2,
            options(nostack, readonly, pure),
        );
    }
    (b0, b1, b2)
}

/// Adds the five `L` of [`sgm_lanes`] to `acc` (`UXTAH`) and returns the
/// state `L − min L` (the minimum of the five lanes in both halves, then
/// `USUB16`, which cannot borrow).
#[inline(always)]
fn sgm_settle(l01: u32, l23: u32, l4: u32, acc: &mut [u32; 5]) -> [u16; 5] {
    let (s01, s23, s4): (u32, u32, u32);
    // SAFETY: reads and writes the five words of `acc` (word-aligned, a
    // `[u32; 5]`); registers only otherwise; no stack, flags clobbered.
    unsafe {
        core::arch::asm!(
            "ldr {t}, [{ap}]",
            "uxtah {t}, {t}, {l01}",
            "str {t}, [{ap}]",
            "ldr {t}, [{ap}, #4]",
            "uxtah {t}, {t}, {l01}, ror #16",
            "str {t}, [{ap}, #4]",
            "ldr {t}, [{ap}, #8]",
            "uxtah {t}, {t}, {l23}",
            "str {t}, [{ap}, #8]",
            "ldr {t}, [{ap}, #12]",
            "uxtah {t}, {t}, {l23}, ror #16",
            "str {t}, [{ap}, #12]",
            "ldr {t}, [{ap}, #16]",
            "uxtah {t}, {t}, {l4}",
            "str {t}, [{ap}, #16]",
            // m = min of the five, in both halves.
            "usub16 {t}, {l01}, {l23}",
            "sel {m}, {l23}, {l01}",
            "mvn {u}, #0",
            "bfi {u}, {l4}, #0, #16",
            "usub16 {t}, {m}, {u}",
            "sel {m}, {u}, {m}",
            "ror {u}, {m}, #16",
            "usub16 {t}, {m}, {u}",
            "sel {m}, {u}, {m}",
            "usub16 {l01}, {l01}, {m}",
            "usub16 {l23}, {l23}, {m}",
            "usub16 {l4}, {l4}, {m}",
            ap = in(reg) acc.as_mut_ptr(),
            l01 = inout(reg) l01 => s01,
            l23 = inout(reg) l23 => s23,
            l4 = inout(reg) l4 => s4,
            t = out(reg) _,
            u = out(reg) _,
            m = out(reg) _,
            options(nostack),
        );
    }
    [
        s01 as u16,
        (s01 >> 16) as u16,
        s23 as u16,
        (s23 >> 16) as u16,
        s4 as u16,
    ]
}
