//! The bank's fast kernels: the symmetric y pass over a window of rows and
//! the chunked symmetric x pass of one unit, exact and equal to the naive
//! [`y_pass`](super::y_pass) and [`x_pass`](super::x_pass).

use super::{Half, Halves, GREY_FRAC, KERNEL_FRAC, MAX_RADIUS, Z, Z_FRAC};
use crate::fixed::round_shift;

/// The symmetric y pass: `col[x] = [E, Yr, Yi]` (`Σ env·v`, `Σ ky_re·v`,
/// `Σ ky_im·v` over the rows, exact in `i32`, see [`Bank`](super::Bank)); with `ky`
/// `None`, only `E` (the rest is left as it was).
pub(super) fn y_sym(
    rows: &[&[u16]],
    env: &Half,
    ky: Option<&[[i32; 2]; MAX_RADIUS + 1]>,
    col: &mut [[i32; 3]],
) {
    let r = rows.len() / 2;
    let Some((lo, rest)) = rows.split_at_checked(r) else {
        return;
    };
    let Some((centre, hi)) = rest.split_first() else {
        return;
    };
    let ec = env.get(r).copied().unwrap_or(0);
    let pairs = lo.iter().zip(hi.iter().rev());
    if let Some(ky) = ky {
        let kc = ky.get(r).map_or(0, |k| k[0]);
        for (o, &v) in col.iter_mut().zip(*centre) {
            let v = i32::from(v);
            *o = [ec * v, kc * v, 0];
        }
        for ((a, b), (&e, k)) in pairs.zip(env.iter().zip(ky)) {
            for ((o, &va), &vb) in col.iter_mut().zip(*a).zip(*b) {
                let (va, vb) = (i32::from(va), i32::from(vb));
                let (p, m) = (va + vb, va - vb);
                o[0] += e * p;
                o[1] += k[0] * p;
                o[2] += k[1] * m;
            }
        }
    } else {
        for (o, &v) in col.iter_mut().zip(*centre) {
            o[0] = ec * i32::from(v);
        }
        for ((a, b), &e) in pairs.zip(env) {
            for ((o, &va), &vb) in col.iter_mut().zip(*a).zip(*b) {
                o[0] += e * (i32::from(va) + i32::from(vb));
            }
        }
    }
}

/// Columns of the x pass per chunk: [`XUnit::run`] works on a local copy of
/// `CHUNK + 2r` columns of `col` with the borders replicated, so that every
/// window is a plain slice (no clamping per pixel).
const CHUNK: usize = 32;

/// `buf[j] = col[clamp(x0 + j − r, 0, w − 1)]` for `j < n + 2r` (the
/// replicated borders of [`x_pass`](super::x_pass)).
fn pad(col: &[[i32; 3]], x0: usize, n: usize, r: usize, buf: &mut [[i32; 3]]) {
    let left = r.saturating_sub(x0);
    let src = col.get(x0.saturating_sub(r)..(x0 + n + r).min(col.len()));
    let (Some(src), Some(first), Some(last)) = (src, col.first(), col.last()) else {
        return;
    };
    let Some((l, rest)) = buf
        .get_mut(..n + 2 * r)
        .and_then(|b| b.split_at_mut_checked(left))
    else {
        return;
    };
    let Some((mid, right)) = rest.split_at_mut_checked(src.len()) else {
        return;
    };
    l.fill(*first);
    mid.copy_from_slice(src);
    right.fill(*last);
}

/// `f(i, m, p)` for the window's pairs: tap `i − R` (`i < R`) at `m` and
/// its mirror at `p` (constant indices once `R` is known).
#[inline(always)]
fn mirror<const R: usize, const T: usize>(
    win: &[[i32; 3]; T],
    mut f: impl FnMut(usize, &[i32; 3], &[i32; 3]),
) {
    for i in 0..R {
        if let (Some(m), Some(p)) = (win.get(i), win.get(2 * R - i)) {
            f(i, m, p);
        }
    }
}

/// `i64` product of two `i32` (one `smull`/`smlal`).
#[inline(always)]
fn mul(k: i32, v: i32) -> i64 {
    i64::from(k) * i64::from(v)
}

/// One component of [`finish`](super::finish) with `b` and `dc` in `i32`: the same bits.
/// `b = bl >> 14` with `|bl| ≤ 2^14·2^30` (Σ env = 2^14, `|E| < 2^30`),
/// so `|b| ≤ 2^30`; the bank keeps `dc` only if it fits `i32`. `|s| <
/// 2^50` (every `|kx| ≤ 2^14` (checked), at most 31 taps, `|Y| < 2^30`,
/// and `s` is a sum or difference of two such correlations) and
/// `|dc·b| ≤ 2^61` (`>> 14`: `2^47`), so `v` and the rounding are exact in
/// `i64` as in [`finish`](super::finish) and the rounded value (`|·| < 2^21`) is exact in
/// `i32`, where the same clamp to `i16` applies.
#[inline(always)]
fn finish1(s: i64, b: i32, dc: i32) -> i16 {
    let v = s - (mul(dc, b) >> KERNEL_FRAC);
    let q = round_shift(v, GREY_FRAC + 2 * KERNEL_FRAC - Z_FRAC) as i32;
    q.clamp(-32768, 32767) as i16
}

