//! The phase step of the stereo stage's refinement and its SGM path steps
//! in assembly: [`PhaseAsm`], which also runs the read-out's cost kernel
//! (`costs.rs`).

use super::costs::costs_asm;
use super::sgm::{min16, sgm_lanes, sgm_settle, uadd16, uqadd16, usub16};
use firmware_sim::pg::disparity::DisparityCell;
use firmware_sim::pg::stereo::phase::{phase_row3, x_pass5, Half, PhaseKernel, TAP_FRAC, Z_FRAC};
use firmware_sim::pg::stereo::DemTable;

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
    fn costs(raw: &mut [i64], total: i64, table: &DemTable<'_>, lo: usize, out: &mut [u16]) {
        costs_asm(raw, total, table, lo, out);
    }

    #[inline]
    fn x_pass5(v: &[i32], ch: &Half, sh: &Half, out: &mut [[i16; 2]]) {
        if !x_pass5_smlad(v, ch, sh, out) {
            x_pass5(v, ch, sh, out);
        }
    }

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

// The refinement's 5-tap x pass, 4 pixels a turn (`x_pass5_smlad` says
// why it is exact): r0 = grey row `v`, r1 = `out`, r2 = the end of its
// groups of 4, r3 = the packed taps `[k21, k12, k0, ks12, kn21]`. The
// pairs of neighbours (x, x + 1) of the window rotate through r8..r11:
// a pixel reads `ab` and `cd` and writes `de` over the pair it no longer
// needs; r12 and lr are its real and imaginary sums. Per pixel: the
// grey, less 32 768, into the top half (`LSL`, `EOR`), `de` (`PKHTB`),
// re = c0·c + (c2, c1)·ab + (c1, c2)·de, im = (−s2, −s1)·ab + (s1,
// s2)·de, each rounded, and one word stored.
macro_rules! x_pass5_asm {
    ($(($ab:literal, $cd:literal, $de:literal)),*) => {
        core::arch::global_asm!(
            ".syntax unified",
            ".section .text.pg_x_pass5,\"ax\",%progbits",
            ".global pg_x_pass5",
            ".type pg_x_pass5,%function",
            ".thumb_func",
            "pg_x_pass5:",
            "push {{r4-r11, lr}}",
            "ldr r4, [r3, #4]",
            "ldr r5, [r3, #8]",
            "ldr r6, [r3, #12]",
            "ldr r7, [r3, #16]",
            "ldr r3, [r3, #0]",
            "ldr r8, [r0], #4",
            "ldr r9, [r0], #4",
            "ldr r10, [r0], #4",
            "ldr r11, [r0], #4",
            "sub r8, r8, #32768",
            "sub r9, r9, #32768",
            "sub r10, r10, #32768",
            "sub r11, r11, #32768",
            "pkhbt r8, r8, r9, lsl #16",
            "pkhbt r9, r9, r10, lsl #16",
            "pkhbt r10, r10, r11, lsl #16",
            "cmp r1, r2",
            "bhs 9f",
            "1:",
            $(
                concat!("ldr ", $de, ", [r0], #4"),
                concat!("lsl ", $de, ", ", $de, ", #16"),
                concat!("eor ", $de, ", ", $de, ", #0x80000000"),
                concat!("pkhtb ", $de, ", ", $de, ", ", $cd, ", asr #16"),
                concat!("smulbb r12, ", $cd, ", r5"),
                concat!("smlad r12, ", $ab, ", r3, r12"),
                concat!("smlad r12, ", $de, ", r4, r12"),
                "add r12, r12, #131072",
                "asr r12, r12, #18",
                concat!("smuad lr, ", $ab, ", r7"),
                concat!("smlad lr, ", $de, ", r6, lr"),
                "add lr, lr, #131072",
                "asr lr, lr, #18",
                "pkhbt r12, r12, lr, lsl #16",
                "str r12, [r1], #4",
            )*
            "cmp r1, r2",
            "blo 1b",
            "9:",
            "pop {{r4-r11, pc}}",
            ".size pg_x_pass5, . - pg_x_pass5",
        );
    };
}

// The kernel's rounding: `>> 18` after `+ 2^17`, core's shift.
const _: () = assert!(TAP_FRAC + 8 - Z_FRAC == 18);

x_pass5_asm!(
    ("r8", "r10", "r11"),
    ("r9", "r11", "r8"),
    ("r10", "r8", "r9"),
    ("r11", "r9", "r10")
);

extern "C" {
    /// The x pass of `(end − out) / 4` pixels, a multiple of 4, reading
    /// `v` up to 4 past them; see `x_pass5_asm`.
    fn pg_x_pass5(v: *const i32, out: *mut [i16; 2], end: *mut [i16; 2], taps: *const [u32; 5]);
}

/// `lo | hi << 16` of two `i16` values held in `i32`s.
#[inline(always)]
fn pack(lo: i32, hi: i32) -> u32 {
    (lo as u32 & 0xffff) | ((hi as u32) << 16)
}

/// The x pass with `SMLAD` (`pg_x_pass5`), or `false` for taps it cannot
/// take. Each grey less 32 768 is an `i16` (greys are 0..=65 280, the
/// contract), and a pair of neighbours one word, so a pixel's real part
/// is `c2·a + c1·b` and `c1·d + c2·e` (two `SMLAD`) plus `c0·c`, its
/// imaginary part two `SMLAD` with `(−s2, −s1)` and `(s1, s2)`. The
/// offset cancels: the real taps sum to 0 (`c0 + 2 c1 + 2 c2 = 0`, checked)
/// and the imaginary ones are odd. The sums are the portable ones,
/// exactly: each is below 2^31 in magnitude (the taps' absolute sum is at
/// most 2^15, `Phase::new`, times at most 2^15). The last `n mod 4`
/// pixels take the portable pass.
fn x_pass5_smlad(v: &[i32], ch: &Half, sh: &Half, out: &mut [[i16; 2]]) -> bool {
    let [c0, c1, c2, ..] = *ch;
    let [_, s1, s2, ..] = *sh;
    let fit = [c0, c1, c2, s1, s2, -s1, -s2]
        .iter()
        .all(|&t| i16::try_from(t).is_ok());
    if !fit || c0 + 2 * c1 + 2 * c2 != 0 {
        return false;
    }
    let taps = [
        pack(c2, c1),
        pack(c1, c2),
        pack(c0, 0),
        pack(s1, s2),
        pack(-s2, -s1),
    ];
    let n = out.len().min(v.len().saturating_sub(4));
    let done = n - n % 4;
    if done > 0 {
        let start = out.as_mut_ptr();
        // SAFETY: the kernel writes `out[..done]` (`done <= out.len()`)
        // and reads `v[..done + 4]` (`done + 4 <= v.len()`), registers
        // otherwise (r4..r11 and lr saved).
        unsafe { pg_x_pass5(v.as_ptr(), start, start.add(done), &taps) };
    }
    if let (Some(v), Some(out)) = (v.get(done..), out.get_mut(done..n)) {
        x_pass5(v, ch, sh, out);
    }
    true
}
