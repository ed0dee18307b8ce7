//! The statistics steps: S, D_fg, C_fg, A^C(d), δ, r, D_ObjReg, ψ, C_ObjReg.
//!
//! Integer only. Disparities are [`Disparity`] bits (1/256 px); means,
//! standard deviations and thresholds carry [`STAT_FRAC_BITS`] fraction bits
//! (1/4096 px), so a threshold is within 1/8192 px of the exact value.

use super::{check_size, Ratio, SegmentError, SegmentParams};
use crate::conspicuity::EdgeCell;
use crate::disparity::DisparityCell;
use crate::fixed::isqrt_round_u64;
use crate::image::{ImageError, ImageView, ImageViewMut};
use core::num::{NonZeroU128, NonZeroU64};

/// Fraction bits of [`SelectedStats`] and [`DisparityRange`] values.
pub const STAT_FRAC_BITS: u32 = 12;

/// Extra fraction bits over the [`Disparity`](crate::disparity::Disparity) bits.
const EXTRA: u32 = STAT_FRAC_BITS - 8;

/// Whole-pixel disparity planes of [`SliceCounts`]: `0..=256`.
pub const PLANES: usize = 257;

/// Mean and standard deviation of the valid disparities of S.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SelectedStats {
    /// Valid (ON) pixels of S.
    pub count: u32,
    /// mean_S, px · 2^[`STAT_FRAC_BITS`].
    pub mean: u32,
    /// σ_S (population), px · 2^[`STAT_FRAC_BITS`].
    pub sigma: u32,
}

/// The open interval of D_fg, px · 2^[`STAT_FRAC_BITS`]: `low < D < high`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Thresholds {
    /// mean_S + 0.1 σ_S.
    pub low: u32,
    /// mean_S + 2 σ_S.
    pub high: u32,
}

/// A closed disparity interval, px · 2^[`STAT_FRAC_BITS`]: `low ≤ D ≤ high`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DisparityRange {
    /// δ − r (may be negative).
    pub low: i64,
    /// δ + r.
    pub high: i64,
}

impl DisparityRange {
    /// True when disparity bits `d` (1/256 px) lie in the range.
    pub fn contains_bits(&self, d: u16) -> bool {
        let q = i64::from(d) << EXTRA;
        self.low <= q && q <= self.high
    }
}

/// `round(x · num / den)` for `den > 0`, ties up.
fn mul_ratio(x: u64, r: Ratio) -> u64 {
    let den = u64::from(r.den.max(1));
    (2 * x * u64::from(r.num) + den) / (2 * den)
}

/// The selected area S of a `width` x `height` map as `(x0, y0, y1)`: S is
/// the columns `x0..width` of the rows `y0..y1`, that is
/// `x > w·left` and `h·top_bottom < y < h·(1 − top_bottom)`, exactly.
pub fn selected_bounds(
    params: &SegmentParams,
    width: usize,
    height: usize,
) -> (usize, usize, usize) {
    let (l, tb) = (params.left_strip, params.top_bottom_strip);
    let (w, h) = (width as u64, height as u64);
    let (ln, ld, tn, td) = (
        u64::from(l.num),
        u64::from(l.den.max(1)),
        u64::from(tb.num),
        u64::from(tb.den.max(1)),
    );
    // x·ld > w·ln  <=>  x >= floor(w·ln / ld) + 1.
    let x0 = w * ln / ld + 1;
    // y·td > h·tn  <=>  y >= floor(h·tn / td) + 1;
    // y·td < h·(td − tn)  <=>  y < ceil(h·(td − tn) / td).
    let y0 = h * tn / td + 1;
    let y1 = (h * (td - tn.min(td))).div_ceil(td);
    let c = |v: u64, max: usize| usize::try_from(v).map_or(max, |v| v.min(max));
    (
        c(x0, width),
        c(y0, height),
        c(y1, height).max(c(y0, height)),
    )
}

