//! The core stages run step by step on owned buffers, so every intermediate
//! map can be shown, plus their panels and summary lines.
//!
//! A later stage (disparity, segmentation, ...) adds a `run_*` function, a
//! result struct with `panels` and `summarise`, and is called from
//! [`crate::demo`].

use crate::error::Result;
use crate::panels::{self, Panel};
use crate::summary::{percent, Summary};
use protogist::conspicuity::{
    conspicuity, rgb_to_luv, row_scratch_len, scratch_bytes, smooth, threshold, Conspicuity,
    EdgeCell, EdgeParams, Luv, LuvTables,
};
use protogist::image::{ImageView, ImageViewMut, Rgb8};
use std::time::{Duration, Instant};

/// Every map of one run of the conspicuity stage, packed row-major.
#[derive(Clone, Debug)]
pub struct ConspicuityMaps {
    /// Frame width.
    pub width: usize,
    /// Frame height.
    pub height: usize,
    /// CIELUV of the input.
    pub luv: Vec<Luv>,
    /// After smoothing.
    pub smoothed: Vec<Luv>,
    /// C~, before the threshold (every cell ON).
    pub raw: Vec<EdgeCell>,
    /// C: C~ above the threshold, else OFF.
    pub edges: Vec<EdgeCell>,
    /// max C~.
    pub max: Conspicuity,
    /// ON cells of `edges`.
    pub on_count: u32,
    /// Time spent in the core calls.
    pub elapsed: Duration,
}

/// Runs the conspicuity stage on a packed `width` x `height` frame, one core
/// step at a time: `rgb_to_luv`, copy, `smooth`, `conspicuity`, `threshold`.
/// The result is the same as `edge_conspicuity` on the same input.
///
/// # Errors
/// The core's [`ImageError`](protogist::image::ImageError) for a bad frame
/// size, or its [`ConspicuityError`](protogist::conspicuity::ConspicuityError).
pub fn run_conspicuity(
    tables: &LuvTables,
    params: &EdgeParams,
    rgb: &[Rgb8],
    width: usize,
    height: usize,
) -> Result<ConspicuityMaps> {
    let input = ImageView::packed(rgb, width, height)?;
    let n = width * height;
    let mut luv = vec![Luv::default(); n];
    let mut smoothed = vec![Luv::default(); n];
    let mut rows = vec![Luv::default(); row_scratch_len(width)];
    let mut raw = vec![EdgeCell::OFF; n];

    let start = Instant::now();
    rgb_to_luv(
        tables,
        &input,
        &mut ImageViewMut::packed(&mut luv, width, height)?,
    )?;
    let mut sm = ImageViewMut::packed(&mut smoothed, width, height)?;
    sm.copy_from(&ImageView::packed(&luv, width, height)?)?;
    smooth(&params.smooth, &mut sm, &mut rows)?;
    let max = conspicuity(
        &sm.as_view(),
        &mut ImageViewMut::packed(&mut raw, width, height)?,
        &mut rows,
    )?;
    let mut edges = raw.clone();
    let on_count = threshold(
        &mut ImageViewMut::packed(&mut edges, width, height)?,
        max,
        params.threshold_percent,
    )?;
    let elapsed = start.elapsed();

    Ok(ConspicuityMaps {
        width,
        height,
        luv,
        smoothed,
        raw,
        edges,
        max,
        on_count,
        elapsed,
    })
}

impl ConspicuityMaps {
    /// The panels of the stage: `lightness`, `smoothed`, `conspicuity`, `edges`.
    pub fn panels(&self) -> Vec<Panel> {
        let (w, h) = (self.width, self.height);
        vec![
            Panel::new("lightness", panels::lightness(&self.luv, w, h)),
            Panel::new("smoothed", panels::luv_image(&self.smoothed, w, h)),
            Panel::new(
                "conspicuity",
                panels::conspicuity(&self.raw, self.max.to_num::<f32>(), w, h),
            ),
            Panel::new("edges", panels::edges(&self.edges, w, h)),
        ]
    }

