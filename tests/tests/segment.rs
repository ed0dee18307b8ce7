//! Mask accuracy on seeded synthetic scenes, GT disparity as input.

use protogist::conspicuity::{edge_conspicuity, EdgeParams, LuvTables};
use protogist::disparity::{from_pixels, DisparityCell};
use protogist::image::{ImageView, ImageViewMut, Rgb8};
use protogist::segment::{segment, SegmentParams};
use protogist::synth::{render_disparity, render_left, render_mask, SceneSpec};
use protogist_tests::{EdgeStorage, SegmentStorage};

const W: usize = 160;
const H: usize = 120;
const SCENES: u64 = 24;

fn iou(a: &[bool], b: &[bool]) -> f64 {
    let inter = a.iter().zip(b).filter(|(x, y)| **x && **y).count();
    let union = a.iter().zip(b).filter(|(x, y)| **x || **y).count();
    if union == 0 {
        0.0
    } else {
        inter as f64 / union as f64
    }
}

/// Best IoU of the detected mask against any GT object mask, and which.
fn scene_iou(seed: u64, params: &SegmentParams) -> (f64, usize, String) {
    let spec = SceneSpec::random(seed, W, H);
    let mut rgb = vec![Rgb8::default(); W * H];
    render_left(&spec, &mut ImageViewMut::packed(&mut rgb, W, H).unwrap()).unwrap();
    let mut edges = EdgeStorage::new(W, H);
    let mut eb = edges.buffers();
    edge_conspicuity(
        &LuvTables::new(),
        &EdgeParams::default(),
        &ImageView::packed(&rgb, W, H).unwrap(),
        &mut eb,
    )
    .unwrap();
    let mut gt = vec![0u8; W * H];
    render_disparity(&spec, &mut ImageViewMut::packed(&mut gt, W, H).unwrap()).unwrap();
    let d: Vec<DisparityCell> = gt.iter().map(|&v| from_pixels(v)).collect();
    let mut store = SegmentStorage::new(W, H);
    let mut masks = vec![false; W * H];
    let report = segment(
        params,
        &ImageView::packed(&d, W, H).unwrap(),
        &eb.conspicuity(),
        &mut store.buffers(),
        &mut masks,
    )
    .unwrap();
    let mut best = (0.0, usize::MAX);
    for i in 0..spec.objects.len() {
        let mut m = vec![0u8; W * H];
        render_mask(&spec, i, &mut ImageViewMut::packed(&mut m, W, H).unwrap()).unwrap();
        let m: Vec<bool> = m.iter().map(|&v| v != 0).collect();
        let v = iou(&masks, &m);
        if v > best.0 {
            best = (v, i);
        }
    }
    let objs: Vec<String> = spec
        .objects
        .iter()
        .map(|o| format!("{:?} {}x{} d{}", o.shape, 2 * o.rx, 2 * o.ry, o.disparity))
        .collect();
    let det = report.objects.first().map_or("none".to_string(), |o| {
        format!(
            "δ{} area {} regions {}/{}",
            o.delta, o.area, o.regions.kept, o.regions.regions
        )
    });
    let info = format!(
        "bg d{} | {} | {}",
        spec.background_disparity,
        objs.join(", "),
        det
    );
    (best.0, best.1, info)
}

#[test]
fn mean_mask_iou_on_seeded_scenes() {
    let params = SegmentParams::default();
    let mut sum = 0.0;
    for seed in 0..SCENES {
        let (v, i, info) = scene_iou(seed, &params);
        println!("scene {seed:2}: IoU {v:.3} (object {i}) {info}");
        sum += v;
    }
    let mean = sum / SCENES as f64;
    println!("mean IoU over {SCENES} scenes: {mean:.3}");
    assert!(mean >= 0.85, "mean IoU {mean:.3} < 0.85");
}
