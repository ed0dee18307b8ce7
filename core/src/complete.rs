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
//! **Tall regions.** One median is right for a surface facing the camera,
//! not for the ground, whose disparity grows row by row from the wall's
//! at the horizon to the nearest at the bottom: its median would put the
//! horizon's edge cells, and the cells next to anything standing on it,
//! at the disparity of its middle rows, a line across the frame that
//! joins objects at that disparity (docs/RECALL_EARLIER.md). A region whose
//! trusted cells lie at least [`CompleteParams::tilt_rows`] rows apart
//! (at most [`MAX_TILTED`] a frame, in label order, and within the tilt
//! table) takes, in row `y`, its median plus its least-squares tilt:
//! `256·median + ⌊slope·(2^16·y − ybar) / 2^32⌋` bits, rounded to whole
//! px (round half up, within 0..=255), with the slope and the mean row
//! from the sums of its trusted cells ([`Tilt`]) within
//! [`CompleteParams::tilt_band`] of its median, in every
//! [`TILT_ROW_STEP`]-th row; when those lie in one row, the median alone.
//! The band keeps the halo of an object before a wall, far from the
//! wall's median, from tilting the wall. Smaller regions keep the median:
//! fitted to a few rows, a tilt is noise, and the median is what replaces
//! the halo next to an object's outline.
//!
//! A region with fewer than `min_trusted` trusted cells, or beyond the region tables' capacity,
//! leaves its cells as they were (the report counts skipped regions).
//! Every step is integer; [`complete_runs`] never panics. It works on bit
//! maps and runs of non-edge cells, with fixed tables and any
//! [`SideColour`] (the pipeline keeps one [`Tone`] byte per pixel): no label
//! map, and no worst-case label tables. (A full-frame form with a label
//! per pixel preceded it; git keeps it, at 57b22a2.)

use crate::image::ImageError;
use crate::segment::{bit_map_len, label_capacity};

mod runs;
pub use runs::{
    complete_runs, pipeline_run_capacity, run_rows_len, run_table_len, RunBuffers, SideColour,
    Tone, DEFAULT_RUN_CAPACITY, LABEL_ROWS,
};

/// Parameters of [`complete_runs`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CompleteParams {
    /// Cells within this many px of an edge are not trusted and are
    /// replaced. Default 1: the edge's own two-pixel ring.
    pub guard: u8,
    /// A region needs at least this many trusted cells to give a median
    /// (at least 1). Default 1.
    pub min_trusted: u32,
    /// A region whose trusted cells lie at least this many rows apart
    /// (first to last) takes its median plus its least-squares tilt in y
    /// (module docs, "Tall regions"); 0: every region takes its median
    /// alone. Default 48.
    pub tilt_rows: u16,
    /// A tall region's tilt is fitted to its trusted cells within this
    /// many disparity bits (1/256 px) of its median, so that the halo of
    /// an object before a wall does not tilt the wall (module docs, "Tall
    /// regions"); `u16::MAX`: every trusted cell. Default 1024 (4 px).
    pub tilt_band: u16,
}

impl CompleteParams {
    /// Guard 1, one trusted cell per median, tall regions (48 rows or
    /// more) along their tilt.
    pub const DEFAULT: Self = Self {
        guard: 1,
        min_trusted: 1,
        tilt_rows: 48,
        tilt_band: 1024,
    };

    /// [`CompleteParams::DEFAULT`] with one median for every region, tall
    /// or not: the completion before the tilt.
    pub const MEDIAN: Self = Self {
        tilt_rows: 0,
        ..Self::DEFAULT
    };
}

impl Default for CompleteParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Why [`complete_runs`] rejected its input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum CompleteError {
    /// The maps differ in size, or a buffer is too short.
    Image(ImageError),
}

impl From<ImageError> for CompleteError {
    fn from(e: ImageError) -> Self {
        Self::Image(e)
    }
}

impl core::fmt::Display for CompleteError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Image(e) => write!(f, "disparity completion: {e}"),
        }
    }
}

impl core::error::Error for CompleteError {}

