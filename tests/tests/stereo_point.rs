//! The pipeline's stereo point (`pipeline::STEREO_DEFAULT`,
//! `C2fParams::HALF_NARROW`) against `C2fParams::FAST`: a small object
//! well in front of its background keeps its disparity with the low SGM
//! penalty, where `fast`'s large-step penalty gives much of it the
//! background's (docs/PIPELINE.md, "The stereo point"); and against
//! `C2fParams::HALF_LOW_PENALTY`: with narrow filters more of a small
//! object's interior takes its disparity (docs/CHOICES.md, "Narrow
//! filters"). And the `accurate` preset's point,
//! `C2fParams::FAST_NARROW_FULL_SEARCH`: the pipeline's point searching
//! every disparity at the half-size level (and refined by phase), which
//! finds a small object of a generated scene that the coarse-to-fine
//! default loses.

use protogist::disparity::DisparityCell;
use protogist::image::{ImageView, ImageViewMut, Rgb8};
use protogist::pipeline::{PipelineParams, STEREO_DEFAULT};
use protogist::segment::Relabel;
use protogist::stereo::c2f::{C2f, C2fParams};
use protogist::stereo::phase::PhaseParams;
use protogist::stereo::DemTable;
use protogist::synth::{render_left, render_right, ObjectSpec, SceneSpec, Shape};
use protogist_host::storage::C2fStorage;

const W: usize = 160;
const H: usize = 120;

/// A textured background at disparity 3 and one small square at `d`.
fn scene(seed: u64, d: u8) -> (SceneSpec, Vec<Rgb8>, Vec<Rgb8>) {
    let mut spec = SceneSpec {
        seed,
        background_disparity: 3,
        background_colour: Rgb8::new(150, 110, 70),
        background_texture: 40,
        ..SceneSpec::demo(W, H)
    };
    spec.objects[0] = ObjectSpec {
        shape: Shape::Rectangle,
        cx: 90,
        cy: 60,
        rx: 9,
        ry: 9,
        disparity: d,
        colour: Rgb8::new(60, 150, 200),
    };
    let mut l = vec![Rgb8::default(); W * H];
    let mut r = l.clone();
    render_left(&spec, &mut ImageViewMut::packed(&mut l, W, H).unwrap()).unwrap();
    render_right(&spec, &mut ImageViewMut::packed(&mut r, W, H).unwrap()).unwrap();
    (spec, l, r)
}

/// `f` on the engine of `p`, with the decoder tables and buffers of a
/// 160x120 run at 32 disparities, and the pair's views.
fn with_engine<R>(
    p: &C2fParams,
    l: &[Rgb8],
    r: &[Rgb8],
    f: impl FnOnce(&C2f, &[DemTable<'_>], &mut C2fStorage, [ImageView<'_, Rgb8>; 2]) -> R,
) -> R {
    let pipeline = PipelineParams {
        stereo: *p,
        ..PipelineParams::DEFAULT
    }
    .with_max_disp(31);
    let bytes = protogist_host::product::tables_for(&pipeline).unwrap();
    let tables: Vec<DemTable<'_>> = bytes.iter().map(|t| DemTable::parse(t).unwrap()).collect();
    let e = C2f::new(&pipeline.stereo).unwrap();
    let mut st = C2fStorage::new(W, H, &pipeline.stereo);
    let views = [
        ImageView::packed(l, W, H).unwrap(),
        ImageView::packed(r, W, H).unwrap(),
    ];
    f(&e, &tables, &mut st, views)
}

/// The map of `p` on the pair.
fn run(p: &C2fParams, l: &[Rgb8], r: &[Rgb8]) -> Vec<DisparityCell> {
    with_engine(p, l, r, |e, tables, st, [lv, rv]| {
        let mut out = vec![DisparityCell::OFF; W * H];
        e.run(
            tables,
            &lv,
            &rv,
            &mut st.buffers(),
            &mut |x, y, c| out[y * W + x] = c,
            &mut (),
        )
        .unwrap();
        out
    })
}

/// The fraction of the object's inner pixels (2 px from its outline)
/// estimated within 2 px of its disparity.
fn object_right(spec: &SceneSpec, map: &[DisparityCell]) -> f64 {
    let o = &spec.objects[0];
    let inner = ObjectSpec {
        rx: o.rx - 2,
        ry: o.ry - 2,
        ..*o
    };
    let (mut n, mut good) = (0u32, 0u32);
    for y in 0..H {
        for x in 0..W {
            if !inner.contains(x as i32, y as i32) {
                continue;
            }
            n += 1;
            let d = map[y * W + x].get().map(f64::from);
            if d.is_some_and(|d| (d - f64::from(o.disparity)).abs() <= 2.0) {
                good += 1;
            }
        }
    }
    f64::from(good) / f64::from(n)
}

