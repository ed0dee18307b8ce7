use super::*;
use protogist::conspicuity::{edge_conspicuity, EdgeBuffers};
use protogist::synth::{render_left, SceneSpec};

#[test]
fn step_by_step_equals_the_whole_stage() {
    let (w, h) = (48, 36);
    let mut px = vec![Rgb8::default(); w * h];
    render_left(
        &SceneSpec::demo(w, h),
        &mut ImageViewMut::packed(&mut px, w, h).unwrap(),
    )
    .unwrap();
    let (tables, params) = (LuvTables::new(), EdgeParams::default());
    let maps = run_conspicuity(&tables, &params, &px, w, h).unwrap();

    let (mut a, mut b, mut r, mut c) = (
        vec![Luv::default(); w * h],
        vec![Luv::default(); w * h],
        vec![Luv::default(); row_scratch_len(w)],
        vec![EdgeCell::OFF; w * h],
    );
    let report = {
        let mut bufs = EdgeBuffers::new(w, h, &mut a, &mut b, &mut r, &mut c).unwrap();
        let input = ImageView::packed(&px, w, h).unwrap();
        edge_conspicuity(&tables, &params, &input, &mut bufs).unwrap()
    };
    assert_eq!((report.max, report.on_count), (maps.max, maps.on_count));
    assert_eq!((a, b, c), (maps.luv, maps.smoothed, maps.edges));
}

#[test]
fn boundary_score_counts_edges_beside_the_outline() {
    // 6x6, object = the right half; edges on column 3 and at (0, 0).
    let (w, h) = (6, 6);
    let mask: Vec<u8> = (0..w * h)
        .map(|i| if i % w >= 3 { 255 } else { 0 })
        .collect();
    let on = EdgeCell::on(Conspicuity::from_num(5)).unwrap();
    let edges: Vec<EdgeCell> = (0..w * h)
        .map(|i| {
            if i % w == 3 || i == 0 {
                on
            } else {
                EdgeCell::OFF
            }
        })
        .collect();
    let s = BoundaryScore::new(&edges, &mask, w, h);
    assert_eq!((s.on_boundary, s.elsewhere), (6, 1));
    assert_eq!((s.outline, s.outline_hit), (6, 6));
}