/// What [`complete_runs`] did.
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
    /// ([`complete_runs`]), left unchanged.
    pub runs_unlabelled: u32,
    /// Tall regions filled along their tilt ([`CompleteParams::tilt_rows`]).
    pub tilted: u16,
}

/// Most tall regions filled along their tilt in a frame; later ones (in
/// label order) take their median alone.
pub const MAX_TILTED: usize = 16;

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

/// Entries of the pipeline's tilt table ([`RegionTables::tilt`]): regions
/// labelled past it take their median alone. The regions that tilt are
/// the few tall ones, labelled early (raster order of their first cell).
pub const PIPELINE_TILT_REGIONS: usize = 128;

/// Bytes of [`complete_runs`]'s inputs and scratch beyond the disparity
/// and C for a `width` x `height` frame with a full run table and region
/// tables of `regions` entries: the [`Tone`] map, the edge and trusted bit
/// maps, the run table, its row index, the label rows and the four tables.
pub const fn scratch_bytes(width: usize, height: usize, regions: usize) -> usize {
    width * height
        + 2 * 4 * bit_map_len(width, height)
        + 2 * run_table_len(width, height)
        + 4 * run_rows_len(width)
        + 2 * LABEL_ROWS * width
        + regions * (4 + 4 + 1 + 1)
}

/// Per-region tables of [`complete_runs`], caller-provided; the capacity is the
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
    /// Each region's first and last trusted rows, for the tall test
    /// ([`CompleteParams::tilt_rows`]; the tall regions' sums are taken in
    /// a later pass, in a table of [`MAX_TILTED`] on the stack); regions
    /// at or past its length take their median alone. May be empty when
    /// `tilt_rows` is 0.
    pub tilt: &'a mut [RowSpan],
}

/// The first and last rows of a region's trusted cells.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct RowSpan {
    /// The first row.
    pub first: u32,
    /// The last row.
    pub last: u32,
}

/// A tall region's tilt is fitted to the rows `y` with `y %
/// TILT_ROW_STEP == 0`: a line needs few rows, and a pass over every
/// trusted cell of the frame would not fit the board's budget.
pub const TILT_ROW_STEP: usize = 4;

/// One region's sums over its trusted cells within
/// [`CompleteParams::tilt_band`] of its median, in every
/// [`TILT_ROW_STEP`]-th row, for its tilt in y: `y` is the row, `b` the
/// cell's `U8F8` bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct RegionSums {
    /// Σ y.
    pub sy: u64,
    /// Σ y².
    pub syy: u64,
    /// Σ b.
    pub sb: u64,
    /// Σ y·b.
    pub syb: u64,
    /// The first row with a trusted cell.
    pub first: u32,
    /// The last row with a trusted cell.
    pub last: u32,
}

/// A tall region's fill: `b(y) = 256·median + ⌊slope·(2^16·y − ybar) /
/// 2^32⌋` bits (`slope` in bits per row and `ybar` in rows, both Q16).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tilt {
    /// The least-squares slope, `⌊2^16·(nΣyb − ΣyΣb) / (nΣy² − (Σy)²)⌋`
    /// (floor division), bits per row, Q16.
    pub slope: i64,
    /// The mean row of the trusted cells, `⌊2^16·Σy / n⌋`, Q16.
    pub ybar: i64,
}

impl Tilt {
    /// The tilt of `n` trusted cells with sums `s`, when their rows span at
    /// least `rows` (`rows > 0`, `n > 0`); `None` otherwise or when a
    /// value leaves `i64`.
    pub fn of(n: u32, s: &RegionSums, rows: u16) -> Option<Self> {
        if rows == 0 || n == 0 || s.last.saturating_sub(s.first) < u32::from(rows) {
            return None;
        }
        let n = i128::from(n);
        let (sy, syy, sb, syb) = (
            i128::from(s.sy),
            i128::from(s.syy),
            i128::from(s.sb),
            i128::from(s.syb),
        );
        let den = n.checked_mul(syy)?.checked_sub(sy.checked_mul(sy)?)?;
        let num = n.checked_mul(syb)?.checked_sub(sy.checked_mul(sb)?)?;
        if den <= 0 {
            return None;
        }
        let slope = num.checked_mul(1 << 16)?.checked_div_euclid(den)?;
        let ybar = sy.checked_mul(1 << 16)?.checked_div_euclid(n)?;
        Some(Self {
            slope: i64::try_from(slope).ok()?,
            ybar: i64::try_from(ybar).ok()?,
        })
    }

