//! Host speed of the conspicuity stage: fixed-point core against the f32
//! reference, single thread, on the built-in synthetic scene.
//!
//! `cargo bench -p protogist-host`; `cargo xtask bench` runs it and writes
//! ns per pixel into docs/BENCHMARKS.md.

use criterion::{criterion_group, criterion_main, Criterion};
use protogist::conspicuity::{
    edge_conspicuity, row_scratch_len, EdgeBuffers, EdgeCell, EdgeParams, Luv, LuvTables,
};
use protogist::image::{ImageView, ImageViewMut, Rgb8};
use protogist::synth::{render_left, SceneSpec};
use protogist_host::reference::conspicuity as reference;
use std::hint::black_box;
use std::time::Duration;

fn scene(w: usize, h: usize) -> Vec<Rgb8> {
    let mut px = vec![Rgb8::default(); w * h];
    let mut view = ImageViewMut::packed(&mut px, w, h).expect("valid size");
    render_left(&SceneSpec::demo(w, h), &mut view).expect("render");
    px
}

fn bench(c: &mut Criterion) {
    let tables = LuvTables::new();
    let params = EdgeParams::default();
    let mut group = c.benchmark_group("conspicuity");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    for (w, h) in [(160, 120), (320, 240)] {
        let px = scene(w, h);
        let rgb = ImageView::packed(&px, w, h).expect("valid size");
        let (mut luv, mut sm, mut rows, mut cmap) = (
            vec![Luv::default(); w * h],
            vec![Luv::default(); w * h],
            vec![Luv::default(); row_scratch_len(w)],
            vec![EdgeCell::OFF; w * h],
        );
        let mut bufs =
            EdgeBuffers::new(w, h, &mut luv, &mut sm, &mut rows, &mut cmap).expect("buffers");
        group.bench_function(format!("fixed/{w}x{h}"), |b| {
            b.iter(|| edge_conspicuity(&tables, &params, black_box(&rgb), &mut bufs))
        });
        group.bench_function(format!("float/{w}x{h}"), |b| {
            b.iter(|| reference::edge_conspicuity(&params, black_box(&rgb)))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
