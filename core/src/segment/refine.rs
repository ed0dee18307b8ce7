//! The depth pass's colour refinement: a slice mask's outline moved to
//! where the left image's colour changes.
//!
//! A slice of the stereo's map ([`super::depth`]) finds an object that has
//! no closed contour of conspicuity edges, but its outline is the
//! stereo's: where the disparity steps from the object to what is behind
//! it the map is blurred over a few pixels, OFF or wrong, and the slice
//! loses a band of the object's border (docs/RECALL.md, "The colour
//! refinement"). The colour of an object whose contrast is too low for an
//! edge of C still differs from its surroundings' on average. So, for a
//! mask `M` of the pass:
//!
//! 1. the *core* is `M` eroded by [`Refine::core`] square steps: the cells
//!    surely of the object;
//! 2. the *reach* is `M` dilated by [`Refine::reach`] square steps; the
//!    *ring* is the reach dilated by [`Refine::ring`] more steps, less the
//!    reach: cells surely behind it;
//! 3. the object's colour is the mean RGB of the left image over the
//!    core, the background's the mean over the ring;
//! 4. a cell of the reach off the core joins the object when its colour
//!    is nearer the object's mean than the background's (squared RGB
//!    distance), leaves it when nearer the background's, and keeps its
//!    place in `M` on a tie;
//! 5. the mask is the largest 4-connected component of the result (the
//!    first in raster order on a tie), holes filled.
//!
//! An empty core or ring leaves `M` as it is. The comparison is exact in
//! integers: with `n` cells of colour sum `S`, the distance of colour `c`
//! to the mean is `Σ (n·c − S)² / n²`, and the two distances are compared
//! by cross-multiplying (`u128`, no overflow for any frame of
//! [`MAX_DIM`](crate::image::MAX_DIM)² pixels).

use super::bits;
use super::buffers::SegmentBuffers;
use super::depth::largest_filled;
use super::SegmentError;
use crate::image::{Rgb8, RgbRows};

/// Settings of the colour refinement of the depth pass's masks
/// ([`DepthPass::refine`](super::DepthPass::refine)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Refine {
    /// Square erosion steps of the mask giving its core, whose colour is
    /// the object's (0 to 8).
    pub core: u8,
    /// Square dilation steps of the mask bounding the cells the colour
    /// decides (0 to 8).
    pub reach: u8,
    /// Square dilation steps beyond the reach giving the ring, whose
    /// colour is the background's (1 to 8).
    pub ring: u8,
}

impl Refine {
    /// A core 2 steps in, a reach of 3 steps out and a ring of 3 more
    /// (docs/CHOICES.md, "The colour refinement").
    pub const DEFAULT: Self = Self {
        core: 2,
        reach: 3,
        ring: 3,
    };

    /// Checks the settings.
    ///
    /// # Errors
    /// [`SegmentError::BadParams`] naming the field.
    pub fn validate(&self) -> Result<(), SegmentError> {
        if self.core > 8 {
            return Err(SegmentError::BadParams("depth_pass.refine.core"));
        }
        if self.reach > 8 {
            return Err(SegmentError::BadParams("depth_pass.refine.reach"));
        }
        if !(1..=8).contains(&self.ring) {
            return Err(SegmentError::BadParams("depth_pass.refine.ring"));
        }
        Ok(())
    }
}

