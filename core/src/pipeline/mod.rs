//! The whole job in one call: a rectified stereo pair in, up to K
//! categorised proto-objects out, most salient first.
//!
//! ```text
//! left, right ─► stereo (c2f) ─► D ──────────────┐
//! left ────────► CIELUV, smoothing, C ─► complete D over C's regions
//!                                          └─► segment (K searches) ─► per object:
//!                                              mask, box, slice ─► shape vector ─► MLP
//!                                              ─► top-5 cosines, known/unknown against Δ
//! ```
//!
//! A [`Pipeline`] is set up once from [`PipelineParams`] and the borrowed
//! assets: one DEM decoder table per stereo level and the classifier's
//! model blob. [`Pipeline::run`] then takes the two frames (anything that
//! gives RGB rows: an [`ImageView`] or a camera's format, see
//! [`RgbRows`]) and one workspace of [`workspace_bytes`] (as `u64` words,
//! [`workspace_words`]), and nothing else: every stage works inside it,
//! reusing the scratch of the stages before ([`layout`]).
//!
//! ```
//! use protogist::image::{ImageView, ImageViewMut, Rgb8};
//! use protogist::pipeline::{workspace_words, Pipeline, PipelineParams};
//! # use protogist::synth::{render_left, render_right, SceneSpec};
//! # let tables: [&[u8]; 3] = [
//! #     include_bytes!("../../../firmware-sim/data/dem_c2f_narrow_l0.bin"),
//! #     include_bytes!("../../../firmware-sim/data/dem_c2f_narrow_l1.bin"),
//! #     include_bytes!("../../../firmware-sim/data/dem_c2f_narrow_l2.bin"),
//! # ];
//! # let model: &[u8] = include_bytes!("../../../host/data/shapes_model.bin");
//! let (w, h) = (160, 120);
//! # let (mut l, mut r) = (vec![Rgb8::default(); w * h], vec![Rgb8::default(); w * h]);
//! # render_left(&SceneSpec::demo(w, h), &mut ImageViewMut::packed(&mut l, w, h)?).unwrap();
//! # render_right(&SceneSpec::demo(w, h), &mut ImageViewMut::packed(&mut r, w, h)?).unwrap();
//! let params = PipelineParams::DEFAULT.with_objects(4);
//! let pipeline = Pipeline::new(&params, &tables, model)?;
//! let mut ws = vec![0u64; workspace_words(w, h, &params)];
//! let frame = pipeline.run(&ImageView::packed(&l, w, h)?, &ImageView::packed(&r, w, h)?, &mut ws)?;
//! for o in frame.objects() {
//!     let best = o.top().first().map(|r| pipeline.class_name(r.class));
//!     println!("{:?} at {:?}, disparity {} px: {:?}", best, o.bbox, o.delta, o.identity);
//! }
//! # assert_eq!(frame.objects().len(), 1);
//! # Ok::<(), protogist::pipeline::PipelineError>(())
//! ```
//!
//! Intermediate maps go to an [`Observer`] ([`Pipeline::run_observed`]),
//! whose methods do nothing by default, so an unobserved run pays nothing.

mod arena;
mod error;
mod frame;
pub mod layout;
mod params;
mod run;

use crate::conspicuity::{ColourKernel, EdgeCell, Luv};
use crate::disparity::DisparityCell;
use crate::image::ImageView;
use crate::mlp::blob::Model;
use crate::mlp::MacKernel;
use crate::segment::{Detection, SegmentBuffers};
use crate::shape::SHAPE_LEN;
use crate::stereo::c2f::{C2f, MAX_COARSE};
use crate::stereo::phase::{PhaseKernel, SafePhase};
use crate::stereo::DemTable;

pub use crate::stereo::c2f::RgbRows;
pub use error::{PipelineError, Region};
pub use frame::{Frame, Object};
pub use layout::{kept_bytes, shared_bytes};
pub use params::{ModelCapacity, PipelineParams, MIRROR_BELOW_DEFAULT, STEREO_DEFAULT};

/// Most objects one run reports.
pub const MAX_OBJECTS: usize = crate::segment::MAX_OBJECTS;
/// Ranked categories per object.
pub const TOP_K: usize = 5;

