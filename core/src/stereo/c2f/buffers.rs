//! The engine's scratch: the `const fn` sizes and the caller's buffers.

use super::C2fParams;
use crate::image::Rgb8;
use crate::stereo::filters::Z;
use crate::stereo::phase::{self, PhaseBuffers};
use crate::stereo::sgm;
use crate::stereo::StereoError;

/// Width of level `k`: `⌊w / 2^k⌋`.
pub const fn level_len(n: usize, k: usize) -> usize {
    n >> k
}

/// `u16` elements of the grey rings: `2r + 1` rows of level 0 per eye.
pub const fn grey_len(w: usize, p: &C2fParams) -> usize {
    2 * (2 * p.dem.radius as usize + 1) * w
}

/// `Rgb8` elements of the row scratch: the longest chain of 2x2 means,
/// `⌊w/2^k⌋ + Σ_{i<k} 2·⌊w/2^i⌋` over the levels.
pub const fn rgb_len(w: usize, p: &C2fParams) -> usize {
    let mut best = 0;
    let mut k = 0;
    while k < p.levels() {
        let mut n = level_len(w, k);
        let mut i = 0;
        while i < k {
            n += 2 * level_len(w, i);
            i += 1;
        }
        if n > best {
            best = n;
        }
        k += 1;
    }
    best
}

/// [`Z`] elements of the response rows: per eye and carrier, one row.
pub const fn z_len(w: usize, p: &C2fParams) -> usize {
    2 * p.dem.carriers as usize * w
}

/// Largest `width · candidates` over the levels.
const fn row_cells(w: usize, p: &C2fParams) -> usize {
    let mut best = 0;
    let mut k = 0;
    while k < p.levels() {
        let n = level_len(w, k) * p.candidates(k);
        if n > best {
            best = n;
        }
        k += 1;
    }
    best
}

/// `i64` elements of the score rows: per eye, pixel and candidate, plus
/// each pixel's total.
pub const fn score_len(w: usize, p: &C2fParams) -> usize {
    let mut best = 0;
    let mut k = 0;
    while k < p.levels() {
        let n = level_len(w, k) * (p.candidates(k) + 1);
        if n > best {
            best = n;
        }
        k += 1;
    }
    2 * best
}

/// `u16` elements of the cost rows, the windows and the voter counts of
/// both eyes, and of the two SGM states.
pub const fn cost_len(w: usize, p: &C2fParams) -> usize {
    let mut state = 0;
    let mut k = 0;
    while k < p.levels() {
        let n = sgm::scratch_len(level_len(w, k), p.candidates(k));
        if n > state {
            state = n;
        }
        k += 1;
    }
    2 * row_cells(w, p) + 4 * w + 2 * state
}

/// `u32` elements of the SGM sums of both eyes.
pub const fn sum_len(w: usize, p: &C2fParams) -> usize {
    2 * row_cells(w, p)
}

/// `i32` elements of the per-row picks (left and right).
pub const fn pick_len(w: usize) -> usize {
    2 * w
}

/// `u8` elements of the window maps: levels 1 and 2 (both eyes), the
/// coarser ones reusing them.
pub const fn map_len(w: usize, h: usize, p: &C2fParams) -> usize {
    let mut n = 0;
    let mut k = 1;
    while k <= 2 && k < p.levels() {
        n += 2 * level_len(w, k) * level_len(h, k);
        k += 1;
    }
    n
}

/// Scratch bytes of the engine at `w` x `h`, beyond the two input frames
/// and the output (the phase refinement's included).
pub const fn scratch_bytes(w: usize, h: usize, p: &C2fParams) -> usize {
    let phase = match &p.phase {
        Some(ph) => phase::scratch_bytes(w, ph, p.dem.max_disp),
        None => 0,
    };
    phase
        + 2 * grey_len(w, p)
        + 3 * rgb_len(w, p)
        + 4 * z_len(w, p)
        + 12 * w
        + 8 * score_len(w, p)
        + 2 * cost_len(w, p)
        + 4 * sum_len(w, p)
        + 4 * pick_len(w)
        + map_len(w, h, p)
}

/// Caller-provided scratch, sized by the `const fn`s of this module.
pub struct C2fBuffers<'a> {
    /// Grey rings ([`grey_len`]).
    pub grey: &'a mut [u16],
    /// RGB rows ([`rgb_len`]).
    pub rgb: &'a mut [Rgb8],
    /// Response rows ([`z_len`]).
    pub z: &'a mut [Z],
    /// y-pass row (`w`), then one pixel's cells while voting.
    pub col: &'a mut [[i32; 3]],
    /// Score rows ([`score_len`]).
    pub scores: &'a mut [i64],
    /// Costs, windows, voters, SGM states ([`cost_len`]).
    pub costs: &'a mut [u16],
    /// SGM sums ([`sum_len`]).
    pub sums: &'a mut [u32],
    /// Row picks ([`pick_len`]).
    pub picks: &'a mut [i32],
    /// Window maps ([`map_len`]).
    pub maps: &'a mut [u8],
    /// The phase refinement's ([`crate::stereo::phase`]; empty slices without
    /// [`C2fParams::phase`]).
    pub phase: PhaseBuffers<'a>,
}

/// The scratch of one level's run (the maps aside).
pub(super) struct Work<'b, 'a> {
    pub(super) grey: &'b mut &'a mut [u16],
    pub(super) rgb: &'b mut &'a mut [Rgb8],
    pub(super) z: &'b mut &'a mut [Z],
    pub(super) col: &'b mut &'a mut [[i32; 3]],
    pub(super) scores: &'b mut &'a mut [i64],
    pub(super) costs: &'b mut &'a mut [u16],
    pub(super) sums: &'b mut &'a mut [u32],
    pub(super) picks: &'b mut &'a mut [i32],
}

/// Moves the first `n` elements of `*s` out ([`StereoError::Buffer`] if
/// there are fewer).
pub(super) fn take<'a, T>(
    s: &mut &'a mut [T],
    n: usize,
    what: &'static str,
) -> Result<&'a mut [T], StereoError> {
    let got = s.len();
    let (head, tail) = core::mem::take(s)
        .split_at_mut_checked(n)
        .ok_or(StereoError::Buffer {
            what,
            needed: n,
            got,
        })?;
    *s = tail;
    Ok(head)
}