/// Row `y` of `frame`, read into `row` over the runs of pixels where one
/// of `maps` (rows `y` of bit maps) has a bit, when one has; the other
/// pixels of `row` are left as they were.
pub(super) fn read<'r, S: RgbRows>(
    frame: &S,
    row: &'r mut [Rgb8],
    y: usize,
    maps: &[&[u32]],
) -> Option<&'r [Rgb8]> {
    let (w, h) = frame.size();
    let row = row.get_mut(..w).filter(|_| y < h)?;
    let words = maps.iter().map(|m| m.len()).max().unwrap_or(0);
    let mut any = false;
    // The start of the run the scan is in, across word boundaries.
    let mut start: Option<usize> = None;
    for i in 0..words {
        let u = maps
            .iter()
            .fold(0u32, |a, m| a | m.get(i).copied().unwrap_or(0));
        let mut pos = 0u32;
        while pos < 32 {
            let rest = u >> pos;
            match start {
                Some(s) => {
                    // The run's ones from `pos`; the shifted-in zeros end it.
                    pos += (!rest).trailing_zeros();
                    if pos >= 32 {
                        break;
                    }
                    frame.rgb_part(y, s..(32 * i + pos as usize).min(w), row);
                    start = None;
                }
                None => {
                    if rest == 0 {
                        break;
                    }
                    pos += rest.trailing_zeros();
                    start = Some(32 * i + pos as usize);
                    any = true;
                }
            }
        }
    }
    if let Some(s) = start {
        frame.rgb_part(y, s..(32 * words).min(w), row);
    }
    any.then_some(&*row)
}

/// Calls `f(x, colour)` for every ON bit `x` of `words` (a row of a bit
/// map) with `row`'s pixel there.
pub(super) fn each(row: &[Rgb8], words: &[u32], mut f: impl FnMut(usize, [i64; 3])) {
    for (i, &word) in words.iter().enumerate() {
        let mut v = word;
        while v != 0 {
            let x = i * 32 + v.trailing_zeros() as usize;
            if let Some(p) = row.get(x) {
                f(x, [i64::from(p.r), i64::from(p.g), i64::from(p.b)]);
            }
            v &= v.wrapping_sub(1);
        }
    }
}

/// One row of `width` pixels in the labelling's run rows (`rows`, at
/// least 8 bytes a column), which a labelling overwrites.
pub(super) fn rgb_row(rows: &mut [u32], width: usize) -> Option<&mut [Rgb8]> {
    bytemuck::try_cast_slice_mut::<u32, u8>(rows)
        .ok()
        .and_then(|b| b.get_mut(..3 * width))
        .and_then(|b| bytemuck::try_cast_slice_mut::<u8, Rgb8>(b).ok())
}

/// A colour sum: cells and the sum of each channel.
#[derive(Clone, Copy, Default)]
pub(super) struct Sum {
    pub(super) n: i64,
    s: [i64; 3],
}

impl Sum {
    pub(super) fn add(&mut self, c: [i64; 3]) {
        self.n += 1;
        for (s, c) in self.s.iter_mut().zip(c) {
            *s += c;
        }
    }

    /// The mean to 1/16 of a level, `⌊(16·S + n/2) / n⌋` per channel;
    /// `None` without cells.
    pub(super) fn mean_q4(&self) -> Option<[i32; 3]> {
        let n = self.n;
        (n > 0).then(|| {
            self.s
                .map(|s| i32::try_from((16 * s + n / 2) / n).unwrap_or(i32::MAX))
        })
    }

    /// `Σ (n·c − S)²`: `n²` times the squared distance of `c` to the mean.
    pub(super) fn scaled_dist(&self, c: [i64; 3]) -> u128 {
        self.s
            .iter()
            .zip(c)
            .map(|(&s, c)| {
                let e = (self.n * c - s).unsigned_abs();
                u128::from(e) * u128::from(e)
            })
            .sum()
    }
}