/// Bytes of the workspace of a `width` x `height` run.
pub const fn workspace_bytes(width: usize, height: usize, params: &PipelineParams) -> usize {
    kept_bytes(width, height, params) + shared_bytes(width, height, params)
}

/// [`workspace_bytes`] as `u64` words, the unit [`Pipeline::run`] takes.
pub const fn workspace_words(width: usize, height: usize, params: &PipelineParams) -> usize {
    workspace_bytes(width, height, params).div_ceil(8)
}

/// Bytes of the workspace's first part, the maps kept for the result
/// (the edge map C, the completed disparity, and per object a bit mask and
/// a shape vector), as `u64` words: the `kept` slice of
/// [`Pipeline::run_split`].
pub const fn kept_words(width: usize, height: usize, params: &PipelineParams) -> usize {
    layout::kept_bytes(width, height, params).div_ceil(8)
}

/// The workspace's second part, the region the stages share in turn, as
/// `u64` words: the `shared` slice of [`Pipeline::run_split`].
/// `kept_words + shared_words == workspace_words`.
pub const fn shared_words(width: usize, height: usize, params: &PipelineParams) -> usize {
    layout::shared_bytes(width, height, params).div_ceil(8)
}

/// The stages of a run, in order, as [`Observer::enter`] reports them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// The stereo engine.
    Stereo,
    /// CIELUV, smoothing, C~ and the threshold.
    Conspicuity,
    /// The completion of the disparity over the conspicuity regions.
    Complete,
    /// Figure-ground, every object.
    Segment,
    /// Shape vectors.
    Shape,
    /// The classifier and the ranking.
    Classify,
    /// The run is over.
    Done,
}

