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

/// D_fg as bits: valid D inside S with `low < D < high`, or `D < high`
/// and nearer than the row's background by the band
/// ([`foreground_rows`](super::foreground_rows)), and, with a ground line,
/// `D > d_g(y) + band` ([`inhibit_ground`](super::inhibit_ground)). Returns
/// the count.
pub(super) fn foreground(
    params: &SegmentParams,
    d: &ImageView<'_, DisparityCell>,
    t: &Thresholds,
    ground: Option<(&GroundLine, u16)>,
    rows: Option<(&[u32], u16)>,
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
    let mut n = 0;
    let cells = d.rows().zip(fg.chunks_exact_mut(g.stride.max(1)));
    for (y, (row, out)) in cells.enumerate().take(y1).skip(y0) {
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
        let span = hi.saturating_sub(lo);
        for (i, (cells, o)) in row.chunks(32).zip(out.iter_mut()).enumerate() {
            let mut word = 0u32;
            for (b, c) in cells.iter().enumerate() {
                let raw = c
                    .get()
                    .map_or(u32::from(u16::MAX), |v| u32::from(v.to_bits()));
                word |= u32::from(raw.wrapping_sub(lo) < span) << b;
            }
            // Columns left of S.
            let first = i * 32;
            if x0 > first {
                word &= u32::MAX.checked_shl((x0 - first) as u32).unwrap_or(0);
            }
            *o = word;
            n += word.count_ones();
        }
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
