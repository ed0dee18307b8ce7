//! The per-pixel step kernels of one SGM path: the fixed-size fused steps
//! for `n <= 9` candidates (with the portable [`sgm_step`] that
//! [`PhaseKernel`]'s default runs) and the plain per-path recurrence for any
//! `n`.

use crate::stereo::phase::PhaseKernel;

/// `c` as an array of `N`.
#[inline(always)]
pub(super) fn arr<const N: usize>(c: &[u16]) -> Option<&[u16; N]> {
    <&[u16; N]>::try_from(c).ok()
}

/// `settle(path(..), acc)`, by kernel `K`'s [`PhaseKernel::sgm_step5`]
/// or [`PhaseKernel::sgm_step9`] for windows of 5 or 9 that start where
/// the predecessor's does (the common case).
#[inline(always)]
pub(super) fn kernel_step<K: PhaseKernel, const N: usize>(
    c: &[u16; N],
    p: &[u16; N],
    (lo, plo): (u16, u16),
    pad: u32,
    pen: (u32, u32),
    acc: &mut [u32; N],
) -> [u16; N] {
    if lo == plo {
        if let (Ok(c5), Ok(p5), Ok(acc5)) = (
            <&[u16; 5]>::try_from(c.as_slice()),
            <&[u16; 5]>::try_from(p.as_slice()),
            <&mut [u32; 5]>::try_from(acc.as_mut_slice()),
        ) {
            let s = K::sgm_step5(c5, p5, pad, pen, acc5);
            return core::array::from_fn(|i| s.get(i).copied().unwrap_or(0));
        }
        if let (Ok(c9), Ok(p9), Ok(acc9)) = (
            <&[u16; 9]>::try_from(c.as_slice()),
            <&[u16; 9]>::try_from(p.as_slice()),
            <&mut [u32; 9]>::try_from(acc.as_mut_slice()),
        ) {
            let s = K::sgm_step9(c9, p9, pad, pen, acc9);
            return core::array::from_fn(|i| s.get(i).copied().unwrap_or(0));
        }
    }
    settle(path(c, p, (lo, plo), pad, pen), acc)
}

/// The portable [`PhaseKernel::sgm_step5`] and
/// [`PhaseKernel::sgm_step9`]: one step of a path for `N` candidates
/// whose predecessor's state `p` has the same window, `L` added to `acc`,
/// the state `L − min L` returned.
#[inline(always)]
pub fn sgm_step<const N: usize>(
    c: &[u16; N],
    p: &[u16; N],
    pad: u32,
    pen: (u32, u32),
    acc: &mut [u32; N],
) -> [u16; N] {
    settle(recur(c, (p.map(u32::from), pad, pad), pen), acc)
}

/// One step of a path for `N` candidates: the pixel's costs `c` (window
/// from `lo`) and its predecessor's state `p` (`L − min L`, window from
/// `plo`; `pad` stands for candidates outside it: `INF`, or 0 for the zero
/// state of a missing predecessor). Returns the pixel's `L` and `min L`.
/// Needs `c + P2 <= 65535` (checked by the caller).
#[inline(always)]
fn path<const N: usize>(
    c: &[u16; N],
    p: &[u16; N],
    (lo, plo): (u16, u16),
    pad: u32,
    pen: (u32, u32),
) -> ([u32; N], u32) {
    if lo == plo {
        recur(c, (p.map(u32::from), pad, pad), pen)
    } else {
        path_shifted(c, p, i32::from(lo) - i32::from(plo), pad, pen)
    }
}

/// [`path`] for windows `off = lo − plo != 0` apart (out of line: the
/// common case `off = 0` stays in registers).
#[inline(never)]
fn path_shifted<const N: usize>(
    c: &[u16; N],
    p: &[u16; N],
    off: i32,
    pad: u32,
    pen: (u32, u32),
) -> ([u32; N], u32) {
    let at = |j: i32| {
        usize::try_from(j)
            .ok()
            .and_then(|j| p.get(j))
            .map_or(pad, |&v| u32::from(v))
    };
    let mut here = [pad; N];
    for (j, e) in (off..).zip(here.iter_mut()) {
        *e = at(j);
    }
    recur(c, (here, at(off - 1), at(off + N as i32)), pen)
}

