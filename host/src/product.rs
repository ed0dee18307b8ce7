//! The product on the desktop: core's [`protogist::pipeline`] on a frame
//! pair, with every intermediate map kept for panels. `run`, the demo and
//! the evaluations call [`run_frame`], so the desktop computes what the
//! board computes, bit for bit.

use crate::dem_tables::{params_of, table_for};
use crate::error::{HostError, Result};
use crate::panels::{self, Panel};
use crate::reference::stereo::c2f::level_params;
use protogist::conspicuity::{EdgeCell, Luv};
use protogist::disparity::DisparityCell;
use protogist::image::{ImageView, Rgb8};
use protogist::mlp::Identity;
use protogist::pipeline::{
    workspace_words, Object, Observer, Pipeline, PipelineParams, Stage, TOP_K,
};
use protogist::segment::{Detection, SegmentBuffers, STAT_FRAC_BITS};
use std::time::{Duration, Instant};

/// The decoder tables of [`PipelineParams::DEFAULT`]'s stereo point
/// (`half-narrow`: 32 disparities, kernels of radius 2; levels 0, 1, 2),
/// the ones the product firmware carries.
pub const DEFAULT_TABLES: [&[u8]; 3] = [
    include_bytes!("../../firmware-sim/data/dem_c2f_narrow_l0.bin"),
    include_bytes!("../../firmware-sim/data/dem_c2f_narrow_l1.bin"),
    include_bytes!("../../firmware-sim/data/dem_c2f_narrow_l2.bin"),
];

/// The tables of the points with the design's kernels (radius 7: `full`,
/// `fast`, `half-low-penalty`, the paper's preset), which the firmware's
/// stereo bench carries.
pub const DESIGN_TABLES: [&[u8]; 3] = [
    include_bytes!("../../firmware-sim/data/dem_c2f_l0.bin"),
    include_bytes!("../../firmware-sim/data/dem_c2f_l1.bin"),
    include_bytes!("../../firmware-sim/data/dem_c2f_l2.bin"),
];

/// The pipeline's named setting `name` (`--preset`:
/// [`PipelineParams::NAMED`]).
///
/// # Errors
/// [`HostError::InvalidArgument`] naming `preset` and the settings, for an
/// unknown name.
pub fn preset(name: &str) -> Result<PipelineParams> {
    PipelineParams::from_name(name).ok_or_else(|| HostError::InvalidArgument {
        name: "preset",
        reason: format!(
            "unknown setting {name:?} ({})",
            PipelineParams::NAMED.map(|(n, _)| n).join(", ")
        ),
    })
}

/// The default largest disparity at a working width: a fifth of it, less
/// 1 (31 at 160 px, the firmware's 32 disparities).
pub fn default_max_disp(width: usize) -> u8 {
    u8::try_from((width / 5).saturating_sub(1).max(1)).unwrap_or(u8::MAX)
}

/// The stereo point's decoder tables, level 0 first: the bundled ones when
/// they fit, else trained (seconds per level).
///
/// # Errors
/// [`HostError`] from training.
pub fn tables_for(params: &PipelineParams) -> Result<Vec<Vec<u8>>> {
    let s = &params.stereo;
    for set in [&DEFAULT_TABLES, &DESIGN_TABLES] {
        let fits = (0..params.tables()).all(|k| {
            set.get(k)
                .and_then(|b| protogist::stereo::DemTable::parse(b).ok())
                .is_some_and(|t| t.layout == s.level_params(k).layout())
        });
        if fits {
            return Ok(set
                .iter()
                .take(params.tables())
                .map(|b| b.to_vec())
                .collect());
        }
    }
    // The same mapping as `protogist stereo --engine reference`.
    let reference = params_of(s);
    (0..params.tables())
        .map(|k| Ok(table_for(&level_params(&reference, k), None)?.to_bytes()))
        .collect()
}

