//! Border refinement, object inhibition and the whole stage.

use super::bits;
use super::buffers::SegmentBuffers;
use super::depth::Union;
use super::ground::{fit_ground, GroundLine};
use super::label::{AreaReport, Connectivity, Labeller};
pub use super::masks::Masks;
use super::morph::dilate_n;
use super::parts;
use super::passes;
use super::stats::{
    plane, select_slice, selected_stats, slice_range, thresholds, DisparityRange, SelectedStats,
    Thresholds,
};
use super::{check_size, SegmentError, SegmentParams, MAX_OBJECTS, SEARCHES_PER_OBJECT};
use crate::conspicuity::EdgeCell;
use crate::disparity::DisparityCell;
use crate::image::{ImageView, ImageViewMut};

/// Border refinement: `region` = the largest 8-connected component of the
/// (ψ ≠ OFF) map dilated `params.refine_dilations` times by
/// `params.disk`; C_Obj = C_ObjReg inside `region`. Returns the ON count of
/// C_Obj. `scratch` is overwritten.
///
/// # Errors
/// [`SegmentError::SizeMismatch`] or [`SegmentError::LabelCapacity`].
pub fn refine_border(
    params: &SegmentParams,
    psi: &ImageView<'_, EdgeCell>,
    c_obj_reg: &ImageView<'_, EdgeCell>,
    region: &mut ImageViewMut<'_, bool>,
    scratch: &mut ImageViewMut<'_, bool>,
    lab: &mut Labeller<'_>,
    c_obj: &mut ImageViewMut<'_, EdgeCell>,
) -> Result<u32, SegmentError> {
    check_size(psi.size(), region.size())?;
    check_size(psi.size(), c_obj_reg.size())?;
    check_size(psi.size(), c_obj.size())?;
    for (s, o) in psi.rows().zip(region.rows_mut()) {
        for (c, o) in s.iter().zip(o.iter_mut()) {
            *o = c.is_on();
        }
    }
    dilate_n(params.disk, region, scratch, params.refine_dilations)?;
    lab.label(&region.as_view(), true, Connectivity::Eight)?;
    let best = lab.largest().map_or(0, |(l, _)| l);
    lab.select(best, region)?;
    let mut n = 0;
    let region = region.as_view();
    for ((s, r), o) in c_obj_reg.rows().zip(region.rows()).zip(c_obj.rows_mut()) {
        for ((&c, &r), o) in s.iter().zip(r).zip(o.iter_mut()) {
            *o = if r { c } else { EdgeCell::OFF };
            n += u32::from(o.is_on());
        }
    }
    Ok(n)
}

/// An axis-aligned box, pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BoundingBox {
    /// Left column.
    pub x: usize,
    /// Top row.
    pub y: usize,
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
}

impl BoundingBox {
    /// The box of the ON bits of bit map `m`, `None` when there are none.
    pub(super) fn of_bits(g: bits::Geom, m: &[u32]) -> Option<Self> {
        bits::bbox(g, m).map(|(x0, y0, x1, y1)| Self {
            x: x0,
            y: y0,
            width: x1 - x0 + 1,
            height: y1 - y0 + 1,
        })
    }
}

/// The bounding box of the ON pixels, `None` when there are none.
pub fn bounding_box(mask: &ImageView<'_, bool>) -> Option<BoundingBox> {
    let mut b: Option<(usize, usize, usize, usize)> = None;
    for (y, row) in mask.rows().enumerate() {
        let first = row.iter().position(|&m| m);
        let last = row.iter().rposition(|&m| m);
        if let (Some(x0), Some(x1)) = (first, last) {
            b = Some(b.map_or((x0, y, x1, y), |(a, b0, c, _)| {
                (a.min(x0), b0, c.max(x1), y)
            }));
        }
    }
    b.map(|(x0, y0, x1, y1)| BoundingBox {
        x: x0,
        y: y0,
        width: x1 - x0 + 1,
        height: y1 - y0 + 1,
    })
}

