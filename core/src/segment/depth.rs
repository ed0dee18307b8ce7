//! The depth pass: figure-ground searched again with the disparity map's
//! steps as edges, for the objects the colour edges do not outline.
//!
//! The paper's figure-ground needs a closed contour of conspicuity edges
//! C around an object; an object whose colour is close to its
//! surroundings' has none, however plainly it stands in front. After the
//! colour searches ([`segment_into`](super::segment_into)), when they found
//! fewer than K objects:
//!
//! 1. every foreground cell whose symmetric pair of neighbours (left and
//!    right, up and down, or either diagonal; both ON) differs by at least
//!    [`DepthPass::step`] becomes a strong edge of C ([`depth_steps`],
//!    [`DEPTH_EDGE`]; the searches read C only on the foreground);
//! 2. the foreground is restored to what it was before the first search,
//!    less the colour objects' masks grown by [`DepthPass::clearance`]
//!    square dilations (their halo in the stereo's map would otherwise
//!    come back as rings and slivers);
//! 3. figure-ground searches again, at most [`DepthPass::searches`] times;
//!    an object of this pass is kept when its mask covers at least
//!    [`DepthPass::min_area`] of the frame and overlaps no mask of the
//!    colour searches.
//!
//! Adding the steps to C for the colour searches instead cuts the
//! contrasted objects' masks along the stereo's halo (docs/RECALL.md,
//! "What reaches the targets").

use super::bits::{self, words_per_row, BitView, Geom};
use super::buffers::SegmentBuffers;
use super::morph::Disk;
use super::pipeline::{run_searches, Masks, SegmentObserver, SegmentReport};
use super::{Ratio, SegmentError, SegmentParams};
use crate::conspicuity::{Conspicuity, EdgeCell};
use crate::disparity::DisparityCell;
use crate::image::{ImageView, ImageViewMut};

/// The depth pass's settings ([`SegmentParams::depth_pass`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DepthPass {
    /// Least disparity step between a cell's symmetric neighbours that
    /// makes it an edge, disparity bits (1/256 px); 1 to
    /// [`MAX_GROUND_BAND`](super::MAX_GROUND_BAND).
    pub step: u16,
    /// Most searches of the pass (1 to 16).
    pub searches: u8,
    /// Square dilations of the colour objects' masks taken out of the
    /// pass's foreground (0 to 16).
    pub clearance: u8,
    /// Least mask area of an object of the pass, a fraction of the frame
    /// (at most 1).
    pub min_area: Ratio,
}

impl DepthPass {
    /// Steps of 4 px, one search, 6 px of clearance around the colour
    /// objects, objects of at least 1/48 of the frame (docs/CHOICES.md,
    /// "The depth pass").
    pub const DEFAULT: Self = Self {
        step: 4 * 256,
        searches: 1,
        clearance: 6,
        min_area: Ratio::new(1, 48),
    };

