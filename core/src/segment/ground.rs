//! Ground-plane inhibition: the v-disparity fit of Labayrade et al. (2002).
//!
//! A ground plane seen by a level stereo camera has, on each image row, one
//! disparity, growing linearly towards the bottom: `d_g(y) = a·y + b`.
//! [`fit_ground`] takes each row's dominant disparity (the mean of the
//! cells within a plane of the row's most common whole-pixel plane, when
//! at least a quarter of the row agrees), finds the line through most of
//! them by a Hough vote over slopes from [`MIN_SLOPE`] to [`MAX_SLOPE`]
//! (1/128 px per row apart; intercepts in half pixels), in which a row
//! within 1/64 px of the row above (a frontal wall) does not vote, and
//! refines it by least squares over the rows near it (within 1/2 px, then
//! twice within 1/4 px). A line is a ground only when at least a quarter
//! of the rows lie on it.
//! [`inhibit_ground`] then turns OFF the D_fg cells no nearer than
//! `d_g(y) + band` ([`SegmentParams::ground_band`](super::SegmentParams)):
//! the ground, its texture and what lies flat on it. Objects standing on
//! the ground rise above the line.
//!
//! Integer only: disparities are [`Disparity`](crate::disparity::Disparity)
//! bits (1/256 px), the line is Q16 in those bits.

use super::stats::{plane, PLANES};
use super::SegmentError;
use crate::disparity::DisparityCell;
use crate::image::{ImageError, ImageView, ImageViewMut};

/// Least slope of a ground line, disparity bits per row (1/32 px per row):
/// a flatter line is a wall or an object face, not a ground.
pub const MIN_SLOPE: i64 = 8;
/// Largest slope searched, bits per row (1/2 px per row).
pub const MAX_SLOPE: i64 = 128;
/// Step between the slopes of the vote, bits per row (1/128 px per row).
const SLOPE_STEP: usize = 2;
/// Bins of the vote's intercepts: half pixels over the planes.
const BINS: usize = 2 * PLANES;
/// The refinements after the vote: each a least-squares fit over the rows
/// whose disparity is within this many bits of the line before it (1/2
/// px around the vote's coarse line, then 1/4 px).
const REFINE: [i64; 3] = [128, 64, 64];

/// The fitted ground: `d_g(y) = (slope·y + offset) / 2^16` disparity bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GroundLine {
    /// Bits per row, Q16.
    pub slope: i64,
    /// Bits at row 0, Q16.
    pub offset: i64,
    /// Rows that lie on the line.
    pub rows: u32,
}

impl GroundLine {
    /// `d_g(y)`, disparity bits (may be negative above the horizon).
    pub fn at(&self, y: usize) -> i64 {
        let y = i64::try_from(y).unwrap_or(i64::MAX);
        self.slope.saturating_mul(y).saturating_add(self.offset) >> 16
    }
}

/// `u32` words of the row buffer [`fit_ground`] takes: one per row.
pub const fn ground_rows_len(height: usize) -> usize {
    height
}

/// Per whole-pixel plane of a row: its cells and the sum of their bits.
struct RowPlanes {
    count: [u16; PLANES],
    sum: [u32; PLANES],
}

impl RowPlanes {
    const fn new() -> Self {
        Self {
            count: [0; PLANES],
            sum: [0; PLANES],
        }
    }
}

/// One row's dominant disparity, bits, when at least a quarter of its
/// cells lie within a plane of its most common whole-pixel plane.
/// `planes` is all zero on entry and is left so.
fn row_disparity(row: &[DisparityCell], planes: &mut RowPlanes) -> Option<u32> {
    // Each plane's count and sum of bits in one pass over the row, and
    // the highest plane it touches: only the planes up to it are searched
    // and cleared after. The counts saturate at 65,535 and the sums are
    // `u32`: exact for rows of up to 65,535 cells.
    let mut hi = 0;
    for c in row {
        let Some(d) = c.get() else {
            continue;
        };
        let b = d.to_bits();
        let p = usize::from(plane(b));
        if let (Some(k), Some(s)) = (planes.count.get_mut(p), planes.sum.get_mut(p)) {
            *k = k.saturating_add(1);
            *s += u32::from(b);
            hi = hi.max(p);
        }
    }
    // The mode: the most common plane, the lowest on a tie (a row
    // without an estimate has every count 0, and no disparity below).
    let (mut top, mut mode) = (0u16, 0);
    for (p, &k) in planes.count.iter().enumerate().take(hi + 1) {
        if k > top {
            (top, mode) = (k, p);
        }
    }
    // The planes within one of the mode.
    let near = mode.saturating_sub(1)..=(mode + 1).min(PLANES - 1);
    let n: u32 = planes
        .count
        .get(near.clone())
        .unwrap_or(&[])
        .iter()
        .map(|&k| u32::from(k))
        .sum();
    let sum: u32 = planes.sum.get(near).unwrap_or(&[]).iter().sum();
    if let (Some(k), Some(s)) = (planes.count.get_mut(..=hi), planes.sum.get_mut(..=hi)) {
        k.fill(0);
        s.fill(0);
    }
    let need = u32::try_from(row.len().div_ceil(4))
        .unwrap_or(u32::MAX)
        .max(1);
    if n < need {
        return None;
    }
    (2 * sum + n).checked_div(2 * n)
}

