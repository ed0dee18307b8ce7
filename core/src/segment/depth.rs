//! The depth pass: the objects the colour edges do not outline, found as
//! slices of the disparity map that stand above their rows' background.
//!
//! The paper's figure-ground needs a closed contour of conspicuity edges
//! C around an object; an object whose colour is close to its
//! surroundings' has none, however plainly it stands in front. After the
//! colour searches ([`segment_into`](super::segment_into)), when they found
//! fewer than K objects:
//!
//! 1. the pass's foreground is every cell of the selected area whose
//!    disparity is at least [`DepthPass::rise`] nearer than its row's
//!    dominant disparity (the rows of the ground fit, `fit_ground`), less
//!    the colour objects' masks grown by [`DepthPass::clearance`] square
//!    dilations (their halo in the stereo's map would otherwise come back
//!    as rings and slivers). The foreground is written with D_fg, in the
//!    same sweep; the dilations are one square, row-wise then column-wise,
//!    the latter only where the foreground has bits
//!    ([`clear_square_bits`](super::clear_square_bits));
//! 2. each search, at most [`DepthPass::searches`]: δ is the whole-pixel
//!    plane with the most foreground cells within one plane of it, its
//!    own counted twice (the lowest on a tie); the slice is the foreground within
//!    [`DepthPass::radius`] of δ; the slice, closed by
//!    [`DepthPass::closing`] square steps, gives its largest 4-connected
//!    component, holes filled, as the mask; the slice grown by one square
//!    step leaves the foreground;
//! 3. with [`DepthPass::refine`], the mask's outline is moved to where the
//!    left image's colour changes ([`Refine`], module `refine`);
//! 4. a mask is an object when it is one for the colour searches
//!    ([`SegmentParams::is_object`]), covers at least
//!    [`DepthPass::min_area`] of the frame and overlaps no colour object;
//! 5. with [`DepthPass::holes`], once every object is found, each mask,
//!    the colour searches' too, loses its holes by colour ([`Holes`],
//!    module `holes`), and its area with them.
//!
//! No contour is needed: the slice's own component is the mask. The
//! stereo's halo around a near object is where the clearance takes it
//! out; what remains in front of its rows is an object or a part of one
//! (docs/CHOICES.md, "The depth pass").

use super::bits::{self, for_each_on, Geom};
use super::buffers::SegmentBuffers;
use super::holes::{open_holes, Holes};
use super::label::AreaReport;
use super::label::Connectivity;
use super::morph::Disk;
use super::pipeline::{emit, Masks, SegmentObserver, SegmentReport, Step};
use super::refine::{refine_mask, Refine};
use super::stats::{plane, DisparityRange, Slice, PLANES, STAT_FRAC_BITS};
use super::{Ratio, SegmentError, SegmentParams};
use crate::conspicuity::EdgeCell;
use crate::disparity::DisparityCell;
use crate::image::{ImageView, RgbRows};

/// The depth pass's settings ([`SegmentParams::depth_pass`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DepthPass {
    /// Least height of a foreground cell above its row's dominant
    /// disparity, disparity bits (1/256 px); 1 to
    /// [`MAX_GROUND_BAND`](super::MAX_GROUND_BAND).
    pub rise: u16,
    /// Half-width of a slice around δ, disparity bits; at most
    /// [`MAX_GROUND_BAND`](super::MAX_GROUND_BAND).
    pub radius: u16,
    /// Square closing steps of the slice before its largest component is
    /// taken (0 to [`MAX_CLOSING_STEPS`](super::MAX_CLOSING_STEPS); the
    /// unbounded plane's closing, as [`close`](super::close)).
    pub closing: u8,
    /// Most searches of the pass (1 to 16).
    pub searches: u8,
    /// Square dilations of the colour objects' masks taken out of the
    /// pass's foreground (0 to 16).
    pub clearance: u8,
    /// Least mask area of an object of the pass, a fraction of the frame
    /// (at most 1).
    pub min_area: Ratio,
    /// The colour refinement of each mask against the left image; `None`:
    /// the slice's component is the mask.
    pub refine: Option<Refine>,
    /// Holes by colour, taken out of every mask, the colour searches' and
    /// the pass's, once all are found ([`Holes`]); `None`: every mask is
    /// filled.
    pub holes: Option<Holes>,
}

