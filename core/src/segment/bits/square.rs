//! A map less another grown by `n` square dilations (the depth pass's
//! clearance), and a map after `n` square erosions or dilations (the
//! holes' and the refinement's insides and rings): row-wise then
//! column-wise, in one pass each.
//!
//! `n` dilations by the 3x3 square with the outside OFF give, at a pixel,
//! the OR of the map over the (2n + 1)-square around it clipped to the
//! map: a square of squares is a square, and every pixel of a path of
//! single steps between two pixels of the map, inside their bounding box,
//! is in the map. The square is separable: a run of 2n + 1 pixels along
//! the row ([`spread_rows`]), then a run of 2n + 1 rows. Along the row,
//! the run is two one-sided spreads, towards higher then towards lower x,
//! each by doubling (a spread over 0..=c and a shift by k <= c + 1 spread
//! over 0..=c + k): every pixel a spread passes lies between a source
//! pixel and its target, so inside the row, and nothing is lost where
//! the words end.

use super::{extent, Geom};
use crate::segment::SegmentError;

/// The shifts of a one-sided spread over 0..=n by doubling, none over
/// 31, into `ks`; returns them.
fn steps(n: u8, ks: &mut [u32; 16]) -> &[u32] {
    let n = u32::from(n);
    let (mut cover, mut len) = (0u32, 0usize);
    for slot in ks.iter_mut() {
        let k = (cover + 1).min(31).min(n - cover.min(n));
        if k == 0 {
            break;
        }
        *slot = k;
        cover += k;
        len += 1;
    }
    ks.get(..len).unwrap_or(&[])
}

/// One row: the OR of its pixels `x − c ..= x + c`, `c` the sum of `ks`,
/// at `x` (bits past the width of the last word are left for the caller
/// to clear).
fn spread_row(row: &mut [u32], ks: &[u32]) {
    // Towards higher x: bit x gets bit x − k, across words.
    for &k in ks {
        let mut prev = 0u32;
        for w in row.iter_mut() {
            let old = *w;
            *w = old | old << (k % 32) | prev >> ((32 - k) % 32);
            prev = old;
        }
    }
    // Towards lower x: bit x gets bit x + k.
    for &k in ks {
        let mut next = 0u32;
        for w in row.iter_mut().rev() {
            let old = *w;
            *w = old | old >> (k % 32) | next << ((32 - k) % 32);
            next = old;
        }
    }
}

/// Every row of `map`, in place: the OR of its pixels `x − n ..= x + n`
/// at `x`, clipped to the row. Only the words from one word's reach
/// before a row's first word with bits to as far after its last are
/// computed: the others stay 0.
fn spread_rows(g: Geom, map: &mut [u32], n: u8) {
    let mut ks = [0u32; 16];
    let ks = steps(n, &mut ks);
    if ks.is_empty() {
        return;
    }
    let reach = usize::from(n).div_ceil(32);
    for row in g.rows_mut(map).take(g.height) {
        let Some(first) = row.iter().position(|&w| w != 0) else {
            continue;
        };
        let last = row.iter().rposition(|&w| w != 0).unwrap_or(first);
        let end = (last + reach).min(row.len().saturating_sub(1));
        if let Some(words) = row.get_mut(first.saturating_sub(reach)..=end) {
            spread_row(words, ks);
        }
        if let Some(l) = row.last_mut() {
            *l &= g.last;
        }
    }
}

/// Every row of `map` with bits, in place: the AND of its pixels
/// `x − n ..= x + n` at `x`, those outside the row counted ON (the bits
/// past the width are set for the spreads and cleared after). The AND of
/// a row, like the OR, composes by doubling.
fn shrink_rows(g: Geom, map: &mut [u32], n: u8) {
    let mut ks = [0u32; 16];
    let ks = steps(n, &mut ks);
    if ks.is_empty() {
        return;
    }
    for row in g.rows_mut(map).take(g.height) {
        if row.iter().all(|&w| w == 0) {
            continue;
        }
        if let Some(l) = row.last_mut() {
            *l |= !g.last;
        }
        // Towards higher x: bit x keeps bit x − k, ON before the row.
        for &k in ks {
            let mut prev = u32::MAX;
            for w in row.iter_mut() {
                let old = *w;
                *w = old & (old << (k % 32) | prev >> ((32 - k) % 32));
                prev = old;
            }
        }
        // Towards lower x: bit x keeps bit x + k, ON past the row.
        for &k in ks {
            let mut next = u32::MAX;
            for w in row.iter_mut().rev() {
                let old = *w;
                *w = old & (old >> (k % 32) | next << ((32 - k) % 32));
                next = old;
            }
        }
        if let Some(l) = row.last_mut() {
            *l &= g.last;
        }
    }
}

/// `out` = `src` after `n` erosions (`erode`, outside ON) or dilations
/// (outside OFF) by the 3x3 square, what [`morph_n`](super::morph_n)
/// gives, in one pass: the rows, then the columns (module docs; an
/// erosion is the complement's dilation). `src` is overwritten (shrunk
/// or spread along its rows). Only the rows and words the result can
/// reach are computed: an eroded row needs its own bits, a dilated one a
/// row with bits within `n`; the rows spread, no word outside them can
/// get a bit.
pub(in crate::segment) fn square(g: Geom, out: &mut [u32], src: &mut [u32], n: u8, erode: bool) {
    if erode {
        shrink_rows(g, src, n);
        columns::<true>(g, out, src, n);
    } else {
        spread_rows(g, src, n);
        columns::<false>(g, out, src, n);
    }
}