/// One extracted object.
///
/// Its mask is chunk `index` (`width · height` cells) of the mask buffer
/// given to [`segment`]. The shape vector comes from that mask: the hook
/// for the `shape` stage is `shape(mask_k)` on that chunk, one call per
/// detection, in this order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Detection {
    /// Rank: 0 for the most salient (the paper's single object).
    pub index: usize,
    /// δ, whole px.
    pub delta: u16,
    /// The object slice `[δ − r, δ + r]`.
    pub range: DisparityRange,
    /// Saliency: A^C(δ)·δ^A; for an object of the depth pass
    /// ([`DepthPass`](super::DepthPass)), which has no C, its slice's
    /// foreground cells in planes δ − 1 to δ + 1, δ's own counted twice.
    pub score: u64,
    /// Mask pixels (0 when the contour never closed).
    pub area: u32,
    /// Bounding box of the mask.
    pub bbox: Option<BoundingBox>,
    /// What the area filter saw.
    pub regions: AreaReport,
}

/// What [`segment`] found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SegmentReport {
    /// mean_S and σ_S; `None` when S holds no valid disparity.
    pub stats: Option<SelectedStats>,
    /// The D_fg interval.
    pub thresholds: Option<Thresholds>,
    /// The ground line, when [`SegmentParams::ground_band`] is set and
    /// one was found.
    pub ground: Option<GroundLine>,
    /// ON cells of D_fg before any object's inhibition (after the
    /// ground's).
    pub foreground: u32,
    /// Objects, most salient first.
    pub objects: heapless::Vec<Detection, MAX_OBJECTS>,
}

/// Inhibits an extracted object in D_fg so the next search finds another:
/// turns OFF the D_fg cells of the object's slice (ON in D_ObjReg) that lie
/// in its refined region or its mask. When that turns nothing OFF (ψ was
/// empty), it turns OFF every D_fg cell whose plane is within 1 of δ, so each
/// search removes at least the cells that chose δ. Returns the cells
/// turned OFF.
///
/// # Errors
/// [`SegmentError::SizeMismatch`].
pub fn inhibit(
    d_fg: &mut ImageViewMut<'_, DisparityCell>,
    d_obj_reg: &ImageView<'_, DisparityCell>,
    region: &ImageView<'_, bool>,
    mask: &ImageView<'_, bool>,
    delta: u16,
) -> Result<u32, SegmentError> {
    check_size(d_fg.size(), d_obj_reg.size())?;
    check_size(d_fg.size(), region.size())?;
    check_size(d_fg.size(), mask.size())?;
    let mut n = 0;
    let rows = d_fg.rows_mut().zip(d_obj_reg.rows());
    for ((d, o), (r, m)) in rows.zip(region.rows().zip(mask.rows())) {
        let cells = d.iter_mut().zip(o).zip(r.iter().zip(m));
        for ((d, o), (&r, &m)) in cells {
            if o.is_on() && (r || m) {
                *d = DisparityCell::OFF;
                n += 1;
            }
        }
    }
    if n == 0 {
        for d in d_fg.rows_mut().flat_map(|r| r.iter_mut()) {
            let near = d
                .get()
                .is_some_and(|v| plane(v.to_bits()).abs_diff(delta) <= 1);
            if near {
                *d = DisparityCell::OFF;
                n += 1;
            }
        }
    }
    Ok(n)
}

/// Runs the whole stage for up to `params.max_objects` objects. `masks`
/// holds one packed `width · height` mask per object; every mask is
/// cleared first, and masks past the detections stay clear. With no valid
/// disparity in S, no foreground or no foreground edge the report has no
/// objects and every map is OFF (never an error).
///
/// The steps are those of the `bool` functions of this module, run on bit
/// maps ([`SegmentBuffers`]); the output is the same bit for bit.
///
/// # Errors
/// [`SegmentError::BadParams`], [`SegmentError::SizeMismatch`] when a map is
/// not the buffers' size, [`SegmentError::MasksTooSmall`], or
/// [`SegmentError::LabelCapacity`].
pub fn segment(
    params: &SegmentParams,
    disparity: &ImageView<'_, DisparityCell>,
    conspicuity: &ImageView<'_, EdgeCell>,
    bufs: &mut SegmentBuffers<'_>,
    masks: &mut [bool],
) -> Result<SegmentReport, SegmentError> {
    segment_timed(params, disparity, conspicuity, bufs, masks, &mut |_| {})
}