impl DepthPass {
    /// Cells 3 px above their row, slices of ±1.5 px closed by 2 steps, 4
    /// searches, 6 px of clearance around the colour objects, masks
    /// refined by colour ([`Refine::DEFAULT`]), objects of at least 1/64
    /// of the frame (docs/CHOICES.md, "The depth pass").
    pub const DEFAULT: Self = Self {
        rise: 3 * 256,
        radius: 384,
        closing: 2,
        searches: 4,
        clearance: 6,
        min_area: Ratio::new(1, 64),
        refine: Some(Refine::DEFAULT),
        holes: Some(Holes::DEFAULT),
    };

    /// Checks the settings.
    ///
    /// # Errors
    /// [`SegmentError::BadParams`] naming the field.
    pub fn validate(&self) -> Result<(), SegmentError> {
        if self.rise == 0 || self.rise > super::MAX_GROUND_BAND {
            return Err(SegmentError::BadParams("depth_pass.rise"));
        }
        if self.radius > super::MAX_GROUND_BAND {
            return Err(SegmentError::BadParams("depth_pass.radius"));
        }
        if self.closing > super::MAX_CLOSING_STEPS {
            return Err(SegmentError::BadParams("depth_pass.closing"));
        }
        if !(1..=16).contains(&self.searches) {
            return Err(SegmentError::BadParams("depth_pass.searches"));
        }
        if self.clearance > 16 {
            return Err(SegmentError::BadParams("depth_pass.clearance"));
        }
        if self.min_area.den == 0 || self.min_area.num > self.min_area.den {
            return Err(SegmentError::BadParams("depth_pass.min_area"));
        }
        self.refine.as_ref().map_or(Ok(()), Refine::validate)?;
        self.holes.as_ref().map_or(Ok(()), Holes::validate)
    }

    /// The least mask area in a `width` x `height` frame, px (rounded up).
    pub fn least_area(&self, width: usize, height: usize) -> u32 {
        let frame = u64::try_from(width * height).unwrap_or(u64::MAX);
        let (n, d) = (
            u64::from(self.min_area.num),
            u64::from(self.min_area.den).max(1),
        );
        u32::try_from((frame * n).div_ceil(d)).unwrap_or(u32::MAX)
    }
}

/// The densest whole-pixel plane of the foreground: the plane δ with the
/// most `fg` cells in planes δ − 1 to δ + 1, δ's own counted twice, the
/// lowest on a tie, and that weighted count; `None` for an empty
/// foreground.
fn densest_plane(d: &ImageView<'_, DisparityCell>, g: Geom, fg: &[u32]) -> Option<(u16, u32)> {
    let mut counts = [0u32; PLANES];
    for_each_on(g, fg, |x, y| {
        if let Some(k) = d
            .get(x, y)
            .and_then(|c| c.get())
            .and_then(|v| counts.get_mut(usize::from(plane(v.to_bits()))))
        {
            *k += 1;
        }
    });
    let c = |p: usize| counts.get(p).copied().unwrap_or(0);
    let mut best: Option<(u16, u32)> = None;
    for p in 0..PLANES {
        // Planes δ − 1 to δ + 1, δ's own twice: a plane between two equal
        // neighbours wins over them.
        let n = p.checked_sub(1).map_or(0, c) + 2 * c(p) + c(p + 1);
        if n > best.map_or(0, |(_, m)| m) {
            best = Some((u16::try_from(p).unwrap_or(u16::MAX), n));
        }
    }
    best
}

