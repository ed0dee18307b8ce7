//! Detection behind one trait, so the benchmark measures any chain the
//! same way.
//!
//! **Adding a detector** (e.g. core's `protogist::pipeline`): write a
//! struct holding its buffers and a reference to [`Shared`] (segmentation
//! parameters with K, and the [`Classifier`] whose class names the scenes
//! were checked against), and `impl Detector` for it, returning one
//! [`Detection`] per object found; add a [`Mode`] variant and its arms in
//! [`Mode::name`], [`Mode::needs_reference_stereo`] and [`make_detector`]
//! (the compiler lists them). Nothing else changes: matching, metrics,
//! report, overview and `cargo xtask bench` (one more entry in its
//! `MODES`) take any detector.

use crate::classify::shipped::categorise_mask;
use crate::error::{HostError, Result};
use crate::reference::stereo::{Decoder, DemParams};
use crate::reference_chain::{run_chain, Source};
use crate::scenes::load::Scene;
use crate::scenes::BoxPx;

use protogist::disparity::{Disparity, DisparityCell};
use protogist::mlp::{Identity, Model};
use protogist::segment::SegmentParams;

/// One object a detector reports.
#[derive(Clone, Debug, PartialEq)]
pub struct Detection {
    /// Its box in the left view.
    pub bbox: BoxPx,
    /// Its mask, row-major over the frame.
    pub mask: Vec<bool>,
    /// The best classes, best first, with their cosine scores (empty when
    /// the mask has no shape).
    pub top5: Vec<(String, f32)>,
    /// Whether the best score reaches the model's Δ (else: unknown).
    pub known: bool,
}

impl Detection {
    /// The class it claims: its best class when known.
    pub fn category(&self) -> Option<&str> {
        self.known
            .then(|| self.top5.first().map(|(c, _)| c.as_str()))
            .flatten()
    }
}

/// Finds objects in a scene.
pub trait Detector {
    /// Up to K objects of `scene`, most salient first.
    ///
    /// # Errors
    /// A stage's typed error.
    fn detect(&mut self, scene: &Scene) -> Result<Vec<Detection>>;
}

/// Which chain runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// Core's fixed-point pipeline ([`protogist::pipeline`]): the product,
    /// the firmware's bits.
    Core,
    /// The f32 reference disparity energy model, completed over the
    /// conspicuity regions, then core segmentation, shape and classifier.
    Reference,
    /// Core's pipeline with the scenes' ground-truth disparity in place
    /// of its stereo and completion
    /// ([`protogist::pipeline::Pipeline::run_with_disparity`]): an upper
    /// bound for the stereo stage.
    GtDisparity,
}

impl Mode {
    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Core => "core",
            Self::Reference => "reference",
            Self::GtDisparity => "gt-disparity",
        }
    }

    /// Whether core's pipeline runs (with its stereo or with the given
    /// disparity), needing [`Shared::tables`].
    pub fn runs_core(self) -> bool {
        matches!(self, Self::Core | Self::GtDisparity)
    }

    /// Whether [`Shared::dem`] must hold the f32 stereo model.
    pub fn needs_reference_stereo(self) -> bool {
        match self {
            Self::Reference => true,
            Self::Core | Self::GtDisparity => false,
        }
    }
}

/// The int8 classifier and the names of its classes.
#[derive(Clone, Debug)]
pub struct Classifier<'a> {
    /// The model.
    pub model: Model<'a>,
}

impl Classifier<'_> {
    /// Categorises a 0/non-zero mask: top 5 and the Δ verdict.
    ///
    /// # Errors
    /// As [`categorise_mask`].
    pub fn categorise(
        &self,
        mask: &[u8],
        w: usize,
        h: usize,
    ) -> Result<(Vec<(String, f32)>, bool)> {
        let Some(c) = categorise_mask(&self.model, mask, w, h)? else {
            return Ok((Vec::new(), false));
        };
        let top = c
            .ranked
            .iter()
            .map(|r| {
                let name = self.model.class_name(usize::from(r.class)).unwrap_or("?");
                (name.to_string(), r.score as f32 / 65536.0)
            })
            .collect();
        Ok((top, matches!(c.identity, Identity::Known(_))))
    }
}

/// What every detector of a run shares: parameters and the classifier.
pub struct Shared<'a> {
    /// The pipeline's named setting (`--preset`): for core's modes
    /// ([`Mode::runs_core`]) every stage's settings ([`core_params`]), for
    /// the reference chain its relabelling.
    pub preset: protogist::pipeline::PipelineParams,
    /// Segmentation parameters (`max_objects` = K): the preset's, for
    /// every mode.
    pub segment: SegmentParams,
    /// The classifier.
    pub classifier: Classifier<'a>,
    /// The stereo model, for [`Mode::Reference`].
    pub dem: Option<(DemParams, Decoder)>,
    /// The model blob, for core's modes.
    pub blob: &'a [u8],
    /// The stereo point's decoder tables, for core's modes (empty
    /// otherwise).
    pub tables: Vec<Vec<u8>>,
}

