//! The inner dot-product kernel of the fully connected layers: the
//! [`MacKernel`] contract and the portable [`SafeKernel`].

/// The low half of a word, sign-extended.
#[inline(always)]
pub(super) fn lo16(v: i32) -> i32 {
    i32::from(v as i16)
}

/// The high half of a word, sign-extended.
#[inline(always)]
pub(super) fn hi16(v: i32) -> i32 {
    v >> 16
}

/// Four multiply-accumulates: weight bytes `w` (excess-128, byte `i` for
/// input `i`) against inputs `x0 | x2 << 16` and `x1 | x3 << 16`. `mask`
/// is `0x00FF_00FF`: it puts bytes 0 and 2 (and 1 and 3) in the two 16-bit
/// halves of a register, so each product reads its operands' halves
/// directly (the Cortex-M4 `SMLAxy` forms). The caller passes the mask
/// through `black_box` so that LLVM keeps the two-lane registers instead of
/// extracting every byte on its own.
#[inline(always)]
fn mac4(acc: i32, w: u32, x02: i32, x13: i32, mask: u32) -> i32 {
    let even = (w & mask) as i32;
    // An arithmetic shift, so that LLVM cannot prove the top half
    // non-negative and turn `hi16` into a logical shift (which `SMLAxT`
    // cannot fold).
    let odd = ((w as i32) >> 8) & mask as i32;
    acc.wrapping_add(lo16(even).wrapping_mul(lo16(x02)))
        .wrapping_add(lo16(odd).wrapping_mul(lo16(x13)))
        .wrapping_add(hi16(even).wrapping_mul(hi16(x02)))
        .wrapping_add(hi16(odd).wrapping_mul(hi16(x13)))
}

/// Four weight bytes as a little-endian word (0 if short: never, the
/// callers pass `chunks_exact(4)`).
#[inline(always)]
fn word(b: &[u8]) -> u32 {
    <[u8; 4]>::try_from(b).map_or(0, u32::from_le_bytes)
}

/// `[x02, x13]` of a group's two words.
#[inline(always)]
fn xpair(xs: &[u32]) -> (i32, i32) {
    match *xs {
        [a, b] => (a as i32, b as i32),
        _ => (0, 0),
    }
}

/// The inner dot-product kernel of [`forward_with`](super::forward_with)
/// (CMSIS-NN style: the portable default is [`SafeKernel`]; a target may
/// supply an optimised one, e.g. with `SMLAD`, as the firmware does).
///
/// Contract of [`MacKernel::dot_rows`]: `w` holds `acc.len()` rows of
/// excess-128 weight bytes, row `r` at `w[r · stride..][..len]` (byte `i`
/// for input `i`), `len` a multiple of 4; `x` holds at least `len / 2`
/// words, inputs packed as [`input_len`](super::input_len) describes
/// (`x0 | x2 << 16`, `x1 | x3 << 16` per group of four). Set
/// `acc[r] = Σ_i u[r][i] · x[i]` with wrapping `i32` arithmetic. Addition
/// modulo 2^32 does not depend on order, so any kernel that honours this
/// gives the same bits as the default. Rows that do not fit in `w` are
/// never passed by `layer`; the default gives them partial sums rather than
/// panicking.
pub trait MacKernel {
    /// `acc[r] = Σ_{i < len} u[r · stride + i] · x[i]`, wrapping.
    #[inline(always)]
    fn dot_rows(w: &[u8], stride: usize, len: usize, x: &[u32], acc: &mut [i32]) {
        safe_dot_rows(w, stride, len, x, acc);
    }
}

/// The portable kernel (`SMLAxy` forms on Cortex-M4), used by
/// [`forward`](super::forward).
#[derive(Clone, Copy, Debug, Default)]
pub struct SafeKernel;

impl MacKernel for SafeKernel {}

/// The portable kernel, as the pipeline's default kernel type.
impl MacKernel for crate::stereo::phase::SafePhase {}

/// The default [`MacKernel::dot_rows`]: four rows at a time sharing each
/// input load, then single rows.
#[inline(always)]
pub fn safe_dot_rows(w: &[u8], stride: usize, len: usize, x: &[u32], acc: &mut [i32]) {
    let xs = x.get(..len / 2).unwrap_or(&[]);
    let row = |r: usize| {
        w.get(r.saturating_mul(stride)..)
            .and_then(|t| t.get(..len))
            .unwrap_or(&[])
    };
    let mut blocks = acc.chunks_exact_mut(4);
    let mut r = 0;
    for a in &mut blocks {
        let s = dot4_rows([row(r), row(r + 1), row(r + 2), row(r + 3)], xs);
        a.copy_from_slice(&s);
        r += 4;
    }
    for a in blocks.into_remainder() {
        *a = dot1_row(row(r), xs);
        r += 1;
    }
}

/// Four rows sharing the inputs.
#[inline(always)]
fn dot4_rows(rows: [&[u8]; 4], x: &[u32]) -> [i32; 4] {
    let mask = core::hint::black_box(0x00FF_00FFu32);
    let [r0, r1, r2, r3] = rows;
    let (mut a0, mut a1, mut a2, mut a3) = (0i32, 0i32, 0i32, 0i32);
    for ((((c0, c1), c2), c3), xs) in r0
        .chunks_exact(4)
        .zip(r1.chunks_exact(4))
        .zip(r2.chunks_exact(4))
        .zip(r3.chunks_exact(4))
        .zip(x.chunks_exact(2))
    {
        let (x02, x13) = xpair(xs);
        a0 = mac4(a0, word(c0), x02, x13, mask);
        a1 = mac4(a1, word(c1), x02, x13, mask);
        a2 = mac4(a2, word(c2), x02, x13, mask);
        a3 = mac4(a3, word(c3), x02, x13, mask);
    }
    [a0, a1, a2, a3]
}

/// One row.
#[inline(always)]
fn dot1_row(row: &[u8], x: &[u32]) -> i32 {
    let mask = core::hint::black_box(0x00FF_00FFu32);
    row.chunks_exact(4)
        .zip(x.chunks_exact(2))
        .fold(0i32, |a, (c, xs)| {
            let (x02, x13) = xpair(xs);
            mac4(a, word(c), x02, x13, mask)
        })
}