/// Least squares of `d = a·y + b` over the rows within `band` bits of
/// `line`.
fn least_squares(rows: &[u32], line: &GroundLine, band: i64) -> Option<GroundLine> {
    // The sums in i64 (no 128-bit multiply per row): with y < 2^16 rows
    // and d < 2^16 bits, Σy² < 2^48 and Σy·d < 2^48; the checks only turn
    // an absurd frame into "no line". The products of sums take i128.
    let (mut n, mut sy, mut sd, mut syy, mut syd) = (0i64, 0i64, 0i64, 0i64, 0i64);
    for (y, &r) in rows.iter().enumerate() {
        let Some(d) = r.checked_sub(1) else { continue };
        let d = i64::from(d);
        if (d - line.at(y)).abs() > band {
            continue;
        }
        let y = i64::try_from(y).ok()?;
        n += 1;
        sy += y;
        sd += d;
        syy = syy.checked_add(y.checked_mul(y)?)?;
        syd = syd.checked_add(y.checked_mul(d)?)?;
    }
    let [n, sy, sd, syy, syd] = [n, sy, sd, syy, syd].map(i128::from);
    let den = n * syy - sy * sy;
    let slope = ((n * syd - sy * sd) << 16).checked_div(den)?;
    let offset = ((sd << 16) - slope * sy).checked_div(n)?;
    Some(GroundLine {
        slope: i64::try_from(slope).ok()?,
        offset: i64::try_from(offset).ok()?,
        rows: u32::try_from(n).ok()?,
    })
}

/// Fits the ground line of `disparity` (see the module docs); `None` when
/// no line of a ground's slope holds a quarter of the rows. `rows` needs
/// [`ground_rows_len`] entries and is overwritten.
///
/// # Errors
/// [`SegmentError::Image`] when `rows` is shorter than the height.
pub fn fit_ground(
    disparity: &ImageView<'_, DisparityCell>,
    rows: &mut [u32],
) -> Result<Option<GroundLine>, SegmentError> {
    let (_, h) = disparity.size();
    let got = rows.len();
    let rows = rows
        .get_mut(..h)
        .ok_or(SegmentError::Image(ImageError::BufferTooSmall {
            needed: ground_rows_len(h),
            got,
        }))?;
    let mut planes = RowPlanes::new();
    for (r, row) in rows.iter_mut().zip(disparity.rows()) {
        // 0: no estimate; else the disparity bits + 1.
        *r = row_disparity(row, &mut planes).map_or(0, |d| d + 1);
    }
    // Hough vote: per slope, the rows' intercepts at the bottom row in
    // half pixels; the best (slope, two neighbouring bins) collects the
    // most rows.
    let mut best: Option<(u32, i64, i64)> = None;
    let mut votes = [0u16; BINS];
    let bottom = i64::try_from(h).unwrap_or(i64::MAX) - 1;
    for slope in (MIN_SLOPE..=MAX_SLOPE).step_by(SLOPE_STEP) {
        // Intercepts at the bottom row (never below the row's own
        // disparity: the slopes are positive). Only the bins between the
        // lowest and the highest vote are cleared and searched: the
        // windows outside hold no vote and cannot lead.
        let (mut lo, mut hi) = (BINS, 0);
        let mut above = 0u32;
        for (y, &r) in rows.iter().enumerate() {
            // A row as far as the one above it is a frontal surface (a
            // wall): it does not vote.
            let flat = above != 0 && i64::from(r.abs_diff(above)) < MIN_SLOPE / 2;
            above = r;
            let Some(d) = r.checked_sub(1).filter(|_| !flat) else {
                continue;
            };
            let y = i64::try_from(y).unwrap_or(i64::MAX);
            let at_bottom = i64::from(d) + slope * (bottom - y);
            let Some(bin) = usize::try_from((at_bottom + 64) >> 7).ok() else {
                continue;
            };
            if let Some(v) = votes.get_mut(bin) {
                *v = v.saturating_add(1);
                (lo, hi) = (lo.min(bin), hi.max(bin));
            }
        }
        if best.is_none() {
            // The first window leads until a fuller one comes.
            let n = votes.iter().take(2).map(|&v| u32::from(v)).sum();
            best = Some((n, slope, 64));
        }
        if lo > hi {
            continue;
        }
        let first = lo.saturating_sub(1);
        let span = votes.get_mut(first..=hi).unwrap_or(&mut []);
        for (i, w) in span.windows(2).enumerate() {
            let n: u32 = w.iter().map(|&v| u32::from(v)).sum();
            if best.is_none_or(|(m, _, _)| n > m) {
                // Between the two bins, in bits.
                let b = i64::try_from(2 * (first + i) + 1).unwrap_or(0) * 64;
                best = Some((n, slope, b));
            }
        }
        span.fill(0);
    }
    let Some((_, slope, b)) = best else {
        return Ok(None);
    };
    let mut line = GroundLine {
        slope: slope << 16,
        offset: (b - slope * bottom) << 16,
        rows: 0,
    };
    for band in REFINE {
        match least_squares(rows, &line, band) {
            Some(l) => line = l,
            None => return Ok(None),
        }
    }
    let quarter = u32::try_from(h.div_ceil(4)).unwrap_or(u32::MAX).max(2);
    Ok((line.rows >= quarter && line.slope >= MIN_SLOPE << 16).then_some(line))
}

