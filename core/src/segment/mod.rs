//! Figure-ground segregation (paper sections 3.1, 3.3 and 3.4): from a
//! disparity map D and a conspicuity map C to binary object masks.
//!
//! The steps, each callable alone so every intermediate map can be observed:
//!
//! 1. [`selected_stats`] (and [`selected_area`] to see S): mean_S and σ_S
//!    over the valid disparities of S, the map without the top and bottom
//!    sixths and the left eighth. [`thresholds`] and [`foreground`]: D_fg
//!    keeps `mean + 0.1σ < D < mean + 2σ`.
//! 2. [`foreground_conspicuity`]: C_fg = C where D_fg is ON.
//! 3. [`slice_counts`], [`select_slice`]: A^C(d), the ON C_fg cells whose
//!    D_fg rounds to `d−1..=d+1`, and δ = argmax A^C(d)·d^A. The paper
//!    leaves the exponent A undefined; [`SegmentParams::exponent`] is 1 by
//!    default (a linear preference for nearer planes). [`slice_range`] and
//!    [`object_region`]: D_ObjReg keeps `δ − r ≤ D_fg ≤ δ + r`, r = σ_S/2.5
//!    (at least [`SegmentParams::min_slice_radius`]).
//! 4. [`object_conspicuity`]: ψ = C where D_ObjReg is ON; [`above_mean`]:
//!    C_ObjReg = ψ above its mean ψ̄ (by default over the whole object
//!    region, inactive cells as 0; see [`PsiMean`]).
//! 5. [`refine_border`]: the largest 8-connected component of the (ψ ≠ OFF)
//!    map dilated 4 times by a radius-1 [`Disk`]; C_Obj = C_ObjReg inside it.
//! 6. [`non_max_suppression`] (C_Obj^M), [`close`] (F_Obj), [`fill_holes`]
//!    and [`area_filter`]: the mask.
//!
//! [`segment`] runs them all on caller-provided [`SegmentBuffers`], for up to
//! [`SegmentParams::max_objects`] objects (beyond the paper, which keeps only
//! the most salient): after each object its cells are inhibited in D_fg and
//! the search runs again (see [`inhibit`]). Also beyond the paper, and off
//! in [`SegmentParams::PAPER`]: the ground plane can be inhibited in D_fg
//! ([`fit_ground`], [`inhibit_ground`], [`SegmentParams::ground_band`]), and
//! masks too small or too wide for an object are searched past
//! ([`SegmentParams::min_object`], [`SegmentParams::max_object_width`]).
//!
//! Per-pixel work is integer only: statistics use `u64`/`u128` sums and an
//! integer square root. Each step is also a function over `bool` and cell
//! maps (labelling with `u16` labels and caller-provided tables,
//! [`Labeller`]), the readable definition; [`segment`] runs the same steps
//! on bit maps (32 pixels a word: morphology and hole filling are word
//! operations, components are labelled by runs) and gives the same output
//! bit for bit. Its buffers are [`scratch_bytes`] long. Nothing allocates.
//!
//! ```
//! use protogist::conspicuity::{Conspicuity, EdgeCell};
//! use protogist::disparity::from_pixels;
//! use protogist::image::ImageView;
//! use protogist::segment::*;
//! const W: usize = 32;
//! const H: usize = 24;
//! // Background at 2 px, a 14x10 box at 9 px; C is strong on the box's border.
//! // (The box must cover over 1/5 of S: above mean + 2σ D counts as wrong.)
//! let inside = |x: isize, y: isize| (10..24).contains(&x) && (7..17).contains(&y);
//! let xy = |i: usize| ((i % W) as isize, (i / W) as isize);
//! let d: Vec<_> = (0..W * H).map(|i| {
//!     let (x, y) = xy(i);
//!     from_pixels(if inside(x, y) { 9 } else { 2 })
//! }).collect();
//! let c: Vec<_> = (0..W * H).map(|i| {
//!     let (x, y) = xy(i);
//!     let ring = inside(x, y) && !(inside(x - 1, y) && inside(x + 1, y) && inside(x, y - 1) && inside(x, y + 1));
//!     // Strong on the outline, weak texture inside (C_ObjReg keeps ψ above its mean).
//!     let v = if ring { 40 } else if inside(x, y) { 5 } else { return EdgeCell::OFF };
//!     EdgeCell::on(Conspicuity::from_num(v)).unwrap()
//! }).collect();
//! let (mut maps, mut table) = (vec![0u32; maps_len(W, H)], vec![0u32; table_len(W, H)]);
//! let mut bufs = SegmentBuffers::new(W, H, &mut maps, &mut table).unwrap();
//! let mut masks = vec![false; W * H];
//! let d = ImageView::packed(&d, W, H).unwrap();
//! let c = ImageView::packed(&c, W, H).unwrap();
//! let report = segment(&SegmentParams::default(), &d, &c, &mut bufs, &mut masks).unwrap();
//! let obj = report.objects[0];
//! assert_eq!(obj.delta, 9);
//! assert_eq!(obj.area, 140);
//! assert_eq!(obj.bbox, Some(BoundingBox { x: 10, y: 7, width: 14, height: 10 }));
//! ```

