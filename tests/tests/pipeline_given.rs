//! Core's pipeline on a given disparity map
//! (`Pipeline::run_with_disparity`): the map stands in for the stereo and
//! its completion, every later stage as in `Pipeline::run`.

use protogist::disparity::DisparityCell;
use protogist::image::{ImageError, ImageView, ImageViewMut, Rgb8};
use protogist::pipeline::{workspace_words, Observer, Pipeline, PipelineError, PipelineParams};
use protogist::synth::{render_left, render_right, SceneSpec};

const TABLES: [&[u8]; 3] = protogist_host::product::DEFAULT_TABLES;
const MODEL: &[u8] = include_bytes!("../../host/data/shapes_model.bin");
const W: usize = 160;
const H: usize = 120;

fn demo_pair() -> (Vec<Rgb8>, Vec<Rgb8>) {
    let spec = SceneSpec::demo(W, H);
    let mut l = vec![Rgb8::default(); W * H];
    let mut r = l.clone();
    render_left(&spec, &mut ImageViewMut::packed(&mut l, W, H).unwrap()).unwrap();
    render_right(&spec, &mut ImageViewMut::packed(&mut r, W, H).unwrap()).unwrap();
    (l, r)
}

/// The map figure-ground segments (after the completion), and the raw one.
#[derive(Default)]
struct Maps {
    raw: Vec<DisparityCell>,
    segmented: Vec<DisparityCell>,
}

fn cells(map: &ImageView<'_, DisparityCell>) -> Vec<DisparityCell> {
    map.rows().flat_map(|r| r.iter().copied()).collect()
}

impl Observer for Maps {
    fn raw_disparity(&mut self, map: &ImageView<'_, DisparityCell>) {
        self.raw = cells(map);
    }
    fn disparity(&mut self, map: &ImageView<'_, DisparityCell>) {
        self.segmented = cells(map);
    }
}

#[test]
fn the_map_the_stereo_made_gives_the_same_frame_when_given() {
    let (l, r) = demo_pair();
    let (lv, rv) = (
        ImageView::packed(&l, W, H).unwrap(),
        ImageView::packed(&r, W, H).unwrap(),
    );
    // The accurate preset also reads the right frame again (the band
    // relabelling's matching).
    for params in [PipelineParams::DEFAULT, PipelineParams::ACCURATE] {
        let tables = protogist_host::product::tables_for(&params).unwrap();
        let refs: Vec<&[u8]> = tables.iter().map(Vec::as_slice).collect();
        let p = Pipeline::new(&params, &refs, MODEL).unwrap();
        let mut ws = vec![0u64; workspace_words(W, H, &params)];
        let mut maps = Maps::default();
        let stereo = p.run_observed(&lv, &rv, &mut ws, &mut maps).unwrap();
        let first: Vec<_> = stereo.objects().to_vec();
        let masks: Vec<_> = first
            .iter()
            .map(|o| stereo.mask(o).unwrap().bools().collect::<Vec<_>>())
            .collect();
        let shapes: Vec<_> = first
            .iter()
            .map(|o| stereo.shape(o).unwrap().to_vec())
            .collect();
        assert!(!first.is_empty(), "no object in the demo scene");
        // The completion changed the stereo's map, so that giving the raw
        // map could not pass for giving the completed one.
        assert_ne!(maps.raw, maps.segmented);

        let given = maps.segmented.clone();
        let dv = ImageView::packed(&given, W, H).unwrap();
        let mut seen = Maps::default();
        ws.iter_mut().for_each(|w| *w = 0xdead_beef_dead_beef);
        let frame = p
            .run_with_disparity_observed(&lv, &rv, &dv, &mut ws, &mut seen)
            .unwrap();
        // Used as it is: no completion.
        assert_eq!(seen.raw, given);
        assert_eq!(seen.segmented, given);
        assert_eq!(frame.objects(), &first[..]);
        for ((o, m), s) in frame.objects().iter().zip(&masks).zip(&shapes) {
            assert_eq!(&frame.mask(o).unwrap().bools().collect::<Vec<_>>(), m);
            assert_eq!(frame.shape(o).unwrap(), &s[..]);
        }

        // The stereo's raw map, given, is segmented as it is: the
        // completion that changed it above does not run.
        let raw = ImageView::packed(&maps.raw, W, H).unwrap();
        let mut seen = Maps::default();
        p.run_with_disparity_observed(&lv, &rv, &raw, &mut ws, &mut seen)
            .unwrap();
        assert_eq!(seen.segmented, maps.raw);

        // A map with no disparity anywhere stands in as well: no object.
        let off = vec![DisparityCell::OFF; W * H];
        let ov = ImageView::packed(&off, W, H).unwrap();
        let none = p.run_with_disparity(&lv, &rv, &ov, &mut ws).unwrap();
        assert!(none.objects().is_empty());
    }
}

#[test]
fn a_map_or_frame_of_another_size_is_a_typed_error() {
    let (l, r) = demo_pair();
    let params = PipelineParams::DEFAULT;
    let p = Pipeline::new(&params, &TABLES, MODEL).unwrap();
    let (lv, rv) = (
        ImageView::packed(&l, W, H).unwrap(),
        ImageView::packed(&r, W, H).unwrap(),
    );
    let mut ws = vec![0u64; workspace_words(W, H, &params)];
    let small = vec![DisparityCell::OFF; (W - 1) * H];
    let sv = ImageView::packed(&small, W - 1, H).unwrap();
    assert_eq!(
        p.run_with_disparity(&lv, &rv, &sv, &mut ws).err(),
        Some(PipelineError::Image(ImageError::SizeMismatch {
            expected: (W, H),
            got: (W - 1, H),
        }))
    );
    let map = vec![DisparityCell::OFF; W * H];
    let mv = ImageView::packed(&map, W, H).unwrap();
    let short = &r[..W * (H - 1)];
    let shortv = ImageView::packed(short, W, H - 1).unwrap();
    assert_eq!(
        p.run_with_disparity(&lv, &shortv, &mv, &mut ws).err(),
        Some(PipelineError::Image(ImageError::SizeMismatch {
            expected: (W, H),
            got: (W, H - 1),
        }))
    );
    let mut few = vec![0u64; workspace_words(W, H, &params) - 1];
    assert!(matches!(
        p.run_with_disparity(&lv, &rv, &mv, &mut few).err(),
        Some(PipelineError::WorkspaceTooSmall { .. })
    ));
}