    /// Appends the stage's summary lines.
    pub fn summarise(&self, s: &mut Summary) {
        let n = self.width * self.height;
        s.push("max C~", format!("{:.2}", self.max.to_num::<f32>()));
        s.push(
            "edge pixels",
            format!(
                "{} ({} %)",
                self.on_count,
                percent(self.on_count as usize, n)
            ),
        );
        s.push(
            "core scratch",
            format!("{} bytes", scratch_bytes(self.width, self.height)),
        );
        s.push(
            "conspicuity time",
            format!("{:.2} ms", self.elapsed.as_secs_f64() * 1e3),
        );
    }

    /// Edge pixels within 1 px of the boundary of a 0/255 object mask
    /// ([`BoundaryScore`]).
    pub fn boundary_score(&self, mask: &[u8]) -> BoundaryScore {
        BoundaryScore::new(&self.edges, mask, self.width, self.height)
    }
}

/// How edges relate to a ground-truth object boundary.
///
/// A pixel is *near the boundary* when its 3x3 neighbourhood holds both
/// object and non-object pixels, i.e. it is within 1 px of the outline.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BoundaryScore {
    /// ON edge cells near the boundary.
    pub on_boundary: usize,
    /// ON edge cells elsewhere (texture, noise).
    pub elsewhere: usize,
    /// Object pixels with a non-object 4-neighbour (the outline).
    pub outline: usize,
    /// Outline pixels with an ON edge cell within 1 px.
    pub outline_hit: usize,
}

impl BoundaryScore {
    /// Scores `edges` against `mask` (non-zero = object), both packed.
    pub fn new(edges: &[EdgeCell], mask: &[u8], width: usize, height: usize) -> Self {
        let at = |m: &[u8], x: isize, y: isize| -> Option<bool> {
            let (x, y) = (usize::try_from(x).ok()?, usize::try_from(y).ok()?);
            (x < width && y < height).then(|| m.get(y * width + x).is_some_and(|&v| v != 0))
        };
        let on = |x: isize, y: isize| {
            let (Ok(x), Ok(y)) = (usize::try_from(x), usize::try_from(y)) else {
                return false;
            };
            x < width && y < height && edges.get(y * width + x).is_some_and(|c| c.is_on())
        };
        let window = |x: isize, y: isize| {
            (-1..=1).flat_map(move |dy| (-1..=1).map(move |dx| (x + dx, y + dy)))
        };
        let mut score = Self {
            on_boundary: 0,
            elsewhere: 0,
            outline: 0,
            outline_hit: 0,
        };
        for y in 0..height as isize {
            for x in 0..width as isize {
                if on(x, y) {
                    let vals: Vec<bool> =
                        window(x, y).filter_map(|(a, b)| at(mask, a, b)).collect();
                    if vals.iter().any(|&v| v) && vals.iter().any(|&v| !v) {
                        score.on_boundary += 1;
                    } else {
                        score.elsewhere += 1;
                    }
                }
                let inside = at(mask, x, y) == Some(true);
                let outline = inside
                    && [(1, 0), (-1, 0), (0, 1), (0, -1)]
                        .iter()
                        .any(|(dx, dy)| at(mask, x + dx, y + dy) == Some(false));
                if outline {
                    score.outline += 1;
                    if window(x, y).any(|(a, b)| on(a, b)) {
                        score.outline_hit += 1;
                    }
                }
            }
        }
        score
    }

