//! Holes by colour: a mask's interior that shows what is behind the
//! object (a ring's hole) taken out of the mask.
//!
//! Figure-ground fills every mask's holes: the stereo's map inside a
//! small hole is the object's own disparity (its support spans the hole's
//! edges), and a hole filled by the conspicuity contour is part of the
//! object. A ring then has a disc's shape vector and is named a circle
//! (docs/CHOICES.md, "Holes by colour"). The left image still shows the
//! hole: what is seen through it has the colour of what surrounds the
//! object. So, for a mask `M`:
//!
//! 1. the *inside* is `M` eroded by [`Holes::band`] square steps; the
//!    *band*, `M` less its inside, has the object's colour;
//! 2. the *ring* is `M` dilated by [`Holes::gap`] + [`Holes::ring`] square
//!    steps less `M` dilated by [`Holes::gap`]: the colour around it;
//! 3. a cell of the inside is a hole candidate when its squared RGB
//!    distance to the ring's mean is less than half its distance to the
//!    band's mean (the object's colour is a mix of object and background
//!    at the outline, so the margin keeps a solid object's inside whole);
//! 4. the candidates are opened by [`Holes::opening`] square steps (a
//!    texture's speck is no hole); each 4-connected component of them
//!    that covers at least [`Holes::min_area`] of `M` is a hole and
//!    leaves `M`.
//!
//! An empty inside, band or ring leaves `M` as it is. The means are kept
//! to 1/16 of a level, `m = ⌊(16·S + n/2) / n⌋` per channel for `n`
//! cells of colour sum `S`, and a cell of colour `c` is decided on
//! `Σ (16·c − m)²` in 32-bit integers (at most 3·4080², no overflow): a
//! few instructions a cell on the board, and the same integers in the
//! reference.
//!
//! The hole by disparity ([`open_depth_hole`], [`DepthHole`]) takes out
//! the hole the colour cannot see, from the disparity map, after the band
//! relabelling.

use super::bits;
use super::buffers::SegmentBuffers;
use super::label::Connectivity;
use super::morph::Disk;
use super::pipeline::{BoundingBox, Detection};
use super::refine::{each, inside_and_ring, read, rgb_row, two_sums};
use super::stats::STAT_FRAC_BITS;
use super::{Ratio, SegmentError};
use crate::disparity::DisparityCell;
use crate::image::{ImageView, RgbRows};

/// Settings of the holes by colour
/// ([`DepthPass::holes`](super::DepthPass::holes)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Holes {
    /// Square erosion steps of the mask giving its inside; the band they
    /// take off gives the object's colour (1 to 8).
    pub band: u8,
    /// Square dilation steps of the mask before the ring starts (0 to 8).
    pub gap: u8,
    /// Square dilation steps of the ring, whose colour is the
    /// surroundings' (1 to 8).
    pub ring: u8,
    /// Square opening steps of the hole candidates (0 to 4).
    pub opening: u8,
    /// Least area of a hole, a fraction of the mask's area (at most 1).
    pub min_area: Ratio,
}

impl Holes {
    /// A band of 3 steps, a ring from 1 to 4 steps out, candidates opened
    /// by one step, holes of at least a tenth of the mask
    /// (docs/CHOICES.md, "Holes by colour").
    pub const DEFAULT: Self = Self {
        band: 3,
        gap: 1,
        ring: 3,
        opening: 1,
        min_area: Ratio::new(1, 10),
    };

    /// Checks the settings.
    ///
    /// # Errors
    /// [`SegmentError::BadParams`] naming the field.
    pub fn validate(&self) -> Result<(), SegmentError> {
        if !(1..=8).contains(&self.band) {
            return Err(SegmentError::BadParams("depth_pass.holes.band"));
        }
        if self.gap > 8 {
            return Err(SegmentError::BadParams("depth_pass.holes.gap"));
        }
        if !(1..=8).contains(&self.ring) {
            return Err(SegmentError::BadParams("depth_pass.holes.ring"));
        }
        if self.opening > 4 {
            return Err(SegmentError::BadParams("depth_pass.holes.opening"));
        }
        if self.min_area.den == 0 || self.min_area.num > self.min_area.den {
            return Err(SegmentError::BadParams("depth_pass.holes.min_area"));
        }
        Ok(())
    }
}

/// `Σ (16·c − m)²` over the channels: 256 times the squared distance of
/// `c` to the mean `m` (1/16 of a level).
fn dist_q4(c: [i64; 3], m: [i32; 3]) -> u32 {
    c.iter()
        .zip(m)
        .map(|(&c, m)| {
            // 16·c ≤ 4080 and m ≤ 4080: at most 3·4080² in all.
            let e = (16 * c as i32 - m).unsigned_abs();
            e * e
        })
        .sum()
}

