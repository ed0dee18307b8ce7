//! The product on the board: per frame, capture a stereo pair → core's
//! pipeline (`protogist::pipeline`) → report each proto-object → LED.
//!
//! The pair comes from a [`StereoCamera`] in the sensor's RGB565 format;
//! the pipeline reads each eye as RGB rows ([`crate::stereo_camera::Rgb565View`]). Frames and
//! workspace are the caller's (statics in `.bss` on the board, sized by
//! [`FRAME_LEN`] and [`WORKSPACE_WORDS`]); the decoder tables and the
//! model are `const`s in flash ([`crate::assets`]). The report's `product`, `object` and
//! `objects-checksum` lines are what `cargo xtask firmware` compares
//! between the desktop, QEMU and `golden/demo_objects.txt`.

use core::fmt::{self, Write};

use embedded_hal::digital::{self, OutputPin};

use crate::camera::CameraError;
use crate::pg::checksum::Fnv1a;
use crate::pg::image::ImageError;
use crate::pg::mlp::Identity;
use crate::pg::pipeline::{
    self, layout, workspace_bytes, Frame, Kernels, Observer, Pipeline, PipelineError,
    PipelineParams, Stage,
};
use crate::pg::segment::{Step as SegmentStep, STAT_FRAC_BITS};
use crate::pg::stereo::phase::{PhaseKernel, SafePhase};
use crate::pg::stereo::Step as StereoStep;
use crate::stereo_camera::{pair_len, StereoCamera};
use crate::Ticks;

/// Frame width the product runs: 160 on the mps2-an386 build, 128 (the
/// Delft board's frame) with the `f405` feature.
pub const WIDTH: usize = if cfg!(feature = "f405") { 128 } else { 160 };
/// Frame height the product runs: 120, or 96 with the `f405` feature.
pub const HEIGHT: usize = if cfg!(feature = "f405") { 96 } else { 120 };
/// The frame sizes whose RAM plans the product reports
/// ([`write_ram_plans`]): the mps2-an386 build's and the F405's.
pub const PLANNED: [(usize, usize); 2] = [(160, 120), (128, 96)];
/// Objects searched per frame (K).
pub const OBJECTS: u8 = 4;
/// The pipeline's parameters: core's defaults with K = [`OBJECTS`] (with
/// the `accurate` feature, [`PipelineParams::ACCURATE`]'s).
pub const PARAMS: PipelineParams = if cfg!(feature = "accurate") {
    PipelineParams::ACCURATE
} else {
    PipelineParams::DEFAULT
}
.with_objects(OBJECTS);
/// `u64` words of the pipeline's workspace at [`WIDTH`] x [`HEIGHT`].
pub const WORKSPACE_WORDS: usize = pipeline::workspace_words(WIDTH, HEIGHT, &PARAMS);
/// Its first part, the maps kept for the result ([`pipeline::kept_words`]):
/// in the F405's core-coupled RAM on that board.
pub const KEPT_WORDS: usize = pipeline::kept_words(WIDTH, HEIGHT, &PARAMS);
/// Its second part, the region the stages share
/// ([`pipeline::shared_words`]).
pub const SHARED_WORDS: usize = pipeline::shared_words(WIDTH, HEIGHT, &PARAMS);
/// `u16`s of a captured RGB565 pair at [`WIDTH`] x [`HEIGHT`].
pub const FRAME_LEN: usize = pair_len(WIDTH, HEIGHT);

pub use crate::assets::{MODEL, TABLES};

/// The stages of a frame, as the report names them: the capture, then
/// the pipeline's.
pub const STAGES: [&str; 7] = [
    "capture",
    "stereo",
    "conspicuity",
    "complete",
    "segment",
    "shape",
    "classify",
];

fn stage_index(s: Stage) -> Option<usize> {
    match s {
        Stage::Stereo => Some(1),
        Stage::Conspicuity => Some(2),
        Stage::Complete => Some(3),
        Stage::Segment => Some(4),
        Stage::Shape => Some(5),
        Stage::Classify => Some(6),
        Stage::Done => None,
    }
}

/// Ticks per stage of one frame ([`STAGES`] order).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StageTicks(pub [u64; 7]);