#[test]
fn the_pipeline_point_is_half_with_one_low_penalty_and_narrow_filters() {
    assert_eq!(STEREO_DEFAULT, C2fParams::HALF_NARROW);
    let mut narrow = C2fParams {
        phase: None,
        ..C2fParams::FAST_LOW_PENALTY
    };
    assert_eq!(narrow, C2fParams::HALF_LOW_PENALTY);
    narrow.dem.radius = 2;
    assert_eq!(narrow, STEREO_DEFAULT);
    assert_eq!(C2fParams::from_name("half-narrow"), Some(STEREO_DEFAULT));
    assert_eq!(STEREO_DEFAULT.name(), Some("half-narrow"));
    // The paper's preset keeps the design's 15-tap kernels.
    assert_eq!(PipelineParams::PAPER.stereo, C2fParams::HALF_LOW_PENALTY);
    let p = C2fParams::FAST_LOW_PENALTY;
    assert_eq!((p.p1, p.p2), (0.25, 0.25));
    assert_eq!(
        C2fParams {
            p1: C2fParams::FAST.p1,
            p2: C2fParams::FAST.p2,
            ..p
        },
        C2fParams::FAST
    );
    assert_eq!(C2fParams::from_name("fast-low-penalty"), Some(p));
    assert_eq!(p.name(), Some("fast-low-penalty"));
}

#[test]
fn a_small_near_object_keeps_its_disparity_at_the_pipeline_point() {
    let (mut fast_sum, mut low_sum) = (0.0, 0.0);
    for seed in 1..=4u64 {
        let (spec, l, r) = scene(seed, 24);
        let fast = object_right(&spec, &run(&C2fParams::FAST, &l, &r));
        let low = object_right(&spec, &run(&STEREO_DEFAULT, &l, &r));
        println!("seed {seed}: object right at fast {fast:.3}, at the pipeline's point {low:.3}");
        assert!(low > fast + 0.25, "seed {seed}: {low} against {fast}");
        fast_sum += fast;
        low_sum += low;
    }
    // Over the seeds, a large part of the object is right at the
    // pipeline's point.
    assert!(low_sum / 4.0 >= 0.4, "{low_sum} against {fast_sum}");
}

#[test]
fn narrow_filters_get_more_of_a_small_object_right() {
    // A 19 px square 9 or 17 px in front of its background: at the
    // coarse level the design's 15-tap kernels average it into its
    // surroundings more than 5-tap ones do.
    let (mut wide_sum, mut narrow_sum, mut n) = (0.0, 0.0, 0.0);
    for d in [12u8, 20] {
        for seed in 1..=6u64 {
            let (spec, l, r) = scene(seed, d);
            let wide = object_right(&spec, &run(&C2fParams::HALF_LOW_PENALTY, &l, &r));
            let narrow = object_right(&spec, &run(&C2fParams::HALF_NARROW, &l, &r));
            println!("d {d} seed {seed}: object right at half-low-penalty {wide:.3}, half-narrow {narrow:.3}");
            wide_sum += wide;
            narrow_sum += narrow;
            n += 1.0;
        }
    }
    assert!(
        narrow_sum / n >= wide_sum / n + 0.15,
        "{narrow_sum} against {wide_sum} over {n} scenes"
    );
}

#[test]
fn run_into_a_map_gives_the_cells_run_gives() {
    let (_, l, r) = scene(5, 20);
    for p in [
        C2fParams::HALF_NARROW,
        C2fParams::HALF_LOW_PENALTY,
        C2fParams::FAST_LOW_PENALTY,
        C2fParams::FULL,
    ] {
        let cells = run(&p, &l, &r);
        with_engine(&p, &l, &r, |e, tables, st, [lv, rv]| {
            // A value no cell takes: the map must come out with every
            // cell written (the pipeline does not clear it first).
            let stale: DisparityCell = Some(protogist::disparity::Disparity::from_num(250)).into();
            let mut map = vec![stale; W * H];
            let mut view = ImageViewMut::packed(&mut map, W, H).unwrap();
            e.run_into(tables, &lv, &rv, &mut st.buffers(), &mut view, &mut ())
                .unwrap();
            assert_eq!(map, cells, "{:?}", p.name());
            // A map of another size is a typed error.
            let mut short = vec![DisparityCell::OFF; W * (H - 1)];
            let mut view = ImageViewMut::packed(&mut short, W, H - 1).unwrap();
            let err = e
                .run_into(tables, &lv, &rv, &mut st.buffers(), &mut view, &mut ())
                .unwrap_err();
            assert!(
                matches!(err, protogist::stereo::StereoError::Image(_)),
                "{err:?}"
            );
        });
    }
}