/// The steps [`segment_timed`] reports to its probe, in order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// mean_S, σ_S, the thresholds and D_fg.
    Foreground,
    /// A^C(d) and δ.
    Slice,
    /// D_ObjReg, ψ and C_ObjReg.
    Region,
    /// The border refinement (dilations, largest component) and C_Obj.
    Refine,
    /// Non-maximum suppression.
    Nms,
    /// The closing.
    Close,
    /// Hole filling.
    Fill,
    /// Area filter, mask output, bounding box and inhibition.
    Mask,
    /// Holes by colour ([`Holes`](super::Holes)), over every mask.
    Holes,
}

/// [`segment`], calling `probe(step)` after each [`Step`] (for per-step
/// timing on the board).
///
/// # Errors
/// As [`segment`].
pub fn segment_timed(
    params: &SegmentParams,
    disparity: &ImageView<'_, DisparityCell>,
    conspicuity: &ImageView<'_, EdgeCell>,
    bufs: &mut SegmentBuffers<'_>,
    masks: &mut [bool],
    probe: &mut dyn FnMut(Step),
) -> Result<SegmentReport, SegmentError> {
    segment_into(
        params,
        disparity,
        conspicuity,
        bufs,
        Masks::Bools(masks),
        &mut StepsOnly(probe),
    )
}

/// Sees the steps and the objects of [`segment_into`]; both methods do
/// nothing by default.
pub trait SegmentObserver {
    /// `step` is done.
    fn step(&mut self, _step: Step) {}
    /// One object's search is done: its mask is written and every map of
    /// `bufs` shows its search (before it is inhibited).
    fn object(&mut self, _det: &Detection, _bufs: &SegmentBuffers<'_>) {}
}

impl SegmentObserver for () {}

struct StepsOnly<'p>(&'p mut dyn FnMut(Step));

impl SegmentObserver for StepsOnly<'_> {
    fn step(&mut self, step: Step) {
        (self.0)(step);
    }
}