mod bits;
mod buffers;
mod depth;
mod ground;
mod holes;
mod label;
mod masks;
mod morph;
mod parts;
mod passes;
mod pipeline;
mod refine;
mod relabel;
mod stats;

pub use bits::{
    bit_map_len, clear_square_bits, closing_map_len, row_runs, run_capacity, square_bits,
    words_per_row, BitView, MAX_CLOSING_STEPS,
};
pub use buffers::{maps_len, scratch_bytes, table_len, SegmentBuffers, BIT_MAPS};
pub use depth::{segment_with_depth_pass, DepthPass};
pub use ground::{fit_ground, ground_rows_len, inhibit_ground, GroundLine, MAX_SLOPE, MIN_SLOPE};
pub use holes::{open_depth_hole, DepthHole, Holes};
pub use label::{area_filter, fill_holes, label_capacity, AreaReport, Connectivity, Labeller};
pub use morph::{
    close, closing_size, dilate, dilate_n, erode, erode_n, non_max_suppression, Disk,
    NMS_DIRECTIONS,
};
pub use pipeline::{
    bounding_box, inhibit, refine_border, segment, segment_into, segment_timed, BoundingBox,
    Detection, Masks, SegmentObserver, SegmentReport, Step,
};
pub use refine::Refine;
pub use relabel::{relabel_len, relabel_object, Relabel};
pub use stats::{
    above_mean, foreground, foreground_conspicuity, foreground_rows, in_selected_area,
    object_conspicuity, object_region, plane, select_slice, selected_area, selected_bounds,
    selected_stats, slice_cells, slice_counts, slice_radius, slice_range, thresholds,
    DisparityRange, PsiMean, SelectedStats, Slice, SliceCounts, Thresholds, PLANES, STAT_FRAC_BITS,
};

use crate::image::ImageError;
use core::fmt;

/// Most objects [`segment`] reports.
pub const MAX_OBJECTS: usize = 8;

/// A non-negative rational `num / den`, for the paper's constants.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ratio {
    /// Numerator.
    pub num: u16,
    /// Denominator (must not be 0).
    pub den: u16,
}

impl Ratio {
    /// `num / den`.
    pub const fn new(num: u16, den: u16) -> Self {
        Self { num, den }
    }
}

