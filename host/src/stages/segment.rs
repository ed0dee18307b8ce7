//! The segmentation stage run on owned buffers, with its panels and
//! summary lines (module [`super`]).

use crate::error::Result;
use crate::panels::{self, Panel};
use crate::summary::Summary;
use protogist::conspicuity::EdgeCell;
use protogist::image::{ImageView, Rgb8};

/// One run of the segmentation stage (paper sections 3.1, 3.3, 3.4) with
/// its intermediate maps, for panels.
#[derive(Clone, Debug)]
pub struct SegmentResult {
    /// Frame width.
    pub width: usize,
    /// Frame height.
    pub height: usize,
    /// The stage's report: statistics, thresholds, detections.
    pub report: protogist::segment::SegmentReport,
    /// One mask per detection slot (`max_objects` of them), row-major.
    pub masks: Vec<bool>,
    /// D_fg, C_fg, D_ObjReg, C_ObjReg, C_Obj of the most salient search.
    pub d_fg: Vec<protogist::disparity::DisparityCell>,
    /// C_fg.
    pub c_fg: Vec<EdgeCell>,
    /// D_ObjReg.
    pub d_obj_reg: Vec<protogist::disparity::DisparityCell>,
    /// C_ObjReg.
    pub c_obj_reg: Vec<EdgeCell>,
    /// C_Obj.
    pub c_obj: Vec<EdgeCell>,
}

/// Runs the core segmentation stage on a disparity map and the edge map C;
/// the depth pass refines its masks and takes their holes by colour
/// against `left` (the left image), and does neither without one.
///
/// # Errors
/// The stage's [`SegmentError`](protogist::segment::SegmentError).
pub fn run_segment(
    params: &protogist::segment::SegmentParams,
    disparity: &[protogist::disparity::DisparityCell],
    edges: &[EdgeCell],
    left: Option<&[Rgb8]>,
    width: usize,
    height: usize,
) -> Result<SegmentResult> {
    let mut store = crate::storage::SegmentStorage::new(width, height);
    let mut masks = vec![false; usize::from(params.max_objects) * width * height];
    let mut bufs = store.buffers()?;
    let mut params = *params;
    let grey = vec![Rgb8::default(); width * height];
    let frame = match left {
        Some(l) => ImageView::packed(l, width, height)?,
        None => {
            if let Some(p) = params.depth_pass.as_mut() {
                p.refine = None;
                p.holes = None;
            }
            ImageView::packed(&grey, width, height)?
        }
    };
    // One view of each input, for the call and for the panels.
    let (dv, cv) = (
        ImageView::packed(disparity, width, height)?,
        ImageView::packed(edges, width, height)?,
    );
    let report = protogist::segment::segment_with_depth_pass(
        &params,
        &dv,
        &cv,
        &frame,
        &mut bufs,
        protogist::segment::Masks::Bools(&mut masks),
        &mut (),
    )?;
    let (d_off, c_off) = (protogist::disparity::DisparityCell::OFF, EdgeCell::OFF);
    Ok(SegmentResult {
        width,
        height,
        d_fg: bufs.d_fg().masked(&dv, d_off).collect(),
        c_fg: bufs.d_fg().masked(&cv, c_off).collect(),
        d_obj_reg: bufs.d_obj_reg().masked(&dv, d_off).collect(),
        c_obj_reg: bufs.c_obj_reg().masked(&cv, c_off).collect(),
        c_obj: bufs.c_obj().masked(&cv, c_off).collect(),
        report,
        masks,
    })
}

/// One px in the segmentation statistics' fixed point.
const STAT_SCALE: f32 = (1u32 << protogist::segment::STAT_FRAC_BITS) as f32;

impl SegmentResult {
    /// The mask of detection `k`, as 0/255 bytes.
    pub fn mask_u8(&self, k: usize) -> Vec<u8> {
        let n = self.width * self.height;
        self.masks
            .iter()
            .skip(k * n)
            .take(n)
            .map(|&m| if m { 255 } else { 0 })
            .collect()
    }

    /// The paper's Fig. 2 panels (c), (e), (f), (g), (h), (i), (j) of the
    /// most salient object; `left` is the left image.
    pub fn panels(&self, left: &[Rgb8]) -> Vec<Panel> {
        let (w, h) = (self.width, self.height);
        let max_d = self
            .d_fg
            .iter()
            .chain(&self.d_obj_reg)
            .filter_map(|c| c.get())
            .map(|d| d.to_num::<f32>())
            .fold(1.0, f32::max);
        let mask0: Vec<bool> = self.masks.iter().take(w * h).copied().collect();
        vec![
            Panel::new(
                "c_foreground_disparity",
                panels::disparity_cells(&self.d_fg, max_d, w, h),
            ),
            Panel::new("e_foreground_conspicuity", panels::edges(&self.c_fg, w, h)),
            Panel::new(
                "f_object_region_disparity",
                panels::disparity_cells(&self.d_obj_reg, max_d, w, h),
            ),
            Panel::new(
                "g_object_region_conspicuity",
                panels::edges(&self.c_obj_reg, w, h),
            ),
            Panel::new("h_object_conspicuity", panels::edges(&self.c_obj, w, h)),
            Panel::new(
                "i_object_mask",
                panels::grey_from(&mask0, w, h, |m| if m { 255 } else { 0 }),
            ),
            Panel::new("j_segregated_object", panels::masked(left, &mask0, w, h)),
        ]
    }

    /// Appends the stage's summary lines; with a GT mask, the IoU of the
    /// most salient detection.
    pub fn summarise(&self, s: &mut Summary, gt_mask: Option<&[u8]>) {
        match self.report.objects.first() {
            None => s.push("objects found", "none"),
            Some(d) => {
                s.push("objects found", self.report.objects.len());
                s.push(
                    "most salient",
                    format!(
                        "δ = {} px, slice {:.1}..{:.1} px, score {}, area {} px",
                        d.delta,
                        d.range.low as f32 / STAT_SCALE,
                        d.range.high as f32 / STAT_SCALE,
                        d.score,
                        d.area
                    ),
                );
                if let Some(gt) = gt_mask {
                    s.push("mask IoU vs GT", format!("{:.3}", self.iou(0, gt)));
                }
            }
        }
    }

    /// Intersection over union of detection `k`'s mask with a 0/non-zero
    /// ground-truth mask (0 when both are empty).
    pub fn iou(&self, k: usize, gt: &[u8]) -> f64 {
        let n = self.width * self.height;
        let m = self.masks.iter().skip(k * n).take(n);
        let (inter, union) = m.zip(gt).fold((0u32, 0u32), |(i, u), (&a, &b)| {
            let b = b != 0;
            (i + u32::from(a && b), u + u32::from(a || b))
        });
        if union == 0 {
            0.0
        } else {
            f64::from(inter) / f64::from(union)
        }
    }
}