/// True when `(x, y)` lies in the selected area S of a `width` x `height`
/// map: `x > w·left` and `h·top_bottom < y < h·(1 − top_bottom)`, exactly.
pub fn in_selected_area(
    params: &SegmentParams,
    width: usize,
    height: usize,
    x: usize,
    y: usize,
) -> bool {
    let (x0, y0, y1) = selected_bounds(params, width, height);
    x >= x0 && x < width && y >= y0 && y < y1
}

/// Writes S: D inside the selected area, OFF outside. Returns its ON count.
///
/// # Errors
/// [`SegmentError::SizeMismatch`].
pub fn selected_area(
    params: &SegmentParams,
    disparity: &ImageView<'_, DisparityCell>,
    s: &mut ImageViewMut<'_, DisparityCell>,
) -> Result<u32, SegmentError> {
    check_size(disparity.size(), s.size())?;
    let (w, h) = disparity.size();
    let mut n = 0;
    for (y, (src, dst)) in disparity.rows().zip(s.rows_mut()).enumerate() {
        for (x, (&d, o)) in src.iter().zip(dst.iter_mut()).enumerate() {
            *o = if in_selected_area(params, w, h, x, y) {
                d
            } else {
                DisparityCell::OFF
            };
            n += u32::from(o.is_on());
        }
    }
    Ok(n)
}

/// mean_S and σ_S over the ON pixels of S (read straight from D); `None`
/// when S holds no valid disparity.
pub fn selected_stats(
    params: &SegmentParams,
    disparity: &ImageView<'_, DisparityCell>,
) -> Option<SelectedStats> {
    let (w, h) = disparity.size();
    let (x0, y0, y1) = selected_bounds(params, w, h);
    let (mut n, mut sum, mut sum2, mut off) = (0u64, 0u64, 0u64, 0u64);
    for row in disparity.rows().take(y1).skip(y0) {
        // Every cell is summed, OFF (u16::MAX) too, and the OFF cells
        // counted, then taken out: no branch per cell. A row is under 2^13
        // cells of at most 2^16 − 1: no overflow.
        let cells = row.get(x0..).unwrap_or(&[]);
        let (mut rsum, mut roff) = (0u32, 0u32);
        for c in cells {
            let b = u32::from(c.raw().to_bits());
            rsum += b;
            roff += (b + 1) >> 16;
            sum2 += u64::from(b) * u64::from(b);
        }
        let len = u32::try_from(cells.len()).unwrap_or(u32::MAX);
        n += u64::from(len - roff);
        sum += u64::from(rsum - roff * u32::from(u16::MAX));
        off += u64::from(roff);
    }
    let max = u64::from(u16::MAX);
    sum2 -= off * max * max;
    // At most 2^26 pixels, so `2n` and `2n²` are 0 only when `n` is.
    let two_n = NonZeroU64::new(2 * n)?;
    let mean = ((sum << (EXTRA + 1)) + n) / two_n;
    // var (bits²) = (n·Σb² − (Σb)²) / n²; in output units × 2^(2·EXTRA).
    let num = u128::from(n) * u128::from(sum2) - u128::from(sum) * u128::from(sum);
    let n2 = u128::from(n) * u128::from(n);
    let var = ((num << (2 * EXTRA + 1)) + n2) / NonZeroU128::new(2 * n2)?;
    let sigma = isqrt_round_u64(u64::try_from(var).unwrap_or(u64::MAX));
    Some(SelectedStats {
        count: u32::try_from(n).unwrap_or(u32::MAX),
        mean: u32::try_from(mean).unwrap_or(u32::MAX),
        sigma: u32::try_from(sigma).unwrap_or(u32::MAX),
    })
}

/// The D_fg interval: `mean + fg_low·σ < D < mean + fg_high·σ`.
pub fn thresholds(params: &SegmentParams, stats: &SelectedStats) -> Thresholds {
    let (m, s) = (u64::from(stats.mean), u64::from(stats.sigma));
    let cap = |v: u64| u32::try_from(v).unwrap_or(u32::MAX);
    Thresholds {
        low: cap(m + mul_ratio(s, params.fg_low)),
        high: cap(m + mul_ratio(s, params.fg_high)),
    }
}

