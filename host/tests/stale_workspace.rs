//! The pipeline does not clear the buffers it carves from the workspace
//! (clearing them cost about 0.24 M instructions a frame on the board):
//! every stage writes what it reads. A frame run in a workspace of random
//! bytes, or in the workspace another frame left, gives the same bits,
//! every intermediate map included, as one run in a zeroed workspace.

use protogist::image::{ImageView, Rgb8};
use protogist::pipeline::{workspace_words, Pipeline, PipelineParams};
use protogist_host::product::{default_max_disp, tables_for, Maps};
use protogist_host::scenes::render::render_scene;
use protogist_host::scenes::{SceneKey, SceneParams, Split};

const MODEL: &[u8] = include_bytes!("../data/shapes_model.bin");

/// Scene `index` of the training split, seed 7, as packed frames.
fn scene(index: u64) -> (Vec<Rgb8>, Vec<Rgb8>, usize, usize) {
    let params = SceneParams {
        width: 160,
        height: 120,
        classes: 19,
        objects: (1, 4),
    };
    let key = SceneKey {
        seed: 7,
        split: Split::Train,
        index,
    };
    let s = render_scene(&params, key).unwrap();
    let px = |im: &image::RgbImage| im.pixels().map(|p| Rgb8::new(p[0], p[1], p[2])).collect();
    (px(&s.left), px(&s.right), 160, 120)
}

/// Every map the observer records, and the objects, of one run in `ws`.
fn run(
    p: &Pipeline,
    (l, r, w, h): &(Vec<Rgb8>, Vec<Rgb8>, usize, usize),
    ws: &mut [u64],
) -> String {
    let mut maps = Maps::default();
    let lv = ImageView::packed(l, *w, *h).unwrap();
    let rv = ImageView::packed(r, *w, *h).unwrap();
    let frame = p.run_observed(&lv, &rv, ws, &mut maps).unwrap();
    let searches: Vec<_> = maps
        .searches
        .iter()
        .map(|s| (&s.d_fg, &s.c_fg, &s.d_obj_reg, &s.c_obj_reg, &s.c_obj))
        .collect();
    format!(
        "{:?} {:?} {:?} {:?} {:?} {:?} {:?}",
        maps.raw_disparity,
        maps.smoothed,
        maps.edges,
        maps.disparity,
        searches,
        frame.objects(),
        frame
            .objects()
            .iter()
            .map(|o| frame.shape(o).map(|v| v.to_vec()))
            .collect::<Vec<_>>(),
    )
}

#[test]
fn a_frame_gives_the_same_bits_whatever_its_workspace_held() {
    let params = PipelineParams::DEFAULT
        .with_objects(4)
        .with_max_disp(default_max_disp(160));
    let tables = tables_for(&params).unwrap();
    let refs: Vec<&[u8]> = tables.iter().map(Vec::as_slice).collect();
    let p = Pipeline::new(&params, &refs, MODEL).unwrap();
    let words = workspace_words(160, 120, &params);
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut noise = || {
        // SplitMix64.
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    // One workspace reused frame after frame, as the firmware does.
    let mut reused = vec![0u64; words];
    for index in 0..6 {
        let frames = scene(index);
        let clean = run(&p, &frames, &mut vec![0u64; words]);
        let mut random: Vec<u64> = (0..words).map(|_| noise()).collect();
        assert!(
            run(&p, &frames, &mut random) == clean,
            "scene {index}: random workspace"
        );
        assert!(
            run(&p, &frames, &mut reused) == clean,
            "scene {index}: reused workspace"
        );
        // All ones: every OFF, every bit set.
        assert!(
            run(&p, &frames, &mut vec![u64::MAX; words]) == clean,
            "scene {index}: ones"
        );
    }
}
