//! Accuracy checks that both tests and `cargo xtask bench` run.

use crate::error::Result;
use crate::reference::stereo::{Decoder, DemParams};
use crate::reference_chain::{run_chain, Source};
use protogist::disparity::from_pixels;
use protogist::image::{ImageViewMut, Rgb8};
use protogist::segment::SegmentParams;
use protogist::synth::{render_disparity, render_left, render_mask, render_right, SceneSpec};

/// Largest disparity of `SceneSpec::random` scenes at 160 px, with margin:
/// the model's search range for the evaluation.
pub const EVAL_MAX_DISP: u8 = 31;

/// Where the segmentation's disparity comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum DisparitySource {
    /// The scene's whole-pixel ground truth.
    Gt,
    /// The f32 disparity energy model on the rendered pair, completed over
    /// the conspicuity regions (`protogist::complete`), as the pipeline
    /// runs it.
    Dem,
    /// The model's raw output, without the completion.
    DemRaw,
}

/// The segmentation of one seeded scene against its ground truth.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneIou {
    /// `SceneSpec::random` seed.
    pub seed: u64,
    /// Best mask IoU of the most salient detection against any GT object
    /// (0 when nothing was found).
    pub iou: f64,
    /// The matched object, when the IoU is positive.
    pub object: Option<usize>,
    /// Objects in the scene.
    pub objects: usize,
}

/// Segments `SceneSpec::random(seed, width, height)` with the real
/// conspicuity stage and disparity from `source`, and scores the most
/// salient mask against the scene's object masks.
///
/// # Errors
/// A stage's typed error (sizes).
pub fn segment_scene_iou(
    seed: u64,
    width: usize,
    height: usize,
    params: &SegmentParams,
    source: DisparitySource,
    dem: Option<&(DemParams, Decoder)>,
) -> Result<SceneIou> {
    let (w, h) = (width, height);
    let spec = SceneSpec::random(seed, w, h);
    let mut rgb = vec![Rgb8::default(); w * h];
    render_left(&spec, &mut ImageViewMut::packed(&mut rgb, w, h)?)?;
    let mut gt = vec![0u8; w * h];
    render_disparity(&spec, &mut ImageViewMut::packed(&mut gt, w, h)?)?;
    let gt: Vec<_> = gt.iter().map(|&v| from_pixels(v)).collect();
    let mut right = vec![Rgb8::default(); w * h];
    render_right(&spec, &mut ImageViewMut::packed(&mut right, w, h)?)?;
    let trained;
    let chain_source = match source {
        DisparitySource::Gt => Source::Given(&gt),
        DisparitySource::Dem | DisparitySource::DemRaw => {
            let (p, dec) = match dem {
                Some((p, d)) => (p, d),
                None => {
                    trained = eval_dem()?;
                    (&trained.0, &trained.1)
                }
            };
            Source::Dem {
                params: p,
                decoder: dec,
                complete: source == DisparitySource::Dem,
            }
        }
    };
    let seg = run_chain(params, chain_source, &rgb, &right, w, h)?.segment;
    let mut best = (0.0, None);
    let mut m = vec![0u8; w * h];
    for i in 0..spec.objects.len() {
        render_mask(&spec, i, &mut ImageViewMut::packed(&mut m, w, h)?)?;
        let v = seg.iou(0, &m);
        if v > best.0 {
            best = (v, Some(i));
        }
    }
    Ok(SceneIou {
        seed,
        iou: best.0,
        object: best.1,
        objects: spec.objects.len(),
    })
}

/// [`segment_scene_iou`] for seeds `0..scenes`.
///
/// # Errors
/// As [`segment_scene_iou`].
pub fn segment_eval(
    scenes: u64,
    width: usize,
    height: usize,
    source: DisparitySource,
) -> Result<Vec<SceneIou>> {
    let params = SegmentParams::default();
    let dem = match source {
        DisparitySource::Dem | DisparitySource::DemRaw => Some(eval_dem()?),
        DisparitySource::Gt => None,
    };
    (0..scenes)
        .map(|seed| segment_scene_iou(seed, width, height, &params, source, dem.as_ref()))
        .collect()
}

/// The model for the evaluation: default parameters with
/// [`EVAL_MAX_DISP`], its decoder trained now (seeded, about 2 s).
///
/// # Errors
/// As [`crate::dem_tables::decoder_for`].
pub fn eval_dem() -> Result<(DemParams, Decoder)> {
    let params = DemParams {
        max_disp: EVAL_MAX_DISP,
        ..DemParams::default()
    };
    let decoder = crate::dem_tables::decoder_for(&params, None)?;
    Ok((params, decoder))
}
