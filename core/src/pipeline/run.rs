//! One frame through every stage, inside the workspace.

use super::arena::Arena;
use super::{
    layout, Frame, Kernels, Object, Observer, Pipeline, PipelineError, Region, RgbRows, Stage,
    MAX_OBJECTS, TOP_K,
};
use crate::complete::{
    complete_runs, pipeline_run_capacity, run_rows_len, RegionTables, RunBuffers, Tone,
    DEFAULT_REGION_CAPACITY, LABEL_ROWS, PIPELINE_TILT_REGIONS,
};
use crate::conspicuity::{self, EdgeCell, Luv};
use crate::disparity::DisparityCell;
use crate::image::{ImageError, ImageView, ImageViewMut, Rgb8};
use crate::mlp::{self, Identity, MirrorScratch, Ranked, Scratch};
use crate::segment::{
    bit_map_len, maps_len, open_depth_hole, relabel_len, relabel_object, segment_with_depth_pass,
    table_len, BitView, Masks, SegmentBuffers, SegmentObserver,
};
use crate::shape::{shape_vector_bits, RadialProfile, ShapeError, ShapeVector, SHAPE_LEN};
use crate::stereo::c2f::{self, C2fBuffers};
use crate::stereo::phase::{self, PhaseBuffers};
use crate::stereo::{Probe, Step};

/// Passes the stereo engine's steps to the observer.
struct StereoSteps<'o, O>(&'o mut O);

impl<O: Observer> Probe for StereoSteps<'_, O> {
    fn enter(&mut self, step: Step) {
        self.0.stereo_step(step);
    }
}

/// Passes figure-ground's steps and objects to the observer.
struct SegmentSteps<'o, O>(&'o mut O);

impl<O: Observer> SegmentObserver for SegmentSteps<'_, O> {
    fn step(&mut self, step: crate::segment::Step) {
        self.0.segment_step(step);
    }

    fn object(&mut self, det: &crate::segment::Detection, bufs: &SegmentBuffers<'_>) {
        self.0.object(det, bufs);
    }
}

/// Where a frame's disparity comes from.
#[derive(Clone, Copy)]
pub(super) enum Depth<'d> {
    /// The stereo engine, then the completion over conspicuity regions.
    Stereo,
    /// The caller's map of the left view, used as it is.
    Given(&'d ImageView<'d, DisparityCell>),
}

pub(super) fn run<'w, S: RgbRows, O: Observer, K: Kernels>(
    p: &Pipeline<'_, K>,
    left: &S,
    right: &S,
    depth: Depth<'_>,
    workspace: &'w mut [u64],
    obs: &mut O,
) -> Result<Frame<'w>, PipelineError> {
    let params = &p.params;
    let (w, h) = left.size();
    // The frames are checked once, by `run_split`.
    let needed = super::workspace_bytes(w, h, params);
    let got = workspace.len() * 8;
    let too_small = PipelineError::WorkspaceTooSmall { needed, got };
    if got < needed {
        return Err(too_small);
    }
    // Checked above; `split_at_mut` would link a panic path the optimiser
    // cannot remove (run-time sizes).
    let (kept, shared) = workspace
        .split_at_mut_checked(super::kept_words(w, h, params))
        .ok_or(too_small)?;
    run_split(p, left, right, depth, kept, shared, obs)
}

