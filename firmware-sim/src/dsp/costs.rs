//! The read-out's costs of a pixel's window in assembly (`pg_costs`), bit
//! for bit core's portable [`costs`] for the
//! firmware's tables (`bias_frac >= weight_frac`) and totals below 2^61;
//! anything else goes to the portable step.
//!
//! Per pixel: the total's shift `sh` and `t`; per candidate the score
//! `((raw >> sh) << kb) − bias·t` as one shift pair with the low bits
//! cleared and one `SMLAL`, written over `raw`, and the largest and
//! smallest score; the span's bit length `L` picks the gaps' shift (right
//! by `L − 15`, or left by `min(m, 15 − L)`: no gap is truncated); then
//! each cost `(gap·256n + G/2) / G` with `G` the gaps' sum and `n` the
//! window's candidates.

use firmware_sim::pg::stereo::c2f::costs;
use firmware_sim::pg::stereo::DemTable;

// r0 = &CostsArgs. Returns 1 when it wrote `out` (and the scores over
// `raw[..5]`, as the portable step does), 0 when the case is not the
// common one, before writing anything. In the folds: r0 raw, r1 bias,
// r2 and r3 the shifts, r4 keep, r5 −t, r6:r7 the score, r8 scratch,
// r9:r10 the largest score, r11:r12 the smallest, lr the end of `raw`.
core::arch::global_asm!(
    ".syntax unified",
    ".section .text.pg_costs,\"ax\",%progbits",
    ".global pg_costs",
    ".type pg_costs,%function",
    ".thumb_func",
    "pg_costs:",
    "push {{r4-r11, lr}}",
    "sub sp, #4",
    "str r0, [sp]",
    // sh = max(0, bitlen(total) − 30) in r4, t = total >> sh (< 2^30).
    "ldrd r2, r3, [r0, #4]",
    "clz r4, r3",
    "clz r5, r2",
    "cmp r3, #0",
    "it eq",
    "addeq r4, r4, r5",
    "rsb r4, r4, #64",
    "subs r4, r4, #30",
    "it lt",
    "movlt r4, #0",
    "rsb r5, r4, #32",
    "lsr r6, r2, r4",
    "lsl r7, r3, r5",
    "orr r6, r6, r7",
    "subs r7, r4, #32",
    "it ge",
    "lsrge r6, r3, r7",
    "rsb r5, r6, #0",
    "ldr r6, [r0, #16]",
    "ldr r1, [r0, #12]",
    "ldr r7, [r0, #28]",
    "ldr r0, [r0, #0]",
    "add lr, r0, r7, lsl #3",
    "mov r9, #0",
    "mov r10, #0x80000000",
    "mvn r11, #0",
    "mvn r12, #0x80000000",
    // Scores (raw >> sh) << kb − bias·t: by a = sh − kb right with the low
    // kb bits cleared, or by kb − sh left with the low sh bits cleared.
    "subs r2, r4, r6",
    "blt 4f",
    "cmp r2, #32",
    "bge 8f",
    "rsb r3, r2, #32",
    "movs r4, #1",
    "lsl r4, r4, r6",
    "subs r4, r4, #1",
    "mvn r4, r4",
    "1:",
    "ldrd r6, r7, [r0]",
    "lsr r6, r6, r2",
    "lsl r8, r7, r3",
    "orr r6, r6, r8",
    "asr r7, r7, r2",
    "and r6, r6, r4",
    "ldrsh r8, [r1], #2",
    "smlal r6, r7, r8, r5",
    "strd r6, r7, [r0], #8",
    "subs r8, r9, r6",
    "sbcs r8, r10, r7",
    "itt lt",
    "movlt r9, r6",
    "movlt r10, r7",
    "subs r8, r6, r11",
    "sbcs r8, r7, r12",
    "itt lt",
    "movlt r11, r6",
    "movlt r12, r7",
    "cmp r0, lr",
    "bne 1b",
    "b 3f",
    "4:",
    "rsb r2, r2, #0",
    "rsb r3, r2, #32",
    "movs r6, #1",
    "lsl r6, r6, r4",
    "subs r6, r6, #1",
    "mvn r4, r6",
    "2:",
    "ldrd r6, r7, [r0]",
    "and r6, r6, r4",
    "lsl r7, r7, r2",
    "lsr r8, r6, r3",
    "orr r7, r7, r8",
    "lsl r6, r6, r2",
    "ldrsh r8, [r1], #2",
    "smlal r6, r7, r8, r5",
    "strd r6, r7, [r0], #8",
    "subs r8, r9, r6",
    "sbcs r8, r10, r7",
    "itt lt",
    "movlt r9, r6",
    "movlt r10, r7",
    "subs r8, r6, r11",
    "sbcs r8, r7, r12",
    "itt lt",
    "movlt r11, r6",
    "movlt r12, r7",
    "cmp r0, lr",
    "bne 2b",
    // The span's bit length L: gaps right by k = L − 15 (r2), or left by
    // kl = min(m, 15 − L) (r4) when L < 15.
    "3:",
    "subs r6, r9, r11",
    "sbc r7, r10, r12",
    "clz r8, r7",
    "clz r6, r6",
    "cmp r7, #0",
    "it eq",
    "addeq r8, r8, r6",
    "rsb r8, r8, #64",
    "ldr r5, [sp]",
    "movs r4, #0",
    "subs r2, r8, #15",
    "bge 5f",
    "ldr r4, [r5, #20]",
    "rsb r2, r2, #0",
    "cmp r4, r2",
    "it hi",
    "movhi r4, r2",
    "movs r2, #0",
    // Gap d = ((best − score) >> k) << kl: the 64-bit shift by k in 0..64
    // as three word shifts (a register shift of 32 or more gives 0).
    "5:",
    "rsb r3, r2, #32",
    "sub r11, r2, #32",
    "ldr r1, [r5, #24]",
    "ldr r6, [r5, #28]",
    "sub r0, r0, r6, lsl #3",
    "movs r12, #0",
    "6:",
    "ldrd r6, r7, [r0], #8",
    "subs r6, r9, r6",
    "sbc r7, r10, r7",
    "lsr r6, r6, r2",
    "lsl r8, r7, r3",
    "orr r6, r6, r8",
    "lsr r7, r7, r11",
    "orr r6, r6, r7",
    "lsl r6, r6, r4",
    "strh r6, [r1], #2",
    "add r12, r12, r6",
    "cmp r0, lr",
    "bne 6b",
    // Costs (g·256n + G/2) / G, G the gaps' sum; with G = 0 every gap,
    // and so every cost, is 0 already.
    "movs r0, #1",
    "cmp r12, #0",
    "beq 9f",
    "ldr r6, [r5, #28]",
    "sub r1, r1, r6, lsl #1",
    "add lr, r1, r6, lsl #1",
    "lsr r3, r12, #1",
    "lsl r8, r6, #8",
    "7:",
    "ldrh r6, [r1]",
    "mla r6, r6, r8, r3",
    "udiv r6, r6, r12",
    "strh r6, [r1], #2",
    "cmp r1, lr",
    "bne 7b",
    "b 9f",
    "8:",
    "movs r0, #0",
    "9:",
    "add sp, #4",
    "pop {{r4-r11, pc}}",
    ".size pg_costs, . - pg_costs",
);