/// The maps of one figure-ground search, for panels.
#[derive(Clone, Debug)]
pub struct SearchMaps {
    /// The search's detection.
    pub detection: Detection,
    /// D_fg.
    pub d_fg: Vec<DisparityCell>,
    /// C_fg.
    pub c_fg: Vec<EdgeCell>,
    /// D_ObjReg.
    pub d_obj_reg: Vec<DisparityCell>,
    /// C_ObjReg.
    pub c_obj_reg: Vec<EdgeCell>,
    /// C_Obj.
    pub c_obj: Vec<EdgeCell>,
}

/// Every intermediate map of a run, and the time of each stage.
#[derive(Clone, Debug, Default)]
pub struct Maps {
    /// The stereo engine's map.
    pub raw_disparity: Vec<DisparityCell>,
    /// The smoothed CIELUV map.
    pub smoothed: Vec<Luv>,
    /// The edge map C.
    pub edges: Vec<EdgeCell>,
    /// The completed disparity.
    pub disparity: Vec<DisparityCell>,
    /// Each figure-ground search, in order.
    pub searches: Vec<SearchMaps>,
    /// Time per stage, in order.
    pub stage_times: Vec<(Stage, Duration)>,
    last: Option<(Stage, Instant)>,
}

impl Observer for Maps {
    fn enter(&mut self, stage: Stage) {
        let now = Instant::now();
        if let Some((s, t)) = self.last.take() {
            self.stage_times.push((s, now - t));
        }
        self.last = Some((stage, now));
    }

    fn raw_disparity(&mut self, map: &ImageView<'_, DisparityCell>) {
        self.raw_disparity = map.pixels().collect();
    }

    fn smoothed_row(&mut self, y: usize, row: &[Luv]) {
        if y == 0 {
            self.smoothed.clear();
        }
        self.smoothed.extend_from_slice(row);
    }

    fn conspicuity(&mut self, edges: &ImageView<'_, EdgeCell>) {
        self.edges = edges.pixels().collect();
    }

    fn disparity(&mut self, map: &ImageView<'_, DisparityCell>) {
        self.disparity = map.pixels().collect();
    }

    fn object(&mut self, det: &Detection, maps: &SegmentBuffers<'_>) {
        let (w, h) = maps.size();
        let (Ok(dv), Ok(cv)) = (
            ImageView::packed(&self.disparity, w, h),
            ImageView::packed(&self.edges, w, h),
        ) else {
            return;
        };
        let (d_off, c_off) = (DisparityCell::OFF, EdgeCell::OFF);
        self.searches.push(SearchMaps {
            detection: *det,
            d_fg: maps.d_fg().masked(&dv, d_off).collect(),
            c_fg: maps.d_fg().masked(&cv, c_off).collect(),
            d_obj_reg: maps.d_obj_reg().masked(&dv, d_off).collect(),
            c_obj_reg: maps.c_obj_reg().masked(&cv, c_off).collect(),
            c_obj: maps.c_obj().masked(&cv, c_off).collect(),
        });
    }
}

/// One categorised object, with owned maps and names.
#[derive(Clone, Debug)]
pub struct FoundObject {
    /// What core reported.
    pub object: Object,
    /// Its mask, row-major.
    pub mask: Vec<bool>,
    /// Its shape vector.
    pub shape: Vec<f32>,
    /// The ranked classes: name and cosine.
    pub top: Vec<(String, f32)>,
    /// The best class when it reaches Δ, else `None` (unknown).
    pub category: Option<String>,
}

impl FoundObject {
    /// The category to print: the known class, or `unknown (best?)`.
    pub fn label(&self) -> String {
        match (&self.category, self.top.first()) {
            (Some(c), Some((_, s))) => format!("{c} {s:.2}"),
            (None, Some((c, s))) => format!("unknown ({c}? {s:.2})"),
            _ => "unknown".to_owned(),
        }
    }