/// The steps of the stereo and figure-ground stages, as the report names
/// them. `stereo-readout` includes the phase refinement, which runs on
/// each row the read-out emits.
pub const STEPS: [&str; 14] = [
    "stereo-pyramid",
    "stereo-filters",
    "stereo-energies",
    "stereo-readout",
    "stereo-sgm",
    "seg-foreground",
    "seg-slice",
    "seg-region",
    "seg-refine",
    "seg-nms",
    "seg-close",
    "seg-fill",
    "seg-mask",
    "seg-holes",
];

fn stereo_step_index(s: StereoStep) -> usize {
    match s {
        StereoStep::Pyramid => 0,
        StereoStep::Filters => 1,
        StereoStep::Energies => 2,
        StereoStep::Readout => 3,
        StereoStep::Sgm => 4,
    }
}

fn segment_step_index(s: SegmentStep) -> usize {
    5 + match s {
        SegmentStep::Foreground => 0,
        SegmentStep::Slice => 1,
        SegmentStep::Region => 2,
        SegmentStep::Refine => 3,
        SegmentStep::Nms => 4,
        SegmentStep::Close => 5,
        SegmentStep::Fill => 6,
        SegmentStep::Mask => 7,
        SegmentStep::Holes => 8,
    }
}

/// Ticks per step of one frame ([`STEPS`] order). A stage's steps need not
/// add up to it: its set-up between steps is in none.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepTicks(pub [u64; 14]);

/// Times the pipeline's stages as it enters them, and the steps of stereo
/// (told as they start) and figure-ground (told as they end).
struct StageClock<'t, T: Ticks> {
    ticks: &'t mut T,
    stage: Option<usize>,
    since: u64,
    spent: StageTicks,
    /// The stereo step running, and when the last step mark was.
    step: Option<usize>,
    step_since: u64,
    steps: StepTicks,
}

impl<T: Ticks> StageClock<'_, T> {
    /// Closes the running stereo step at `now`.
    fn close_step(&mut self, now: u64) {
        if let Some(slot) = self.step.and_then(|i| self.steps.0.get_mut(i)) {
            *slot += now - self.step_since;
        }
        self.step = None;
        self.step_since = now;
    }
}

impl<T: Ticks> Observer for StageClock<'_, T> {
    fn enter(&mut self, stage: Stage) {
        let now = self.ticks.now();
        if let Some(slot) = self.stage.and_then(|i| self.spent.0.get_mut(i)) {
            *slot += now - self.since;
        }
        self.close_step(now);
        self.stage = stage_index(stage);
        self.since = now;
    }

    fn stereo_step(&mut self, step: StereoStep) {
        let now = self.ticks.now();
        self.close_step(now);
        self.step = Some(stereo_step_index(step));
    }

    fn segment_step(&mut self, step: SegmentStep) {
        // Told when the step is done: the time since the last mark is its.
        let now = self.ticks.now();
        if let Some(slot) = self.steps.0.get_mut(segment_step_index(step)) {
            *slot += now - self.step_since;
        }
        self.step_since = now;
    }
}

/// Why a frame failed.
#[derive(Debug)]
pub enum ProductError<E> {
    /// The camera failed.
    Camera(E),
    /// The captured pair does not fit the frame buffer.
    Frame(ImageError),
    /// The pipeline rejected the pair or the workspace.
    Pipeline(PipelineError),
    /// The status LED failed.
    Pin(digital::ErrorKind),
    /// The report sink failed.
    Report,
}

impl<E: CameraError> fmt::Display for ProductError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Camera(e) => write!(f, "camera: {} ({e:?})", e.kind()),
            Self::Frame(e) => write!(f, "captured pair: {e}"),
            Self::Pipeline(e) => write!(f, "pipeline: {e}"),
            Self::Pin(e) => write!(f, "status LED pin: {e:?}"),
            Self::Report => f.write_str("report sink failed"),
        }
    }
}

impl<E: CameraError> ProductError<E> {
    /// The message without `Debug` formatting, whose `core` code links
    /// panic paths (the board's report uses this; [`fmt::Display`] says
    /// more).
    ///
    /// # Errors
    /// When `out` fails.
    pub fn write_plain(&self, out: &mut impl Write) -> fmt::Result {
        match self {
            Self::Camera(e) => write!(out, "camera: {}", e.kind()),
            Self::Frame(_) => out.write_str("the captured pair does not fit the frame buffer"),
            Self::Pipeline(e) => write_pipeline_error(out, e),
            Self::Pin(_) => out.write_str("status LED pin failed"),
            Self::Report => out.write_str("report sink failed"),
        }
    }
}

