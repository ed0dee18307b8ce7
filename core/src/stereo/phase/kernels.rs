//! The per-row kernels of the phase refiner: the replaceable
//! [`PhaseKernel`] and its portable [`SafePhase`], the pooled phase step,
//! the grey and x passes of the Gabor filter, and the arc tangent in turns.

use super::{Half, MAX_TURN, TAP_FRAC, Z_FRAC};
use crate::disparity::DisparityCell;
use crate::fixed::U8F8;
use crate::image::{Rgb8, RgbRows};
use crate::stereo::DemTable;

/// The phase step of a row with 3-pixel pooling (the default `pool` 1),
/// replaceable by a target's kernel, as [`crate::mlp::MacKernel`]: the
/// portable default is [`SafePhase`]; the firmware passes one in
/// assembly (`SMUAD`/`SMLSDX` for the products, which safe Rust cannot
/// ask for).
///
/// Contract of [`PhaseKernel::phase_row3`]: with `w = cells.len()`, `zl`
/// holds the left responses of columns `−1..=w` (`w + 2`), `zr` the
/// right's of columns `−1 − max_disp..=w` (`w + 2 + max_disp`), and
/// `lambda_q8` is λ in `U8F8` (at most 64·256). Refine each ON cell
/// exactly as [`phase_row3`] does and return the number refined; any
/// kernel that honours this gives the same bits. Shorter slices are
/// never passed by the refiner; the default refines what fits.
pub trait PhaseKernel {
    /// The phase step of one row ([`phase_row3`]).
    #[inline(always)]
    fn phase_row3(
        max_disp: u8,
        lambda_q8: i32,
        zl: &[[i16; 2]],
        zr: &[[i16; 2]],
        cells: &mut [DisparityCell],
    ) -> usize {
        phase_row3(max_disp, lambda_q8, zl, zr, cells)
    }

    /// The stereo stage's other hot step: one path step of the
    /// semi-global aggregation for a pixel with 5 candidates whose
    /// predecessor's window starts at the same candidate
    /// ([`crate::stereo::sgm::sgm_step`], the portable default; the
    /// engine's windows of 5 at its finer levels). `c` are the pixel's
    /// costs, `p` the predecessor's state `L − min L`, `pad` stands for
    /// the candidates just outside the window (`1 << 30`, or 0 for a
    /// missing predecessor), `pen` is `(P1, P2)`. Adds the pixel's `L` to
    /// `acc` and returns its state `L − min L`.
    ///
    /// Contract: `P1 <= P2 <= 65535`, every `c[d] + P2 <= 65535` (the
    /// aggregation checks it), every `p[d] <= 65535` and `pad` is 0 or
    /// at least 65535; any kernel that honours it must give the same
    /// integers as the default (so a 16-bit lane with saturating sums
    /// serves).
    #[inline(always)]
    fn sgm_step5(
        c: &[u16; 5],
        p: &[u16; 5],
        pad: u32,
        pen: (u32, u32),
        acc: &mut [u32; 5],
    ) -> [u16; 5] {
        crate::stereo::sgm::sgm_step(c, p, pad, pen, acc)
    }

    /// The refinement's 5-tap x pass of one row (radius 2, the default):
    /// `out[x] = (re, im)` of `v[x..x + 5]` with the taps `ch[..3]`,
    /// `sh[1..3]` (the zero-DC real and odd imaginary halves of
    /// [`Phase`](super::Phase)), each rounded to `I12F4`.
    ///
    /// Contract: `v` holds greys of [`grey8`] (0..=65280), and the real
    /// taps sum to zero, `c0 = −2 (c1 + c2)` (as [`Phase`](super::Phase)
    /// makes them); any kernel that honours it must give the same
    /// integers as the default.
    #[inline(always)]
    fn x_pass5(v: &[i32], ch: &Half, sh: &Half, out: &mut [[i16; 2]]) {
        x_pass5(v, ch, sh, out);
    }

    /// [`PhaseKernel::sgm_step5`] for 9 candidates (the coarsest level's
    /// full search at 32 disparities), with the same contract.
    #[inline(always)]
    fn sgm_step9(
        c: &[u16; 9],
        p: &[u16; 9],
        pad: u32,
        pen: (u32, u32),
        acc: &mut [u32; 9],
    ) -> [u16; 9] {
        crate::stereo::sgm::sgm_step(c, p, pad, pen, acc)
    }

