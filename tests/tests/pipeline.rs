//! Core's pipeline end to end: the demo scene through every stage, and
//! every kind of bad input.

use protogist::image::{ImageView, ImageViewMut, Rgb8};
use protogist::mlp::Identity;
use protogist::pipeline::{
    kept_words, shared_words, workspace_bytes, workspace_words, Observer, Pipeline, PipelineError,
    PipelineParams, Region, Stage,
};
use protogist::synth::{render_left, render_mask, render_right, SceneSpec};

/// The product point's tables (`half-narrow`).
const TABLES: [&[u8]; 3] = protogist_host::product::DEFAULT_TABLES;
const MODEL: &[u8] = include_bytes!("../../host/data/shapes_model.bin");
const W: usize = 160;
const H: usize = 120;

fn demo_pair() -> (Vec<Rgb8>, Vec<Rgb8>, Vec<u8>) {
    let spec = SceneSpec::demo(W, H);
    let mut l = vec![Rgb8::default(); W * H];
    let mut r = l.clone();
    let mut m = vec![0u8; W * H];
    render_left(&spec, &mut ImageViewMut::packed(&mut l, W, H).unwrap()).unwrap();
    render_right(&spec, &mut ImageViewMut::packed(&mut r, W, H).unwrap()).unwrap();
    render_mask(&spec, 0, &mut ImageViewMut::packed(&mut m, W, H).unwrap()).unwrap();
    (l, r, m)
}

#[derive(Default)]
struct Stages(Vec<Stage>, usize);

impl Observer for Stages {
    fn enter(&mut self, stage: Stage) {
        self.0.push(stage);
    }
    fn object(
        &mut self,
        _det: &protogist::segment::Detection,
        _maps: &protogist::segment::SegmentBuffers<'_>,
    ) {
        self.1 += 1;
    }
}

#[test]
fn the_demo_scene_gives_its_object_with_a_category() {
    let (l, r, gt) = demo_pair();
    let params = PipelineParams::DEFAULT.with_objects(2);
    let p = Pipeline::new(&params, &TABLES, MODEL).unwrap();
    let mut ws = vec![0u64; workspace_words(W, H, &params)];
    let mut stages = Stages::default();
    let lv = ImageView::packed(&l, W, H).unwrap();
    let rv = ImageView::packed(&r, W, H).unwrap();
    let frame = p.run_observed(&lv, &rv, &mut ws, &mut stages).unwrap();
    assert_eq!(
        stages.0,
        [
            Stage::Stereo,
            Stage::Conspicuity,
            Stage::Complete,
            Stage::Segment,
            Stage::Shape,
            Stage::Classify,
            Stage::Done
        ]
    );
    assert_eq!(stages.1, frame.searches());
    let objects = frame.objects();
    assert!(!objects.is_empty(), "no object in the demo scene");
    let o = objects[0];
    assert!(o.area > 0);
    assert_eq!(o.top().len(), 5);
    assert!(o.top().windows(2).all(|p| p[0].score >= p[1].score));
    match o.identity {
        Identity::Known(c) => assert_eq!(c, o.top[0].class),
        Identity::Unknown => assert!(o.top[0].score < p.delta_q16()),
    }
    // The mask covers the scene's object: IoU with its ground truth.
    let mask = frame.mask(&o).unwrap();
    let (mut inter, mut union) = (0u32, 0u32);
    for y in 0..H {
        for x in 0..W {
            let (a, b) = (mask.get(x, y), gt[y * W + x] != 0);
            inter += u32::from(a && b);
            union += u32::from(a || b);
        }
    }
    let iou = f64::from(inter) / f64::from(union.max(1));
    assert!(iou > 0.8, "mask IoU {iou:.3}");
    assert_eq!(mask.count(), o.area);
    assert_eq!(frame.shape(&o).unwrap().len(), 720);
    // Deterministic, and the same in a workspace that held garbage.
    let first: Vec<_> = objects.to_vec();
    ws.iter_mut().for_each(|w| *w = 0xdead_beef_dead_beef);
    let again = p.run(&lv, &rv, &mut ws).unwrap();
    assert_eq!(again.objects(), &first[..]);
}

#[test]
fn a_split_workspace_gives_the_same_frame() {
    // As the F405 runs it: the kept maps in one RAM, the shared region in
    // another.
    let (l, r, _) = demo_pair();
    let params = PipelineParams::DEFAULT;
    let p = Pipeline::new(&params, &TABLES, MODEL).unwrap();
    let lv = ImageView::packed(&l, W, H).unwrap();
    let rv = ImageView::packed(&r, W, H).unwrap();
    let (kw, sw) = (kept_words(W, H, &params), shared_words(W, H, &params));
    assert_eq!(kw + sw, workspace_words(W, H, &params));
    let mut ws = vec![0u64; workspace_words(W, H, &params)];
    let one = p.run(&lv, &rv, &mut ws).unwrap();
    let (mut kept, mut shared) = (vec![0u64; kw], vec![0u64; sw]);
    let split = p.run_split(&lv, &rv, &mut kept, &mut shared).unwrap();
    assert!(!one.objects().is_empty());
    assert_eq!(one.objects(), split.objects());
    for (a, b) in one.objects().iter().zip(split.objects()) {
        assert_eq!(one.shape(a), split.shape(b));
        assert_eq!(
            one.mask(a).map(|m| m.count()),
            split.mask(b).map(|m| m.count())
        );
    }
    // A short part is an error naming it, with the bytes it needs.
    let mut short = vec![0u64; kw - 1];
    assert_eq!(
        p.run_split(&lv, &rv, &mut short, &mut shared).err(),
        Some(PipelineError::RegionTooSmall {
            region: Region::Kept,
            needed: kw * 8,
            got: (kw - 1) * 8,
        })
    );
    let mut short = vec![0u64; sw - 1];
    assert_eq!(
        p.run_split(&lv, &rv, &mut kept, &mut short).err(),
        Some(PipelineError::RegionTooSmall {
            region: Region::Shared,
            needed: sw * 8,
            got: (sw - 1) * 8,
        })
    );
}