/// A pipeline error without `Debug` formatting (see
/// [`ProductError::write_plain`]).
///
/// # Errors
/// When `out` fails.
pub fn write_pipeline_error(out: &mut impl Write, e: &PipelineError) -> fmt::Result {
    let stage = match e {
        PipelineError::BadParams(what) => return write!(out, "pipeline parameters: {what}"),
        PipelineError::WorkspaceTooSmall { needed, got } => {
            return write!(
                out,
                "workspace of {got} bytes is too small: the run needs {needed}"
            )
        }
        PipelineError::RegionTooSmall {
            region,
            needed,
            got,
        } => {
            return write!(
                out,
                "workspace part '{region}' of {got} bytes is too small: the run needs {needed}"
            );
        }
        PipelineError::TableCount { .. } | PipelineError::Table(_) => "decoder tables",
        PipelineError::Model(_) | PipelineError::ModelMismatch { .. } => "model",
        PipelineError::WorkspaceAlignment => "workspace alignment",
        PipelineError::Image(_) => "frame",
        PipelineError::Stereo(_) => "stereo",
        PipelineError::Conspicuity(_) => "conspicuity",
        PipelineError::Complete(_) => "completion",
        PipelineError::Segment(_) => "figure-ground",
        PipelineError::Shape(_) => "shape",
        PipelineError::Mlp(_) => "classifier",
        _ => "pipeline",
    };
    write!(out, "pipeline failed in: {stage}")
}

impl<E> From<fmt::Error> for ProductError<E> {
    fn from(_: fmt::Error) -> Self {
        Self::Report
    }
}

/// What one frame gave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameSummary {
    /// Objects reported.
    pub objects: usize,
    /// FNV-1a 32 of the objects list ([`objects_checksum`]).
    pub checksum: u32,
    /// Ticks per stage.
    pub ticks: StageTicks,
    /// Ticks per step of stereo and figure-ground.
    pub steps: StepTicks,
    /// Ticks from the capture's start to the pipeline's result.
    pub total: u64,
}

/// The product: a stereo camera, the pipeline and a status LED; `K` is
/// the pipeline's stereo phase step ([`Pipeline::with_kernel`]: the
/// board's assembly one, the same bits as the portable [`SafePhase`]).
pub struct Product<'a, C, P, K = SafePhase> {
    camera: C,
    led: P,
    pipeline: Pipeline<'a, K>,
}

impl<'a, C: StereoCamera, P: OutputPin, K: Kernels> Product<'a, C, P, K> {
    /// The product around a set-up pipeline.
    pub fn new(camera: C, led: P, pipeline: Pipeline<'a, K>) -> Self {
        Self {
            camera,
            led,
            pipeline,
        }
    }

    /// The pipeline.
    pub fn pipeline(&self) -> &Pipeline<'a, K> {
        &self.pipeline
    }

    /// One frame: captures a `width` x `height` pair into `frame`, runs
    /// the pipeline in the workspace's two parts, `kept` ([`KEPT_WORDS`])
    /// and `shared` ([`SHARED_WORDS`]), which may lie in different RAMs,
    /// writes the report ([`write_frame`]) to `out`; the LED is on
    /// meanwhile.
    ///
    /// # Errors
    /// [`ProductError`]: the camera's, a pair that does not fit `frame`,
    /// the pipeline's (e.g. a short workspace, with the bytes needed), the
    /// LED's, or the sink's.
    pub fn frame<T: Ticks, W: Write>(
        &mut self,
        size: (usize, usize),
        frame: &mut [u16],
        (kept, shared): (&mut [u64], &mut [u64]),
        ticks: &mut T,
        out: &mut W,
    ) -> Result<FrameSummary, ProductError<C::Error>> {
        let (width, height) = size;
        self.led
            .set_high()
            .map_err(|e| ProductError::Pin(digital::Error::kind(&e)))?;
        let t0 = ticks.now();
        let layout = self
            .camera
            .capture_pair(frame, width, height)
            .map_err(ProductError::Camera)?;
        let t1 = ticks.now();
        let (left, right) = layout.views(frame).map_err(ProductError::Frame)?;
        let mut clock = StageClock {
            ticks,
            // The pipeline's checks before its first stage count as stereo.
            stage: Some(1),
            since: t1,
            spent: StageTicks::default(),
            step: None,
            step_since: t1,
            steps: StepTicks::default(),
        };
        let result = self
            .pipeline
            .run_split_observed(&left, &right, kept, shared, &mut clock)
            .map_err(ProductError::Pipeline)?;
        let (mut spent, steps) = (clock.spent, clock.steps);
        let total = clock.ticks.now() - t0;
        spent.0[0] = t1 - t0;
        let checksum = write_frame(out, &self.pipeline, &result)?;
        self.led
            .set_low()
            .map_err(|e| ProductError::Pin(digital::Error::kind(&e)))?;
        Ok(FrameSummary {
            objects: result.objects().len(),
            checksum,
            ticks: spent,
            steps,
            total,
        })
    }

    /// Gives back the camera and the LED.
    pub fn release(self) -> (C, P) {
        (self.camera, self.led)
    }
}