pub(super) fn run_split<'w, S: RgbRows, O: Observer, K: Kernels>(
    p: &Pipeline<'_, K>,
    left: &S,
    right: &S,
    depth: Depth<'_>,
    kept: &'w mut [u64],
    shared: &'w mut [u64],
    obs: &mut O,
) -> Result<Frame<'w>, PipelineError> {
    let params = &p.params;
    let (w, h) = left.size();
    let tables = p.tables.as_slice();
    match depth {
        Depth::Stereo => p.c2f.check(tables, (w, h), right.size())?,
        Depth::Given(d) => {
            crate::image::buffer_len(w, h, w)?;
            for got in [right.size(), d.size()] {
                if got != (w, h) {
                    return Err(ImageError::SizeMismatch {
                        expected: (w, h),
                        got,
                    }
                    .into());
                }
            }
        }
    }
    for (region, words, needed) in [
        (Region::Kept, kept.len(), layout::kept_bytes(w, h, params)),
        (
            Region::Shared,
            shared.len(),
            layout::shared_bytes(w, h, params),
        ),
    ] {
        if words * 8 < needed {
            return Err(PipelineError::RegionTooSmall {
                region,
                needed,
                got: words * 8,
            });
        }
    }
    let n = w * h;
    let k = usize::from(params.segment.max_objects);
    let mut a = Arena::new(kept);
    let edges: &'w mut [EdgeCell] = a.take(n)?;
    let disparity: &'w mut [DisparityCell] = a.take(n)?;
    let masks: &'w mut [u32] = a.take(k * bit_map_len(w, h))?;
    let vectors = a.take(k * SHAPE_LEN)?;

    // Stereo: its buffers take the shared region first.
    obs.enter(Stage::Stereo);
    if let Depth::Given(given) = depth {
        for (o, v) in disparity.iter_mut().zip(given.pixels()) {
            *o = v;
        }
    } else {
        let mut s = Arena::new(&mut *shared);
        let sp = &params.stereo;
        let phase = match &sp.phase {
            Some(ph) => PhaseBuffers {
                rgb: s.take(w)?,
                v: s.take(phase::v_len(w, ph))?,
                z: s.take(phase::z_len(w, ph, sp.dem.max_disp))?,
                row: s.take(w)?,
            },
            None => PhaseBuffers {
                rgb: &mut [],
                v: &mut [],
                z: &mut [],
                row: &mut [],
            },
        };
        let mut bufs = C2fBuffers {
            grey: s.take(c2f::grey_len(w, sp))?,
            rgb: s.take(c2f::rgb_len(w, sp))?,
            z: s.take(c2f::z_len(w, sp))?,
            col: s.take(w)?,
            scores: s.take(c2f::score_len(w, sp))?,
            costs: s.take(c2f::cost_len(w, sp))?,
            sums: s.take(c2f::sum_len(w, sp))?,
            picks: s.take(c2f::pick_len(w))?,
            maps: s.take(c2f::map_len(w, h, sp))?,
            phase,
        };
        // `run_into` writes every cell: no clearing first.
        p.c2f.run_into(
            tables,
            left,
            right,
            &mut bufs,
            &mut ImageViewMut::packed(&mut *disparity, w, h)?,
            &mut StereoSteps(obs),
        )?;
    }
    obs.raw_disparity(&ImageView::packed(&*disparity, w, h)?);

    // Conspicuity on a rolling window of rows, keeping one byte of
    // smoothed colour per pixel for the completion's edge cells.
    obs.enter(Stage::Conspicuity);
    {
        let mut s = Arena::new(&mut *shared);
        let smooth = &params.edges.smooth;
        let rows: &mut [Luv] = s.take(conspicuity::stream_scratch_len(w, smooth))?;
        let rgb: &mut [Rgb8] = s.take(w)?;
        let tone: &mut [Tone] = s.take(n)?;
        let mut c_v = ImageViewMut::packed(&mut *edges, w, h)?;
        conspicuity::stream_with::<K>(
            smooth,
            params.edges.threshold_percent,
            rows,
            &mut c_v,
            |y, out| left.luv_row(y, rgb, out),
            |y, row| {
                obs.smoothed_row(y, row);
                if let Some(t) = tone.get_mut(y * w..(y + 1) * w) {
                    for (t, &c) in t.iter_mut().zip(row) {
                        *t = Tone::of(c);
                    }
                }
            },
        )?;
        obs.conspicuity(&c_v.as_view());

        obs.enter(Stage::Complete);
        let mut bufs = RunBuffers {
            open: s.take(bit_map_len(w, h))?,
            trusted: s.take(bit_map_len(w, h))?,
            runs: s.take(pipeline_run_capacity(w, h))?,
            rows: s.take(run_rows_len(w))?,
            labels: s.take(LABEL_ROWS * w)?,
        };
        let r = DEFAULT_REGION_CAPACITY;
        let mut tables = RegionTables {
            total: s.take(r)?,
            below: s.take(r)?,
            lo: s.take(r)?,
            hi: s.take(r)?,
            tilt: s.take(if params.complete.tilt_rows > 0 {
                PIPELINE_TILT_REGIONS
            } else {
                0
            })?,
        };
        // A given map is used as it is.
        if matches!(depth, Depth::Stereo) {
            complete_runs(
                &params.complete,
                &c_v.as_view(),
                &ImageView::packed(&*tone, w, h)?,
                &mut ImageViewMut::packed(&mut *disparity, w, h)?,
                &mut bufs,
                &mut tables,
            )?;
        }
    }
    let disparity: &'w [DisparityCell] = disparity;
    let disparity_v = ImageView::packed(disparity, w, h)?;
    obs.disparity(&disparity_v);

    // Figure-ground (with the depth pass, C takes the disparity map's
    // steps), then shape and the classifier per object.
    obs.enter(Stage::Segment);
    let edges: &'w [EdgeCell] = edges;
    let edges_v = ImageView::packed(edges, w, h)?;
    let report = {
        // The maps are free once the objects' masks are written: the
        // classifier's buffers take their place.
        let mut s = Arena::new(&mut *shared);
        let mut seg = SegmentBuffers::new(w, h, s.take(maps_len(w, h))?, s.take(table_len(w, h))?)?;
        let mut report = segment_with_depth_pass(
            &params.segment,
            &disparity_v,
            &edges_v,
            left,
            &mut seg,
            Masks::Bits(&mut *masks),
            &mut SegmentSteps(obs),
        )?;
        if let Some(r) = &params.relabel {
            let rows = s.take(relabel_len(w))?;
            for det in report.objects.iter_mut() {
                relabel_object(r, left, right, &edges_v, det, masks, &mut seg, rows)?;
            }
        }
        if let Some(d) = &params.depth_hole {
            for det in report.objects.iter_mut() {
                open_depth_hole(d, &disparity_v, det, masks, &mut seg)?;
            }
        }
        report
    };

    let masks: &'w [u32] = masks;

    obs.enter(Stage::Shape);
    let mut profile = RadialProfile::new();
    let mut shaped: heapless::Vec<(usize, crate::shape::Centroid), MAX_OBJECTS> =
        heapless::Vec::new();
    let words = bit_map_len(w, h);
    for (det, v) in report
        .objects
        .iter()
        .zip(vectors.chunks_exact_mut(SHAPE_LEN))
    {
        if det.area == 0 || det.bbox.is_none() {
            continue;
        }
        let Some(mask) = masks.get(det.index * words..(det.index + 1) * words) else {
            continue;
        };
        let Ok(out) = <&mut ShapeVector>::try_from(v) else {
            continue;
        };
        match shape_vector_bits(&BitView::new(mask, w, h)?, &mut profile, out) {
            Ok(r) => {
                let _ = shaped.push((det.index, r.centroid));
            }
            Err(ShapeError::EmptyMask | ShapeError::ZeroVariance) => {}
            Err(e) => return Err(e.into()),
        }
    }
    let vectors: &'w [crate::shape::ShapeElem] = vectors;

    obs.enter(Stage::Classify);
    let m = &p.model;
    let mut s = Arena::new(shared);
    let mut scratch = Scratch {
        input: s.take(mlp::packed_len(m.inputs(), m.hidden()))?,
        hidden: s.take(mlp::hidden_len(m.hidden()))?,
        output: s.take(mlp::output_len(m.classes()))?,
    };
    let mut mirror = if params.mirror_check {
        let k = usize::from(params.model.classes);
        Some(MirrorScratch {
            vector: s.take(SHAPE_LEN)?,
            outputs: s.take(mlp::mirror_outputs_len(k))?,
            mean: s.take(mlp::mirror_mean_len(k))?,
        })
    } else {
        None
    };
    let mut objects = heapless::Vec::new();
    for &(search, centroid) in &shaped {
        let Some(det) = report.objects.get(search) else {
            continue;
        };
        let Some(bbox) = det.bbox else {
            continue;
        };
        let v = vectors
            .get(search * SHAPE_LEN..(search + 1) * SHAPE_LEN)
            .unwrap_or(&[]);
        let mut top = [Ranked::default(); TOP_K];
        let filled = match mirror.as_mut() {
            Some(mirror) => mlp::mirror_check_below_with::<K>(
                m,
                v,
                &mut scratch,
                mirror,
                &mut top,
                params.mirror_below_q16,
            )?,
            None => {
                let outputs = mlp::forward_with::<K>(m, v, &mut scratch)?;
                mlp::top_k(m, outputs, &mut top)?
            }
        };
        let identity = match top.first() {
            Some(b) if filled > 0 && b.score >= p.delta_q16 => Identity::Known(b.class),
            _ => Identity::Unknown,
        };
        let _ = objects.push(Object {
            rank: objects.len(),
            search,
            bbox,
            centroid,
            area: det.area,
            delta: det.delta,
            range: det.range,
            score: det.score,
            top,
            top_len: u8::try_from(filled).unwrap_or(0),
            identity,
        });
    }
    obs.enter(Stage::Done);
    Ok(Frame {
        width: w,
        height: h,
        objects,
        searches: report.objects.len(),
        masks,
        vectors,
        edges: edges_v,
        disparity: disparity_v,
    })
}