#[test]
fn flat_frames_give_no_object_and_no_error() {
    let params = PipelineParams::DEFAULT;
    let p = Pipeline::new(&params, &TABLES, MODEL).unwrap();
    let grey = vec![Rgb8::new(90, 90, 90); W * H];
    let v = ImageView::packed(&grey, W, H).unwrap();
    let mut ws = vec![0u64; workspace_words(W, H, &params)];
    let frame = p.run(&v, &v, &mut ws).unwrap();
    assert!(frame.objects().is_empty());
}

#[test]
fn bad_input_gets_typed_errors() {
    let (l, r, _) = demo_pair();
    let params = PipelineParams::DEFAULT;
    let p = Pipeline::new(&params, &TABLES, MODEL).unwrap();
    let lv = ImageView::packed(&l, W, H).unwrap();
    // Frames of different sizes.
    let small = ImageView::packed(&r[..(W - 8) * H], W - 8, H).unwrap();
    let mut ws = vec![0u64; workspace_words(W, H, &params)];
    assert!(matches!(
        p.run(&lv, &small, &mut ws),
        Err(PipelineError::Stereo(
            protogist::stereo::StereoError::SizeMismatch { .. }
        ))
    ));
    // Frames too small for the engine.
    let tiny = ImageView::packed(&l[..16 * 12], 16, 12).unwrap();
    assert!(matches!(
        p.run(&tiny, &tiny, &mut ws),
        Err(PipelineError::Stereo(_))
    ));
    // A short workspace, with the size needed in the error.
    let rv = ImageView::packed(&r, W, H).unwrap();
    let mut short = vec![0u64; workspace_words(W, H, &params) - 1];
    assert_eq!(
        p.run(&lv, &rv, &mut short).err(),
        Some(PipelineError::WorkspaceTooSmall {
            needed: workspace_bytes(W, H, &params),
            got: short.len() * 8,
        })
    );
    // K = 0 and K past the most objects.
    for k in [0, 9] {
        assert_eq!(
            Pipeline::new(&params.with_objects(k), &TABLES, MODEL).err(),
            Some(PipelineError::BadParams("objects (K) must be 1..=8"))
        );
    }
    // One table short, a corrupt table, a corrupt model.
    assert_eq!(
        Pipeline::new(&params, &TABLES[..2], MODEL).err(),
        Some(PipelineError::TableCount {
            expected: 3,
            got: 2
        })
    );
    let cut = &TABLES[0][..TABLES[0].len() / 2];
    assert!(matches!(
        Pipeline::new(&params, &[cut, TABLES[1], TABLES[2]], MODEL),
        Err(PipelineError::Table(_))
    ));
    assert!(matches!(
        Pipeline::new(&params, &TABLES, &MODEL[..100]),
        Err(PipelineError::Model(_))
    ));
    // A model larger than the workspace is laid out for.
    let mut narrow = params;
    narrow.model.hidden = 16;
    assert_eq!(
        Pipeline::new(&narrow, &TABLES, MODEL).err(),
        Some(PipelineError::ModelMismatch {
            what: "hidden",
            expected: 16,
            got: protogist::mlp::Model::parse(MODEL).unwrap().hidden()
        })
    );
    narrow.model.hidden = 2048;
    narrow.model.classes = 4;
    assert!(matches!(
        Pipeline::new(&narrow, &TABLES, MODEL),
        Err(PipelineError::ModelMismatch {
            what: "classes",
            ..
        })
    ));
    // Tables of another layout (the point's max disparity differs).
    assert!(matches!(
        Pipeline::new(&params.with_max_disp(20), &TABLES, MODEL)
            .unwrap()
            .run(&lv, &rv, &mut ws),
        Err(PipelineError::Stereo(
            protogist::stereo::StereoError::DecoderMismatch { .. }
        ))
    ));
}

#[test]
fn the_workspace_is_the_kept_maps_plus_the_largest_phase() {
    use protogist::pipeline::layout::{colour_bytes, object_bytes, stereo_bytes};
    let p = PipelineParams::DEFAULT.with_objects(4);
    let shared = stereo_bytes(W, H, &p)
        .max(colour_bytes(W, H, &p))
        .max(object_bytes(W, H, &p));
    assert_eq!(
        workspace_bytes(W, H, &p),
        protogist::pipeline::kept_bytes(W, H, &p) + shared
    );
    // The colour phase (streamed conspicuity, completion by runs) is
    // never the largest: it stays below figure-ground's or the stereo's at
    // the board's two sizes.
    for (w, h) in [(W, H), (128, 96)] {
        eprintln!(
            "workspace {w}x{h} K=4: {} B (kept {}, stereo {}, colour {}, objects {})",
            workspace_bytes(w, h, &p),
            protogist::pipeline::kept_bytes(w, h, &p),
            stereo_bytes(w, h, &p),
            colour_bytes(w, h, &p),
            object_bytes(w, h, &p)
        );
        assert!(
            colour_bytes(w, h, &p) < object_bytes(w, h, &p).max(stereo_bytes(w, h, &p)),
            "{w}x{h}"
        );
    }
    // More objects need more kept bytes, never less.
    assert!(workspace_bytes(W, H, &p) > workspace_bytes(W, H, &p.with_objects(1)));
}