/// FNV-1a 32 of a frame's objects, in order: for each, its box, area,
/// centroid, δ, slice, saliency score, every element of its shape vector
/// (I4F12 bits), its ranked classes with their scores, and its verdict;
/// all little endian.
pub fn objects_checksum(frame: &Frame<'_>) -> u32 {
    let mut h = Fnv1a::new();
    for o in frame.objects() {
        for v in [o.bbox.x, o.bbox.y, o.bbox.width, o.bbox.height] {
            h.write(&(v as u64).to_le_bytes());
        }
        h.write(&o.area.to_le_bytes());
        h.write(&o.centroid.x_q8.to_le_bytes());
        h.write(&o.centroid.y_q8.to_le_bytes());
        h.write(&o.delta.to_le_bytes());
        h.write(&o.range.low.to_le_bytes());
        h.write(&o.range.high.to_le_bytes());
        h.write(&o.score.to_le_bytes());
        for e in frame.shape(o).unwrap_or(&[]) {
            h.write(&e.to_bits().to_le_bytes());
        }
        for r in o.top() {
            h.write(&r.class.to_le_bytes());
            h.write(&r.score.to_le_bytes());
        }
        match o.identity {
            Identity::Known(c) => h.write(&[1, c.to_le_bytes()[0], c.to_le_bytes()[1]]),
            Identity::Unknown => h.write(&[0]),
        }
    }
    h.finish()
}

/// A Q16 cosine with 4 decimals, rounded, without float formatting.
struct Q16(u32);

impl fmt::Display for Q16 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let t = (u64::from(self.0) * 10_000 + 32_768) >> 16;
        write!(f, "{}.{:04}", t / 10_000, t % 10_000)
    }
}

/// A fixed-point value with `.1` fraction bits, printed with 2 decimals,
/// rounded half away from zero, without float formatting.
struct Fixed(i64, u32);

impl fmt::Display for Fixed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let half = (1u128 << self.1) >> 1;
        // Below 2^64 once shifted for any `.1` >= 7; printed as `u64`,
        // whose formatting links no panic path (`u128`'s does, with
        // rustc 1.96).
        let h = (u128::from(self.0.unsigned_abs()) * 100 + half) >> self.1;
        let h = u64::try_from(h).unwrap_or(u64::MAX);
        let sign = if self.0 < 0 && h > 0 { "-" } else { "" };
        write!(f, "{sign}{}.{:02}", h / 100, h % 100)
    }
}

