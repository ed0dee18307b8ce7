//! `protogist run`: the product on a stereo pair. By default core's
//! fixed-point pipeline ([`protogist::pipeline`], the firmware's bits):
//! stereo, conspicuity, completion, figure-ground for K objects, shape
//! vectors and categories, with per-object Fig. 2 panels, shape plots and
//! a `report.json`. `--reference` runs the f32 chain (the reference stereo,
//! or given ground truth with `--gt-disparity`) and prints its agreement
//! with core's.

use crate::dem_tables::decoder_for;
use crate::error::{HostError, Result};
use crate::pair::load_pair;
use crate::panels::disparity_panel;
use crate::panels::{rgb_from, Panel};
use crate::product::{default_max_disp, run_frame, tables_for};
use crate::reference::stereo::DemParams;
use crate::reference_chain::{run_chain, Source};
use crate::stages::run_shape;
use crate::summary::Summary;
use protogist::disparity::{Disparity, DisparityCell};
use protogist::pipeline::PipelineParams;
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
    /// Objects to detect (K), most salient first (the paper: 1).
    #[arg(long, default_value_t = 4)]
    pub objects: u8,
    /// The classifier's model blob (default: the shipped model).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Also run the f32 reference chain, and print its agreement with
    /// core's pipeline (implied by `--gt-disparity`).
    #[arg(long)]
    pub reference: bool,
    /// Segment the model's raw disparity, without the completion over
    /// conspicuity regions (`protogist::complete`).
    #[arg(long)]
    pub raw_disparity: bool,
    /// Largest disparity searched, px of the working size (default: a
    /// fifth of the working width, less 1: 31 at 160 px).
    #[arg(long)]
    pub max_disp: Option<u8>,
    /// The pipeline's named setting (`default`, `paper` or `accurate`:
    /// `protogist::pipeline::PipelineParams::NAMED`).
    #[arg(long, default_value = "default")]
    pub preset: String,
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