/// Sees the intermediate maps of a run (for panels, tests and timing).
/// Every method does nothing by default.
pub trait Observer {
    /// A stage starts (and so the one before it ends).
    fn enter(&mut self, _stage: Stage) {}
    /// A step of the stereo engine starts.
    fn stereo_step(&mut self, _step: crate::stereo::Step) {}
    /// A step of figure-ground is done (figure-ground tells its steps as
    /// they end; the stereo engine, as they start).
    fn segment_step(&mut self, _step: crate::segment::Step) {}
    /// The stereo engine's map.
    fn raw_disparity(&mut self, _map: &ImageView<'_, DisparityCell>) {}
    /// Row `y` of the smoothed CIELUV map, rows in order (the stage runs
    /// on a rolling window of rows: no full map exists).
    fn smoothed_row(&mut self, _y: usize, _row: &[Luv]) {}
    /// The edge map C.
    fn conspicuity(&mut self, _edges: &ImageView<'_, EdgeCell>) {}
    /// The completed disparity, as segmentation takes it.
    fn disparity(&mut self, _map: &ImageView<'_, DisparityCell>) {}
    /// One figure-ground search (rank `det.index`), with every map of its
    /// search, before it is inhibited.
    fn object(&mut self, _det: &Detection, _maps: &SegmentBuffers<'_>) {}
}

impl Observer for () {}

/// The set-up pipeline: checked parameters, stereo kernels, colour
/// tables, the parsed decoder tables and model. `K` is the stereo phase
/// refinement's row step ([`PhaseKernel`]), the colour stage's hot
/// loops ([`ColourKernel`]) and the classifier's dot products
/// ([`MacKernel`]): the portable [`SafePhase`] from
/// [`Pipeline::new`], a target's own (e.g. the firmware's assembly one)
/// from [`Pipeline::with_kernel`]; the same bits either way.
#[derive(Clone, Debug)]
pub struct Pipeline<'a, K = SafePhase> {
    params: PipelineParams,
    c2f: C2f<K>,
    tables: heapless::Vec<DemTable<'a>, { MAX_COARSE + 1 }>,
    model: Model<'a>,
    delta_q16: u32,
}

impl<'a> Pipeline<'a> {
    /// Checks `params`, parses the decoder tables (level 0 first) and the
    /// model blob, and sets up the stereo kernels (one-time setup), with
    /// the portable phase step [`SafePhase`].
    ///
    /// # Errors
    /// [`PipelineError::BadParams`] (K not in 1..=8, …),
    /// [`PipelineError::TableCount`], [`PipelineError::Table`],
    /// [`PipelineError::Model`], [`PipelineError::ModelMismatch`], and the
    /// stereo engine's [`StereoError::BadParams`](crate::stereo::StereoError::BadParams).
    pub fn new(
        params: &PipelineParams,
        tables: &[&'a [u8]],
        model: &'a [u8],
    ) -> Result<Self, PipelineError> {
        Self::with_kernel(params, tables, model)
    }
}

impl<'a, K: PhaseKernel> Pipeline<'a, K> {
    /// [`Pipeline::new`] with the stereo phase refinement's row step by
    /// kernel `K` (e.g. the firmware's assembly one).
    ///
    /// # Errors
    /// As [`Pipeline::new`].
    pub fn with_kernel(
        params: &PipelineParams,
        tables: &[&'a [u8]],
        model: &'a [u8],
    ) -> Result<Self, PipelineError> {
        let k = usize::from(params.segment.max_objects);
        if !(1..=MAX_OBJECTS).contains(&k) {
            return Err(PipelineError::BadParams("objects (K) must be 1..=8"));
        }
        params.segment.validate()?;
        if let Some(r) = &params.relabel {
            r.validate()?;
        }
        if let Some(d) = &params.depth_hole {
            d.validate()?;
        }
        if params.edges.threshold_percent > 100 {
            return Err(PipelineError::BadParams("edge threshold above 100 %"));
        }
        let c2f = C2f::with_kernel(&params.stereo)?;
        if tables.len() != params.tables() {
            return Err(PipelineError::TableCount {
                expected: params.tables(),
                got: tables.len(),
            });
        }
        let mut parsed = heapless::Vec::new();
        for t in tables {
            let t = DemTable::parse(t)?;
            parsed
                .push(t)
                .map_err(|_| PipelineError::BadParams("too many decoder tables"))?;
        }
        let model = Model::parse(model)?;
        let fits = [
            (
                "inputs",
                SHAPE_LEN,
                model.inputs(),
                model.inputs() == SHAPE_LEN,
            ),
            (
                "hidden",
                usize::from(params.model.hidden),
                model.hidden(),
                model.hidden() <= usize::from(params.model.hidden),
            ),
            (
                "classes",
                usize::from(params.model.classes),
                model.classes(),
                model.classes() <= usize::from(params.model.classes),
            ),
        ];
        if let Some(&(what, expected, got, _)) = fits.iter().find(|f| !f.3) {
            return Err(PipelineError::ModelMismatch {
                what,
                expected,
                got,
            });
        }
        Ok(Self {
            params: *params,
            c2f,
            tables: parsed,
            delta_q16: params.delta_q16.unwrap_or(model.delta_q16()),
            model,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &PipelineParams {
        &self.params
    }

    /// The classifier.
    pub fn model(&self) -> &Model<'a> {
        &self.model
    }

    /// Class `c`'s name (`"?"` past the model's classes).
    pub fn class_name(&self, c: u16) -> &'a str {
        self.model.class_name(usize::from(c)).unwrap_or("?")
    }

    /// The acceptance threshold Δ in force, Q16.
    pub fn delta_q16(&self) -> u32 {
        self.delta_q16
    }
}

/// The kernels a pipeline runs: the stereo engine's ([`PhaseKernel`]), the
/// colour stage's ([`ColourKernel`]) and the classifier's ([`MacKernel`]).
/// Every type that is all three is one.
pub trait Kernels: PhaseKernel + ColourKernel + MacKernel {}

impl<K: PhaseKernel + ColourKernel + MacKernel> Kernels for K {}

impl<K: Kernels> Pipeline<'_, K> {
    /// Runs a frame pair through every stage (see the module docs).
    ///
    /// # Errors
    /// [`PipelineError::Stereo`] for frames of different sizes or too
    /// small for the engine, [`PipelineError::WorkspaceTooSmall`] with the
    /// bytes needed; both before any work. A frame with no object is an
    /// empty result, not an error.
    pub fn run<'w, S: RgbRows>(
        &self,
        left: &S,
        right: &S,
        workspace: &'w mut [u64],
    ) -> Result<Frame<'w>, PipelineError> {
        self.run_observed(left, right, workspace, &mut ())
    }

    /// [`Pipeline::run`], showing the intermediate maps to `observer`.
    ///
    /// # Errors
    /// As [`Pipeline::run`].
    pub fn run_observed<'w, S: RgbRows, O: Observer>(
        &self,
        left: &S,
        right: &S,
        workspace: &'w mut [u64],
        observer: &mut O,
    ) -> Result<Frame<'w>, PipelineError> {
        run::run(self, left, right, run::Depth::Stereo, workspace, observer)
    }

    /// [`Pipeline::run`] with the disparity of the left view given:
    /// `disparity` (the frames' size, OFF where unknown) takes the place
    /// of the stereo engine's map and of its completion, and every stage
    /// after them runs as in [`Pipeline::run`], the right frame serving
    /// the band relabelling's matching. For boards whose depth comes from
    /// elsewhere (a stereo ASIC, a depth camera registered to the left
    /// view), and for the benchmark's upper bound of the stereo stage
    /// (`protogist gist-eval --mode gt-disparity`). The workspace is
    /// [`workspace_bytes`], as for [`Pipeline::run`].
    ///
    /// # Errors
    /// [`PipelineError::Image`] when the right frame or `disparity` is not
    /// the left frame's size, or for a zero or too large size;
    /// [`PipelineError::WorkspaceTooSmall`] with the bytes needed; both
    /// before any work.
    pub fn run_with_disparity<'w, S: RgbRows>(
        &self,
        left: &S,
        right: &S,
        disparity: &ImageView<'_, DisparityCell>,
        workspace: &'w mut [u64],
    ) -> Result<Frame<'w>, PipelineError> {
        self.run_with_disparity_observed(left, right, disparity, workspace, &mut ())
    }

    /// [`Pipeline::run_with_disparity`], showing the intermediate maps to
    /// `observer` (the given map as the raw disparity).
    ///
    /// # Errors
    /// As [`Pipeline::run_with_disparity`].
    pub fn run_with_disparity_observed<'w, S: RgbRows, O: Observer>(
        &self,
        left: &S,
        right: &S,
        disparity: &ImageView<'_, DisparityCell>,
        workspace: &'w mut [u64],
        observer: &mut O,
    ) -> Result<Frame<'w>, PipelineError> {
        run::run(
            self,
            left,
            right,
            run::Depth::Given(disparity),
            workspace,
            observer,
        )
    }

    /// [`Pipeline::run`] in a workspace of two slices, for boards whose
    /// RAM comes in parts: `kept` ([`kept_words`]) holds the maps the
    /// result borrows, `shared` ([`shared_words`]) the stages' scratch. On
    /// the STM32F405 the kept maps fit the core-coupled RAM, which no DMA
    /// reaches, and the frames stay in the SRAM (docs/PIPELINE.md).
    ///
    /// # Errors
    /// As [`Pipeline::run`], with [`PipelineError::RegionTooSmall`] for
    /// a short part.
    pub fn run_split<'w, S: RgbRows>(
        &self,
        left: &S,
        right: &S,
        kept: &'w mut [u64],
        shared: &'w mut [u64],
    ) -> Result<Frame<'w>, PipelineError> {
        self.run_split_observed(left, right, kept, shared, &mut ())
    }

    /// [`Pipeline::run_split`], showing the intermediate maps to
    /// `observer`.
    ///
    /// # Errors
    /// As [`Pipeline::run_split`].
    pub fn run_split_observed<'w, S: RgbRows, O: Observer>(
        &self,
        left: &S,
        right: &S,
        kept: &'w mut [u64],
        shared: &'w mut [u64],
        observer: &mut O,
    ) -> Result<Frame<'w>, PipelineError> {
        run::run_split(
            self,
            left,
            right,
            run::Depth::Stereo,
            kept,
            shared,
            observer,
        )
    }
}