/// Writes D_fg: the disparities of S strictly inside `t`, else OFF. Returns
/// the ON count.
///
/// # Errors
/// [`SegmentError::SizeMismatch`].
pub fn foreground(
    params: &SegmentParams,
    disparity: &ImageView<'_, DisparityCell>,
    t: &Thresholds,
    d_fg: &mut ImageViewMut<'_, DisparityCell>,
) -> Result<u32, SegmentError> {
    check_size(disparity.size(), d_fg.size())?;
    let (w, h) = disparity.size();
    let mut n = 0;
    for (y, (src, dst)) in disparity.rows().zip(d_fg.rows_mut()).enumerate() {
        for (x, (&d, o)) in src.iter().zip(dst.iter_mut()).enumerate() {
            let keep = d.get().is_some_and(|v| {
                let q = u32::from(v.to_bits()) << EXTRA;
                t.low < q && q < t.high
            }) && in_selected_area(params, w, h, x, y);
            *o = if keep { d } else { DisparityCell::OFF };
            n += u32::from(keep);
        }
    }
    Ok(n)
}

/// Background inhibition by rows
/// ([`SegmentParams::row_background`](super::SegmentParams::row_background)):
/// adds to D_fg the disparities of S under `t.high` that are more than
/// `band` bits nearer than their row's estimate (`rows`, as
/// [`fit_ground`](super::fit_ground) writes it: the bits + 1, 0 for none).
/// Returns the count added.
///
/// # Errors
/// [`SegmentError::SizeMismatch`], or [`SegmentError::Image`] for `rows`
/// shorter than the height.
pub fn foreground_rows(
    params: &SegmentParams,
    disparity: &ImageView<'_, DisparityCell>,
    t: &Thresholds,
    rows: &[u32],
    band: u16,
    d_fg: &mut ImageViewMut<'_, DisparityCell>,
) -> Result<u32, SegmentError> {
    check_size(disparity.size(), d_fg.size())?;
    let (w, h) = disparity.size();
    if rows.len() < h {
        return Err(SegmentError::Image(ImageError::BufferTooSmall {
            needed: super::ground_rows_len(h),
            got: rows.len(),
        }));
    }
    let mut n = 0;
    for (y, ((src, dst), &r)) in disparity.rows().zip(d_fg.rows_mut()).zip(rows).enumerate() {
        for (x, (&d, o)) in src.iter().zip(dst.iter_mut()).enumerate() {
            let add = !o.is_on()
                && r > 0
                && d.get().is_some_and(|v| {
                    let b = u32::from(v.to_bits());
                    b >= r + u32::from(band) && (b << EXTRA) < t.high
                })
                && in_selected_area(params, w, h, x, y);
            if add {
                *o = d;
                n += 1;
            }
        }
    }
    Ok(n)
}

/// `dst = c` where `mask` is ON, else OFF; returns the ON count of `dst`.
/// This is C_fg (mask D_fg) and ψ (mask D_ObjReg).
fn masked(
    c: &ImageView<'_, EdgeCell>,
    mask: &ImageView<'_, DisparityCell>,
    dst: &mut ImageViewMut<'_, EdgeCell>,
) -> Result<u32, SegmentError> {
    check_size(c.size(), mask.size())?;
    check_size(c.size(), dst.size())?;
    let mut n = 0;
    for ((c, m), o) in c.rows().zip(mask.rows()).zip(dst.rows_mut()) {
        for ((&c, &m), o) in c.iter().zip(m).zip(o.iter_mut()) {
            *o = if m.is_on() { c } else { EdgeCell::OFF };
            n += u32::from(o.is_on());
        }
    }
    Ok(n)
}