    /// The object's JSON record for reports.
    pub fn to_json(&self, scale: f64) -> serde_json::Value {
        let o = &self.object;
        let q = f64::from(1u32 << STAT_FRAC_BITS);
        serde_json::json!({
            "rank": o.rank,
            "bbox": {"x": o.bbox.x, "y": o.bbox.y, "width": o.bbox.width, "height": o.bbox.height},
            "bbox_input_px": {
                "x": o.bbox.x as f64 * scale, "y": o.bbox.y as f64 * scale,
                "width": o.bbox.width as f64 * scale, "height": o.bbox.height as f64 * scale,
            },
            "centroid": [f64::from(o.centroid.x_q8) / 256.0, f64::from(o.centroid.y_q8) / 256.0],
            "area_px": o.area,
            "delta_px": o.delta,
            "disparity_range_px": [o.range.low as f64 / q, o.range.high as f64 / q],
            "saliency": o.score,
            "category": self.category,
            "known": self.category.is_some(),
            "top5": self.top.iter().map(|(c, s)| serde_json::json!({"class": c, "cosine": s})).collect::<Vec<_>>(),
            "shape_vector": self.shape,
        })
    }
}

/// What [`run_frame`] gives.
#[derive(Clone, Debug)]
pub struct FrameRun {
    /// Frame width.
    pub width: usize,
    /// Frame height.
    pub height: usize,
    /// The objects, most salient first.
    pub objects: Vec<FoundObject>,
    /// Figure-ground searches run.
    pub searches: usize,
    /// Every intermediate map.
    pub maps: Maps,
    /// The pipeline's run (setup excluded).
    pub elapsed: Duration,
    /// Workspace bytes.
    pub workspace_bytes: usize,
}

/// Runs core's pipeline on a packed `w x h` pair.
///
/// # Errors
/// [`HostError::Pipeline`] for what the pipeline rejects.
pub fn run_frame(
    params: &PipelineParams,
    tables: &[Vec<u8>],
    model: &[u8],
    left: &[Rgb8],
    right: &[Rgb8],
    w: usize,
    h: usize,
) -> Result<FrameRun> {
    run_frame_from(params, tables, model, (left, right), None, (w, h))
}

/// [`run_frame`] with the left view's disparity given (`w x h` cells, OFF
/// where unknown) in place of the stereo and its completion
/// ([`Pipeline::run_with_disparity`]).
///
/// # Errors
/// [`HostError::Pipeline`] for what the pipeline rejects, a map of
/// another size included.
pub fn run_frame_with_disparity(
    params: &PipelineParams,
    tables: &[Vec<u8>],
    model: &[u8],
    (left, right): (&[Rgb8], &[Rgb8]),
    disparity: &[DisparityCell],
    w: usize,
    h: usize,
) -> Result<FrameRun> {
    run_frame_from(
        params,
        tables,
        model,
        (left, right),
        Some(disparity),
        (w, h),
    )
}

fn run_frame_from(
    params: &PipelineParams,
    tables: &[Vec<u8>],
    model: &[u8],
    (left, right): (&[Rgb8], &[Rgb8]),
    disparity: Option<&[DisparityCell]>,
    (w, h): (usize, usize),
) -> Result<FrameRun> {
    let refs: Vec<&[u8]> = tables.iter().map(Vec::as_slice).collect();
    let p = Pipeline::new(params, &refs, model)?;
    let mut ws = vec![0u64; workspace_words(w, h, params)];
    let mut maps = Maps::default();
    let (lv, rv) = (
        ImageView::packed(left, w, h)?,
        ImageView::packed(right, w, h)?,
    );
    let start = Instant::now();
    let frame = match disparity {
        Some(d) => {
            let dv = ImageView::packed(d, w, h)?;
            p.run_with_disparity_observed(&lv, &rv, &dv, &mut ws, &mut maps)?
        }
        None => p.run_observed(&lv, &rv, &mut ws, &mut maps)?,
    };
    let elapsed = start.elapsed();
    let objects = frame
        .objects()
        .iter()
        .map(|o| {
            let mask = frame
                .mask(o)
                .map(|m| m.bools().collect())
                .unwrap_or_default();
            let shape = frame
                .shape(o)
                .map(|v| v.iter().map(|e| e.to_num::<f32>()).collect())
                .unwrap_or_default();
            let top = o
                .top()
                .iter()
                .take(TOP_K)
                .map(|r| (p.class_name(r.class).to_owned(), r.score as f32 / 65536.0))
                .collect();
            let category = match o.identity {
                Identity::Known(c) => Some(p.class_name(c).to_owned()),
                Identity::Unknown => None,
            };
            FoundObject {
                object: *o,
                mask,
                shape,
                top,
                category,
            }
        })
        .collect();
    Ok(FrameRun {
        width: w,
        height: h,
        objects,
        searches: frame.searches(),
        maps,
        elapsed,
        workspace_bytes: protogist::pipeline::workspace_bytes(w, h, params),
    })
}