/// Every parameter of the stage, with the paper's defaults.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SegmentParams {
    /// Height fraction of the top and of the bottom strip left out of S (1/6).
    pub top_bottom_strip: Ratio,
    /// Width fraction of the left strip left out of S (1/8).
    pub left_strip: Ratio,
    /// D_fg lower bound, σ_S above mean_S (0.1), exclusive.
    pub fg_low: Ratio,
    /// D_fg upper bound, σ_S above mean_S (2), exclusive.
    pub fg_high: Ratio,
    /// r / σ_S (the paper's r = σ_S / 2.5, so 2/5).
    pub range: Ratio,
    /// The exponent A of δ = argmax A^C(d)·d^A (undefined in the paper;
    /// default 1). At most 8.
    pub exponent: u8,
    /// Which cells ψ̄ averages over (the paper is silent; see [`PsiMean`]).
    pub psi_mean: PsiMean,
    /// Structuring element of every dilation and erosion.
    pub disk: Disk,
    /// Dilations before the border refinement's largest component (4).
    pub refine_dilations: u8,
    /// Dilations, then as many erosions, of the closing (4), at most
    /// [`MAX_CLOSING_STEPS`]. The closing is the unbounded plane's: the
    /// frame is padded by OFF pixels ([`close`]).
    pub closing_steps: u8,
    /// A filled region is kept when its area is at least this fraction of
    /// the largest one's (1/5).
    pub min_area: Ratio,
    /// Objects to extract, 1 (the paper) to [`MAX_OBJECTS`].
    pub max_objects: u8,
    /// Ground-plane inhibition: when a ground line is found
    /// ([`fit_ground`]), the D_fg cells at most this many disparity bits
    /// (1/256 px) nearer than it are OFF ([`inhibit_ground`]). `None`: no
    /// inhibition (the paper). At most [`MAX_GROUND_BAND`].
    pub ground_band: Option<u16>,
    /// Background inhibition by rows: a cell of S nearer than its row's
    /// dominant disparity (the row estimate of [`fit_ground`], a wall's or
    /// the ground's) by more than this many disparity bits (1/256 px) is
    /// foreground even under the band's lower bound (never over its upper
    /// one), so that an object in front of a far wall counts though it is
    /// farther than the frame's mean. `None`: the paper's band alone. At
    /// most [`MAX_GROUND_BAND`].
    pub row_background: Option<u16>,
    /// Least mask area of an object, a fraction of the frame's area
    /// (at most 1). A search whose mask is smaller is inhibited like any
    /// other but is not an object and does not count towards
    /// `max_objects`; at most [`SEARCHES_PER_OBJECT`] · `max_objects`
    /// searches run. 0 (the paper): every mask is an object.
    pub min_object: Ratio,
    /// Widest object box, a fraction of the frame's width (above 0, at
    /// most 1). A wider mask (a horizon, a wall's edge across the frame)
    /// is not an object, as with `min_object`. 1 (the paper): any width.
    pub max_object_width: Ratio,
    /// Most elongated object box: a mask whose box's longer side is more
    /// than this many times its shorter side (a strip along the horizon,
    /// a wall's edge) is not an object, as with `min_object`. 0 (the
    /// paper): any shape.
    pub max_aspect: u8,
    /// Whether the solid interiors of one search's mask (several objects
    /// of one slice whose contours touch) are each an object of their own.
    /// `false`: the paper.
    pub split_interiors: bool,
    /// Least slice radius r, disparity bits (1/256 px): the slice is
    /// `[δ − r, δ + r]` with r at least this. δ is chosen from the counts
    /// of the whole-px planes δ − 1 to δ + 1 ([`slice_cells`]) and the
    /// completion writes whole px, so a slice narrower than ±1 px can
    /// leave out cells counted for it. 0 (the paper): r = σ_S · `range`
    /// alone. At most [`MAX_GROUND_BAND`].
    pub min_slice_radius: u16,
    /// The depth pass: when the searches on C found fewer than
    /// `max_objects` objects, the disparity map's slices that stand above
    /// their rows' background are objects too, no contour needed
    /// ([`segment_with_depth_pass`], [`DepthPass`]). `None` (the paper):
    /// C alone.
    pub depth_pass: Option<DepthPass>,
}

/// Searches [`segment`] runs per object of `max_objects` at most, when
/// some masks are not objects ([`SegmentParams::min_object`],
/// [`SegmentParams::max_object_width`], [`SegmentParams::max_aspect`]).
pub const SEARCHES_PER_OBJECT: usize = 2;

/// Largest [`SegmentParams::ground_band`]: 16 px.
pub const MAX_GROUND_BAND: u16 = 16 * 256;

impl Default for SegmentParams {
    fn default() -> Self {
        Self::PAPER
    }
}

impl SegmentParams {
    /// The paper's values (A = 1, ψ̄ over the region, which the paper
    /// leaves open), one object.
    pub const PAPER: Self = Self {
        top_bottom_strip: Ratio::new(1, 6),
        left_strip: Ratio::new(1, 8),
        fg_low: Ratio::new(1, 10),
        fg_high: Ratio::new(2, 1),
        range: Ratio::new(2, 5),
        exponent: 1,
        psi_mean: PsiMean::Region,
        disk: Disk::Cross,
        refine_dilations: 4,
        closing_steps: 4,
        min_area: Ratio::new(1, 5),
        max_objects: 1,
        ground_band: None,
        row_background: None,
        min_object: Ratio::new(0, 1),
        max_object_width: Ratio::new(1, 1),
        max_aspect: 0,
        split_interiors: false,
        min_slice_radius: 0,
        depth_pass: None,
    };

