//! The per-pixel statistics steps of [`segment`](super::segment) on bit
//! maps: the same decisions as the `bool`/cell functions of `stats`, with
//! the selected area as bounds and the masks as bits.

use super::bits::{for_each_on, Geom};
use super::ground::GroundLine;
use super::stats::{
    plane, selected_bounds, DisparityRange, PsiMean, SliceCounts, Thresholds, PLANES,
    STAT_FRAC_BITS,
};
use super::SegmentParams;
use crate::conspicuity::EdgeCell;
use crate::disparity::DisparityCell;
use crate::image::ImageView;

/// Extra fraction bits of the thresholds over the disparity bits.
const EXTRA: u32 = STAT_FRAC_BITS - 8;

fn set(g: Geom, m: &mut [u32], x: usize, y: usize) {
    if let Some(w) = m.get_mut(y * g.stride + x / 32) {
        *w |= 1 << (x % 32);
    }
}

fn bits_at(d: &ImageView<'_, DisparityCell>, x: usize, y: usize) -> Option<u16> {
    d.get(x, y).and_then(|c| c.get()).map(|v| v.to_bits())
}

/// The depth pass's foreground, written by [`foreground`] in the same
/// sweep: `rows` the rows' estimates as `fit_ground` writes them (the
/// disparity bits + 1, 0 for none), `rise` the least height above them
/// ([`DepthPass::rise`](super::DepthPass::rise)), `fg` its bit map.
pub(super) struct Rise<'a> {
    pub rows: &'a [u32],
    pub rise: u16,
    pub fg: &'a mut [u32],
}

/// The cells `c` of a row's word (at most 32, cell `i` at bit `i`) with
/// `lo <= c < lo + span` (wrapping), `c` the raw bits (OFF is `u16::MAX`),
/// in the first word for `a = (lo, span)`, in the second for `b` (0
/// without `TWO`).
fn band_words<const TWO: bool>(
    cells: &[DisparityCell],
    (a_lo, a_span): (u32, u32),
    (b_lo, b_span): (u32, u32),
) -> (u32, u32) {
    let (mut a, mut b) = (0u32, 0u32);
    for (i, c) in cells.iter().enumerate().take(32) {
        let raw = u32::from(c.raw().to_bits());
        a |= u32::from(raw.wrapping_sub(a_lo) < a_span) << (i % 32);
        if TWO {
            b |= u32::from(raw.wrapping_sub(b_lo) < b_span) << (i % 32);
        }
    }
    (a, b)
}

/// [`band_words`] for a whole word of cells, written out cell by cell: a
/// constant bit per cell, set by one conditional instruction (the
/// compiler unrolls the loop only in part, and shifts by the cell's index
/// cost more than the test). Each half word of cells builds one word, the
/// first map's bits in its low half and the second's in its high half:
/// one chain of tests, cell after cell, keeps every cell in a register.
#[inline(always)]
fn band_words_32<const TWO: bool>(
    cells: &[DisparityCell; 32],
    (a_lo, a_span): (u32, u32),
    (b_lo, b_span): (u32, u32),
) -> (u32, u32) {
    macro_rules! half {
        ($($c:ident $k:literal)*) => {{
            let mut w = 0u32;
            $(
                let raw = u32::from($c.raw().to_bits());
                if raw.wrapping_sub(a_lo) < a_span {
                    w |= 1 << $k;
                }
                if TWO && raw.wrapping_sub(b_lo) < b_span {
                    w |= 1 << (16 + $k);
                }
            )*
            w
        }};
    }
    let [c0, c1, c2, c3, c4, c5, c6, c7, c8, c9, c10, c11, c12, c13, c14, c15, c16, c17, c18, c19, c20, c21, c22, c23, c24, c25, c26, c27, c28, c29, c30, c31] =
        *cells;
    let lo = half!(
        c0 0 c1 1 c2 2 c3 3 c4 4 c5 5 c6 6 c7 7
        c8 8 c9 9 c10 10 c11 11 c12 12 c13 13 c14 14 c15 15
    );
    let hi = half!(
        c16 0 c17 1 c18 2 c19 3 c20 4 c21 5 c22 6 c23 7
        c24 8 c25 9 c26 10 c27 11 c28 12 c29 13 c30 14 c31 15
    );
    ((lo & 0xFFFF) | hi << 16, lo >> 16 | (hi & 0xFFFF_0000))
}

