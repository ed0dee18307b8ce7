//! The f32 chain beside core's pipeline: one orchestration of the stages
//! for every front end that compares against it (`run --reference` and
//! `--gt-disparity`, `gist-eval --mode reference`, `segment-eval` and the
//! demo's ground-truth row).
//!
//! Stereo is the host's f32 disparity energy model (or a given disparity,
//! e.g. ground truth); the conspicuity, the completion and figure-ground
//! are core's stages run step by step ([`crate::stages`]), with the
//! pipeline's segmentation parameters, and the band relabelling is the
//! reference's ([`ChainRun::relabel`]), so that the chain differs from
//! the product only where its disparity comes from.

use crate::error::Result;
use crate::reference::stereo::{Decoder, DemParams};
use crate::scenes::BoxPx;
use crate::stages::{run_complete, run_conspicuity, run_segment, ConspicuityMaps, SegmentResult};
use protogist::complete::{CompleteParams, CompleteReport};
use protogist::conspicuity::{EdgeParams, LuvTables};
use protogist::disparity::DisparityCell;
use protogist::image::{ImageView, Rgb8};
use protogist::segment::{BoundingBox, DepthHole, Relabel, SegmentParams};

/// Where the chain's disparity comes from.
#[derive(Clone, Copy, Debug)]
pub enum Source<'a> {
    /// A given map (ground truth, or the synthetic scene's), used as is.
    Given(&'a [DisparityCell]),
    /// The f32 disparity energy model on the pair, completed over the
    /// conspicuity regions as the pipeline does (`complete: false` keeps
    /// the model's raw map).
    Dem {
        /// The model's parameters.
        params: &'a DemParams,
        /// Its decoder.
        decoder: &'a Decoder,
        /// Complete the map over the conspicuity regions.
        complete: bool,
    },
}

/// One frame through the chain.
#[derive(Clone, Debug)]
pub struct ChainRun {
    /// The conspicuity stage's maps (smoothed CIELUV, C).
    pub edges: ConspicuityMaps,
    /// The disparity figure-ground segmented.
    pub disparity: Vec<DisparityCell>,
    /// The completion's report, when it ran.
    pub completion: Option<CompleteReport>,
    /// Figure-ground: the report and one mask per search slot.
    pub segment: SegmentResult,
}

/// Runs the chain on a `width` x `height` pair with figure-ground's
/// `segment` parameters (the pipeline's: `PipelineParams::segment`).
///
/// # Errors
/// A stage's typed error: frame sizes, bad parameters, a given map of
/// another size.
pub fn run_chain(
    segment: &SegmentParams,
    source: Source<'_>,
    left: &[Rgb8],
    right: &[Rgb8],
    width: usize,
    height: usize,
) -> Result<ChainRun> {
    let (w, h) = (width, height);
    let edges = run_conspicuity(&LuvTables::new(), &EdgeParams::default(), left, w, h)?;
    let (disparity, completion) = match source {
        Source::Given(d) => (d.to_vec(), None),
        Source::Dem {
            params,
            decoder,
            complete,
        } => {
            let maps = crate::reference::stereo::stereo(
                params,
                decoder,
                &ImageView::packed(left, w, h)?,
                &ImageView::packed(right, w, h)?,
            )?;
            if complete {
                let (done, report) = run_complete(
                    &CompleteParams::default(),
                    &edges.edges,
                    &edges.smoothed,
                    &maps.disparity,
                    w,
                    h,
                )?;
                (done, Some(report))
            } else {
                (maps.disparity, None)
            }
        }
    };
    let segment = run_segment(segment, &disparity, &edges.edges, Some(left), w, h)?;
    Ok(ChainRun {
        edges,
        disparity,
        completion,
        segment,
    })
}