/// Runs core's pipeline (and, when asked, the f32 chain), and writes the
/// panels and `report.json`.
///
/// # Errors
/// [`HostError`] for unreadable or mismatched inputs, bad parameters, or an
/// unwritable output directory, checked before any training. Nothing is
/// left under a final name when a run fails.
pub fn run_pipeline(opts: &RunOptions) -> Result<Summary> {
    let start = Instant::now();
    if !(1..=8).contains(&opts.objects) {
        return Err(HostError::InvalidArgument {
            name: "objects",
            reason: format!("must be 1..=8, got {}", opts.objects),
        });
    }
    let model = match &opts.model {
        Some(path) => std::fs::read(path).map_err(|e| HostError::io(path, e))?,
        None => crate::classify::shipped::SHIPPED_MODEL.to_vec(),
    };
    let pair = load_pair(
        &opts.left,
        &opts.right,
        opts.gt_disparity.as_deref(),
        opts.gt_scale,
        opts.width,
    )?;
    let (w, h) = (pair.width, pair.height);
    let max_disp = opts.max_disp.unwrap_or_else(|| default_max_disp(w));
    if usize::from(max_disp) * 2 >= w {
        return Err(HostError::InvalidArgument {
            name: "max-disp",
            reason: format!("must be below half the working width {w}, got {max_disp}"),
        });
    }
    let preset = crate::product::preset(&opts.preset)?;
    let params = preset.with_objects(opts.objects).with_max_disp(max_disp);
    // The model is checked before any table is trained.
    let mut model_check = params;
    model_check.stereo = PipelineParams::DEFAULT.stereo;
    protogist::pipeline::Pipeline::new(&model_check, &crate::product::DEFAULT_TABLES, &model)
        .map_err(|e| match (&opts.model, e) {
            (Some(path), protogist::pipeline::PipelineError::Model(source)) => {
                HostError::BadModel {
                    path: path.clone(),
                    reason: source.to_string(),
                }
            }
            (_, e) => e.into(),
        })?;
    let scale = f64::from(pair.input_size.0) / w as f64;
    let mut s = Summary::new(format!("protogist run: {}", opts.left.display()));
    s.push(
        "working size",
        format!(
            "{w}x{h} (input {}x{}, scale {scale:.3})",
            pair.input_size.0, pair.input_size.1
        ),
    );
    s.push(
        "pipeline",
        format!(
            "core, fixed point (the firmware's bits), preset {}, max disparity {max_disp}, K = {}",
            opts.preset, opts.objects
        ),
    );
    let tables = tables_for(&params)?;
    let run = run_frame(&params, &tables, &model, &pair.left, &pair.right, w, h)?;
    s.push(
        "objects",
        format!("{} found in {} searches", run.objects.len(), run.searches),
    );
    for o in &run.objects {
        let b = o.object.bbox;
        s.push(
            format!("object {}", o.object.rank),
            format!(
                "{} at ({}, {}) {}x{}, {} px, disparity {} px; top 5: {}",
                o.label(),
                b.x,
                b.y,
                b.width,
                b.height,
                o.object.area,
                o.object.delta,
                o.top
                    .iter()
                    .map(|(c, v)| format!("{c} {v:.2}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        );
    }
    s.push(
        "pipeline time",
        format!(
            "{:.1} ms ({} bytes of workspace)",
            run.elapsed.as_secs_f64() * 1e3,
            run.workspace_bytes
        ),
    );
    let mut panels = run.panels(&pair.left);
    panels.push(run.objects_panel(&pair.left));
    let mut report = serde_json::json!({
        "left": opts.left.display().to_string(),
        "right": opts.right.display().to_string(),
        "input_size": [pair.input_size.0, pair.input_size.1],
        "width": w,
        "height": h,
        "scale": scale,
        "max_disp": max_disp,
        "pipeline": "core",
        "preset": opts.preset,
        "objects": run.objects.iter().map(|o| o.to_json(scale)).collect::<Vec<_>>(),
    });
    if opts.reference || opts.gt_disparity.is_some() {
        let r = reference_chain(opts, &pair, max_disp, &mut s)?;
        let ious: Vec<String> = run
            .objects
            .iter()
            .zip(&r.masks)
            .map(|(o, m)| format!("{:.3}", mask_iou(&o.mask, m)))
            .collect();
        s.push(
            "agreement with the f32 chain",
            format!(
                "{} objects against {}; mask IoU by rank: [{}] ({})",
                run.objects.len(),
                r.masks.len(),
                ious.join(", "),
                r.source
            ),
        );
        report["reference"] = serde_json::json!({
            "disparity": r.source,
            "objects": r.objects,
            "mask_iou_by_rank": ious,
        });
        panels.extend(r.panels);
    }
    let mut out = crate::output::Output::dir(&opts.out);
    out.add_json("report.json", &report)?;
    crate::output::finish_with(out, panels, &mut s, start)?;
    Ok(s)
}

/// IoU of two masks of one size.
fn mask_iou(a: &[bool], b: &[bool]) -> f64 {
    let (i, u) = a.iter().zip(b).fold((0usize, 0usize), |(i, u), (&x, &y)| {
        (i + usize::from(x && y), u + usize::from(x || y))
    });
    if u == 0 {
        1.0
    } else {
        i as f64 / u as f64
    }
}

/// What the f32 reference chain found.
struct ReferenceRun {
    panels: Vec<Panel>,
    objects: Vec<serde_json::Value>,
    /// Masks of the objects with an area, most salient first.
    masks: Vec<Vec<bool>>,
    source: &'static str,
}

/// The f32 chain: the reference stereo (or ground truth), core's
/// completion, segmentation and shape.
fn reference_chain(
    opts: &RunOptions,
    pair: &crate::pair::Pair,
    max_disp: u8,
    s: &mut Summary,
) -> Result<ReferenceRun> {
    let preset = crate::product::preset(&opts.preset)?;
    let seg_params = SegmentParams {
        max_objects: opts.objects,
        ..preset.segment
    };
    seg_params.validate()?;
    let (w, h) = (pair.width, pair.height);

    let gt: Option<Vec<DisparityCell>> = pair
        .gt
        .as_ref()
        .map(|gt| gt.data.iter().map(|&v| gt_cell(v)).collect());
    let dem = DemParams {
        max_disp,
        ..DemParams::default()
    };
    let decoder;
    let chain_source = match &gt {
        Some(d) => Source::Given(d),
        None => {
            decoder = decoder_for(&dem, None)?;
            Source::Dem {
                params: &dem,
                decoder: &decoder,
                complete: !opts.raw_disparity,
            }
        }
    };
    let mut chain = run_chain(&seg_params, chain_source, &pair.left, &pair.right, w, h)?;
    chain.relabel(preset.relabel.as_ref(), &pair.left, &pair.right);
    chain.depth_hole(preset.depth_hole.as_ref());
    if let Some(report) = &chain.completion {
        s.push(
            "disparity completion",
            format!(
                "{} regions, {} cells replaced, {} filled",
                report.regions, report.replaced, report.filled
            ),
        );
    }
    let source = match (&gt, opts.raw_disparity) {
        (Some(_), _) => "ground truth",
        (None, true) => "disparity energy model (f32), raw",
        (None, false) => "disparity energy model (f32), completed over conspicuity regions",
    };
    let disparity_f32: Vec<Option<f32>> = match &pair.gt {
        Some(gt) => gt.data.clone(),
        None => chain
            .disparity
            .iter()
            .map(|c| c.get().map(|d| d.to_num::<f32>()))
            .collect(),
    };
    let edges = &chain.edges;
    s.push("reference disparity", source);
    let max_d = disparity_f32
        .iter()
        .flatten()
        .fold(1.0f32, |a, &b| a.max(b));
    let seg = &chain.segment;
    seg.summarise(s, None);

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
        if d.area == 0 {
            continue;
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
    let masks = seg
        .report
        .objects
        .iter()
        .enumerate()
        .filter(|(_, d)| d.area > 0)
        .map(|(k, _)| seg.mask_u8(k).iter().map(|&m| m != 0).collect())
        .collect();
    Ok(ReferenceRun {
        panels: panels
            .into_iter()
            .map(|p| Panel::new(format!("reference_{}", p.name), p.image))
            .collect(),
        objects,
        masks,
        source,
    })
}