    /// The read-out's third hot step: one pixel's `Q8` costs from its
    /// window's scores, every candidate valid ([`crate::stereo::c2f::costs`],
    /// the portable default; every pixel whose window lies within the
    /// disparity range: windows of 5 at the engine's finer levels, and its
    /// coarsest level's full search).
    ///
    /// Contract: `raw[..n]` are the window's scores (`n = out.len()`) and
    /// may be left with any values; `total > 0`. Any kernel must write the
    /// same `out` as the default.
    #[inline(always)]
    fn costs(raw: &mut [i64], total: i64, table: &DemTable<'_>, lo: usize, out: &mut [u16]) {
        crate::stereo::c2f::costs(raw, total, table, lo, out);
    }
}

/// The portable phase step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SafePhase;

impl PhaseKernel for SafePhase {}

/// The portable phase step of a row with 3-pixel pooling (see
/// [`PhaseKernel`]).
#[inline(always)]
pub fn phase_row3(
    max_disp: u8,
    lambda_q8: i32,
    zl: &[[i16; 2]],
    zr: &[[i16; 2]],
    cells: &mut [DisparityCell],
) -> usize {
    phase_row_at::<3>(max_disp, lambda_q8, zl, zr, cells)
}

/// The phase step of one row with `S = 2·pool + 1` known: each ON cell's
/// pooled product `P` over `S` pixels at its shift, its argument, the
/// refined disparity. Returns the cells refined.
#[inline(always)]
pub(super) fn phase_row_at<const S: usize>(
    max_disp: u8,
    lambda: i32,
    zl: &[[i16; 2]],
    zr: &[[i16; 2]],
    cells: &mut [DisparityCell],
) -> usize {
    let md = usize::from(max_disp);
    let top = (md as i32) << 8;
    let mut refined = 0;
    // `a` starts at left column `x − pool`; `zr[md..]` at right column
    // `−pool`, so right column `x − s − pool` is `zr[x + md − s]`.
    for (x, (cell, a)) in cells.iter_mut().zip(zl.windows(S)).enumerate() {
        let Some(d) = cell.get() else { continue };
        let s = ((usize::from(d.to_bits()) + 128) >> 8).min(md);
        let i = x + md - s;
        let (Ok(a), Some(Ok(b))) = (
            <&[[i16; 2]; S]>::try_from(a),
            zr.get(i..i + S).map(<&[[i16; 2]; S]>::try_from),
        ) else {
            continue;
        };
        let (re, im) = product(a, b);
        if let Some(rq8) = remainder_q8(im, re, lambda) {
            let v = (((s as i32) << 8) + rq8).clamp(0, top);
            *cell = DisparityCell::from_raw(U8F8::from_bits(v as u16));
            refined += 1;
        }
    }
    refined
}

/// `Σ a · conj(b)` of two windows of responses, exact in `i32`.
#[inline(always)]
fn product<const S: usize>(a: &[[i16; 2]; S], b: &[[i16; 2]; S]) -> (i32, i32) {
    let (mut re, mut im) = (0i32, 0i32);
    for (&[ar, ai], &[br, bi]) in a.iter().zip(b) {
        let (ar, ai, br, bi) = (i32::from(ar), i32::from(ai), i32::from(br), i32::from(bi));
        re += ar * br + ai * bi;
        im += ai * br - ar * bi;
    }
    (re, im)
}

/// The remainder `arg P · λ / 2π` in `U8F8` px (`lambda` is λ in `U8F8`),
/// or `None` for `P = 0` (no phase) and beyond ±[`MAX_TURN`] (at ±½ turn
/// either sign fits, so the remainder is ambiguous): the cell is kept.
#[inline(always)]
fn remainder_q8(im: i32, re: i32, lambda: i32) -> Option<i32> {
    let turns = atan2_turns(im, re)?;
    if turns.abs() > MAX_TURN {
        return None;
    }
    Some((turns * lambda + (1 << 15)) >> 16)
}

/// The grey of an RGB pixel with 8-bit weights, `U8F8` exactly:
/// `(77 R + 150 G + 29 B) / 256` (BT.601's 0.299, 0.587, 0.114 to 1/256;
/// the weights sum to 256, so white is 255).
#[inline(always)]
pub fn grey8(p: Rgb8) -> i32 {
    77 * i32::from(p.r) + 150 * i32::from(p.g) + 29 * i32::from(p.b)
}

/// The grey of row `y` of `eye` ([`RgbRows::grey8_row`], `rgb` its
/// scratch) into `v[r..r + w]`, then the padding replicated.
#[inline(always)]
pub(super) fn grey_row<S: RgbRows>(eye: &S, y: usize, rgb: &mut [Rgb8], v: &mut [i32], r: usize) {
    let w = rgb.len();
    if let Some(inner) = v.get_mut(r..r + w) {
        eye.grey8_row(y, rgb, inner);
    }
    let first = v.get(r).copied().unwrap_or(0);
    let last = v.get(r + w.max(1) - 1).copied().unwrap_or(0);
    v.iter_mut().take(r).for_each(|o| *o = first);
    v.iter_mut().skip(r + w).for_each(|o| *o = last);
}

