//! `protogist run`: the whole pipeline on a stereo pair: conspicuity,
//! disparity (the f32 disparity energy model, or given ground truth),
//! figure-ground, object masks and shape vectors, with the paper's Fig. 2
//! panels, Fig. 4-style shape plots and a `report.json`.

use crate::demo::finish_with;
use crate::error::{HostError, Result};
use crate::panels::{rgb_from, Panel};
use crate::reference::stereo::DemParams;
use crate::stages::{run_complete, run_conspicuity, run_segment, run_shape};
use crate::stereo_cmd::{decoder_for, disparity_panel, load_pair};
use crate::summary::Summary;
use protogist::complete::CompleteParams;
use protogist::conspicuity::{EdgeParams, LuvTables};
use protogist::disparity::{Disparity, DisparityCell};
use protogist::image::ImageView;
use protogist::segment::{SegmentParams, STAT_FRAC_BITS};
use std::path::PathBuf;
use std::time::Instant;

/// Options of `protogist run`.
#[derive(Clone, Debug, PartialEq, clap::Args)]
pub struct RunOptions {
    /// Left image (PNG or JPEG).
    #[arg(long)]
    pub left: PathBuf,
    /// Right image, the same size as the left.
    #[arg(long)]
    pub right: PathBuf,
    /// Ground-truth disparity of the left view at the input size, used
    /// instead of the model: a grey PNG (0 = unknown) or a PFM.
    #[arg(long)]
    pub gt_disparity: Option<PathBuf>,
    /// PNG ground-truth values per pixel of disparity.
    #[arg(long, default_value_t = 1.0)]
    pub gt_scale: f32,
    /// Working width, px (area-averaged down, aspect kept).
    #[arg(long, default_value_t = 160)]
    pub width: u32,
    /// Objects to detect, most salient first (the paper: 1).
    #[arg(long, default_value_t = 1)]
    pub objects: u8,
    /// Segment the model's raw disparity, without the completion over
    /// conspicuity regions (`protogist::complete`).
    #[arg(long)]
    pub raw_disparity: bool,
    /// Largest disparity the model searches, px of the working size.
    #[arg(long, default_value_t = 15)]
    pub max_disp: u8,
    /// Border refinement radius of the model, px (0: off, the default).
    #[arg(long, default_value_t = 0)]
    pub refine: u8,
    /// Output directory (created if missing).
    #[arg(long)]
    pub out: PathBuf,
}

/// A GT disparity in px as a cell (OFF when unknown or out of range).
fn gt_cell(v: Option<f32>) -> DisparityCell {
    v.filter(|v| v.is_finite() && (0.0..255.0).contains(v))
        .map(Disparity::from_num)
        .into()
}

/// Runs the pipeline and writes the panels and `report.json`.
///
/// # Errors
/// [`HostError`] for unreadable or mismatched inputs, bad parameters, or an
/// unwritable output directory. Nothing is left under a final name when a
/// run fails.
pub fn run_pipeline(opts: &RunOptions) -> Result<Summary> {
    let start = Instant::now();
    let seg_params = SegmentParams {
        max_objects: opts.objects,
        ..SegmentParams::default()
    };
    seg_params.validate()?;
    let pair = load_pair(
        &opts.left,
        &opts.right,
        opts.gt_disparity.as_deref(),
        opts.gt_scale,
        opts.width,
    )?;
    let (w, h) = (pair.width, pair.height);
    let mut s = Summary::new(format!("protogist run: {}", opts.left.display()));
    s.push("working size", format!("{w}x{h}"));

    let edges = run_conspicuity(&LuvTables::new(), &EdgeParams::default(), &pair.left, w, h)?;
    let (disparity, disparity_f32, source) = match &pair.gt {
        Some(gt) => (
            gt.data.iter().map(|&v| gt_cell(v)).collect::<Vec<_>>(),
            gt.data.clone(),
            "ground truth",
        ),
        None => {
            let params = DemParams {
                max_disp: opts.max_disp,
                refine_radius: opts.refine,
                ..DemParams::default()
            };
            let decoder = decoder_for(&params, None)?;
            let maps = crate::reference::stereo::stereo(
                &params,
                &decoder,
                &ImageView::packed(&pair.left, w, h)?,
                &ImageView::packed(&pair.right, w, h)?,
            )?;
            if opts.raw_disparity {
                (
                    maps.disparity,
                    maps.disparity_f32,
                    "disparity energy model (f32), raw",
                )
            } else {
                let (done, report) = run_complete(
                    &CompleteParams::default(),
                    &edges.edges,
                    &edges.smoothed,
                    &maps.disparity,
                    w,
                    h,
                )?;
                s.push(
                    "disparity completion",
                    format!(
                        "{} regions, {} cells replaced, {} filled",
                        report.regions, report.replaced, report.filled
                    ),
                );
                let f32s = done
                    .iter()
                    .map(|c| c.get().map(|d| d.to_num::<f32>()))
                    .collect();
                (
                    done,
                    f32s,
                    "disparity energy model (f32), completed over conspicuity regions",
                )
            }
        }
    };
    s.push("disparity", source);
    let max_d = disparity_f32
        .iter()
        .flatten()
        .fold(1.0f32, |a, &b| a.max(b));
    let seg = run_segment(&seg_params, &disparity, &edges.edges, w, h)?;
    seg.summarise(&mut s, None);

    let mut panels = vec![
        Panel::new("a_left", rgb_from(&pair.left, w, h)),
        Panel::new("b_disparity", disparity_panel(&disparity_f32, w, h, max_d)),
        Panel::new("d_conspicuity", crate::panels::edges(&edges.edges, w, h)),
    ];
    panels.extend(seg.panels(&pair.left));
    let scale = f64::from(1u32 << STAT_FRAC_BITS);
    let mut objects = Vec::new();
    for (k, d) in seg.report.objects.iter().enumerate() {
        let shape = if d.area > 0 {
            match run_shape(&seg.mask_u8(k), w, h, "segmented mask") {
                Ok(r) => Some(r),
                Err(HostError::Shape(_)) => None,
                Err(e) => return Err(e),
            }
        } else {
            None
        };
        if let Some(sh) = &shape {
            panels.push(Panel::new(
                format!("shape_vector_{k}"),
                crate::plot::shape_vector(&sh.vector, w as u32, h as u32),
            ));
        }
        objects.push(serde_json::json!({
            "rank": k,
            "bbox": d.bbox.map(|b| serde_json::json!({
                "x": b.x, "y": b.y, "width": b.width, "height": b.height
            })),
            "disparity_range_px": [d.range.low as f64 / scale, d.range.high as f64 / scale],
            "delta_px": d.delta,
            "saliency": d.score,
            "area_px": d.area,
            "shape_vector": shape.map(|sh| sh.vector),
        }));
    }
    let report = serde_json::json!({
        "left": opts.left.display().to_string(),
        "right": opts.right.display().to_string(),
        "width": w,
        "height": h,
        "disparity": source,
        "objects": objects,
    });
    let mut out = crate::output::Output::dir(&opts.out);
    out.add_json("report.json", &report)?;
    finish_with(out, panels, &mut s, start)?;
    Ok(s)
}