/// `out` row `y` = the AND (`E`) or OR of the rows `y − n ..= y + n` of
/// `src` that exist (those outside are neutral).
fn columns<const E: bool>(g: Geom, out: &mut [u32], src: &[u32], n: u8) {
    let Some((a, b, c0, c1)) = extent(g, src) else {
        out.fill(0);
        return;
    };
    let (s, n) = (g.stride.max(1), usize::from(n));
    let last = g.height.saturating_sub(1);
    let (y0, y1) = if E {
        (a, b)
    } else {
        (a.saturating_sub(n), (b + n).min(last))
    };
    for (y, o) in g.rows_mut(out).take(g.height).enumerate() {
        if y < y0 || y > y1 {
            o.fill(0);
            continue;
        }
        let lo = y.saturating_sub(n);
        let rows = src.get(lo * s..((y + n).min(last) + 1) * s).unwrap_or(&[]);
        for (j, o) in o.iter_mut().enumerate() {
            *o = if j < c0 || j > c1 {
                0
            } else if E {
                rows.iter().skip(j).step_by(s).fold(u32::MAX, |m, &w| m & w)
            } else {
                rows.iter().skip(j).step_by(s).fold(0, |m, &w| m | w)
            };
        }
    }
}

/// The geometry of `width` x `height` bit maps whose shortest buffer has
/// `got` words.
///
/// # Errors
/// [`SegmentError::Image`] for a bad size or too few words.
fn checked(width: usize, height: usize, got: usize) -> Result<Geom, SegmentError> {
    crate::image::buffer_len(width, height, width)?;
    let g = Geom::new(width, height);
    if got < g.len() {
        return Err(crate::image::ImageError::BufferTooSmall {
            needed: g.len(),
            got,
        }
        .into());
    }
    Ok(g)
}

/// `out` = `map` after `n` erosions (`erode`) or dilations by the 3x3
/// square, as [`erode_n`](crate::segment::erode_n) and
/// [`dilate_n`](crate::segment::dilate_n) with
/// [`Disk::Square`](crate::segment::Disk::Square) give them; all are
/// `width` x `height` maps in the layout of
/// [`BitView`](crate::segment::BitView), bits past the width 0; `map` is
/// overwritten. The holes' and the refinement's insides and rings.
///
/// # Errors
/// [`SegmentError::Image`] for a bad size or too few words.
pub fn square_bits(
    out: &mut [u32],
    map: &mut [u32],
    width: usize,
    height: usize,
    n: u8,
    erode: bool,
) -> Result<(), SegmentError> {
    let g = checked(width, height, out.len().min(map.len()))?;
    if let (Some(out), Some(map)) = (out.get_mut(..g.len()), map.get_mut(..g.len())) {
        square(g, out, map, n, erode);
    }
    Ok(())
}

/// `out` = `fg` less `taken` grown by `n` square dilations (module
/// docs); `taken` is overwritten (spread along its rows). The column-wise
/// OR, of the rows `y − n ..= y + n` that exist, is taken only for the
/// words of `fg` with bits.
pub(in crate::segment) fn clear_square(
    g: Geom,
    out: &mut [u32],
    fg: &[u32],
    taken: &mut [u32],
    n: u8,
) {
    spread_rows(g, taken, n);
    let (s, n) = (g.stride.max(1), usize::from(n));
    let last = g.height.saturating_sub(1);
    let rows = g.rows_mut(out).zip(g.rows(fg)).take(g.height);
    for (y, (o, f)) in rows.enumerate() {
        let lo = y.saturating_sub(n);
        let count = (y + n).min(last) + 1 - lo;
        for (j, (o, &f)) in o.iter_mut().zip(f).enumerate() {
            *o = if f == 0 {
                0
            } else {
                let (mut m, mut i) = (0u32, lo * s + j);
                for _ in 0..count {
                    m |= taken.get(i).copied().unwrap_or(0);
                    i += s;
                }
                f & !m
            };
        }
    }
}

/// `out` = `fg` less the map `taken` grown by `n` dilations by the 3x3
/// square (outside OFF, what [`dilate_n`](crate::segment::dilate_n) with
/// [`Disk::Square`](crate::segment::Disk::Square) gives): the depth
/// pass's clearance. All are `width` x `height` maps in the layout of
/// [`BitView`](crate::segment::BitView), bits past the width 0; `taken`
/// is overwritten.
///
/// # Errors
/// [`SegmentError::Image`] for a bad size or too few words.
pub fn clear_square_bits(
    out: &mut [u32],
    fg: &[u32],
    taken: &mut [u32],
    width: usize,
    height: usize,
    n: u8,
) -> Result<(), SegmentError> {
    let g = checked(width, height, out.len().min(fg.len()).min(taken.len()))?;
    let (out, fg) = (out.get_mut(..g.len()), fg.get(..g.len()));
    if let (Some(out), Some(fg), Some(taken)) = (out, fg, taken.get_mut(..g.len())) {
        clear_square(g, out, fg, taken, n);
    }
    Ok(())
}