    /// Checks the parameters.
    ///
    /// # Errors
    /// [`SegmentError::BadParams`] naming the first bad field.
    pub fn validate(&self) -> Result<(), SegmentError> {
        let ratios = [
            ("top_bottom_strip", self.top_bottom_strip),
            ("left_strip", self.left_strip),
            ("fg_low", self.fg_low),
            ("fg_high", self.fg_high),
            ("range", self.range),
            ("min_area", self.min_area),
            ("min_object", self.min_object),
            ("max_object_width", self.max_object_width),
        ];
        if let Some((name, _)) = ratios.iter().find(|(_, r)| r.den == 0) {
            return Err(SegmentError::BadParams(name));
        }
        // Each strip at most a half, so S is not empty by construction.
        if 2 * u32::from(self.top_bottom_strip.num) >= u32::from(self.top_bottom_strip.den) {
            return Err(SegmentError::BadParams("top_bottom_strip"));
        }
        if self.left_strip.num >= self.left_strip.den {
            return Err(SegmentError::BadParams("left_strip"));
        }
        // A least area above the frame, or a widest box of 0, would
        // reject every object.
        if self.min_object.num > self.min_object.den {
            return Err(SegmentError::BadParams("min_object"));
        }
        let mw = self.max_object_width;
        if mw.num == 0 || mw.num > mw.den {
            return Err(SegmentError::BadParams("max_object_width"));
        }
        if self.ground_band.is_some_and(|b| b > MAX_GROUND_BAND) {
            return Err(SegmentError::BadParams("ground_band"));
        }
        if self.row_background.is_some_and(|b| b > MAX_GROUND_BAND) {
            return Err(SegmentError::BadParams("row_background"));
        }
        if self.min_slice_radius > MAX_GROUND_BAND {
            return Err(SegmentError::BadParams("min_slice_radius"));
        }
        if self.closing_steps > MAX_CLOSING_STEPS {
            return Err(SegmentError::BadParams("closing_steps"));
        }
        if self.exponent > 8 {
            return Err(SegmentError::BadParams("exponent"));
        }
        if self.max_objects == 0 || usize::from(self.max_objects) > MAX_OBJECTS {
            return Err(SegmentError::BadParams("max_objects"));
        }
        if let Some(pass) = &self.depth_pass {
            pass.validate()?;
        }
        Ok(())
    }

    /// Whether every mask is an object (the paper): no least area, no
    /// widest box and no most elongated box, so one search per object.
    pub fn every_mask_is_an_object(&self) -> bool {
        self.min_object.num == 0
            && self.max_object_width.num >= self.max_object_width.den
            && self.max_aspect == 0
    }

    /// Whether `area` px is at least an object's least area in a `width`
    /// x `height` frame: `min_object` of the frame (by products, no
    /// division).
    pub fn large_enough(&self, area: u64, width: usize, height: usize) -> bool {
        let mo = self.min_object;
        let frame = u64::try_from(width * height).unwrap_or(u64::MAX);
        area.saturating_mul(u64::from(mo.den)) >= frame.saturating_mul(u64::from(mo.num))
    }

    /// Whether a mask of `area` px with a `box_width` x `box_height` box is
    /// an object in a `width` x `height` frame: at least `min_object` of
    /// the frame, at most `max_object_width` of its width, and at most
    /// `max_aspect` times as long as it is wide (either way).
    pub fn is_object(
        &self,
        area: u32,
        (box_width, box_height): (usize, usize),
        (width, height): (usize, usize),
    ) -> bool {
        let mw = self.max_object_width;
        let a = usize::from(self.max_aspect);
        self.large_enough(u64::from(area), width, height)
            && box_width * usize::from(mw.den) <= width * usize::from(mw.num)
            && (a == 0 || (box_width <= a * box_height && box_height <= a * box_width))
    }
}

/// Errors of the segmentation stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum SegmentError {
    /// A buffer cannot be viewed as an image of the working size.
    Image(ImageError),
    /// Two maps differ in size.
    SizeMismatch {
        /// The expected `(width, height)`.
        expected: (usize, usize),
        /// The given `(width, height)`.
        got: (usize, usize),
    },
    /// A labelling needs more provisional labels than the tables hold.
    LabelCapacity {
        /// Table entries available (label 0 included).
        capacity: usize,
    },
    /// The mask buffer cannot hold `max_objects` masks.
    MasksTooSmall {
        /// Elements needed.
        needed: usize,
        /// Elements given.
        got: usize,
    },
    /// A parameter is out of range; the field's name.
    BadParams(&'static str),
}

impl fmt::Display for SegmentError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Image(e) => write!(f, "segmentation buffer: {e}"),
            Self::SizeMismatch { expected, got } => write!(
                f,
                "map is {}x{}, expected {}x{}",
                got.0, got.1, expected.0, expected.1
            ),
            Self::LabelCapacity { capacity } => write!(
                f,
                "connected components need more than {capacity} label table entries"
            ),
            Self::MasksTooSmall { needed, got } => {
                write!(f, "mask buffer holds {got} pixels, needs {needed}")
            }
            Self::BadParams(name) => write!(f, "segmentation parameter `{name}` is out of range"),
        }
    }
}

impl core::error::Error for SegmentError {}

impl From<ImageError> for SegmentError {
    fn from(e: ImageError) -> Self {
        Self::Image(e)
    }
}

fn check_size(expected: (usize, usize), got: (usize, usize)) -> Result<(), SegmentError> {
    if expected == got {
        Ok(())
    } else {
        Err(SegmentError::SizeMismatch { expected, got })
    }
}