    /// Checks the settings.
    ///
    /// # Errors
    /// [`SegmentError::BadParams`] naming the field.
    pub fn validate(&self) -> Result<(), SegmentError> {
        if self.step == 0 || self.step > super::MAX_GROUND_BAND {
            return Err(SegmentError::BadParams("depth_pass.step"));
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
        Ok(())
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

/// The conspicuity a depth step takes: a CIELUV distance of 64, above
/// most colour edges' C̃, so that non-maximum suppression keeps it beside
/// them; a stronger colour edge keeps its own value.
pub const DEPTH_EDGE: Conspicuity = Conspicuity::from_bits(64 << 6);

/// Marks every cell of `edges` (within the bit map `within`, when given)
/// whose symmetric pair of neighbours in `disparity` (both ON) differs by
/// at least `step` bits as [`DEPTH_EDGE`], unless it is stronger already;
/// the frame's border rows and columns, which lack a pair, are left as
/// they are. Returns the cells marked.
///
/// # Errors
/// [`SegmentError::SizeMismatch`] when the maps differ in size.
pub fn depth_steps(
    edges: &mut ImageViewMut<'_, EdgeCell>,
    disparity: &ImageView<'_, DisparityCell>,
    step: u16,
    within: Option<&BitView<'_>>,
) -> Result<u32, SegmentError> {
    super::check_size(edges.size(), disparity.size())?;
    if let Some(m) = within {
        super::check_size(m.size(), disparity.size())?;
    }
    let (w, h) = disparity.size();
    if w < 3 || h < 3 {
        return Ok(0);
    }
    // Cells are `U8F8` bits with OFF as `u16::MAX`; a disparity is below
    // 256 px, so `hi == u16::MAX` alone says a pair has an OFF member.
    let is_step = |a: u16, b: u16| {
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        hi != u16::MAX && hi - lo >= step
    };
    let strong = EdgeCell::from_raw(DEPTH_EDGE);
    let stride = words_per_row(w);
    let mut marked = 0;
    for y in 1..h - 1 {
        let (Some(up), Some(mid), Some(dn), Some(out)) = (
            disparity.row(y - 1),
            disparity.row(y),
            disparity.row(y + 1),
            edges.row_mut(y),
        ) else {
            break;
        };
        let b = |r: &[DisparityCell], x: usize| r.get(x).map_or(u16::MAX, |c| c.raw().to_bits());
        let mut cell = |x: usize| {
            let stepped = is_step(b(mid, x - 1), b(mid, x + 1))
                | is_step(b(up, x), b(dn, x))
                | is_step(b(up, x - 1), b(dn, x + 1))
                | is_step(b(up, x + 1), b(dn, x - 1));
            if let Some(e) = out
                .get_mut(x)
                .filter(|e| stepped && e.get().is_none_or(|c| c < DEPTH_EDGE))
            {
                *e = strong;
                marked += 1;
            }
        };
        match within {
            None => (1..w - 1).for_each(&mut cell),
            Some(m) => {
                let words = m.words().get(y * stride..(y + 1) * stride).unwrap_or(&[]);
                for (i, &word) in words.iter().enumerate() {
                    let mut bits = word;
                    while bits != 0 {
                        let x = 32 * i + bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        if (1..w - 1).contains(&x) {
                            cell(x);
                        }
                    }
                }
            }
        }
    }
    Ok(marked)
}

/// The colour searches of [`segment_into`](super::segment_into), then,
/// when `params.depth_pass` is set and they found fewer than K objects,
/// the depth pass (module docs): `edges` takes the depth steps, and
/// `first_fg` (a bit map, [`bit_map_len`](super::bit_map_len) words) keeps
/// the foreground between the two. Without a depth pass this is
/// [`segment_into`](super::segment_into) and `edges` is not written.
///
/// # Errors
/// As [`segment_into`](super::segment_into); [`SegmentError::MasksTooSmall`]
/// when `first_fg` is shorter than a bit map.
pub fn segment_with_depth_pass(
    params: &SegmentParams,
    disparity: &ImageView<'_, DisparityCell>,
    edges: &mut ImageViewMut<'_, EdgeCell>,
    bufs: &mut SegmentBuffers<'_>,
    mut masks: Masks<'_>,
    observer: &mut impl SegmentObserver,
    first_fg: &mut [u32],
) -> Result<SegmentReport, SegmentError> {
    let Some(pass) = params.depth_pass else {
        return super::segment_into(params, disparity, &edges.as_view(), bufs, masks, observer);
    };
    // `segment_saving` validates `params`, the pass's settings with them.
    let words = bufs.g.len();
    let Some(first_fg) = first_fg.get_mut(..words) else {
        return Err(SegmentError::MasksTooSmall {
            needed: words,
            got: first_fg.len(),
        });
    };
    let mut report = super::pipeline::segment_saving(
        params,
        disparity,
        &edges.as_view(),
        bufs,
        masks.reborrow(),
        observer,
        Some(&mut *first_fg),
    )?;
    let k = usize::from(params.max_objects);
    if report.objects.len() >= k || report.stats.is_none() {
        return Ok(report);
    }
    let g = bufs.g;
    let (w, h) = bufs.size();
    depth_steps(
        edges,
        disparity,
        pass.step,
        Some(&BitView::with_geom(first_fg, g)),
    )?;
    bits::copy_map(bufs.d_fg, first_fg);
    // The colour objects, grown by the clearance, leave the foreground.
    let chunk = masks.chunk(g);
    bufs.mask.fill(0);
    for i in 0..report.objects.len() {
        masks.or_into(i, chunk, g, bufs.mask);
    }
    bits::morph_n(
        g,
        Disk::Square,
        bufs.mask,
        bufs.scratch,
        bufs.morph_rows,
        pass.clearance,
        false,
    );
    for (f, m) in bufs.d_fg.iter_mut().zip(bufs.mask.iter()) {
        *f &= !m;
    }
    let union = Union {
        min_area: pass.least_area(w, h),
        first: report.objects.len(),
    };
    run_searches(
        params,
        disparity,
        &edges.as_view(),
        bufs,
        &mut masks,
        &mut report,
        observer,
        usize::from(pass.searches),
        Some(union),
    )?;
    Ok(report)
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
