//! Disparity completion over conspicuity regions: the border step of the
//! stereo stage (dem-spec §6 "Borders", our reading), between the disparity
//! energy model and figure-ground segregation.
//!
//! Energy models are weakest where segmentation needs them most: at object
//! borders. Their receptive fields straddle the border, so the nearer
//! surface's disparity spills a few pixels across it, and the left-right
//! check turns the occluded side OFF. The object's outline, which the
//! segmentation must find inside its disparity slice, is then mostly OFF or
//! wrong and the contour never closes.
//!
//! The conspicuity map C already knows where the borders are. Its edge cells
//! cut the frame into regions (4-connected components of non-edge cells).
//! This stage trusts a disparity only away from edges, and gives every other
//! cell the median trusted disparity of its region:
//!
//! 1. **Regions**: label the non-edge cells of C, 4-connected (edges are
//!    8-connected curves, so 4-connected regions cannot leak through their
//!    diagonal steps).
//! 2. **Trusted cells**: ON, and no edge within `guard` px (Chebyshev).
//! 3. **Region medians**: the lower median of the trusted disparities of
//!    each region, in whole px (round half up), found by bisection over
//!    0..=255 with one counting pass per bit: no sorting, no histogram per
//!    region.
//! 4. **Targets**: OFF cells and cells within `guard` px of an edge take the
//!    median of their region, as whole px. An edge cell belongs to no region:
//!    it takes the region of the non-edge neighbour (radius 1, else 2,
//!    raster order, first minimum) whose colour is closest to its own, so a
//!    border cell goes to the side it looks like.
//!
//! A region with fewer than `min_trusted` trusted cells, or beyond the region tables' capacity,
//! leaves its cells as they were (the report counts skipped regions).
//! Every step is integer; [`complete`] never panics.
//!
//! [`complete_runs`] is the same stage on bit maps and runs of non-edge
//! cells, with fixed tables and any [`SideColour`] (the pipeline keeps one
//! [`Tone`] byte per pixel): no label map, and no worst-case label tables.

use crate::conspicuity::{EdgeCell, Luv};
use crate::disparity::{from_pixels, DisparityCell};
use crate::image::{ImageError, ImageView, ImageViewMut};
use crate::segment::{label_capacity, Connectivity, Labeller, SegmentError};

mod runs;
pub use runs::{
    complete_runs, pipeline_run_capacity, run_rows_len, run_table_len, RunBuffers, SideColour,
    Tone, DEFAULT_RUN_CAPACITY, LABEL_ROWS,
};

/// Parameters of [`complete`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CompleteParams {
    /// Cells within this many px of an edge are not trusted and are
    /// replaced. Default 1: the edge's own two-pixel ring.
    pub guard: u8,
    /// A region needs at least this many trusted cells to give a median
    /// (at least 1). Default 1.
    pub min_trusted: u32,
}

impl CompleteParams {
    /// Guard 1, one trusted cell per median.
    pub const DEFAULT: Self = Self {
        guard: 1,
        min_trusted: 1,
    };
}

impl Default for CompleteParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Why [`complete`] rejected its input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum CompleteError {
    /// The maps differ in size, or a buffer is too short.
    Image(ImageError),
    /// The labelling failed (its tables are too small for this frame).
    Label(SegmentError),
}

impl From<ImageError> for CompleteError {
    fn from(e: ImageError) -> Self {
        Self::Image(e)
    }
}

impl From<SegmentError> for CompleteError {
    fn from(e: SegmentError) -> Self {
        Self::Label(e)
    }
}

impl core::fmt::Display for CompleteError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Image(e) => write!(f, "disparity completion: {e}"),
            Self::Label(e) => write!(f, "disparity completion: {e:?}"),
        }
    }
}

impl core::error::Error for CompleteError {}

/// What [`complete`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CompleteReport {
    /// Regions of the conspicuity map.
    pub regions: u16,
    /// Regions with at least `min_trusted` trusted cells.
    pub regions_with_median: u16,
    /// Regions past the tables' capacity, left unchanged.
    pub regions_skipped: u16,
    /// ON cells given their region's median.
    pub replaced: u32,
    /// OFF cells given their region's median.
    pub filled: u32,
    /// Runs of non-edge cells past the run table's capacity
    /// ([`complete_runs`]), left unchanged; always 0 for [`complete`].
    pub runs_unlabelled: u32,
}

/// Entries each region table needs so that no region of a `width` x
/// `height` frame is ever skipped: one per label the labelling can return,
/// label 0 included. Smaller tables are fine: regions past their capacity
/// are left unchanged and counted in [`CompleteReport::regions_skipped`].
pub const fn region_table_len(width: usize, height: usize) -> usize {
    label_capacity(width, height)
}