    /// Appends the score's summary lines.
    pub fn summarise(&self, s: &mut Summary) {
        let total = self.on_boundary + self.elsewhere;
        s.push(
            "edges on GT boundary (±1 px)",
            format!(
                "{} ({} % of edges)",
                self.on_boundary,
                percent(self.on_boundary, total)
            ),
        );
        s.push(
            "edges elsewhere",
            format!(
                "{} ({} % of edges)",
                self.elsewhere,
                percent(self.elsewhere, total)
            ),
        );
        s.push(
            "GT outline found (±1 px)",
            format!(
                "{} of {} px ({} %)",
                self.outline_hit,
                self.outline,
                percent(self.outline_hit, self.outline)
            ),
        );
    }
}

/// The shape vector of one object mask (paper section 3.5).
#[derive(Clone, Debug)]
pub struct ShapeResult {
    /// The 720 z-scores (max profile, then min profile), as f32.
    pub vector: Vec<f32>,
    /// Centroid, contour and saturation counts.
    pub report: protogist::shape::ShapeReport,
    /// What the mask is, for the summary ("GT mask", "segmented mask").
    pub source: &'static str,
}

/// Runs the core shape stage on a packed 0/non-zero mask.
///
/// # Errors
/// [`ImageError`](protogist::image::ImageError) for a bad size, or the
/// stage's [`ShapeError`](protogist::shape::ShapeError) (empty mask, zero
/// variance).
pub fn run_shape(
    mask: &[u8],
    width: usize,
    height: usize,
    source: &'static str,
) -> Result<ShapeResult> {
    use protogist::shape::{shape_vector, RadialProfile, ShapeElem, SHAPE_LEN};
    let view = ImageView::packed(mask, width, height)?;
    let mut profile = RadialProfile::new();
    let mut v = [ShapeElem::ZERO; SHAPE_LEN];
    let report = shape_vector(&view, &mut profile, &mut v)?;
    Ok(ShapeResult {
        vector: v.iter().map(|e| e.to_num::<f32>()).collect(),
        report,
        source,
    })
}

impl ShapeResult {
    /// The profile plot, `width` x `height`.
    pub fn panels(&self, width: usize, height: usize) -> Vec<Panel> {
        let (w, h) = (width as u32, height as u32);
        vec![Panel::new(
            "shape_vector",
            crate::plot::shape_vector(&self.vector, w, h),
        )]
    }

    /// Appends the stage's summary lines.
    pub fn summarise(&self, s: &mut Summary) {
        let c = &self.report.centroid;
        s.push(
            format!("shape vector ({})", self.source),
            format!(
                "720 values, centroid ({:.1}, {:.1}), {} contour px, {} empty bins, {} saturated",
                c.x_q8 as f32 / 256.0,
                c.y_q8 as f32 / 256.0,
                self.report.profile.contour_pixels,
                self.report.profile.empty_bins,
                self.report.saturated
            ),
        );
    }
}

/// The disparity energy model's output on a pair, with its GT scores.
#[derive(Clone, Debug)]
pub struct DemResult {
    /// Frame width.
    pub width: usize,
    /// Frame height.
    pub height: usize,
    /// Left-referenced disparity, U8F8 px or OFF.
    pub disparity: Vec<protogist::disparity::DisparityCell>,
    /// The same in f32.
    pub disparity_f32: Vec<Option<f32>>,
    /// Scores against the whole-pixel GT.
    pub metrics: crate::ground_truth::Metrics,
    /// Largest GT disparity, px (for the colour scale).
    pub max_gt: f32,
    /// Time in the model.
    pub elapsed: Duration,
}

/// Runs the f32 disparity energy model on a packed pair, and scores it
/// against whole-pixel GT.
///
/// # Errors
/// The stage's typed errors (sizes, a decoder of other parameters).
pub fn run_dem(
    params: &crate::reference::stereo::DemParams,
    decoder: &crate::reference::stereo::Decoder,
    left: &[Rgb8],
    right: &[Rgb8],
    gt: &[u8],
    width: usize,
    height: usize,
) -> Result<DemResult> {
    use crate::reference::stereo::stereo;
    let start = Instant::now();
    let maps = stereo(
        params,
        decoder,
        &ImageView::packed(left, width, height)?,
        &ImageView::packed(right, width, height)?,
    )?;
    let elapsed = start.elapsed();
    let gt_f: Vec<Option<f32>> = gt.iter().map(|&d| Some(f32::from(d))).collect();
    Ok(DemResult {
        width,
        height,
        metrics: crate::ground_truth::metrics(&maps.disparity_f32, &gt_f),
        max_gt: gt.iter().copied().max().map_or(1.0, f32::from),
        disparity: maps.disparity,
        disparity_f32: maps.disparity_f32,
        elapsed,
    })
}

