//! Every parameter of a run ([`PipelineParams`]) and the named settings
//! ([`PipelineParams::NAMED`]: the paper's, the default, the accurate).

use crate::complete::CompleteParams;
use crate::conspicuity::EdgeParams;
use crate::segment::{DepthHole, DepthPass, Ratio, Relabel, SegmentParams};
use crate::stereo::c2f::C2fParams;

/// The classifier sizes a workspace is laid out for: any model with at most
/// this many hidden units and classes (and [`SHAPE_LEN`](crate::shape::SHAPE_LEN) inputs) runs in it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ModelCapacity {
    /// Hidden units.
    pub hidden: u16,
    /// Classes.
    pub classes: u16,
}

/// Every parameter of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PipelineParams {
    /// The stereo engine's operating point (its `dem.max_disp` is the
    /// largest disparity, px).
    pub stereo: C2fParams,
    /// Smoothing and the edge threshold.
    pub edges: EdgeParams,
    /// The completion of the disparity over the conspicuity regions.
    pub complete: CompleteParams,
    /// Figure-ground; `max_objects` is K, the objects searched (1..=8).
    pub segment: SegmentParams,
    /// The acceptance threshold Δ of identification, a Q16 cosine
    /// (65536 = 1); `None` takes the model's own.
    pub delta_q16: Option<u32>,
    /// The largest classifier the workspace holds.
    pub model: ModelCapacity,
    /// The mirror check ([`crate::mlp::mirror`]): also run the classifier
    /// on each object's mirror images that some class looks the same
    /// under (the model's per-class symmetry) and score each class on its
    /// mean output over the object and its own mirrors. Up to two more
    /// forward passes per object (about 0.28 M M4 instructions each with
    /// the shipped 720-256-19 model) and [`crate::mlp::mirror_scratch_bytes`]
    /// of workspace; nothing changes with a model without symmetry.
    pub mirror_check: bool,
    /// With the mirror check, the bar under which an object's own best
    /// cosine (Q16, 65536 = 1) sends it to the check
    /// ([`crate::mlp::mirror_check_below_with`]); an object at or above
    /// it keeps the plain ranking, after one forward pass. `u32::MAX`:
    /// every object.
    pub mirror_below_q16: u32,
    /// The band relabelling of masks whose outline C does not follow
    /// ([`crate::segment::relabel_object`]): colour and stereo matching
    /// with a smoothness term re-decide the cells near the outline. Both
    /// eyes' rows are read again; [`crate::segment::relabel_len`] words
    /// of workspace. `None`: off.
    pub relabel: Option<Relabel>,
    /// The hole by disparity, after the relabelling
    /// ([`crate::segment::open_depth_hole`]): the cells behind an
    /// object's slice at the centre of its box leave its mask (a ring's
    /// hole, which neither the colour nor the relabelling keeps). `None`:
    /// off.
    pub depth_hole: Option<DepthHole>,
}

/// [`PipelineParams::mirror_below_q16`] of the default: 0.95. On the
/// training scenes the objects under it are about a fifth of those
/// found, and they hold what the check changes (docs/CLASSIFY.md, "Only
/// the unsure objects, in the default").
pub const MIRROR_BELOW_DEFAULT: u32 = 62_259;

/// The stereo point the pipeline runs by default,
/// [`C2fParams::HALF_NARROW`]: the half-size search, each cell spread
/// over its 2x2 block, with a low SGM penalty that keeps small objects'
/// disparity steps (docs/PIPELINE.md, "The stereo point") and Gabor
/// kernels of 5 taps, whose disparity spreads less beyond an object's
/// outline (docs/CHOICES.md, "Narrow filters").
pub const STEREO_DEFAULT: C2fParams = C2fParams::HALF_NARROW;

impl PipelineParams {
    /// The paper's settings: [`C2fParams::HALF_LOW_PENALTY`] (the
    /// design's 15-tap kernels) with 32 disparities, the
    /// paper's conspicuity and figure-ground values (the foreground band
    /// mean + 0.1σ .. mean + 2σ, r = σ/2.5, A = 1), one object, the
    /// model's Δ, and room for classifiers up to 2048 hidden units and 64
    /// classes.
    pub const PAPER: Self = Self {
        stereo: C2fParams::HALF_LOW_PENALTY,
        edges: EdgeParams::DEFAULT,
        complete: CompleteParams::MEDIAN,
        segment: SegmentParams::PAPER,
        delta_q16: None,
        model: ModelCapacity {
            hidden: 2048,
            classes: 64,
        },
        mirror_check: false,
        mirror_below_q16: u32::MAX,
        relabel: None,
        depth_hole: None,
    };