/// The x pass of one [`Unit`](super::Unit) (see [`Bank`](super::Bank)): the envelope's halves, and
/// for each carrier of the unit its halves (its DC term for `b`) and its
/// output row.
pub(super) struct XUnit<'h, 'o> {
    pub(super) env: &'h Half,
    pub(super) a: Option<(&'h Halves, &'o mut [Z])>,
    pub(super) b: Option<([i32; 2], &'o mut [Z])>,
    pub(super) e: Option<(&'h Halves, &'o mut [Z])>,
}

/// `out[x] = [Σ k_re·(m + p) + k_re(R)·c, Σ k_im·(m − p)]` on channel
/// `ch` of every window (centre `c`, pairs `m`, `p`) of `buf`: an even and
/// an odd correlation sharing the loads, two accumulators.
#[inline(always)]
fn sym2<const R: usize, const T: usize>(
    buf: &[[i32; 3]],
    ch: usize,
    k: &[[i32; 2]; MAX_RADIUS + 1],
    out: &mut [[i64; 2]],
) {
    let kt = |i: usize| k.get(i).copied().unwrap_or([0; 2]);
    let at = |c: &[i32; 3]| c.get(ch).copied().unwrap_or(0);
    let wins = buf.windows(T).filter_map(|w| w.first_chunk::<T>());
    for (win, o) in wins.zip(out) {
        let (mut even, mut odd) = (mul(kt(R)[0], win.get(R).map_or(0, at)), 0);
        mirror::<R, T>(win, |i, m, p| {
            let (m, p, k) = (at(m), at(p), kt(i));
            even += mul(k[0], m + p);
            odd += mul(k[1], m - p);
        });
        *o = [even, odd];
    }
}

impl XUnit<'_, '_> {
    /// Runs over the row with radius `R` (the bank's, `T = 2R + 1` taps),
    /// [`CHUNK`] columns at a time, in sweeps over each chunk with at most
    /// two 64-bit accumulators each (they stay in registers):
    /// `bl = Σ env·E`, kept as `b = bl >> 14` (`|b| ≤ 2^30`, see
    /// [`finish1`]); the rider `e`'s `Σ kx·E`; `A = Σ kx_re·Yr`, `D = Σ
    /// kx_im·Yr`; `C = Σ kx_re·Yi`, `B = Σ kx_im·Yi`; then the rounding.
    pub(super) fn run<const R: usize, const T: usize>(self, col: &[[i32; 3]]) {
        let env = self.env;
        let ec = env.get(R).copied().unwrap_or(0);
        let et = |i: usize| env.get(i).copied().unwrap_or(0);
        let mut a = self.a.map(|(h, o)| (h, o.chunks_mut(CHUNK)));
        let mut b = self.b.map(|(dc, o)| (dc, o.chunks_mut(CHUNK)));
        let mut e = self.e.map(|(h, o)| (h, o.chunks_mut(CHUNK)));
        let w = col.len();
        let mut x0 = 0;
        // Scratch of every chunk, zeroed once: each chunk writes what it
        // reads (`pad` its `n + 2R` columns, the sweeps their `n` sums).
        let mut padded = [[0i32; 3]; CHUNK + 2 * MAX_RADIUS];
        let mut bs = [0i32; CHUNK];
        let (mut s, mut t) = ([[0i64; 2]; CHUNK], [[0i64; 2]; CHUNK]);
        while x0 < w {
            let n = CHUNK.min(w - x0);
            pad(col, x0, n, R, &mut padded);
            x0 += n;
            let buf = padded.get(..n + 2 * R).unwrap_or(&[]);
            let wins = buf.windows(T).filter_map(|w| w.first_chunk::<T>());
            for (win, bo) in wins.zip(&mut bs) {
                let mut bl = mul(ec, win.get(R).map_or(0, |c| c[0]));
                mirror::<R, T>(win, |i, m, p| bl += mul(et(i), m[0] + p[0]));
                *bo = (bl >> KERNEL_FRAC) as i32;
            }
            if let Some((h, oe)) = e.as_mut().and_then(|(h, o)| Some((*h, o.next()?))) {
                sym2::<R, T>(buf, 0, &h.kx, &mut s);
                for ((o, &[re, im]), &bv) in oe.iter_mut().zip(&s).zip(&bs) {
                    *o = [finish1(re, bv, h.dc32[0]), finish1(im, bv, h.dc32[1])];
                }
            }
            let Some((h, oa)) = a.as_mut().and_then(|(h, o)| Some((*h, o.next()?))) else {
                continue;
            };
            // z_a = (A − B) + i(C + D), z_b = (A + B) + i(D − C).
            sym2::<R, T>(buf, 1, &h.kx, &mut s);
            sym2::<R, T>(buf, 2, &h.kx, &mut t);
            let sums = s.iter().zip(&t).zip(&bs);
            for (((&[sa, sd], &[sc, sb]), &bv), o) in sums.clone().zip(oa) {
                *o = [
                    finish1(sa - sb, bv, h.dc32[0]),
                    finish1(sc + sd, bv, h.dc32[1]),
                ];
            }
            if let Some((dc, ob)) = b.as_mut().and_then(|(dc, o)| Some((*dc, o.next()?))) {
                for (((&[sa, sd], &[sc, sb]), &bv), o) in sums.zip(ob) {
                    *o = [finish1(sa + sb, bv, dc[0]), finish1(sd - sc, bv, dc[1])];
                }
            }
        }
    }
}