/// Turns OFF the D_fg cells whose disparity is at most `d_g(y) + band`
/// bits. Returns the cells turned OFF.
///
/// # Errors
/// [`SegmentError::SizeMismatch`].
pub fn inhibit_ground(
    line: &GroundLine,
    band: u16,
    d_fg: &mut ImageViewMut<'_, DisparityCell>,
) -> Result<u32, SegmentError> {
    let mut n = 0;
    for (y, row) in d_fg.rows_mut().enumerate() {
        let top = line.at(y).saturating_add(i64::from(band));
        for d in row.iter_mut() {
            if d.get().is_some_and(|v| i64::from(v.to_bits()) <= top) {
                *d = DisparityCell::OFF;
                n += 1;
            }
        }
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::disparity::Disparity;

    fn cells(px: &[u16]) -> [DisparityCell; 8] {
        core::array::from_fn(|i| {
            px.get(i).map_or(DisparityCell::OFF, |&p| {
                DisparityCell::on(Disparity::from_bits(p * 256)).unwrap_or(DisparityCell::OFF)
            })
        })
    }

    #[test]
    fn a_row_takes_the_most_common_plane_and_the_lower_on_a_tie() {
        let mut hist = RowPlanes::new();
        // Planes 9 and 5 twice each, then 30: the tie goes to 5 although 9
        // reached the count first; 5's neighbours within a plane (4, 6)
        // join its mean.
        let row = cells(&[9, 9, 5, 30, 5, 6, 20, 12]);
        assert_eq!(
            row_disparity(&row, &mut hist),
            Some(((5 + 5 + 6) * 256 + 1) / 3)
        );
        // 12 three times leads.
        let row = cells(&[9, 9, 12, 12, 5, 12, 20, 3]);
        assert_eq!(row_disparity(&row, &mut hist), Some(12 * 256));
        // Under a quarter of the row agrees: no disparity.
        let row = cells(&[1, 9, 20, 30]);
        assert_eq!(row_disparity(&row, &mut hist), None);
        // Each row counts afresh: the rows before left nothing behind
        // (9 and 12 led them; here 20 does, alone).
        let row = cells(&[20, 20, 9, 12]);
        assert_eq!(row_disparity(&row, &mut hist), Some(20 * 256));
        assert!(hist.count.iter().all(|&k| k == 0) && hist.sum.iter().all(|&s| s == 0));
        // The top plane (256: bits from 65,408 to 65,534) and the one below it.
        let top = |bits: u16| DisparityCell::on(Disparity::from_bits(bits)).unwrap();
        let mut row = [DisparityCell::OFF; 8];
        row[..3].copy_from_slice(&[top(65_534), top(65_500), top(255 * 256)]);
        assert_eq!(
            row_disparity(&row, &mut hist),
            Some((2 * (65_534 + 65_500 + 255 * 256) + 3) / 6)
        );
    }
}