    /// The whole px of row `y` for a region of median `median` px:
    /// `b(y)` rounded half up, within 0..=255.
    pub fn at(&self, median: u8, y: usize) -> u8 {
        // In i64 when the product fits (any frame under 2^15 rows with a
        // slope under 2^16 px a row), else in i128: the same integers.
        let dy = i64::try_from(y)
            .ok()
            .and_then(|y| y.checked_mul(1 << 16))
            .and_then(|y| y.checked_sub(self.ybar));
        let d = match dy.and_then(|dy| self.slope.checked_mul(dy)) {
            Some(d) => i128::from(d),
            None => {
                let y = i128::try_from(y).unwrap_or(i128::MAX >> 20) << 16;
                i128::from(self.slope).saturating_mul(y.saturating_sub(i128::from(self.ybar)))
            }
        };
        let b = (i128::from(median) << 8).saturating_add(d >> 32);
        u8::try_from(((b + 128) >> 8).clamp(0, 255)).unwrap_or(u8::MAX)
    }
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

/// The whole px of the ON cell with U8F8 bits `b` (≤ 65 534), rounded half
/// up, at most 255: non-decreasing in `b`,
/// so the whole px of the least and greatest bits of a set of cells are
/// the least and greatest whole px.
#[inline(always)]
fn whole_bits(b: u16) -> u8 {
    u8::try_from((u32::from(b) + 128) >> 8).unwrap_or(u8::MAX)
}

/// The raw cell bits below which a cell is ON with [`whole_bits`] at most
/// `mid`: for ON bits `b` (≤ 65 534), `min(255, (b + 128) >> 8) <= mid` is
/// `b + 128 < 256 (mid + 1)` when `mid < 255` and always true when
/// `mid = 255`; OFF (65 535) is never below the limit.
#[inline(always)]
fn at_most_limit(mid: u8) -> u32 {
    if mid == u8::MAX {
        u32::from(u16::MAX)
    } else {
        (u32::from(mid) + 1) * 256 - 128
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::disparity::DisparityCell;
    use crate::fixed::U8F8;
    use crate::off::MaybeOff;

    /// Whole px of a disparity cell, rounded half up, as the medians
    /// count them.
    fn whole_px(c: DisparityCell) -> Option<u8> {
        c.get()
            .map(|d| u8::try_from((u32::from(d.to_bits()) + 128) >> 8).unwrap_or(u8::MAX))
    }

    #[test]
    fn the_bit_limit_is_the_whole_px_compare_for_every_cell() {
        let check = |mid: u8, b: u16| {
            let c: DisparityCell = MaybeOff::from_raw(U8F8::from_bits(b));
            let want = whole_px(c).is_some_and(|v| v <= mid);
            assert_eq!(
                u32::from(b) < at_most_limit(mid),
                want,
                "bits {b}, mid {mid}"
            );
            if c.is_on() {
                assert_eq!(whole_px(c), Some(whole_bits(b)), "bits {b}");
            }
        };
        // Every cell for the ends and a middle value of `mid`; every
        // `mid` at each rounding boundary and the top of the range.
        for mid in [0, 1, 127, 254, 255] {
            (0..=u16::MAX).for_each(|b| check(mid, b));
        }
        for mid in 0..=u8::MAX {
            for k in 0..=256u32 {
                let edge = (k * 256).saturating_sub(128);
                for b in edge.saturating_sub(2)..=(edge + 2).min(65_535) {
                    check(mid, b as u16);
                }
            }
            (65_400..=u16::MAX).for_each(|b| check(mid, b));
        }
    }
}