/// Writes C_fg: C where D_fg is ON. Returns its ON count.
///
/// # Errors
/// [`SegmentError::SizeMismatch`].
pub fn foreground_conspicuity(
    c: &ImageView<'_, EdgeCell>,
    d_fg: &ImageView<'_, DisparityCell>,
    c_fg: &mut ImageViewMut<'_, EdgeCell>,
) -> Result<u32, SegmentError> {
    masked(c, d_fg, c_fg)
}

/// ON C_fg cells per whole-pixel plane (D_fg rounded to nearest, ties
/// up), and the range of planes D_fg covers.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SliceCounts {
    /// Cells per plane.
    pub counts: [u32; PLANES],
    /// D_fg min and max, whole px; `None` when D_fg is all OFF.
    pub planes: Option<(u16, u16)>,
}

/// `round(d)` in whole pixels, ties up.
pub fn plane(d: u16) -> u16 {
    ((u32::from(d) + 128) >> 8) as u16
}

/// Counts the ON C_fg cells of every D_fg plane.
///
/// # Errors
/// [`SegmentError::SizeMismatch`].
pub fn slice_counts(
    c_fg: &ImageView<'_, EdgeCell>,
    d_fg: &ImageView<'_, DisparityCell>,
) -> Result<SliceCounts, SegmentError> {
    check_size(c_fg.size(), d_fg.size())?;
    let mut out = SliceCounts {
        counts: [0; PLANES],
        planes: None,
    };
    for (c, d) in c_fg.rows().zip(d_fg.rows()) {
        for (c, d) in c.iter().zip(d) {
            let Some(d) = d.get() else { continue };
            let p = plane(d.to_bits());
            out.planes = Some(out.planes.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))));
            if c.is_on() {
                if let Some(k) = out.counts.get_mut(usize::from(p)) {
                    *k += 1;
                }
            }
        }
    }
    Ok(out)
}

/// The chosen disparity slice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Slice {
    /// δ, whole px.
    pub delta: u16,
    /// A^C(δ).
    pub cells: u32,
    /// A^C(δ) · δ^A, saturated at `u64::MAX`: the saliency score.
    pub score: u64,
}

/// A^C(d): the counts of planes `d−1..=d+1` that lie in the D_fg range
/// (so 2 planes at either end).
pub fn slice_cells(counts: &SliceCounts, d: u16) -> u32 {
    let Some((lo, hi)) = counts.planes else {
        return 0;
    };
    (d.saturating_sub(1).max(lo)..=d.saturating_add(1).min(hi))
        .filter_map(|i| counts.counts.get(usize::from(i)))
        .sum()
}

/// δ = argmax A^C(d)·d^A over the D_fg planes; the nearest (largest d) wins
/// ties. `None` when every score is zero (no foreground edge).
pub fn select_slice(counts: &SliceCounts, exponent: u8) -> Option<Slice> {
    let (lo, hi) = counts.planes?;
    let mut best: Option<Slice> = None;
    for d in lo..=hi {
        let cells = slice_cells(counts, d);
        let w = u128::from(d)
            .checked_pow(u32::from(exponent))
            .unwrap_or(u128::MAX);
        let score = u64::try_from(u128::from(cells).saturating_mul(w)).unwrap_or(u64::MAX);
        if score > 0 && best.is_none_or(|b| score >= b.score) {
            best = Some(Slice {
                delta: d,
                cells,
                score,
            });
        }
    }
    best
}

/// r = σ_S · range (the paper's σ_S / 2.5), at least
/// [`SegmentParams::min_slice_radius`], px · 2^[`STAT_FRAC_BITS`].
pub fn slice_radius(params: &SegmentParams, stats: &SelectedStats) -> u32 {
    let r = u32::try_from(mul_ratio(u64::from(stats.sigma), params.range)).unwrap_or(u32::MAX);
    // Disparity bits are 1/256 px.
    r.max(u32::from(params.min_slice_radius) << (STAT_FRAC_BITS - 8))
}

