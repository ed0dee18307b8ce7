//! The dot-product kernel of the classifier (issue 5 §10), [`SmladKernel`]:
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

use firmware_sim::pg::mlp::{safe_dot_rows, MacKernel};

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

/// The product pipeline's kernel type runs the classifier with [`SmladKernel`].
impl MacKernel for super::PhaseAsm {
    #[inline]
    fn dot_rows(w: &[u8], stride: usize, len: usize, x: &[u32], acc: &mut [i32]) {
        SmladKernel::dot_rows(w, stride, len, x, acc);
    }
}