#[test]
fn the_accurate_preset_is_the_default_with_a_full_search_at_half_size_refined_by_phase() {
    let p = PipelineParams::ACCURATE;
    // The default pipeline but for the stereo point's coarse levels, the
    // mirror check, which it runs on every object, the band
    // relabelling of low-contrast masks and the hole by disparity.
    assert!(p.mirror_check);
    assert_eq!(p.mirror_below_q16, u32::MAX);
    assert_eq!(p.relabel, Some(Relabel::DEFAULT));
    assert_eq!(PipelineParams::DEFAULT.relabel, None);
    assert_eq!(p.depth_hole, Some(protogist::segment::DepthHole::DEFAULT));
    assert_eq!(PipelineParams::DEFAULT.depth_hole, None);
    assert_eq!(
        PipelineParams {
            stereo: STEREO_DEFAULT,
            mirror_below_q16: protogist::pipeline::MIRROR_BELOW_DEFAULT,
            relabel: None,
            depth_hole: None,
            ..p
        },
        PipelineParams::DEFAULT
    );
    assert_eq!(p.stereo, C2fParams::FAST_NARROW_FULL_SEARCH);
    assert_eq!(
        p.stereo,
        C2fParams {
            coarse: 1,
            phase: Some(PhaseParams::DEFAULT),
            ..C2fParams::HALF_NARROW
        }
    );
    // Every disparity at the half-size level, refined to the frame's
    // resolution by phase; two tables, levels 0 and 1 of the default's.
    assert_eq!((p.stereo.coarse, p.stereo.finest), (1, 1));
    assert_eq!(p.stereo.phase, Some(PhaseParams::DEFAULT));
    assert_eq!(p.stereo.candidates(1), 17);
    assert_eq!(p.tables(), 2);
    let tables = protogist_host::product::tables_for(&p).unwrap();
    let bundled: Vec<Vec<u8>> = protogist_host::product::DEFAULT_TABLES[..2]
        .iter()
        .map(|t| t.to_vec())
        .collect();
    assert_eq!(tables, bundled);
    // By name, both ways, for the preset and its stereo point.
    assert_eq!(PipelineParams::from_name("accurate"), Some(p));
    assert_eq!(p.name(), Some("accurate"));
    assert_eq!(PipelineParams::DEFAULT.name(), Some("default"));
    assert_eq!(
        C2fParams::from_name("fast-narrow-full-search"),
        Some(p.stereo)
    );
    assert_eq!(p.stereo.name(), Some("fast-narrow-full-search"));
    assert_eq!(
        protogist_host::product::preset("accurate").unwrap(),
        PipelineParams::ACCURATE
    );
    // The workspace at 160x120 with K = 4, as the product runs. The
    // half-size level's full search and the phase step's rows make the
    // stereo's phase 81,336 B (2,880 B of it the phase step's). The
    // relabelling's rows (10,720 B) share figure-ground's phase (70,752 B
    // of maps, the default's largest phase) and make it the preset's
    // largest, 136 B above the stereo's.
    let bytes = |p: &PipelineParams| protogist::pipeline::workspace_bytes(W, H, &p.with_objects(4));
    assert_eq!(bytes(&p), 173_632);
    assert_eq!(bytes(&p) - bytes(&PipelineParams::DEFAULT), 10_720);
    assert_eq!(protogist::pipeline::layout::relabel_bytes(W, &p), 10_720);
    assert_eq!(
        bytes(&p) - bytes(&PipelineParams { relabel: None, ..p }),
        136
    );
    let unrefined = PipelineParams {
        stereo: C2fParams {
            phase: None,
            ..p.stereo
        },
        ..p
    };
    assert_eq!(bytes(&unrefined), bytes(&p));
    assert_eq!(
        bytes(&p)
            - bytes(&PipelineParams {
                relabel: None,
                ..unrefined
            }),
        136 + 2_880
    );
}