/// The filter of one row on the padded grey: `z = Σ (c, s)·v`, rounded
/// to `I12F4`, with the kernels' symmetry (`c` even, `s` odd): `re = c_0
/// v_0 + Σ_i c_i (v_{−i} + v_i)`, `im = Σ_i s_i (v_i − v_{−i})`, the same
/// integers with half the multiplies.
#[inline(always)]
pub(super) fn x_pass<const N: usize>(v: &[i32], ch: &Half, sh: &Half, out: &mut [[i16; 2]]) {
    let r = N / 2;
    let shift = TAP_FRAC + 8 - Z_FRAC;
    let (c0, ch, sh) = (ch[0], &ch[1..], &sh[1..]);
    for (win, o) in v.windows(N).zip(out.iter_mut()) {
        if let Ok(win) = <&[i32; N]>::try_from(win) {
            // `lo` holds v_{−r..−1}, `hi` v_{1..r} (both `r` long).
            let (lo, rest) = win.split_at(r);
            let (centre, hi) = rest.split_at(1);
            let mut re = c0 * centre.first().copied().unwrap_or(0);
            let mut im = 0i32;
            for (((&a, &b), &c), &s) in lo.iter().rev().zip(hi).zip(ch).zip(sh) {
                re += c * (a + b);
                im += s * (b - a);
            }
            *o = [
                ((re + (1 << (shift - 1))) >> shift) as i16,
                ((im + (1 << (shift - 1))) >> shift) as i16,
            ];
        }
    }
}

/// The portable [`PhaseKernel::x_pass5`]: the general x pass for 5 taps
/// (the default radius 2), the same integers: the real parts, then the
/// imaginary ones, each in one sweep, so that each pixel loads one grey
/// value per sweep and the taps stay in registers.
#[inline(always)]
pub fn x_pass5(v: &[i32], ch: &Half, sh: &Half, out: &mut [[i16; 2]]) {
    let shift = TAP_FRAC + 8 - Z_FRAC;
    let half = 1 << (shift - 1);
    let [c0, c1, c2, ..] = *ch;
    let [_, s1, s2, ..] = *sh;
    sweep5(v, out, |[a, b, c, d, e], o| {
        o[0] = ((c0 * c + c1 * (b + d) + c2 * (a + e) + half) >> shift) as i16;
    });
    sweep5(v, out, |[a, b, _, d, e], o| {
        o[1] = ((s1 * (d - b) + s2 * (e - a) + half) >> shift) as i16;
    });
}

/// `f(window, out[x])` for the 5-wide windows of `v`, the window sliding
/// through locals (one load per pixel).
#[inline(always)]
fn sweep5(v: &[i32], out: &mut [[i16; 2]], f: impl Fn([i32; 5], &mut [i16; 2])) {
    let mut it = v.iter().copied();
    let (Some(mut a), Some(mut b), Some(mut c), Some(mut d)) =
        (it.next(), it.next(), it.next(), it.next())
    else {
        return;
    };
    for (o, e) in out.iter_mut().zip(it) {
        f([a, b, c, d, e], o);
        (a, b, c, d) = (b, c, d, e);
    }
}

/// `atan2(y, x)` in turns, `Q16` (`−2^15..=2^15`; `y = 0 > x` gives
/// `+2^15`, half a turn, as `atan2(+0, x)`), or `None` at the origin:
/// octant reduction, `t = min/max` in `Q15` (one division, after both are
/// shifted below 2^16), and `atan t ≈ π/4·t + 0.273·t(1 − t)` (within
/// 0.0038 rad on `0..=1`).
pub fn atan2_turns(y: i32, x: i32) -> Option<i32> {
    let (ax, ay) = (x.unsigned_abs(), y.unsigned_abs());
    let (mn, mx) = if ay > ax { (ax, ay) } else { (ay, ax) };
    let mx_nz = core::num::NonZeroU32::new(mx)?;
    let k = (32 - mx_nz.leading_zeros()).saturating_sub(16);
    let (mn, mx) = (mn >> k, mx >> k);
    let mx = core::num::NonZeroU32::new(mx)?;
    // mn ≤ mx < 2^16, so mn·2^15 < 2^31.
    let t = ((mn << 15) / mx) as i32;
    // t/8 turns + 0.273/2π · t(1 − t), in Q16 (2847 = 0.273/2π · 2^16).
    let tt = (t * (32768 - t)) >> 15;
    let mut a = (t >> 2) + ((2847 * tt) >> 15);
    if ay > ax {
        a = 16384 - a;
    }
    if x < 0 {
        a = 32768 - a;
    }
    if y < 0 {
        a = -a;
    }
    Some(a)
}