/// Region-table entries that suit frames up to 160x120 on a board: the
/// synthetic scenes have a handful of regions and Aloe at 160 px about 600.
pub const DEFAULT_REGION_CAPACITY: usize = 1024;

/// Scratch bytes of [`complete`] for a `width` x `height` frame with region
/// tables of `regions` entries: the edge/trusted map and the four tables.
/// The labeller's buffers come on top (`segment::label_capacity`); the
/// segmentation stage that follows can lend its own.
pub const fn scratch_bytes(width: usize, height: usize, regions: usize) -> usize {
    width * height + regions * (4 + 4 + 1 + 1)
}

/// Per-region tables of [`complete`], caller-provided; the capacity is the
/// shortest of the four.
#[derive(Debug)]
pub struct RegionTables<'a> {
    /// Trusted cells per region.
    pub total: &'a mut [u32],
    /// Trusted cells at or below the bisection midpoint.
    pub below: &'a mut [u32],
    /// Bisection lower bound; the median once done.
    pub lo: &'a mut [u8],
    /// Bisection upper bound.
    pub hi: &'a mut [u8],
}

impl RegionTables<'_> {
    fn capacity(&self) -> usize {
        self.total
            .len()
            .min(self.below.len())
            .min(self.lo.len())
            .min(self.hi.len())
    }
}

/// Whole px of a disparity cell, rounded half up (U8F8 bits ≤ 65534).
fn whole_px(c: DisparityCell) -> Option<u8> {
    c.get()
        .map(|d| u8::try_from((u32::from(d.to_bits()) + 128) >> 8).unwrap_or(u8::MAX))
}

/// True when an edge (label 0) lies within Chebyshev distance `g` of
/// `(x, y)`.
fn near_edge(labels: &ImageView<'_, u16>, x: usize, y: usize, g: usize) -> bool {
    let (w, h) = labels.size();
    let (x0, x1) = (x.saturating_sub(g), (x + g).min(w.saturating_sub(1)));
    let (y0, y1) = (y.saturating_sub(g), (y + g).min(h.saturating_sub(1)));
    (y0..=y1).any(|yy| {
        labels
            .row(yy)
            .and_then(|r| r.get(x0..=x1))
            .is_some_and(|r| r.contains(&0))
    })
}

fn colour_dist2(a: Luv, b: Luv) -> u64 {
    a.to_bits()
        .iter()
        .zip(b.to_bits())
        .map(|(&p, q)| {
            let d = i64::from(p) - i64::from(q);
            d.unsigned_abs() * d.unsigned_abs()
        })
        .sum()
}

/// The region label an edge cell joins: that of its non-edge neighbour of
/// closest colour within radius 1, else 2 (raster order, first minimum);
/// 0 when none.
fn edge_region(
    labels: &ImageView<'_, u16>,
    colour: &ImageView<'_, Luv>,
    x: usize,
    y: usize,
) -> u16 {
    let (w, h) = labels.size();
    let Some(own) = colour.get(x, y) else {
        return 0;
    };
    for r in 1..=2usize {
        let mut best: Option<(u64, u16)> = None;
        for yy in y.saturating_sub(r)..=(y + r).min(h.saturating_sub(1)) {
            for xx in x.saturating_sub(r)..=(x + r).min(w.saturating_sub(1)) {
                let (Some(c), Some(l)) = (colour.get(xx, yy), labels.get(xx, yy)) else {
                    continue;
                };
                if l == 0 {
                    continue;
                }
                let d = colour_dist2(own, c);
                if best.is_none_or(|(bd, _)| d < bd) {
                    best = Some((d, l));
                }
            }
        }
        if let Some((_, l)) = best {
            return l;
        }
    }
    0
}