/// From the mask in `bufs.mask`: `closed` = it eroded by `inner` square
/// steps; `filled` = it dilated by `near`; `region` = `filled` dilated by
/// `ring` more, less `filled`. `scratch` is scratch.
pub(super) fn inside_and_ring(bufs: &mut SegmentBuffers<'_>, inner: u8, near: u8, ring: u8) {
    let g = bufs.g;
    // Each a square of its own size from the mask, in one pass: `near`
    // then `ring` dilations are `near + ring` of them.
    bits::copy_map(bufs.scratch, bufs.mask);
    bits::square(g, bufs.closed, bufs.scratch, inner, true);
    bits::copy_map(bufs.scratch, bufs.mask);
    bits::square(g, bufs.filled, bufs.scratch, near, false);
    bits::copy_map(bufs.scratch, bufs.mask);
    bits::square(
        g,
        bufs.region,
        bufs.scratch,
        near.saturating_add(ring),
        false,
    );
    for (r, f) in bufs.region.iter_mut().zip(bufs.filled.iter()) {
        *r &= !f;
    }
}

/// The colour sums of `left` over the bit maps `a` and `b`, read a row
/// at a time into `row`.
pub(super) fn two_sums<S: RgbRows>(
    left: &S,
    row: &mut [Rgb8],
    g: bits::Geom,
    a: &[u32],
    b: &[u32],
) -> (Sum, Sum) {
    let (mut sa, mut sb) = (Sum::default(), Sum::default());
    for y in 0..g.height {
        let row_of = |m| g.row(m, y).unwrap_or(&[]);
        let (ra, rb) = (row_of(a), row_of(b));
        if let Some(px) = read(left, row, y, &[ra, rb]) {
            each(px, ra, |_, c| sa.add(c));
            each(px, rb, |_, c| sb.add(c));
        }
    }
    (sa, sb)
}

/// Refines the mask in `bufs.mask` (module docs) against `left`, a frame
/// of the maps' size; uses `closed`, `filled`, `region` and `scratch` as
/// scratch, and the labelling's run rows (`rows`, at least 8 bytes a
/// column) for one row of `left`. Returns the new area.
///
/// # Errors
/// [`SegmentError::LabelCapacity`] from the labelling.
#[inline(never)]
pub(super) fn refine_mask<S: RgbRows>(
    refine: &Refine,
    left: &S,
    bufs: &mut SegmentBuffers<'_>,
) -> Result<u32, SegmentError> {
    let g = bufs.g;
    let area = |m: &[u32]| m.iter().map(|w| w.count_ones()).sum::<u32>();
    // closed = core, filled = reach, region = ring.
    inside_and_ring(bufs, refine.core, refine.reach, refine.ring);
    // One row of `left` in the run rows, which the labelling below
    // overwrites.
    let Some(row) = rgb_row(bufs.rows, g.width) else {
        return Ok(area(bufs.mask));
    };
    // The two means.
    let (object, behind) = two_sums(left, row, g, bufs.closed, bufs.region);
    if object.n == 0 || behind.n == 0 {
        return Ok(area(bufs.mask));
    }
    let (no, nb) = (
        u128::from(object.n.unsigned_abs()),
        u128::from(behind.n.unsigned_abs()),
    );
    // The reach's cells off the core, decided into `closed` (the core).
    for (f, c) in bufs.filled.iter_mut().zip(bufs.closed.iter()) {
        *f &= !c;
    }
    for y in 0..g.height {
        let span = y * g.stride..(y + 1) * g.stride;
        let (Some(band), Some(m), Some(out)) = (
            bufs.filled.get(span.clone()),
            bufs.mask.get(span.clone()),
            bufs.closed.get_mut(span),
        ) else {
            continue;
        };
        let Some(px) = read(left, row, y, &[band]) else {
            continue;
        };
        each(px, band, |x, c| {
            let to_object = object.scaled_dist(c) * nb * nb;
            let to_behind = behind.scaled_dist(c) * no * no;
            let was = m.get(x / 32).is_some_and(|w| w >> (x % 32) & 1 == 1);
            let joins = to_object < to_behind || (to_object == to_behind && was);
            if let Some(w) = out.get_mut(x / 32).filter(|_| joins) {
                *w |= 1 << (x % 32);
            }
        });
    }
    // Its largest 4-connected component, holes filled.
    largest_filled(bufs)?;
    Ok(area(bufs.mask))
}