/// Takes the holes of the mask in `bufs.mask` (module docs) out of it,
/// against `left`, a frame of the maps' size; uses `closed`, `filled`,
/// `region` and `scratch` as scratch, and the labelling's run rows for
/// one row of `left`. Returns the new area when it took a hole, `None`
/// when the mask is as it was.
///
/// # Errors
/// [`SegmentError::LabelCapacity`] from the labelling.
#[inline(never)]
pub(super) fn open_holes<S: RgbRows>(
    holes: &Holes,
    left: &S,
    bufs: &mut SegmentBuffers<'_>,
) -> Result<Option<u32>, SegmentError> {
    let g = bufs.g;
    let area = |m: &[u32]| m.iter().map(|w| w.count_ones()).sum::<u32>();
    let before = area(bufs.mask);
    let morph = |m: &mut [u32], s: &mut [u32], r: &mut [u32], n: u8, erode: bool| {
        bits::morph_n(g, Disk::Square, m, s, r, n, erode);
    };
    // closed = inside; filled = M grown by the gap; region = the ring.
    inside_and_ring(bufs, holes.band, holes.gap, holes.ring);
    if bufs.closed.iter().all(|&w| w == 0) {
        return Ok(None);
    }
    // filled = the band, M less its inside.
    for ((f, m), c) in bufs
        .filled
        .iter_mut()
        .zip(bufs.mask.iter())
        .zip(bufs.closed.iter())
    {
        *f = m & !c;
    }
    let Some(row) = rgb_row(bufs.rows, g.width) else {
        return Ok(None);
    };
    let (object, around) = two_sums(left, row, g, bufs.filled, bufs.region);
    let (Some(object), Some(around)) = (object.mean_q4(), around.mean_q4()) else {
        return Ok(None);
    };
    // The candidates, into `region`: cells of the inside nearer the
    // surroundings' colour by the margin.
    bufs.region.fill(0);
    for y in 0..g.height {
        let span = y * g.stride..(y + 1) * g.stride;
        let (Some(inside), Some(out)) = (bufs.closed.get(span.clone()), bufs.region.get_mut(span))
        else {
            continue;
        };
        let Some(px) = read(left, row, y, &[inside]) else {
            continue;
        };
        each(px, inside, |x, c| {
            if let Some(w) = out
                .get_mut(x / 32)
                .filter(|_| 2 * dist_q4(c, around) < dist_q4(c, object))
            {
                *w |= 1 << (x % 32);
            }
        });
    }
    if bufs.region.iter().all(|&w| w == 0) {
        return Ok(None);
    }
    morph(
        bufs.region,
        bufs.scratch,
        bufs.morph_rows,
        holes.opening,
        true,
    );
    morph(
        bufs.region,
        bufs.scratch,
        bufs.morph_rows,
        holes.opening,
        false,
    );
    for (r, c) in bufs.region.iter_mut().zip(bufs.closed.iter()) {
        *r &= c;
    }
    // The large components are holes.
    let comps = bits::components(g, bufs.region, Connectivity::Four, bufs.rows, bufs.table)?;
    let (num, den) = (u64::from(holes.min_area.num), u64::from(holes.min_area.den));
    let least = |a: u32| u64::from(a) * den >= u64::from(before) * num;
    let taken = comps.select(g, bufs.region, bufs.table, bufs.filled, |_, a| least(a));
    if taken == 0 {
        return Ok(None);
    }
    for (m, f) in bufs.mask.iter_mut().zip(bufs.filled.iter()) {
        *m &= !f;
    }
    Ok(Some(before.saturating_sub(taken)))
}

#[cfg(test)]
mod tests {
    use super::super::refine::Sum;
    use super::dist_q4;

    #[test]
    fn means_round_half_up_to_a_sixteenth() {
        let mut s = Sum::default();
        for c in [[1, 2, 0], [0, 0, 0], [0, 0, 1]] {
            s.add(c);
        }
        // 16/3 = 5.33 → 5, 32/3 = 10.67 → 11, 16/3 → 5.
        assert_eq!(s.mean_q4(), Some([5, 11, 5]));
        let mut half = Sum::default();
        half.add([0, 1, 255]);
        half.add([0, 0, 255]);
        // Exact means stay: 16/2 = 8, 16·255 = 4080.
        assert_eq!(half.mean_q4(), Some([0, 8, 4080]));
        let mut odd = Sum::default();
        for c in [[1, 0, 0]; 32] {
            odd.add(c);
        }
        odd.add([0, 0, 0]);
        // 512/33 = 15.52 → 16; floor would give 15.
        assert_eq!(odd.mean_q4(), Some([16, 0, 0]));
        assert_eq!(Sum::default().mean_q4(), None);
    }

    #[test]
    fn distances_are_in_sixteenths_squared() {
        assert_eq!(dist_q4([1, 2, 3], [16, 32, 48]), 0);
        assert_eq!(dist_q4([255, 0, 0], [0, 0, 0]), 4080 * 4080);
        assert_eq!(dist_q4([0, 0, 0], [4080, 4080, 4080]), 3 * 4080 * 4080);
    }
}