/// Scene `index` of the training split, seed 1, 1 to 4 objects (the set
/// of `protogist gen-scenes --scenes 1000 --seed 1 --split train`), as
/// packed frames, with its truth.
fn training_scene(
    index: u64,
) -> (
    Vec<Rgb8>,
    Vec<Rgb8>,
    Vec<protogist_host::scenes::ObjectTruth>,
) {
    use protogist_host::scenes::{render::render_scene, SceneKey, SceneParams, Split};
    let params = SceneParams {
        width: W as u32,
        height: H as u32,
        classes: 19,
        objects: (1, 4),
    };
    let key = SceneKey {
        seed: 1,
        split: Split::Train,
        index,
    };
    let s = render_scene(&params, key).unwrap();
    let px = |im: &image::RgbImage| im.pixels().map(|p| Rgb8::new(p[0], p[1], p[2])).collect();
    (px(&s.left), px(&s.right), s.objects)
}

/// The boxes of the objects `params` (K = 4, as `gist-eval`) finds, from
/// their masks as `gist-eval` takes them.
fn found_boxes(
    params: &PipelineParams,
    l: &[Rgb8],
    r: &[Rgb8],
) -> Vec<protogist_host::scenes::BoxPx> {
    let params = params
        .with_objects(4)
        .with_max_disp(protogist_host::product::default_max_disp(W));
    let tables = protogist_host::product::tables_for(&params).unwrap();
    let model = protogist_host::classify::shipped::SHIPPED_MODEL;
    let run = protogist_host::product::run_frame(&params, &tables, model, l, r, W, H).unwrap();
    run.objects
        .iter()
        .filter_map(|o| {
            protogist_host::scenes::BoxPx::of(W as u32, H as u32, |x, y| {
                o.mask[y as usize * W + x as usize]
            })
        })
        .collect()
}

#[test]
fn the_accurate_preset_runs_a_frame() {
    // The demo pair, frame in, objects out, in a workspace of the
    // preset's size with its two tables.
    let spec = SceneSpec::demo(W, H);
    let (mut l, mut r) = (vec![Rgb8::default(); W * H], vec![Rgb8::default(); W * H]);
    render_left(&spec, &mut ImageViewMut::packed(&mut l, W, H).unwrap()).unwrap();
    render_right(&spec, &mut ImageViewMut::packed(&mut r, W, H).unwrap()).unwrap();
    let params = PipelineParams::ACCURATE.with_objects(4);
    let tables = protogist_host::product::tables_for(&params).unwrap();
    let refs: Vec<&[u8]> = tables.iter().map(Vec::as_slice).collect();
    let model = protogist_host::classify::shipped::SHIPPED_MODEL;
    let pipeline = protogist::pipeline::Pipeline::new(&params, &refs, model).unwrap();
    let mut ws = vec![0u64; protogist::pipeline::workspace_words(W, H, &params)];
    let (lv, rv) = (
        ImageView::packed(&l, W, H).unwrap(),
        ImageView::packed(&r, W, H).unwrap(),
    );
    let frame = pipeline.run(&lv, &rv, &mut ws).unwrap();
    let objects = frame.objects();
    assert_eq!(objects.len(), 1, "{objects:?}");
    // The demo's object, about where it is drawn.
    let o = &spec.objects[0];
    let b = objects[0].bbox;
    let (cx, cy) = (b.x + b.width / 2, b.y + b.height / 2);
    assert!(
        cx.abs_diff(o.cx as usize) <= 4 && cy.abs_diff(o.cy as usize) <= 4,
        "{b:?} against {o:?}"
    );
    // One table fewer than the default is an error, not a wrong map.
    assert!(protogist::pipeline::Pipeline::new(&params, &refs[..1], model).is_err());
}

#[test]
fn the_accurate_preset_finds_a_small_object_the_default_loses() {
    // Scene 11 of the training set: one arrow, 23x15 px, 21 px of
    // disparity. At the default's coarsest level (40x30) it is about 6x4
    // cells and averages into the wall; the full search at 80x60 keeps
    // it. (From the 1-object scenes of `gist-eval --mode core` with and
    // without the full search: 9 of 261 found only with it, none lost.)
    let (l, r, truth) = training_scene(11);
    assert_eq!(truth.len(), 1);
    let t = &truth[0];
    assert_eq!((t.bbox.width, t.bbox.height), (23, 15));
    let matched = |params: &PipelineParams| {
        let found = found_boxes(params, &l, &r);
        let best = found.iter().map(|b| b.iou(&t.bbox)).fold(0.0, f64::max);
        println!(
            "{:?}: {} objects, best box IoU with the truth {best:.3}",
            params.name(),
            found.len()
        );
        best >= 0.5
    };
    assert!(
        !matched(&PipelineParams::DEFAULT),
        "the default finds it now: pick another scene the default loses"
    );
    assert!(matched(&PipelineParams::ACCURATE));
}