impl FrameRun {
    /// The left view with each object's box, category and score, drawn by
    /// `protogist::draw` (the code that draws them on a board's display).
    pub fn objects_panel(&self, left: &[Rgb8]) -> Panel {
        let names: Vec<&str> = self
            .objects
            .iter()
            .map(|o| match (&o.category, o.top.first()) {
                (Some(c), _) => crate::classify::shipped::display_name(c),
                (None, _) => "unknown",
            })
            .collect();
        let labels: Vec<_> = self
            .objects
            .iter()
            .zip(&names)
            .map(|(o, n)| o.object.label(n))
            .collect();
        let img = panels::rgb_from(left, self.width, self.height);
        Panel::new("objects", panels::labelled(&img, &labels))
    }

    /// The panels: left view, the engine's and the completed disparity, the
    /// edges, and per object its figure-ground maps, mask and segregated
    /// object (suffix `_k` for object `k`).
    pub fn panels(&self, left: &[Rgb8]) -> Vec<Panel> {
        let (w, h) = (self.width, self.height);
        let max_d = self
            .maps
            .disparity
            .iter()
            .filter_map(|c| c.get())
            .map(|d| d.to_num::<f32>())
            .fold(1.0, f32::max);
        let mut out = vec![
            Panel::new("a_left", panels::rgb_from(left, w, h)),
            Panel::new(
                "b_disparity",
                panels::disparity_cells(&self.maps.raw_disparity, max_d, w, h),
            ),
            Panel::new(
                "b_disparity_completed",
                panels::disparity_cells(&self.maps.disparity, max_d, w, h),
            ),
            Panel::new("d_conspicuity", panels::edges(&self.maps.edges, w, h)),
        ];
        for o in &self.objects {
            let k = o.object.rank;
            let Some(s) = self.maps.searches.get(o.object.search) else {
                continue;
            };
            out.extend([
                Panel::new(
                    format!("c_foreground_disparity_{k}"),
                    panels::disparity_cells(&s.d_fg, max_d, w, h),
                ),
                Panel::new(
                    format!("e_foreground_conspicuity_{k}"),
                    panels::edges(&s.c_fg, w, h),
                ),
                Panel::new(
                    format!("f_object_region_disparity_{k}"),
                    panels::disparity_cells(&s.d_obj_reg, max_d, w, h),
                ),
                Panel::new(
                    format!("g_object_region_conspicuity_{k}"),
                    panels::edges(&s.c_obj_reg, w, h),
                ),
                Panel::new(
                    format!("h_object_conspicuity_{k}"),
                    panels::edges(&s.c_obj, w, h),
                ),
                Panel::new(
                    format!("i_object_mask_{k}"),
                    panels::grey_from(&o.mask, w, h, |m| if m { 255 } else { 0 }),
                ),
                Panel::new(
                    format!("j_segregated_object_{k}"),
                    panels::masked(left, &o.mask, w, h),
                ),
                Panel::new(
                    format!("shape_vector_{k}"),
                    crate::plot::shape_vector(&o.shape, w as u32, h as u32),
                ),
            ]);
        }
        out
    }
}

impl From<protogist::pipeline::PipelineError> for HostError {
    fn from(e: protogist::pipeline::PipelineError) -> Self {
        Self::Pipeline(e)
    }
}