/// The frame's report, returning [`objects_checksum`]:
///
/// ```text
/// product 160x120 K=4 searches=4 objects=1
/// object 0 box=64,26,53x69 area=2769 centroid=90.00,60.00 delta=11 slice=9.63..12.37 score=2596 class=04_circle cos=0.9554 verdict=known
/// objects-checksum 160x120 0x1234abcd
/// ```
///
/// `box` is x, y, width x height; δ is in whole pixels of disparity, the
/// slice `[δ − r, δ + r]` in pixels with two decimals; `class` and `cos` are the best category and its
/// cosine with the category's template; the verdict is against Δ.
///
/// # Errors
/// When `out` fails.
pub fn write_frame<K: PhaseKernel>(
    out: &mut impl Write,
    p: &Pipeline<'_, K>,
    frame: &Frame<'_>,
) -> Result<u32, fmt::Error> {
    let (w, h) = frame.size();
    writeln!(
        out,
        "product {w}x{h} K={} searches={} objects={}",
        p.params().segment.max_objects,
        frame.searches(),
        frame.objects().len()
    )?;
    for o in frame.objects() {
        let b = &o.bbox;
        write!(
            out,
            "object {} box={},{},{}x{} area={} centroid={},{} delta={} slice={}..{} score={}",
            o.rank,
            b.x,
            b.y,
            b.width,
            b.height,
            o.area,
            Fixed(o.centroid.x_q8.into(), 8),
            Fixed(o.centroid.y_q8.into(), 8),
            o.delta,
            Fixed(o.range.low, STAT_FRAC_BITS),
            Fixed(o.range.high, STAT_FRAC_BITS),
            o.score
        )?;
        match o.top().first() {
            Some(best) => write!(
                out,
                " class={} cos={}",
                p.class_name(best.class),
                Q16(best.score)
            )?,
            None => write!(out, " class=- cos=-")?,
        }
        let verdict = match o.identity {
            Identity::Known(_) => "known",
            Identity::Unknown => "unknown",
        };
        writeln!(out, " verdict={verdict}")?;
    }
    let sum = objects_checksum(frame);
    writeln!(out, "objects-checksum {w}x{h} 0x{sum:08x}")?;
    Ok(sum)
}

/// The lines of a report that must be equal wherever the product runs.
pub fn is_compared(line: &str) -> bool {
    ["product ", "object ", "objects-checksum "]
        .iter()
        .any(|p| line.starts_with(p))
}

/// Bytes of the product's RAM plan at `width` x `height`: the RGB565 pair
/// and the workspace by part (kept maps, then the three phases that share
/// one region, the largest of which counts).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RamPlan {
    /// The captured pair.
    pub frames: usize,
    /// Kept for the frame's result: edge map, disparity, K masks and vectors.
    pub kept: usize,
    /// Stereo's scratch.
    pub stereo: usize,
    /// The colour phase: the streamed conspicuity stage, the completion's
    /// bit maps and the rest (its run and region tables, label rows).
    pub colour: usize,
    /// The colour phase's streamed conspicuity stage: row rings, an RGB
    /// row, a `Tone` byte per pixel.
    pub luv: usize,
    /// The colour phase's bit maps (non-edge and trusted cells).
    pub edge_map: usize,
    /// Segmentation and the classifier.
    pub objects: usize,
    /// The workspace: `kept` plus the largest phase.
    pub workspace: usize,
}

impl RamPlan {
    /// The plan at `width` x `height` with [`PARAMS`].
    pub const fn at(width: usize, height: usize) -> Self {
        Self {
            frames: 2 * pair_len(width, height),
            kept: layout::kept_bytes(width, height, &PARAMS),
            stereo: layout::stereo_bytes(width, height, &PARAMS),
            colour: layout::colour_bytes(width, height, &PARAMS),
            luv: layout::colour_stream_bytes(width, height, &PARAMS),
            edge_map: layout::colour_bit_map_bytes(width, height),
            objects: layout::object_bytes(width, height, &PARAMS),
            workspace: workspace_bytes(width, height, &PARAMS),
        }
    }

    /// Frames plus workspace.
    pub const fn total(&self) -> usize {
        self.frames + self.workspace
    }
}

/// `ram-plan WxH frames=… kept=… stereo=… colour=… luv=… edge-map=…
/// labelling=… objects=… workspace=… total=…` (`labelling` is the rest of
/// the colour phase).
///
/// # Errors
/// When `out` fails.
pub fn write_ram_plan(out: &mut impl Write, width: usize, height: usize) -> fmt::Result {
    let r = RamPlan::at(width, height);
    writeln!(
        out,
        "ram-plan {width}x{height} frames={} kept={} stereo={} colour={} luv={} edge-map={} labelling={} objects={} workspace={} total={}",
        r.frames,
        r.kept,
        r.stereo,
        r.colour,
        r.luv,
        r.edge_map,
        r.colour.saturating_sub(r.luv + r.edge_map),
        r.objects,
        r.workspace,
        r.total()
    )
}

/// [`write_ram_plan`] at each of [`PLANNED`].
///
/// # Errors
/// When `out` fails.
pub fn write_ram_plans(out: &mut impl Write) -> fmt::Result {
    PLANNED
        .iter()
        .try_for_each(|&(w, h)| write_ram_plan(out, w, h))
}