    /// The default: [`PipelineParams::PAPER`] without the foreground
    /// band's upper cut, which treats the nearest objects as wrong
    /// estimates; with the foreground over the whole frame but its left
    /// sixteenth (the paper leaves out the top and bottom sixths and the
    /// left eighth, cutting objects near the border); with the ground
    /// plane inhibited up to 4 px above its fitted line; and with masks
    /// under 1/128 of the frame, boxes over 3/4 of its width or boxes more
    /// than 4 times as long as wide not taken as objects; with cells 2 px
    /// nearer than their row's background foreground too
    /// ([`SegmentParams::row_background`]); and touching objects of one
    /// slice split along their contours
    /// ([`SegmentParams::split_interiors`]); with an object's slice at
    /// least ±1 px wide ([`SegmentParams::min_slice_radius`]); and tall
    /// regions completed along their tilt ([`CompleteParams::tilt_rows`],
    /// fitted near their median, [`CompleteParams::tilt_band`]); with the
    /// stereo's narrow filters ([`STEREO_DEFAULT`]); and the depth pass
    /// for what C does not outline ([`SegmentParams::depth_pass`];
    /// docs/CHOICES.md); and the mirror check for the objects whose own
    /// best cosine is under 0.95 ([`MIRROR_BELOW_DEFAULT`]).
    pub const DEFAULT: Self = Self {
        stereo: STEREO_DEFAULT,
        complete: CompleteParams::DEFAULT,
        segment: SegmentParams {
            fg_high: Ratio::new(100, 1),
            top_bottom_strip: Ratio::new(0, 1),
            left_strip: Ratio::new(1, 16),
            ground_band: Some(4 * 256),
            min_object: Ratio::new(1, 128),
            max_object_width: Ratio::new(3, 4),
            max_aspect: 4,
            split_interiors: true,
            row_background: Some(2 * 256),
            min_slice_radius: 256,
            depth_pass: Some(DepthPass::DEFAULT),
            ..Self::PAPER.segment
        },
        mirror_check: true,
        mirror_below_q16: MIRROR_BELOW_DEFAULT,
        ..Self::PAPER
    };

    /// **Accurate**: [`PipelineParams::DEFAULT`] with the stereo point
    /// [`C2fParams::FAST_NARROW_FULL_SEARCH`], every disparity searched at
    /// the half-size level instead of coarse to fine from a quarter of the
    /// frame, where small objects average away, and the map refined to
    /// the frame's resolution by phase. More objects found (on 1,000
    /// training-split scenes, K = 4: recall 87.4 → 90.7 %, precision
    /// 95.5 → 96.3 %; docs/PIPELINE.md, "The stereo point") for about 2.5
    /// times the default's M4 instructions a 160x120 frame (the
    /// product's budget is 32 M) and more workspace there: a setting for
    /// boards with several times the cycles. Two decoder tables, levels 0
    /// and 1 of the default's. With the mirror check
    /// ([`PipelineParams::mirror_check`]) for every object, where the
    /// default's budget holds it for the unsure ones, the band
    /// relabelling of low-contrast masks ([`Relabel::DEFAULT`]) and the
    /// hole by disparity ([`DepthHole::DEFAULT`]).
    pub const ACCURATE: Self = Self {
        stereo: C2fParams::FAST_NARROW_FULL_SEARCH,
        mirror_below_q16: u32::MAX,
        relabel: Some(Relabel::DEFAULT),
        depth_hole: Some(DepthHole::DEFAULT),
        ..Self::DEFAULT
    };

    /// The named settings, by the name the CLI takes.
    pub const NAMED: [(&'static str, Self); 3] = [
        ("default", Self::DEFAULT),
        ("paper", Self::PAPER),
        ("accurate", Self::ACCURATE),
    ];

    /// The named setting `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        crate::named::by_name(&Self::NAMED, name)
    }

    /// The name of these parameters if they are a named setting
    /// ([`PipelineParams::NAMED`]; with its own K or largest disparity a
    /// setting is no longer the named one).
    pub fn name(&self) -> Option<&'static str> {
        crate::named::name_of(&Self::NAMED, self)
    }

    /// These parameters searching `k` objects.
    #[must_use]
    pub const fn with_objects(mut self, k: u8) -> Self {
        self.segment.max_objects = k;
        self
    }

    /// These parameters with `d` as the largest disparity, px.
    #[must_use]
    pub const fn with_max_disp(mut self, d: u8) -> Self {
        self.stereo.dem.max_disp = d;
        self
    }

    /// These parameters with the mirror check on or off.
    #[must_use]
    pub const fn with_mirror_check(mut self, on: bool) -> Self {
        self.mirror_check = on;
        self
    }

    /// The largest disparity, px.
    pub const fn max_disp(&self) -> u8 {
        self.stereo.dem.max_disp
    }

    /// Decoder tables the stereo engine needs: one per level.
    pub const fn tables(&self) -> usize {
        self.stereo.coarse as usize + 1
    }
}

impl Default for PipelineParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}