/// The D_fg and rise words of a row (see [`foreground`]).
#[inline(always)]
fn row_words<const TWO: bool>(
    row: &[DisparityCell],
    a: (u32, u32),
    b: (u32, u32),
    x0: usize,
    out: &mut [u32],
    mut out_b: Option<&mut [u32]>,
) -> u32 {
    let mut n = 0;
    for (i, (o, cells)) in out.iter_mut().zip(row.chunks(32)).enumerate() {
        let (mut wa, mut wb) = match <&[DisparityCell; 32]>::try_from(cells) {
            Ok(cells) => band_words_32::<TWO>(cells, a, b),
            Err(_) => band_words::<TWO>(cells, a, b),
        };
        // Columns left of S.
        let first = i * 32;
        if x0 > first {
            let keep = u32::MAX.checked_shl((x0 - first) as u32).unwrap_or(0);
            wa &= keep;
            wb &= keep;
        }
        *o = wa;
        n += wa.count_ones();
        if let Some(w) = out_b.as_deref_mut().and_then(|m| m.get_mut(i)) {
            *w = wb;
        }
    }
    n
}

/// [`row_words`] when the second band lies within the first: its cells
/// are among the first's, so only those are tested, one by one.
fn row_words_within(
    row: &[DisparityCell],
    a: (u32, u32),
    (b_lo, b_span): (u32, u32),
    x0: usize,
    out: &mut [u32],
    out_b: &mut [u32],
) -> u32 {
    let mut n = 0;
    let words = out.iter_mut().zip(out_b.iter_mut()).zip(row.chunks(32));
    for (i, ((o, ob), cells)) in words.enumerate() {
        let (mut wa, _) = match <&[DisparityCell; 32]>::try_from(cells) {
            Ok(cells) => band_words_32::<false>(cells, a, (0, 0)),
            Err(_) => band_words::<false>(cells, a, (0, 0)),
        };
        // Columns left of S.
        let first = i * 32;
        if x0 > first {
            wa &= u32::MAX.checked_shl((x0 - first) as u32).unwrap_or(0);
        }
        *o = wa;
        n += wa.count_ones();
        let (mut wb, mut rest) = (0u32, wa);
        while rest != 0 {
            let k = rest.trailing_zeros();
            let rises = cells
                .get(k as usize)
                .is_some_and(|c| u32::from(c.raw().to_bits()).wrapping_sub(b_lo) < b_span);
            if rises {
                wb |= 1 << (k % 32);
            }
            rest &= rest - 1;
        }
        *ob = wb;
    }
    n
}

/// D_fg as bits: valid D inside S with `low < D < high`, or `D < high`
/// and nearer than the row's background by the band
/// ([`foreground_rows`](super::foreground_rows)), and, with a ground line,
/// `D > d_g(y) + band` ([`inhibit_ground`](super::inhibit_ground)). With
/// `rise`, its map gets in the same sweep the depth pass's foreground:
/// the ON cells inside S at least `rise.rise` bits nearer than their
/// row's estimate (b >= r − 1 + rise, none in rows without one). Returns
/// the count of D_fg.
#[allow(clippy::too_many_arguments)]
pub(super) fn foreground(
    params: &SegmentParams,
    d: &ImageView<'_, DisparityCell>,
    t: &Thresholds,
    ground: Option<(&GroundLine, u16)>,
    rows: Option<(&[u32], u16)>,
    mut rise: Option<Rise<'_>>,
    g: Geom,
    fg: &mut [u32],
) -> u32 {
    let (x0, y0, y1) = selected_bounds(params, g.width, g.height);
    // low < b·2^EXTRA < high  <=>  lo <= b < hi.
    // Valid bits are below u16::MAX, the OFF value: capping `hi` there
    // changes no valid decision and leaves OFF out, so one comparison
    // decides both.
    let lo = (t.low >> EXTRA) + 1;
    let hi = t.high.div_ceil(1 << EXTRA).min(u32::from(u16::MAX));
    let off = u32::from(u16::MAX);
    let stride = g.stride.max(1);
    let mut n = 0;
    for (y, row) in d.rows().enumerate().take(y1).skip(y0) {
        let Some(out) = fg.get_mut(y * stride..(y + 1) * stride) else {
            break;
        };
        // Nearer than the row's background: b > r − 1 + band  <=>
        // b >= r + band, r the row's estimate + 1 (0: none).
        let lo = rows.map_or(lo, |(r, band)| match r.get(y) {
            Some(&r) if r > 0 => lo.min(r + u32::from(band)),
            _ => lo,
        });
        // Above the ground: b > d_g(y) + band  <=>  b >= d_g(y) + band + 1.
        let lo = ground.map_or(lo, |(l, band)| {
            let above = l.at(y).saturating_add(i64::from(band) + 1);
            lo.max(u32::try_from(above.max(0)).unwrap_or(u32::MAX))
        });
        let a = (lo, hi.saturating_sub(lo));
        // The rise: b >= (r − 1) + rise and not OFF  <=>
        // lo' <= b < u16::MAX; rows without an estimate get no bit.
        n += match rise.as_mut() {
            Some(p) => {
                let lo_b = match p.rows.get(y) {
                    Some(&r) if r > 0 => r - 1 + u32::from(p.rise),
                    _ => off,
                };
                let span = off.saturating_sub(lo_b);
                let out_b = p.fg.get_mut(y * stride..(y + 1) * stride);
                if span == 0 {
                    // No cell of the row rises: D_fg alone.
                    if let Some(o) = out_b {
                        o.fill(0);
                    }
                    row_words::<false>(row, a, (off, 0), x0, out, None)
                } else {
                    // The rise's band within D_fg's (lo <= lo' and the same
                    // top, u16::MAX): only D_fg's cells can rise.
                    let within = lo_b >= a.0 && u64::from(a.0) + u64::from(a.1) >= u64::from(off);
                    match out_b {
                        Some(ob) if within => row_words_within(row, a, (lo_b, span), x0, out, ob),
                        out_b => row_words::<true>(row, a, (lo_b, span), x0, out, out_b),
                    }
                }
            }
            None => row_words::<false>(row, a, (off, 0), x0, out, None),
        };
    }
    n
}