/// The recurrence from the predecessor's `L − min L` at the pixel's
/// candidates (`here`), just below the first and just above the last:
/// `L` and `min L`.
#[inline(always)]
fn recur<const N: usize>(
    c: &[u16; N],
    (here, below, above): ([u32; N], u32, u32),
    (p1, p2): (u32, u32),
) -> ([u32; N], u32) {
    let mut l = [0u32; N];
    let mut min = u32::MAX;
    let mut below = below;
    let aboves = here.iter().skip(1).copied().chain(core::iter::once(above));
    for (((v, &cd), &h), a) in l.iter_mut().zip(c).zip(&here).zip(aboves) {
        *v = u32::from(cd) + p2.min(h).min(below.min(a) + p1);
        min = min.min(*v);
        below = h;
    }
    (l, min)
}

/// Adds a step's `L` to `acc` and returns the state `L − min L`.
#[inline(always)]
fn settle<const N: usize>((l, min): ([u32; N], u32), acc: &mut [u32; N]) -> [u16; N] {
    for (s, &v) in acc.iter_mut().zip(&l) {
        *s += v;
    }
    l.map(|v| (v - min) as u16)
}

/// A step whose predecessor is `state` itself, at window `plo` (the
/// horizontal and vertical paths; `None`: no predecessor): `state` becomes
/// the pixel's `L`, added to `out` (or stored, with `set`).
#[allow(clippy::too_many_arguments)]
pub(super) fn step_self(
    c: &[u16],
    lo: u16,
    state: &mut [u16],
    plo: Option<u16>,
    pen: (u32, u32),
    tmp: &mut [u16],
    out: &mut [u32],
    set: bool,
) {
    for (t, &v) in tmp.iter_mut().zip(state.iter()) {
        *t = v;
    }
    step(c, lo, plo.map(|p| (&*tmp, p)), pen, state, out, set);
}

/// Larger than any `L − min + P1` (both below 2^17), and no overflow.
pub(super) const INF: u32 = 1 << 30;

/// One step of a path into `new`: the pixel's costs `c` over its window
/// `lo..lo + n`, and the predecessor's `L` over its window (`None`: no
/// predecessor, `L = C`). Candidates outside the predecessor's window are
/// `+∞`. Needs `c + P2 <= 65535` (checked by the caller). Each new value
/// is also added to `out` (or stored, with `set`).
pub(super) fn step(
    c: &[u16],
    lo: u16,
    prev: Option<(&[u16], u16)>,
    (p1, p2): (u32, u32),
    new: &mut [u16],
    out: &mut [u32],
    set: bool,
) {
    let Some((prev, plo)) = prev else {
        for ((o, s), &cd) in new.iter_mut().zip(out).zip(c) {
            *o = cd;
            *s = if set {
                u32::from(cd)
            } else {
                *s + u32::from(cd)
            };
        }
        return;
    };
    let min = prev.iter().copied().min().map_or(0, u32::from);
    // `L − min` of the predecessor at candidates `lo − 1, lo, ..` (`INF`
    // outside its window), read once each.
    let off = i32::from(lo) - i32::from(plo);
    let at = |j: i32| {
        usize::try_from(j)
            .ok()
            .and_then(|j| prev.get(j))
            .map_or(INF, |&v| u32::from(v).saturating_sub(min))
    };
    let (mut below, mut here) = (at(off - 1), at(off));
    for (j, ((o, s), &cd)) in (off + 1..).zip(new.iter_mut().zip(out).zip(c)) {
        let above = at(j);
        let m = p2.min(here).min(below.min(above) + p1);
        let v = u32::from(cd) + m;
        *o = u16::try_from(v).unwrap_or(u16::MAX);
        *s = if set { v } else { *s + v };
        (below, here) = (here, above);
    }
}