/// `dst` = the cells of `fg` whose disparity lies in `range`.
fn slice_bits(
    d: &ImageView<'_, DisparityCell>,
    range: &DisparityRange,
    g: Geom,
    fg: &[u32],
    dst: &mut [u32],
) -> u32 {
    dst.fill(0);
    let mut n = 0;
    for_each_on(g, fg, |x, y| {
        let inside = d
            .get(x, y)
            .and_then(|c| c.get())
            .is_some_and(|v| range.contains_bits(v.to_bits()));
        if let Some(w) = dst.get_mut(y * g.stride + x / 32).filter(|_| inside) {
            *w |= 1 << (x % 32);
            n += 1;
        }
    });
    n
}

/// The colour searches of [`segment_into`](super::segment_into), then,
/// when `params.depth_pass` is set and they found fewer than K objects,
/// the depth pass (module docs), whose colour refinement reads `left`.
/// Without a depth pass this is [`segment_into`](super::segment_into).
///
/// # Errors
/// As [`segment_into`](super::segment_into), and
/// [`SegmentError::SizeMismatch`] for a `left` image of another size than
/// the maps.
pub fn segment_with_depth_pass<S: RgbRows>(
    params: &SegmentParams,
    disparity: &ImageView<'_, DisparityCell>,
    edges: &ImageView<'_, EdgeCell>,
    left: &S,
    bufs: &mut SegmentBuffers<'_>,
    mut masks: Masks<'_>,
    observer: &mut impl SegmentObserver,
) -> Result<SegmentReport, SegmentError> {
    if left.size() != bufs.size() {
        return Err(SegmentError::SizeMismatch {
            expected: bufs.size(),
            got: left.size(),
        });
    }
    // `segment_into` validates `params`, the pass's settings with them.
    let mut report =
        super::segment_into(params, disparity, edges, bufs, masks.reborrow(), observer)?;
    let Some(pass) = params.depth_pass else {
        return Ok(report);
    };
    depth_searches(
        &pass,
        params,
        disparity,
        left,
        bufs,
        masks.reborrow(),
        &mut report,
        observer,
    )?;
    if let Some(holes) = &pass.holes {
        let g = bufs.g;
        let chunk = masks.chunk(g);
        for (i, det) in report.objects.iter_mut().enumerate() {
            bufs.mask.fill(0);
            masks.or_into(i, chunk, g, bufs.mask);
            if let Some(area) = open_holes(holes, left, bufs)? {
                det.area = area;
                masks.write(i, chunk, g, bufs.mask);
            }
        }
        observer.step(Step::Holes);
    }
    Ok(report)
}