/// The pipeline's parameters: `shared`'s preset with its segmentation
/// (K) and the scenes' width's largest disparity.
pub fn core_params(shared: &Shared<'_>, width: usize) -> protogist::pipeline::PipelineParams {
    protogist::pipeline::PipelineParams {
        segment: shared.segment,
        ..shared.preset
    }
    .with_max_disp(crate::product::default_max_disp(width))
}

/// A GT disparity in px as a cell (OFF when unknown or out of range).
fn cell(v: Option<f32>) -> DisparityCell {
    v.filter(|v| v.is_finite() && (0.0..255.0).contains(v))
        .map(Disparity::from_num)
        .into()
}

/// Runs the reference chain on `scene` (its stereo completed over the
/// conspicuity regions) and categorises every object found.
fn segment_and_classify(shared: &Shared<'_>, scene: &Scene) -> Result<Vec<Detection>> {
    let (w, h) = (scene.width, scene.height);
    let Some((params, decoder)) = shared.dem.as_ref() else {
        return Err(HostError::InvalidArgument {
            name: "mode",
            reason: "the reference chain needs a stereo model".into(),
        });
    };
    let source = Source::Dem {
        params,
        decoder,
        complete: true,
    };
    let mut chain = run_chain(&shared.segment, source, &scene.left, &scene.right, w, h)?;
    chain.relabel(shared.preset.relabel.as_ref(), &scene.left, &scene.right);
    chain.depth_hole(shared.preset.depth_hole.as_ref());
    let seg = chain.segment;
    let n = w * h;
    let mut out = Vec::new();
    for (k, obj) in seg.report.objects.iter().enumerate() {
        let mask: Vec<bool> = seg.masks.iter().skip(k * n).take(n).copied().collect();
        let Some(bbox) = BoxPx::of(w as u32, h as u32, |x, y| {
            mask[(y as usize) * w + x as usize]
        }) else {
            continue;
        };
        if obj.area == 0 {
            continue;
        }
        let (top5, known) = shared.classifier.categorise(&seg.mask_u8(k), w, h)?;
        out.push(Detection {
            bbox,
            mask,
            top5,
            known,
        });
    }
    Ok(out)
}

/// The f32 reference chain ([`Mode::Reference`]).
pub struct ReferenceDetector<'s, 'm> {
    shared: &'s Shared<'m>,
}

impl Detector for ReferenceDetector<'_, '_> {
    fn detect(&mut self, scene: &Scene) -> Result<Vec<Detection>> {
        segment_and_classify(self.shared, scene)
    }
}

/// The chain on ground-truth disparity ([`Mode::GtDisparity`]).
pub struct GtDisparityDetector<'s, 'm> {
    shared: &'s Shared<'m>,
}

impl Detector for GtDisparityDetector<'_, '_> {
    fn detect(&mut self, scene: &Scene) -> Result<Vec<Detection>> {
        let d: Vec<DisparityCell> = scene.disparity.iter().map(|&v| cell(v)).collect();
        let run = crate::product::run_frame_with_disparity(
            &core_params(self.shared, scene.width),
            &self.shared.tables,
            self.shared.blob,
            (&scene.left, &scene.right),
            &d,
            scene.width,
            scene.height,
        )?;
        Ok(core_detections(run))
    }
}

/// Core's pipeline ([`Mode::Core`]), through [`crate::product::run_frame`]
/// as `protogist run` calls it.
pub struct CoreDetector<'s, 'm> {
    shared: &'s Shared<'m>,
}

impl Detector for CoreDetector<'_, '_> {
    fn detect(&mut self, scene: &Scene) -> Result<Vec<Detection>> {
        let params = core_params(self.shared, scene.width);
        let run = crate::product::run_frame(
            &params,
            &self.shared.tables,
            self.shared.blob,
            &scene.left,
            &scene.right,
            scene.width,
            scene.height,
        )?;
        Ok(core_detections(run))
    }
}

/// The detections of one run of core's pipeline, each with its mask's box.
fn core_detections(run: crate::product::FrameRun) -> Vec<Detection> {
    let (w, h) = (run.width, run.height);
    run.objects
        .into_iter()
        .filter_map(|o| {
            let bbox = BoxPx::of(w as u32, h as u32, |x, y| {
                o.mask
                    .get(y as usize * w + x as usize)
                    .copied()
                    .unwrap_or(false)
            })?;
            Some(Detection {
                bbox,
                known: o.category.is_some(),
                top5: o.top,
                mask: o.mask,
            })
        })
        .collect()
}

/// A detector of `mode` over `shared` (one per worker thread).
pub fn make_detector<'s>(mode: Mode, shared: &'s Shared<'_>) -> Box<dyn Detector + Send + 's> {
    match mode {
        Mode::Core => Box::new(CoreDetector { shared }),
        Mode::Reference => Box::new(ReferenceDetector { shared }),
        Mode::GtDisparity => Box::new(GtDisparityDetector { shared }),
    }
}
