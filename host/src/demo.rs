//! The built-in demo: a deterministic synthetic stereo scene through every
//! stage the core has, with panels and a summary.
//!
//! Each stage contributes panels and summary lines; a new stage is one more
//! block in [`run_demo`]. Everything is rendered in memory first, and only
//! then written by [`crate::output::finish`], so a failure leaves no half-written output.

use crate::error::{HostError, Result};
use crate::panels::{self, Panel};
use crate::reference_chain::{run_chain, Source};
use crate::stages::run_conspicuity;
use crate::summary::Summary;
use protogist::conspicuity::{EdgeParams, LuvTables};
use protogist::disparity::from_pixels;
use protogist::image::{buffer_len, ImageViewMut, Rgb8};
use protogist::pipeline::PipelineParams;
use protogist::synth::{render_disparity, render_left, render_mask, render_right, SceneSpec};
use std::path::PathBuf;
use std::time::Instant;

/// Options of the demo.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DemoOptions {
    /// Output directory.
    pub out: PathBuf,
    /// Frame width.
    pub width: usize,
    /// Frame height.
    pub height: usize,
}

impl Default for DemoOptions {
    fn default() -> Self {
        Self {
            out: PathBuf::from("protogist-out"),
            width: 160,
            height: 120,
        }
    }
}

/// The synthetic scene and its ground truth, packed row-major.
struct Scene {
    spec: SceneSpec,
    left: Vec<Rgb8>,
    right: Vec<Rgb8>,
    disparity: Vec<u8>,
    /// Union of all object masks, 0 or 255.
    mask: Vec<u8>,
}

fn render_scene(width: usize, height: usize) -> Result<Scene> {
    let spec = SceneSpec::demo(width, height);
    let n = width * height;
    let (mut left, mut right) = (vec![Rgb8::default(); n], vec![Rgb8::default(); n]);
    let (mut disparity, mut mask, mut one) = (vec![0u8; n], vec![0u8; n], vec![0u8; n]);
    render_left(&spec, &mut ImageViewMut::packed(&mut left, width, height)?)?;
    render_right(&spec, &mut ImageViewMut::packed(&mut right, width, height)?)?;
    render_disparity(
        &spec,
        &mut ImageViewMut::packed(&mut disparity, width, height)?,
    )?;
    for i in 0..spec.objects.len() {
        render_mask(
            &spec,
            i,
            &mut ImageViewMut::packed(&mut one, width, height)?,
        )?;
        mask.iter_mut().zip(&one).for_each(|(m, &o)| *m |= o);
    }
    Ok(Scene {
        spec,
        left,
        right,
        disparity,
        mask,
    })
}

fn describe_objects(spec: &SceneSpec) -> String {
    let objects: Vec<String> = spec
        .objects
        .iter()
        .map(|o| {
            format!(
                "{:?} at ({}, {}) {}x{} px, disparity {}",
                o.shape,
                o.cx,
                o.cy,
                2 * o.rx + 1,
                2 * o.ry + 1,
                o.disparity
            )
        })
        .collect();
    format!(
        "{} ({}); background disparity {}",
        spec.objects.len(),
        objects.join("; "),
        spec.background_disparity
    )
}

/// Runs the demo and writes its panels; returns the summary to print.
///
/// # Errors
/// [`HostError`] for a bad frame size or an output directory that cannot be
/// written; nothing final-named is then left from this run.
pub fn run_demo(opts: &DemoOptions) -> Result<Summary> {
    let start = Instant::now();
    let (w, h) = (opts.width, opts.height);
    if w == 0 {
        return Err(HostError::ZeroDimension { name: "width" });
    }
    if h == 0 {
        return Err(HostError::ZeroDimension { name: "height" });
    }
    buffer_len(w, h, w)?;

    let mut summary = Summary::new("protogist demo: synthetic stereo scene");
    let scene = render_scene(w, h)?;
    summary.push("scene", format!("{w}x{h}"));
    summary.push("objects", describe_objects(&scene.spec));
    let mut out = vec![
        Panel::new("left", panels::rgb_from(&scene.left, w, h)),
        Panel::new("right", panels::rgb_from(&scene.right, w, h)),
        Panel::new("gt_disparity", panels::disparity(&scene.disparity, w, h)),
        Panel::new("gt_mask", panels::grey_from(&scene.mask, w, h, |v| v)),
    ];

    // Stage 1: edge conspicuity of the left image.
    let maps = run_conspicuity(&LuvTables::new(), &EdgeParams::default(), &scene.left, w, h)?;
    out.extend(maps.panels());
    maps.summarise(&mut summary);
    maps.boundary_score(&scene.mask).summarise(&mut summary);

    // Stages 2 to 5: core's pipeline, the firmware's bits: stereo,
    // completion, figure-ground, shape vectors and categories.
    let params = PipelineParams::DEFAULT
        .with_objects(4)
        .with_max_disp(crate::product::default_max_disp(w));
    let tables = crate::product::tables_for(&params)?;
    let run = crate::product::run_frame(
        &params,
        &tables,
        crate::classify::shipped::SHIPPED_MODEL,
        &scene.left,
        &scene.right,
        w,
        h,
    )?;
    out.extend(
        run.panels(&scene.left)
            .into_iter()
            .filter(|p| p.name != "a_left"),
    );
    summary.push(
        "pipeline",
        format!(
            "core, fixed point (the firmware's bits): {} objects in {} searches, {:.1} ms, {} bytes of workspace",
            run.objects.len(),
            run.searches,
            run.elapsed.as_secs_f64() * 1e3,
            run.workspace_bytes
        ),
    );
    for o in &run.objects {
        let iou = mask_iou(&o.mask, &scene.mask);
        summary.push(
            format!("object {}", o.object.rank),
            format!(
                "{} (top 5: {}), disparity {} px, mask IoU with GT {iou:.3}",
                o.label(),
                o.top
                    .iter()
                    .map(|(c, v)| format!("{c} {v:.2}"))
                    .collect::<Vec<_>>()
                    .join(", "),
                o.object.delta
            ),
        );
    }
    // Figure-ground from ground-truth disparity, for comparison.
    let gt_disparity: Vec<_> = scene.disparity.iter().map(|&d| from_pixels(d)).collect();
    let mut chain_gt = run_chain(
        &params.segment,
        Source::Given(&gt_disparity),
        &scene.left,
        &scene.right,
        w,
        h,
    )?;
    chain_gt.relabel(params.relabel.as_ref(), &scene.left, &scene.right);
    chain_gt.depth_hole(params.depth_hole.as_ref());
    let seg_gt = chain_gt.segment;
    summary.push(
        "mask IoU, GT disparity",
        format!("{:.3}", seg_gt.iou(0, &scene.mask)),
    );
    crate::classify::shipped::summarise_objects(&seg_gt, ", GT disparity", &mut summary)?;
    // The result as the board would draw it: boxes and categories.
    out.push(run.objects_panel(&scene.left));

    crate::output::finish(&opts.out, out, &mut summary, start)?;
    Ok(summary)
}

/// IoU of a mask and a 0/255 GT mask.
fn mask_iou(a: &[bool], gt: &[u8]) -> f64 {
    let (i, u) = a.iter().zip(gt).fold((0usize, 0usize), |(i, u), (&x, &y)| {
        let y = y != 0;
        (i + usize::from(x && y), u + usize::from(x || y))
    });
    if u == 0 {
        1.0
    } else {
        i as f64 / u as f64
    }
}