/// Completes `disparity` in place over the regions of the conspicuity map
/// `edges`, with `colour` (the stage's smoothed CIELUV) deciding the side of
/// each edge cell. `edge_map` is scratch (the edges, then the trusted
/// cells); `lab` and `tables` hold the labelling and the per-region medians.
///
/// # Errors
/// [`CompleteError::Image`] when the maps or buffers differ in size, and
/// [`CompleteError::Label`] when the labeller's tables are too small.
pub fn complete(
    params: &CompleteParams,
    edges: &ImageView<'_, EdgeCell>,
    colour: &ImageView<'_, Luv>,
    disparity: &mut ImageViewMut<'_, DisparityCell>,
    edge_map: &mut ImageViewMut<'_, bool>,
    lab: &mut Labeller<'_>,
    tables: &mut RegionTables<'_>,
) -> Result<CompleteReport, CompleteError> {
    let size = edges.size();
    for other in [colour.size(), disparity.size(), edge_map.size(), lab.size()] {
        if other != size {
            return Err(ImageError::SizeMismatch {
                expected: size,
                got: other,
            }
            .into());
        }
    }
    for (src, dst) in edges.rows().zip(edge_map.rows_mut()) {
        for (s, d) in src.iter().zip(dst.iter_mut()) {
            *d = s.is_on();
        }
    }
    let regions = lab.label(&edge_map.as_view(), false, Connectivity::Four)?;
    let labels = lab.labels().ok_or(ImageError::BufferTooSmall {
        needed: size.0 * size.1,
        got: 0,
    })?;
    // From here on an edge is label 0, and `edge_map` holds the trusted
    // cells: ON, and no edge within `guard` px.
    let g = usize::from(params.guard);
    for (y, (trow, drow)) in edge_map
        .rows_mut()
        .zip(disparity.as_view().rows())
        .enumerate()
    {
        for (x, (t, c)) in trow.iter_mut().zip(drow).enumerate() {
            *t = c.is_on() && !near_edge(&labels, x, y, g);
        }
    }
    let trusted_map = edge_map.as_view();
    let cap = tables.capacity();
    let min_trusted = params.min_trusted.max(1);
    let mut report = CompleteReport {
        regions,
        regions_skipped: u16::try_from(usize::from(regions).saturating_sub(cap.saturating_sub(1)))
            .unwrap_or(u16::MAX),
        ..CompleteReport::default()
    };
    tables.total.fill(0);
    tables.lo.fill(0);
    tables.hi.fill(u8::MAX);

    // Trusted cells, visited once per pass: (label, whole px).
    let disp = disparity.as_view();
    let trusted = |f: &mut dyn FnMut(usize, u8)| {
        for ((drow, lrow), trow) in disp.rows().zip(labels.rows()).zip(trusted_map.rows()) {
            for ((&c, &l), &t) in drow.iter().zip(lrow).zip(trow) {
                if let (true, Some(v)) = (t && usize::from(l) < cap, whole_px(c)) {
                    f(usize::from(l), v);
                }
            }
        }
    };
    trusted(&mut |l, _| {
        if let Some(t) = tables.total.get_mut(l) {
            *t += 1;
        }
    });
    for _ in 0..8 {
        tables.below.fill(0);
        let (lo, hi, below) = (&*tables.lo, &*tables.hi, &mut *tables.below);
        trusted(&mut |l, v| {
            let mid = match (lo.get(l), hi.get(l)) {
                (Some(&a), Some(&b)) => (u16::from(a) + u16::from(b)) / 2,
                _ => return,
            };
            if u16::from(v) <= mid {
                if let Some(c) = below.get_mut(l) {
                    *c += 1;
                }
            }
        });
        for (((lo, hi), &below), &total) in tables
            .lo
            .iter_mut()
            .zip(tables.hi.iter_mut())
            .zip(tables.below.iter())
            .zip(tables.total.iter())
        {
            let mid = u8::try_from((u16::from(*lo) + u16::from(*hi)) / 2).unwrap_or(u8::MAX);
            // Lower median: the k-th smallest, k = (total - 1) / 2, 0-based.
            if total > 0 && below > (total - 1) / 2 {
                *hi = mid;
            } else {
                *lo = mid.saturating_add(1).min(*hi);
            }
        }
    }
    report.regions_with_median = u16::try_from(
        tables
            .total
            .iter()
            .skip(1)
            .take(usize::from(regions))
            .filter(|&&t| t >= min_trusted)
            .count(),
    )
    .unwrap_or(u16::MAX);

    let (w, h) = size;
    for y in 0..h {
        for x in 0..w {
            let Some(cell) = disparity.get(x, y) else {
                continue;
            };
            if trusted_map.get(x, y) != Some(false) {
                continue;
            }
            let l = match labels.get(x, y) {
                Some(0) => edge_region(&labels, colour, x, y),
                l => l.unwrap_or(0),
            };
            let l = usize::from(l);
            if l == 0 || tables.total.get(l).copied().unwrap_or(0) < min_trusted {
                continue;
            }
            let Some(&v) = tables.lo.get(l) else {
                continue;
            };
            if cell.is_on() {
                report.replaced += 1;
            } else {
                report.filled += 1;
            }
            disparity.set(x, y, from_pixels(v));
        }
    }
    Ok(report)
}