/// [`segment_timed`] with the masks as `bool`s or bit maps ([`Masks`]),
/// reporting its steps and each object's maps to `observer`.
///
/// # Errors
/// As [`segment`] ([`SegmentError::MasksTooSmall`] counts `bool`s or
/// words).
pub fn segment_into(
    params: &SegmentParams,
    disparity: &ImageView<'_, DisparityCell>,
    conspicuity: &ImageView<'_, EdgeCell>,
    bufs: &mut SegmentBuffers<'_>,
    mut masks: Masks<'_>,
    observer: &mut impl SegmentObserver,
) -> Result<SegmentReport, SegmentError> {
    params.validate()?;
    let (w, h) = bufs.size();
    check_size((w, h), disparity.size())?;
    check_size((w, h), conspicuity.size())?;
    let k = usize::from(params.max_objects);
    let chunk = match masks {
        Masks::Bools(_) => (w * h).max(1),
        Masks::Bits(_) => bufs.g.len().max(1),
    };
    let needed = k * chunk;
    if masks.len() < needed {
        return Err(SegmentError::MasksTooSmall {
            needed,
            got: masks.len(),
        });
    }
    match &mut masks {
        Masks::Bools(m) => m.fill(false),
        Masks::Bits(m) => m.fill(0),
    }
    bufs.clear();
    let g = bufs.g;
    let mut report = SegmentReport {
        stats: None,
        thresholds: None,
        ground: None,
        foreground: 0,
        objects: heapless::Vec::new(),
    };
    let Some(stats) = selected_stats(params, disparity) else {
        return Ok(report);
    };
    let t = thresholds(params, &stats);
    report.stats = Some(stats);
    report.thresholds = Some(t);
    // The rows' dominant disparities (`bufs.ground_rows`) serve the ground
    // fit and the background by rows.
    let rows_needed = params.ground_band.is_some()
        || params.row_background.is_some()
        || params.depth_pass.is_some();
    if rows_needed {
        let line = fit_ground(disparity, bufs.ground_rows)?;
        report.ground = line.filter(|_| params.ground_band.is_some());
    }
    let ground = report.ground.as_ref().zip(params.ground_band);
    let rows = params.row_background.map(|b| (&*bufs.ground_rows, b));
    // The depth pass's foreground is written in the same sweep and kept
    // in `bufs.rise` until the pass runs.
    let rise = params.depth_pass.map(|pass| passes::Rise {
        rows: &*bufs.ground_rows,
        rise: pass.rise,
        fg: &mut *bufs.rise,
    });
    report.foreground = passes::foreground(params, disparity, &t, ground, rows, rise, g, bufs.d_fg);
    observer.step(Step::Foreground);
    let searches = if params.every_mask_is_an_object() {
        k
    } else {
        k * SEARCHES_PER_OBJECT
    };
    run_searches(
        params,
        disparity,
        conspicuity,
        bufs,
        &mut masks,
        &mut report,
        observer,
        searches,
    )?;
    Ok(report)
}