impl ChainRun {
    /// Relabels every object's mask with `relabel` (the pipeline's
    /// [`PipelineParams::relabel`](protogist::pipeline::PipelineParams::relabel))
    /// as core's pipeline does after figure-ground: by the reference
    /// [`relabel_mask`](crate::reference::relabel::relabel_mask), against
    /// the pair, C and each row's dominant disparity of the chain's map,
    /// updating the object's area and box. `None` leaves the masks as they
    /// are.
    pub fn relabel(&mut self, relabel: Option<&Relabel>, left: &[Rgb8], right: &[Rgb8]) {
        let Some(relabel) = relabel else { return };
        let (w, h) = (self.segment.width, self.segment.height);
        let n = w * h;
        let df: Vec<crate::reference::segment::DispF> = self
            .disparity
            .iter()
            .map(|v| v.get().map(f32::from))
            .collect();
        let ground = crate::reference::segment::row_disparities(&df, w, h);
        for det in &mut self.segment.report.objects {
            let Some(slot) = self
                .segment
                .masks
                .get_mut(det.index * n..(det.index + 1) * n)
            else {
                continue;
            };
            let Some(mask) = crate::reference::relabel::relabel_mask(
                relabel,
                slot,
                left,
                right,
                &self.edges.edges,
                &ground,
                det.range,
                w,
                h,
            ) else {
                continue;
            };
            slot.copy_from_slice(&mask);
            set_area_and_box(det, slot, w, h);
        }
    }

    /// Takes each object's hole by disparity out of its mask with `p`
    /// (the pipeline's
    /// [`PipelineParams::depth_hole`](protogist::pipeline::PipelineParams::depth_hole))
    /// as core's pipeline does after the relabelling: by the reference
    /// [`depth_hole`](crate::reference::holes::depth_hole) against the
    /// chain's map, updating the object's area and box. `None` leaves
    /// the masks as they are.
    pub fn depth_hole(&mut self, p: Option<&DepthHole>) {
        let Some(p) = p else { return };
        let (w, h) = (self.segment.width, self.segment.height);
        let n = w * h;
        for det in &mut self.segment.report.objects {
            let (Some(b), Some(slot)) = (
                det.bbox,
                self.segment
                    .masks
                    .get_mut(det.index * n..(det.index + 1) * n),
            ) else {
                continue;
            };
            let bbox = (b.x, b.y, b.width, b.height);
            if !crate::reference::holes::depth_hole(p, slot, &self.disparity, det.range, bbox, w, h)
            {
                continue;
            }
            set_area_and_box(det, slot, w, h);
        }
    }
}

/// `det`'s area and box: those of its `w x h` mask `mask`.
fn set_area_and_box(det: &mut protogist::segment::Detection, mask: &[bool], w: usize, h: usize) {
    det.area = mask.iter().map(|&b| u32::from(b)).sum();
    det.bbox = BoxPx::of(w as u32, h as u32, |x, y| mask[y as usize * w + x as usize]).map(|b| {
        BoundingBox {
            x: b.x as usize,
            y: b.y as usize,
            width: b.width as usize,
            height: b.height as usize,
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use protogist::disparity::from_pixels;
    use protogist::pipeline::PipelineParams;

    /// A frame with a bright square in front of a dark wall.
    fn square() -> (Vec<Rgb8>, Vec<DisparityCell>, usize, usize) {
        let (w, h) = (64usize, 48usize);
        let inside = |i: usize| (20..44).contains(&(i % w)) && (14..34).contains(&(i / w));
        let rgb = (0..w * h)
            .map(|i| {
                if inside(i) {
                    Rgb8::new(230, 200, 40)
                } else {
                    Rgb8::new(30, 40, 90)
                }
            })
            .collect();
        let d = (0..w * h)
            .map(|i| from_pixels(if inside(i) { 9 } else { 2 }))
            .collect();
        (rgb, d, w, h)
    }

    #[test]
    fn a_given_disparity_is_segmented_as_is() {
        let (rgb, d, w, h) = square();
        let p = PipelineParams::DEFAULT.with_objects(1).segment;
        let run = run_chain(&p, Source::Given(&d), &rgb, &rgb, w, h).unwrap();
        assert_eq!(run.disparity, d);
        assert!(run.completion.is_none());
        let obj = &run.segment.report.objects[0];
        assert!(obj.area > 300, "{obj:?}");
    }

    #[test]
    fn a_given_map_of_another_size_is_an_error() {
        let (rgb, d, w, h) = square();
        let p = PipelineParams::DEFAULT.segment;
        assert!(run_chain(&p, Source::Given(&d[1..]), &rgb, &rgb, w, h).is_err());
    }
}