impl DemResult {
    /// Fig. 2 (b): the disparity map (OFF black).
    pub fn panels(&self) -> Vec<Panel> {
        let (w, h) = (self.width, self.height);
        vec![Panel::new(
            "b_disparity",
            crate::panels::disparity_panel(&self.disparity_f32, w, h, self.max_gt),
        )]
    }

    /// bad-2 both ways, density and time.
    pub fn summarise(&self, s: &mut Summary) {
        let m = &self.metrics;
        s.push(
            "disparity bad-2",
            format!(
                "{:.1} % of estimated px, {:.1} % of all px (missing = bad); density {:.1} %",
                m.bad_estimated[1], m.bad_all[1], m.density
            ),
        );
        s.push(
            "disparity time (f32)",
            format!("{:.1} ms", self.elapsed.as_secs_f64() * 1e3),
        );
    }
}

/// Runs the core disparity completion (`protogist::complete`) on packed
/// maps: the conspicuity stage's edges and smoothed colour, and the model's
/// disparity. Same arguments as the reference
/// [`crate::reference::complete::complete`].
///
/// # Errors
/// The stage's [`CompleteError`](protogist::complete::CompleteError) for
/// maps of different sizes.
pub fn run_complete(
    params: &protogist::complete::CompleteParams,
    edges: &[EdgeCell],
    colour: &[Luv],
    disparity: &[protogist::disparity::DisparityCell],
    width: usize,
    height: usize,
) -> Result<(
    Vec<protogist::disparity::DisparityCell>,
    protogist::complete::CompleteReport,
)> {
    use protogist::complete::{
        complete_runs, region_table_len, run_rows_len, run_table_len, RegionTables, RowSpan,
        RunBuffers, Tone, LABEL_ROWS,
    };
    use protogist::segment::bit_map_len;
    let (w, h) = (width, height);
    let tone: Vec<Tone> = colour.iter().map(|&c| Tone::of(c)).collect();
    let (mut open, mut trusted) = (vec![0u32; bit_map_len(w, h)], vec![0u32; bit_map_len(w, h)]);
    let (mut runs, mut rows) = (vec![0u16; run_table_len(w, h)], vec![0u32; run_rows_len(w)]);
    let mut labels = vec![0u16; LABEL_ROWS * w];
    let mut bufs = RunBuffers {
        open: &mut open,
        trusted: &mut trusted,
        runs: &mut runs,
        rows: &mut rows,
        labels: &mut labels,
    };
    let n = region_table_len(w, h);
    let (mut total, mut below, mut lo, mut hi) =
        (vec![0u32; n], vec![0u32; n], vec![0u8; n], vec![0u8; n]);
    let mut spans = vec![RowSpan::default(); n];
    let mut tables = RegionTables {
        total: &mut total,
        below: &mut below,
        lo: &mut lo,
        hi: &mut hi,
        tilt: &mut spans,
    };
    let mut out = disparity.to_vec();
    let report = complete_runs(
        params,
        &ImageView::packed(edges, w, h)?,
        &ImageView::packed(&tone, w, h)?,
        &mut ImageViewMut::packed(&mut out, w, h)?,
        &mut bufs,
        &mut tables,
    )?;
    Ok((out, report))
}

mod segment;
pub use segment::{run_segment, SegmentResult};

#[cfg(test)]
mod tests;