/// Up to `searches` searches of figure-ground on the foreground in
/// `bufs.d_fg`, adding objects to `report` and `masks` until it holds K.
#[allow(clippy::too_many_arguments)]
pub(super) fn run_searches(
    params: &SegmentParams,
    disparity: &ImageView<'_, DisparityCell>,
    conspicuity: &ImageView<'_, EdgeCell>,
    bufs: &mut SegmentBuffers<'_>,
    masks: &mut Masks<'_>,
    report: &mut SegmentReport,
    observer: &mut impl SegmentObserver,
    searches: usize,
) -> Result<(), SegmentError> {
    let Some(stats) = report.stats else {
        return Ok(());
    };
    let g = bufs.g;
    let (w, h) = (g.width, g.height);
    let k = usize::from(params.max_objects);
    let chunk = masks.chunk(g);
    // `w·h >= 1` (`check_size`); `max` shows the compiler, so that the
    // chunk loops have no panic path.
    for search in 0..searches {
        if report.objects.len() >= k {
            break;
        }
        let counts = passes::slice_counts(conspicuity, disparity, g, bufs.d_fg);
        let Some(slice) = select_slice(&counts, params.exponent) else {
            break;
        };
        observer.step(Step::Slice);
        let range = slice_range(params, &stats, slice.delta);
        passes::object(
            params.psi_mean,
            conspicuity,
            disparity,
            &range,
            g,
            bufs.d_fg,
            bufs.d_obj_reg,
            bufs.region,
            bufs.c_obj_reg,
        );
        observer.step(Step::Region);
        bits::morph_n(
            g,
            params.disk,
            bufs.region,
            bufs.scratch,
            bufs.morph_rows,
            params.refine_dilations,
            false,
        );
        let comps = bits::components(g, bufs.region, Connectivity::Eight, bufs.rows, bufs.table)?;
        let best = comps.largest.map(|(r, _)| r);
        comps.select(g, bufs.region, bufs.table, bufs.scratch, |r, _| {
            Some(r) == best
        });
        bits::copy_map(bufs.region, bufs.scratch);
        for ((o, &a), &b) in bufs
            .c_obj
            .iter_mut()
            .zip(bufs.c_obj_reg.iter())
            .zip(bufs.region.iter())
        {
            *o = a & b;
        }
        observer.step(Step::Refine);
        bits::nms(g, conspicuity, bufs.c_obj, bufs.nms);
        observer.step(Step::Nms);
        bits::copy_map(bufs.closed, bufs.nms);
        bits::close(
            g,
            params.disk,
            bufs.closed,
            bufs.scratch,
            bufs.morph_rows,
            params.closing_steps,
        );
        observer.step(Step::Close);
        bits::fill_holes(g, bufs.closed, bufs.filled, bufs.scratch);
        observer.step(Step::Fill);
        let comps = bits::components(g, bufs.filled, Connectivity::Eight, bufs.rows, bufs.table)?;
        let largest = comps.largest.map_or(0, |(_, a)| a);
        let keep = params.min_area;
        let kept = |area: u32| {
            u64::from(area) * u64::from(keep.den) >= u64::from(largest) * u64::from(keep.num)
        };
        let mut kept_regions = 0u32;
        let area = comps.select(g, bufs.filled, bufs.table, bufs.mask, |_, a| kept(a));
        comps.for_each_root(bufs.table, |a| kept_regions += u32::from(kept(a)));
        let regions = AreaReport {
            regions: u16::try_from(comps.count).unwrap_or(u16::MAX),
            kept: u16::try_from(kept_regions).unwrap_or(u16::MAX),
            largest,
            area,
        };
        // Several objects of one slice whose contours touch: each solid
        // interior its own object (`split_interiors`).
        let mut roots = [0u32; MAX_OBJECTS];
        let split = if params.split_interiors && params.large_enough(u64::from(area / 2), w, h) {
            let (n, ic) = parts::solid_interiors(params, bufs, &mut roots)?;
            (n >= 2).then_some((n, ic))
        } else {
            None
        };
        // One object, or each solid interior.
        let (parts_n, ic) = split.map_or((1, None), |(n, ic)| (n, Some(ic)));
        for &root in roots.iter().take(parts_n) {
            if report.objects.len() >= k {
                break;
            }
            let mut regions = regions;
            if let Some(ic) = &ic {
                regions.area = parts::part_mask(params, bufs, ic, root);
            }
            emit(
                params, masks, chunk, &slice, range, regions, bufs, report, observer, None,
            );
        }
        if ic.is_some() {
            // The inhibition takes every part.
            bits::copy_map(bufs.mask, bufs.filled);
        }
        // Inhibit only before another search, so that after the run every
        // map shows what the last search saw (for K = 1, the paper's maps).
        if report.objects.len() < k && search + 1 < searches {
            passes::inhibit(
                disparity,
                g,
                bufs.d_fg,
                bufs.d_obj_reg,
                bufs.region,
                bufs.mask,
                slice.delta,
            );
        }
        observer.step(Step::Mask);
    }
    Ok(())
}

/// Reports `bufs.mask` as the next object when it is one.
#[allow(clippy::too_many_arguments)]
pub(super) fn emit(
    params: &SegmentParams,
    masks: &mut Masks<'_>,
    chunk: usize,
    slice: &super::stats::Slice,
    range: DisparityRange,
    regions: AreaReport,
    bufs: &mut SegmentBuffers<'_>,
    report: &mut SegmentReport,
    observer: &mut impl SegmentObserver,
    union: Option<Union>,
) {
    let g = bufs.g;
    let (w, h) = (g.width, g.height);
    let index = report.objects.len();
    let area = regions.area;
    let bbox = BoundingBox::of_bits(g, bufs.mask);
    let box_size = bbox.map_or((0, 0), |b| (b.width, b.height));
    let object = params.is_object(area, box_size, (w, h))
        && union.is_none_or(|u| u.keeps(g, area, bufs.mask, masks, chunk));
    if object {
        masks.write(index, chunk, g, bufs.mask);
    }
    let det = Detection {
        index,
        delta: slice.delta,
        range,
        score: slice.score,
        area,
        bbox,
        regions,
    };
    if object {
        observer.object(&det, bufs);
        // Capacity MAX_OBJECTS >= max_objects, checked by `validate`.
        let _ = report.objects.push(det);
    }
}