/// Settings of the hole by disparity
/// ([`PipelineParams::depth_hole`](crate::pipeline::PipelineParams::depth_hole)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DepthHole {
    /// How far behind the low end of the object's slice a cell's
    /// disparity must be, disparity bits (1/256 px); at most
    /// [`MAX_GROUND_BAND`](super::MAX_GROUND_BAND).
    pub margin: u16,
    /// Square opening steps of the cells behind (0 to 4).
    pub opening: u8,
}

impl DepthHole {
    /// Cells more than 1 px behind the slice, opened by 2 steps
    /// (docs/RECALL.md, "Holes by disparity").
    pub const DEFAULT: Self = Self {
        margin: 256,
        opening: 2,
    };

    /// Checks the settings.
    ///
    /// # Errors
    /// [`SegmentError::BadParams`] naming the field.
    pub fn validate(&self) -> Result<(), SegmentError> {
        if self.margin > super::MAX_GROUND_BAND {
            return Err(SegmentError::BadParams("depth_hole.margin"));
        }
        if self.opening > 4 {
            return Err(SegmentError::BadParams("depth_hole.opening"));
        }
        Ok(())
    }
}

/// The hole by disparity: a ring whose colour is close to what is seen
/// through it keeps no hole by colour ([`Holes`]), and the band
/// relabelling fills every hole, but the disparity map still shows what
/// is behind it. For object `det` (its mask is slot `det.index` of
/// `masks`, bit maps of `bufs`' geometry):
///
/// 1. the cells *behind* are the mask's cells whose disparity is ON and
///    more than [`DepthHole::margin`] under the low end of the object's
///    slice (`det.range`);
/// 2. they are opened by [`DepthHole::opening`] square steps (the
///    stereo's specks inside an object are no hole);
/// 3. when the centre of the object's box, `(x + ⌊w/2⌋, y + ⌊h/2⌋)`, is
///    one of them, their 8-connected component holding it leaves the
///    mask (a ring's hole is at its centre; a cell behind elsewhere is
///    as likely the stereo's error), and the object's area and box
///    follow.
///
/// Returns whether the mask changed. Uses `closed`, `filled`, `region`
/// and `scratch` as scratch. Integer only; the reference
/// (`protogist_host::reference::holes::depth_hole`) takes the same cells
/// (docs/ERROR_BOUNDS.md, bound 0).
///
/// # Errors
/// [`SegmentError::SizeMismatch`] for a map of another size.
pub fn open_depth_hole(
    p: &DepthHole,
    disparity: &ImageView<'_, DisparityCell>,
    det: &mut Detection,
    masks: &mut [u32],
    bufs: &mut SegmentBuffers<'_>,
) -> Result<bool, SegmentError> {
    let g = bufs.g;
    if disparity.size() != (g.width, g.height) {
        return Err(SegmentError::SizeMismatch {
            expected: (g.width, g.height),
            got: disparity.size(),
        });
    }
    let chunk = g.len();
    let Some(slot) = masks.get_mut(det.index * chunk..(det.index + 1) * chunk) else {
        return Ok(false);
    };
    let Some(b) = det.bbox else {
        return Ok(false);
    };
    // Disparity bits (1/256 px) under which a cell is behind.
    let low = (det.range.low >> (STAT_FRAC_BITS - 8)) - i64::from(p.margin);
    bufs.closed.fill(0);
    let mut any = false;
    let behind = &mut *bufs.closed;
    bits::for_each_on(g, slot, |x, y| {
        let d = disparity.get(x, y).and_then(|c| c.get());
        if d.is_some_and(|d| i64::from(d.to_bits()) < low) {
            g.set(behind, x, y, true);
            any = true;
        }
    });
    if !any {
        return Ok(false);
    }
    for erode in [true, false] {
        bits::morph_n(
            g,
            Disk::Square,
            bufs.closed,
            bufs.scratch,
            bufs.morph_rows,
            p.opening,
            erode,
        );
    }
    let (cx, cy) = (b.x + b.width / 2, b.y + b.height / 2);
    if !g.bit(bufs.closed, cx, cy) {
        return Ok(false);
    }
    // The component of the centre: grown a square step at a time within
    // the cells behind, until it stops (at most once per cell).
    let cells: u32 = bufs.closed.iter().map(|w| w.count_ones()).sum();
    bufs.filled.fill(0);
    g.set(bufs.filled, cx, cy, true);
    for _ in 0..cells {
        bits::copy_map(bufs.scratch, bufs.filled);
        bits::square(g, bufs.region, bufs.scratch, 1, false);
        let mut grew = false;
        for ((r, c), f) in bufs
            .region
            .iter_mut()
            .zip(bufs.closed.iter())
            .zip(bufs.filled.iter_mut())
        {
            let next = *r & *c;
            grew |= next != *f;
            *f = next;
        }
        if !grew {
            break;
        }
    }
    for (m, f) in slot.iter_mut().zip(bufs.filled.iter()) {
        *m &= !*f;
    }
    det.area = slot.iter().map(|w| w.count_ones()).sum();
    det.bbox = BoundingBox::of_bits(g, slot);
    Ok(true)
}