/// The arguments of `pg_costs` (offsets in bytes: 0, 4, 12, 16, 20, 24,
/// 28).
#[repr(C)]
struct CostsArgs {
    /// The window's `n` scores (overwritten with the scores `n(d)`).
    raw: *mut i64,
    /// The total, low word then high word.
    total: [u32; 2],
    /// The window's `n` biases, little-endian `i16` (halfword-aligned).
    bias: *const u8,
    /// `bias_frac − weight_frac`.
    kb: u32,
    /// `weight_frac`.
    m: u32,
    /// The `n` costs (out).
    out: *mut u16,
    /// `n`, the window's candidates (at least 1).
    n: u32,
}

extern "C" {
    /// One pixel's costs; see [`CostsArgs`]. Returns 1 when done.
    fn pg_costs(args: *const CostsArgs) -> u32;
}

/// [`costs`] in assembly where the case is the common one, else the
/// portable step: the same `out` either way.
#[inline]
pub(super) fn costs_asm(
    raw: &mut [i64],
    total: i64,
    table: &DemTable<'_>,
    lo: usize,
    out: &mut [u16],
) {
    let n = out.len();
    let (wf, bf) = (u32::from(table.weight_frac), u32::from(table.bias_frac));
    let bias = table.bias_bytes().get(2 * lo..2 * (lo + n));
    if let (Some(bias), Ok(n32)) = (bias, u32::try_from(n)) {
        if wf <= bf
            && total > 0
            && (1..=256).contains(&n)
            && raw.len() >= n
            && bias.as_ptr() as usize % 2 == 0
        {
            let args = CostsArgs {
                raw: raw.as_mut_ptr(),
                total: [total as u32, (total >> 32) as u32],
                bias: bias.as_ptr(),
                kb: bf - wf,
                m: wf,
                out: out.as_mut_ptr(),
                n: n32,
            };
            // SAFETY: the kernel reads and writes `raw[..n]` (`n` `i64`s,
            // checked), reads the `2n` bytes of `bias` as `n` halfwords
            // (aligned, checked), writes the `n` `u16`s of `out` and one
            // word of its own stack frame. It keeps the AAPCS (saves
            // r4-r11, restores sp) and touches no other memory.
            if unsafe { pg_costs(&args) } != 0 {
                return;
            }
        }
    }
    costs(raw, total, table, lo, out);
}