/// The depth pass's searches (module docs, steps 1 to 4), when the colour
/// searches of `report` found fewer than K objects.
#[allow(clippy::too_many_arguments)]
fn depth_searches<S: RgbRows>(
    pass: &DepthPass,
    params: &SegmentParams,
    disparity: &ImageView<'_, DisparityCell>,
    left: &S,
    bufs: &mut SegmentBuffers<'_>,
    mut masks: Masks<'_>,
    report: &mut SegmentReport,
    observer: &mut impl SegmentObserver,
) -> Result<(), SegmentError> {
    let k = usize::from(params.max_objects);
    if report.objects.len() >= k || report.stats.is_none() {
        return Ok(());
    }
    let g = bufs.g;
    let (w, h) = bufs.size();
    // The colour objects, grown by the clearance, leave the foreground
    // (`bufs.rise`, written with D_fg by `segment_into`).
    let chunk = masks.chunk(g);
    bufs.mask.fill(0);
    for i in 0..report.objects.len() {
        masks.or_into(i, chunk, g, bufs.mask);
    }
    bits::clear_square(g, bufs.d_fg, bufs.rise, bufs.mask, pass.clearance);
    observer.step(Step::Foreground);
    let union = Union {
        min_area: pass.least_area(w, h),
        first: report.objects.len(),
    };
    let extra = STAT_FRAC_BITS - 8;
    for _ in 0..pass.searches {
        if report.objects.len() >= k {
            break;
        }
        let Some((delta, cells)) = densest_plane(disparity, g, bufs.d_fg) else {
            break;
        };
        if cells < union.min_area {
            break;
        }
        let centre = i64::from(delta) << 8;
        let r = i64::from(pass.radius);
        let range = DisparityRange {
            low: (centre - r) << extra,
            high: (centre + r) << extra,
        };
        let slice = Slice {
            delta,
            cells,
            score: u64::from(cells),
        };
        slice_bits(disparity, &range, g, bufs.d_fg, bufs.region);
        observer.step(Step::Slice);
        bits::copy_map(bufs.closed, bufs.region);
        bits::close(
            g,
            Disk::Square,
            bufs.closed,
            bufs.scratch,
            bufs.morph_rows,
            pass.closing,
        );
        observer.step(Step::Close);
        let (count, largest) = largest_filled(bufs)?;
        // The slice, grown by a step, leaves the foreground.
        bits::morph_n(
            g,
            Disk::Square,
            bufs.region,
            bufs.scratch,
            bufs.morph_rows,
            1,
            false,
        );
        for (f, m) in bufs.d_fg.iter_mut().zip(bufs.region.iter()) {
            *f &= !m;
        }
        let area = match &pass.refine {
            Some(r) => refine_mask(r, left, bufs)?,
            None => bufs.mask.iter().map(|w| w.count_ones()).sum(),
        };
        observer.step(Step::Fill);
        let regions = AreaReport {
            regions: u16::try_from(count).unwrap_or(u16::MAX),
            kept: 1,
            largest,
            area,
        };
        emit(
            params,
            &mut masks,
            chunk,
            &slice,
            range,
            regions,
            bufs,
            report,
            observer,
            Some(union),
        );
        observer.step(Step::Mask);
    }
    Ok(())
}

/// `bufs.mask` = the largest 4-connected component of `bufs.closed` (the
/// first in raster order on a tie), holes filled; `filled` and `scratch`
/// are scratch. Returns the components and the largest's area.
///
/// # Errors
/// [`SegmentError::LabelCapacity`] from the labelling.
pub(super) fn largest_filled(bufs: &mut SegmentBuffers<'_>) -> Result<(u32, u32), SegmentError> {
    let g = bufs.g;
    let comps = bits::components(g, bufs.closed, Connectivity::Four, bufs.rows, bufs.table)?;
    let (best, largest) = comps.largest.map_or((None, 0), |(r, a)| (Some(r), a));
    comps.select(g, bufs.closed, bufs.table, bufs.filled, |r, _| {
        Some(r) == best
    });
    bits::fill_holes(g, bufs.filled, bufs.mask, bufs.scratch);
    Ok((comps.count, largest))
}

/// What the depth pass keeps: objects of at least `min_area` px that
/// overlap none of the first `first` masks (the colour searches').
#[derive(Clone, Copy, Debug)]
pub(super) struct Union {
    pub(super) min_area: u32,
    pub(super) first: usize,
}

impl Union {
    /// Whether a mask of `area` px in `mask` (a bit map of geometry `g`)
    /// is kept against the colour objects' slots in `masks`.
    pub(super) fn keeps(
        &self,
        g: Geom,
        area: u32,
        mask: &[u32],
        masks: &Masks<'_>,
        chunk: usize,
    ) -> bool {
        if area < self.min_area {
            return false;
        }
        let clash = (0..self.first).any(|i| match masks {
            Masks::Bits(m) => m
                .get(i * chunk..(i + 1) * chunk)
                .is_some_and(|m1| m1.iter().zip(mask).any(|(a, b)| a & b != 0)),
            Masks::Bools(m) => m.get(i * chunk..(i + 1) * chunk).is_some_and(|m1| {
                let mut hit = false;
                bits::for_each_on(g, mask, |x, y| {
                    hit |= m1.get(y * g.width + x).copied().unwrap_or(false);
                });
                hit
            }),
        });
        !clash
    }
}