/// The object slice `[δ − r, δ + r]`.
pub fn slice_range(params: &SegmentParams, stats: &SelectedStats, delta: u16) -> DisparityRange {
    let c = i64::from(delta) << STAT_FRAC_BITS;
    let r = i64::from(slice_radius(params, stats));
    DisparityRange {
        low: c - r,
        high: c + r,
    }
}

/// Writes D_ObjReg: D_fg inside `range`, else OFF. Returns the ON count.
///
/// # Errors
/// [`SegmentError::SizeMismatch`].
pub fn object_region(
    d_fg: &ImageView<'_, DisparityCell>,
    range: &DisparityRange,
    d_obj_reg: &mut ImageViewMut<'_, DisparityCell>,
) -> Result<u32, SegmentError> {
    check_size(d_fg.size(), d_obj_reg.size())?;
    let mut n = 0;
    for (s, o) in d_fg.rows().zip(d_obj_reg.rows_mut()) {
        for (&d, o) in s.iter().zip(o.iter_mut()) {
            let keep = d.get().is_some_and(|v| range.contains_bits(v.to_bits()));
            *o = if keep { d } else { DisparityCell::OFF };
            n += u32::from(keep);
        }
    }
    Ok(n)
}

/// Writes ψ: C where D_ObjReg is ON. Returns its ON count.
///
/// # Errors
/// [`SegmentError::SizeMismatch`].
pub fn object_conspicuity(
    c: &ImageView<'_, EdgeCell>,
    d_obj_reg: &ImageView<'_, DisparityCell>,
    psi: &mut ImageViewMut<'_, EdgeCell>,
) -> Result<u32, SegmentError> {
    masked(c, d_obj_reg, psi)
}

/// Which cells the mean ψ̄ of C_ObjReg = (ψ > ψ̄) is taken over.
///
/// The paper defines ψ as C inside D_ObjReg and OFF elsewhere, and keeps the
/// "active-above-average" cells without saying whether inactive (OFF) cells
/// inside the object region count in the average.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PsiMean {
    /// Over every cell of the object region (D_ObjReg ON), an OFF ψ cell
    /// counting as 0: the mean activity of the region's cell population.
    /// The default; see `docs/SEGMENT.md` for the measurements behind it.
    #[default]
    Region,
    /// Over the ON ψ cells only. On an object whose only edges are its
    /// outline this drops about half the outline.
    OnCells,
}

/// Writes C_ObjReg: ψ where ψ is above its mean ψ̄ (exact: `n·ψ > Σψ`,
/// `n` and `Σψ` as `over` says). Returns the ON count.
///
/// # Errors
/// [`SegmentError::SizeMismatch`].
pub fn above_mean(
    over: PsiMean,
    psi: &ImageView<'_, EdgeCell>,
    d_obj_reg: &ImageView<'_, DisparityCell>,
    c_obj_reg: &mut ImageViewMut<'_, EdgeCell>,
) -> Result<u32, SegmentError> {
    check_size(psi.size(), c_obj_reg.size())?;
    check_size(psi.size(), d_obj_reg.size())?;
    let (mut n, mut sum) = (0u64, 0u64);
    for (c, d) in psi.pixels().zip(d_obj_reg.pixels()) {
        let counted = match over {
            PsiMean::Region => d.is_on(),
            PsiMean::OnCells => c.is_on(),
        };
        n += u64::from(counted);
        sum += c.get().map_or(0, |v| u64::from(v.to_bits()));
    }
    let mut on = 0;
    for (s, o) in psi.rows().zip(c_obj_reg.rows_mut()) {
        for (&c, o) in s.iter().zip(o.iter_mut()) {
            let keep = c.get().is_some_and(|v| n * u64::from(v.to_bits()) > sum);
            *o = if keep { c } else { EdgeCell::OFF };
            on += u32::from(keep);
        }
    }
    Ok(on)
}