/// A^C(d) as [`slice_counts`](super::slice_counts) gives it from D_fg (the
/// bits of `fg` over D) and C_fg (C where `fg`).
pub(super) fn slice_counts(
    c: &ImageView<'_, EdgeCell>,
    d: &ImageView<'_, DisparityCell>,
    g: Geom,
    fg: &[u32],
) -> SliceCounts {
    let mut out = SliceCounts {
        counts: [0; PLANES],
        planes: None,
    };
    let (mut lo, mut hi) = (u16::MAX, 0u16);
    for_each_on(g, fg, |x, y| {
        let Some(b) = bits_at(d, x, y) else { return };
        let p = plane(b);
        lo = lo.min(p);
        hi = hi.max(p);
        if c.get(x, y).is_some_and(|c| c.is_on()) {
            if let Some(k) = out.counts.get_mut(usize::from(p)) {
                *k += 1;
            }
        }
    });
    if lo <= hi {
        out.planes = Some((lo, hi));
    }
    out
}

/// D_ObjReg (`fg` inside `range`), the ψ ≠ OFF map (into `psi_on`) and
/// C_ObjReg (ψ above its mean, [`above_mean`](super::above_mean)) as bits.
#[allow(clippy::too_many_arguments)]
pub(super) fn object(
    over: PsiMean,
    c: &ImageView<'_, EdgeCell>,
    d: &ImageView<'_, DisparityCell>,
    range: &DisparityRange,
    g: Geom,
    fg: &[u32],
    obj: &mut [u32],
    psi_on: &mut [u32],
    c_obj_reg: &mut [u32],
) {
    obj.fill(0);
    psi_on.fill(0);
    c_obj_reg.fill(0);
    let (mut n, mut sum) = (0u64, 0u64);
    for_each_on(g, fg, |x, y| {
        let inside = bits_at(d, x, y).is_some_and(|b| range.contains_bits(b));
        if !inside {
            return;
        }
        set(g, obj, x, y);
        let v = c.get(x, y).and_then(EdgeCell::get);
        if let Some(v) = v {
            set(g, psi_on, x, y);
            sum += u64::from(v.to_bits());
        }
        n += u64::from(match over {
            PsiMean::Region => true,
            PsiMean::OnCells => v.is_some(),
        });
    });
    for_each_on(g, psi_on, |x, y| {
        let keep = c
            .get(x, y)
            .and_then(EdgeCell::get)
            .is_some_and(|v| n * u64::from(v.to_bits()) > sum);
        if keep {
            set(g, c_obj_reg, x, y);
        }
    });
}

/// [`inhibit`](super::inhibit) on bits.
pub(super) fn inhibit(
    d: &ImageView<'_, DisparityCell>,
    g: Geom,
    fg: &mut [u32],
    obj: &[u32],
    region: &[u32],
    mask: &[u32],
    delta: u16,
) -> u32 {
    let mut n = 0;
    for (((f, &o), &r), &m) in fg.iter_mut().zip(obj).zip(region).zip(mask) {
        let off = *f & o & (r | m);
        n += off.count_ones();
        *f &= !off;
    }
    if n == 0 {
        let clear =
            |x: usize, y: usize| bits_at(d, x, y).is_some_and(|b| plane(b).abs_diff(delta) <= 1);
        let stride = g.stride.max(1);
        for (y, row) in fg.chunks_exact_mut(stride).take(g.height).enumerate() {
            for (i, w) in row.iter_mut().enumerate() {
                let mut v = *w;
                while v != 0 {
                    let b = v.trailing_zeros();
                    if clear(i * 32 + b as usize, y) {
                        *w &= !(1 << b);
                        n += 1;
                    }
                    v &= v - 1;
                }
            }
        }
    }
    n
}
