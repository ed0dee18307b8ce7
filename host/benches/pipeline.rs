//! Host speed of the whole product pipeline (core, fixed point, single
//! thread) on the demo stereo pair at 160x120 with K = 4: the figure to
//! set beside OpenCV SGBM's time for stereo alone (docs/BENCHMARKS.md).
//!
//! `cargo bench -p protogist-host`; `cargo xtask bench` runs it.

use criterion::{criterion_group, criterion_main, Criterion};
use protogist::image::{ImageView, ImageViewMut, Rgb8};
use protogist::pipeline::{workspace_words, Pipeline, PipelineParams};
use protogist::synth::{render_left, render_right, SceneSpec};
use protogist_host::classify::shipped::SHIPPED_MODEL;
use protogist_host::product::DEFAULT_TABLES;
use std::hint::black_box;
use std::time::Duration;

fn bench(c: &mut Criterion) {
    let (w, h) = (160, 120);
    let spec = SceneSpec::demo(w, h);
    let (mut l, mut r) = (vec![Rgb8::default(); w * h], vec![Rgb8::default(); w * h]);
    render_left(
        &spec,
        &mut ImageViewMut::packed(&mut l, w, h).expect("size"),
    )
    .expect("render");
    render_right(
        &spec,
        &mut ImageViewMut::packed(&mut r, w, h).expect("size"),
    )
    .expect("render");
    let params = PipelineParams::DEFAULT.with_objects(4);
    let pipeline = Pipeline::new(&params, &DEFAULT_TABLES, SHIPPED_MODEL).expect("set-up");
    let mut ws = vec![0u64; workspace_words(w, h, &params)];
    let (lv, rv) = (
        ImageView::packed(&l, w, h).expect("size"),
        ImageView::packed(&r, w, h).expect("size"),
    );
    let mut group = c.benchmark_group("pipeline");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    group.bench_function(format!("core/{w}x{h}"), |b| {
        b.iter(|| {
            pipeline
                .run(black_box(&lv), black_box(&rv), &mut ws)
                .map(|f| f.objects().len())
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
