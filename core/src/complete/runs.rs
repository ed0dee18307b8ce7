//! The completion (module [`super`]) on bit maps and runs, with bounded
//! tables: the pipeline's completion.
//!
//! The regions are labelled by runs (maximal horizontal stretches of
//! non-edge cells), one table entry per run, not a label per pixel. Every
//! later pass walks the runs again in the same order, so a run's region is
//! its table entry and no label map is kept: the medians are counted run by
//! run, and the last pass rebuilds five rows of labels at a time for the
//! edge cells, which look up to two rows away. The edges and the trusted
//! cells are bit maps. The colour that gives an edge cell its side is any
//! [`SideColour`]; the pipeline keeps one byte per pixel ([`Tone`]).
//!
//! With tables large enough ([`run_table_len`], and region tables of
//! [`region_table_len`](super::region_table_len)), and [`Luv`] as the
//! colour, the result is that of the f32 reference (`host/src/reference/
//! complete.rs`, checked bit for bit). With fewer table entries it
//! degrades gracefully: runs past the
//! run table's capacity belong to no region and are left unchanged (and
//! counted), as are regions past the region tables' capacity.
//!
//! The medians' bisection starts from each region's smallest and largest
//! trusted disparity and runs as many passes as the widest of those ranges
//! needs (5 for disparities up to 31 px), not 8; a pass skips the runs of
//! regions whose median is already found.

use super::{
    at_most_limit, whole_bits, CompleteError, CompleteParams, CompleteReport, RegionSums,
    RegionTables, RowSpan, Tilt, MAX_TILTED, TILT_ROW_STEP,
};
use crate::conspicuity::{EdgeCell, Luv};
use crate::disparity::{from_pixels, DisparityCell};
use crate::image::{ImageError, ImageView, ImageViewMut};
use crate::segment::{bit_map_len, row_runs, words_per_row};

mod tone;
mod walk;
pub use tone::Tone;
use walk::{bit, count_below, get16, label_row, label_runs, trusted_row, Walk};

/// A colour the completion compares to give an edge cell to the side it
/// looks like.
pub trait SideColour: Copy {
    /// A squared distance between two colours (only its order matters).
    fn dist2(self, other: Self) -> u32;
}

impl SideColour for Luv {
    /// The exact squared CIELUV distance in Q12 (channels within
    /// ±16 383 LSB, so it fits `u32`).
    fn dist2(self, other: Self) -> u32 {
        let (a, b) = (self.to_bits(), other.to_bits());
        let sq = |x: i16, y: i16| {
            let d = i32::from(x) - i32::from(y);
            d.unsigned_abs() * d.unsigned_abs()
        };
        sq(a[0], b[0]) + sq(a[1], b[1]) + sq(a[2], b[2])
    }
}

/// Run-table entries that label any `width` x `height` map: one per run,
/// at most `⌈width/2⌉` runs a row, capped at `u16::MAX`.
pub const fn run_table_len(width: usize, height: usize) -> usize {
    let n = row_runs(width) * height;
    if n > u16::MAX as usize {
        u16::MAX as usize
    } else {
        n
    }
}

/// Most run-table entries the pipeline takes: 16 KB of table, three
/// times the runs of non-edge cells of the synthetic scenes at 160x120
/// (at most about 2,400; test `the_default_run_table_holds_the_runs_of_synthetic_scenes`),
/// and every run of any frame up to 128x96 ([`run_table_len`] is 6,144).
pub const DEFAULT_RUN_CAPACITY: usize = 8192;

/// The run-table entries the pipeline takes at `width` x `height`:
/// [`run_table_len`], at most [`DEFAULT_RUN_CAPACITY`].
pub const fn pipeline_run_capacity(width: usize, height: usize) -> usize {
    let n = run_table_len(width, height);
    if n < DEFAULT_RUN_CAPACITY {
        n
    } else {
        DEFAULT_RUN_CAPACITY
    }
}

/// `u32` words of the `rows` buffer of [`RunBuffers`]: two rows of runs.
pub const fn run_rows_len(width: usize) -> usize {
    4 * row_runs(width)
}

/// Label rows [`RunBuffers::labels`] holds: the edge cells of a row look
/// two rows up and down.
pub const LABEL_ROWS: usize = 5;

/// The buffers of [`complete_runs`], caller-provided.
#[derive(Debug)]
pub struct RunBuffers<'a> {
    /// Bit map ([`bit_map_len`] words): the non-edge cells.
    pub open: &'a mut [u32],
    /// Bit map: the trusted cells.
    pub trusted: &'a mut [u32],
    /// The run table, one `u16` per run; its length is the capacity.
    pub runs: &'a mut [u16],
    /// Two rows of runs ([`run_rows_len`] words).
    pub rows: &'a mut [u32],
    /// [`LABEL_ROWS`] rows of region labels (`LABEL_ROWS * width`).
    pub labels: &'a mut [u16],
}

/// The completion over bit maps and runs (module docs):
/// completes `disparity` in place over the regions of the conspicuity map
/// `edges`, with `colour` deciding the side of each edge cell.
///
/// # Errors
/// [`CompleteError::Image`] when the maps differ in size or a buffer is
/// too short for the frame.
pub fn complete_runs<C: SideColour>(
    params: &CompleteParams,
    edges: &ImageView<'_, EdgeCell>,
    colour: &ImageView<'_, C>,
    disparity: &mut ImageViewMut<'_, DisparityCell>,
    bufs: &mut RunBuffers<'_>,
    tables: &mut RegionTables<'_>,
) -> Result<CompleteReport, CompleteError> {
    let size = edges.size();
    let (w, h) = size;
    for other in [colour.size(), disparity.size()] {
        if other != size {
            return Err(ImageError::SizeMismatch {
                expected: size,
                got: other,
            }
            .into());
        }
    }
    let stride = words_per_row(w);
    let short = |needed: usize, got: usize| -> Result<(), CompleteError> {
        if got < needed {
            Err(ImageError::BufferTooSmall { needed, got }.into())
        } else {
            Ok(())
        }
    };
    short(bit_map_len(w, h), bufs.open.len())?;
    short(bit_map_len(w, h), bufs.trusted.len())?;
    short(run_rows_len(w), bufs.rows.len())?;
    short(LABEL_ROWS * w, bufs.labels.len())?;

    // The non-edge cells, as bits.
    for (row, out) in edges.rows().zip(bufs.open.chunks_exact_mut(stride.max(1))) {
        for (word, cells) in out.iter_mut().zip(row.chunks(32)) {
            let mut b = 0u32;
            for (i, c) in cells.iter().enumerate() {
                b |= u32::from(c.is_off()) << i;
            }
            *word = b;
        }
    }
    let (regions, runs) = label_runs(bufs.open, stride, h, bufs.runs, bufs.rows);
    let run_cap = bufs.runs.len().min(u16::MAX as usize);
    let g = usize::from(params.guard);
    {
        let disp = disparity.as_view();
        for (y, out) in bufs
            .trusted
            .chunks_exact_mut(stride.max(1))
            .take(h)
            .enumerate()
        {
            let drow = disp.row(y).unwrap_or(&[]);
            trusted_row(bufs.open, stride, size, y, g, drow, out);
        }
    }

    let cap = tables.capacity();
    let min_trusted = params.min_trusted.max(1);
    let mut report = CompleteReport {
        regions,
        regions_skipped: u16::try_from(usize::from(regions).saturating_sub(cap.saturating_sub(1)))
            .unwrap_or(u16::MAX),
        runs_unlabelled: u32::try_from(runs.saturating_sub(run_cap)).unwrap_or(u32::MAX),
        ..CompleteReport::default()
    };
    // Only the labels in use (0..=regions, within the capacity) are set
    // and read: the rest of the tables may hold anything.
    let used = usize::from(regions).saturating_add(1).min(cap);
    if let Some(t) = tables.total.get_mut(..used) {
        t.fill(0);
    }
    if let Some(t) = tables.lo.get_mut(..used) {
        t.fill(u8::MAX);
    }
    if let Some(t) = tables.hi.get_mut(..used) {
        t.fill(0);
    }
    let tilting = params.tilt_rows > 0;
    if tilting {
        let n = used.min(tables.tilt.len());
        if let Some(t) = tables.tilt.get_mut(..n) {
            t.fill(RowSpan::default());
        }
    }

    let open = &*bufs.open;
    let trusted = &*bufs.trusted;
    let table = &*bufs.runs;
    let disp = disparity.as_view();
    let walk = Walk {
        open,
        trusted,
        table,
        stride,
        height: h,
        cap,
    };
    // Counts, and each region's range.
    let tilt = &mut *tables.tilt;
    walk.for_each_trusted(&disp, |l, y, drow, xs| {
        let (Some(t), Some(lo), Some(hi)) = (
            tables.total.get_mut(l),
            tables.lo.get_mut(l),
            tables.hi.get_mut(l),
        ) else {
            return;
        };
        // Per run in registers: the count and the least and greatest ON
        // bits, whose whole px are the run's least and greatest.
        let (mut n, mut least, mut most) = (0u32, u16::MAX, 0u16);
        for x in xs {
            if let Some(&c) = drow.get(x) {
                if c.is_on() {
                    let b = c.raw().to_bits();
                    n += 1;
                    least = least.min(b);
                    most = most.max(b);
                }
            }
        }
        if n > 0 {
            if tilting {
                // The rows, for the tall test; the sums come later, over
                // the cells near the median.
                if let Some(s) = tilt.get_mut(l) {
                    if *t == 0 {
                        s.first = u32::try_from(y).unwrap_or(u32::MAX);
                    }
                    s.last = u32::try_from(y).unwrap_or(u32::MAX);
                }
            }
            *t += n;
            *lo = (*lo).min(whole_bits(least));
            *hi = (*hi).max(whole_bits(most));
        }
    });
    let widest = tables
        .lo
        .iter()
        .zip(tables.hi.iter())
        .zip(tables.total.iter())
        .take(used)
        .filter(|&(_, &t)| t > 0)
        .map(|((&lo, &hi), _)| hi.saturating_sub(lo))
        .max()
        .unwrap_or(0);
    let passes = 8 - widest.leading_zeros();
    for _ in 0..passes {
        if let Some(b) = tables.below.get_mut(..used) {
            b.fill(0);
        }
        let (lo, hi, below) = (&*tables.lo, &*tables.hi, &mut *tables.below);
        walk.for_each_run(&disp, |l, _, drow, trow, span| {
            let (Some(&a), Some(&b), Some(c)) = (lo.get(l), hi.get(l), below.get_mut(l)) else {
                return;
            };
            if a == b {
                // Converged: the update below keeps it whatever the count.
                return;
            }
            // `whole_px(c) <= mid` as one compare of the bits.
            let lim = at_most_limit(((u16::from(a) + u16::from(b)) / 2) as u8);
            *c += count_below(trow, drow, span, lim);
        });
        for (((lo, hi), &below), &total) in tables
            .lo
            .iter_mut()
            .zip(tables.hi.iter_mut())
            .zip(tables.below.iter())
            .zip(tables.total.iter())
            .take(used)
        {
            if total == 0 {
                continue;
            }
            let mid = ((u16::from(*lo) + u16::from(*hi)) / 2) as u8;
            // Lower median: the k-th smallest, k = (total - 1) / 2, 0-based.
            if below > (total - 1) / 2 {
                *hi = mid;
            } else {
                *lo = mid.saturating_add(1).min(*hi);
            }
        }
    }
    report.regions_with_median = u16::try_from(
        tables
            .total
            .iter()
            .take(used)
            .skip(1)
            .filter(|&&t| t >= min_trusted)
            .count(),
    )
    .unwrap_or(u16::MAX);

    // The tall regions (at most MAX_TILTED, in label order): their slot
    // + 1 in `below`, free since the medians, 0 for the other regions.
    let mut tall = [(0usize, 0u32, RegionSums::default()); MAX_TILTED];
    let mut n_tall = 0;
    if tilting {
        if let Some(b) = tables.below.get_mut(..used) {
            b.fill(0);
        }
        for (l, (s, &t)) in tables
            .tilt
            .iter()
            .zip(tables.total.iter())
            .enumerate()
            .skip(1)
        {
            if n_tall >= MAX_TILTED || l >= used {
                break;
            }
            if t >= min_trusted && s.last.saturating_sub(s.first) >= u32::from(params.tilt_rows) {
                if let (Some(slot), Some(b)) = (tall.get_mut(n_tall), tables.below.get_mut(l)) {
                    slot.0 = l;
                    n_tall += 1;
                    *b = n_tall as u32;
                }
            }
        }
    }
    // Their sums over the trusted cells within `tilt_band` of the median,
    // in every TILT_ROW_STEP-th row.
    if n_tall > 0 {
        let (below, lo) = (&*tables.below, &*tables.lo);
        let band = u32::from(params.tilt_band);
        walk.for_each_trusted(&disp, |l, y, drow, xs| {
            if y % TILT_ROW_STEP != 0 {
                return;
            }
            let k = below.get(l).copied().unwrap_or(0) as usize;
            let (Some((_, n_k, s)), Some(&m)) = (tall.get_mut(k.wrapping_sub(1)), lo.get(l)) else {
                return;
            };
            let m = u32::from(m) << 8;
            // Per run in registers: the count and the sum of the bits.
            let (mut n, mut sum) = (0u32, 0u32);
            for x in xs {
                if let Some(&c) = drow.get(x) {
                    let b = u32::from(c.raw().to_bits());
                    if c.is_on() && b.abs_diff(m) <= band {
                        n += 1;
                        sum = sum.wrapping_add(b);
                    }
                }
            }
            if n > 0 {
                // A run has at most 2^16 cells below 2^16: `sum` is exact
                // when the row is narrower than 2^16 px.
                let (y64, n64, b64) = (y as u64, u64::from(n), u64::from(sum));
                if *n_k == 0 {
                    s.first = u32::try_from(y).unwrap_or(u32::MAX);
                }
                s.last = u32::try_from(y).unwrap_or(u32::MAX);
                *n_k += n;
                s.sy = s.sy.wrapping_add(y64 * n64);
                s.syy = s.syy.wrapping_add(y64 * y64 * n64);
                s.sb = s.sb.wrapping_add(b64);
                s.syb = s.syb.wrapping_add(y64 * b64);
            }
        });
    }
    // Their tilts: those whose cells near the median span two rows or more.
    let mut tilts = [(0usize, Tilt { slope: 0, ybar: 0 }); MAX_TILTED];
    let mut n_tilts = 0;
    for &(l, n, ref s) in tall.iter().take(n_tall) {
        if let (Some(tl), Some(slot)) = (Tilt::of(n, s, 1), tilts.get_mut(n_tilts)) {
            *slot = (l, tl);
            n_tilts += 1;
        }
    }
    let tilts = tilts.get(..n_tilts).unwrap_or(&[]);
    report.tilted = u16::try_from(n_tilts).unwrap_or(u16::MAX);

    // Targets, row by row, with the labels of two rows each side.
    let labels = &mut *bufs.labels;
    let (mut built, mut first_run) = (0usize, 0usize);
    for y in 0..h {
        while built < h && built <= y + 2 {
            let orow = open
                .get(built * stride..(built + 1) * stride)
                .unwrap_or(&[]);
            let slot = (built % LABEL_ROWS) * w;
            let out = labels.get_mut(slot..slot + w).unwrap_or(&mut []);
            first_run += label_row(orow, table, first_run, out);
            built += 1;
        }
        let label_at = |xx: usize, yy: usize| {
            let slot = (yy % LABEL_ROWS) * w;
            get16(labels, slot + xx)
        };
        let orow = open.get(y * stride..(y + 1) * stride).unwrap_or(&[]);
        let trow = trusted.get(y * stride..(y + 1) * stride).unwrap_or(&[]);
        // The last region filled in this row and its value (a tall
        // region's value depends on the row only).
        let mut last: Option<(usize, u8)> = None;
        // The untrusted cells: edges, and OFF or near-edge cells.
        for (i, &tw) in trow.iter().enumerate() {
            let mut m = !tw
                & if (i + 1) * 32 > w {
                    (1u32 << (w % 32)) - 1
                } else {
                    u32::MAX
                };
            while m != 0 {
                let x = i * 32 + m.trailing_zeros() as usize;
                m &= m - 1;
                let l = if bit(orow, x) {
                    label_at(x, y)
                } else {
                    edge_region(open, stride, size, colour, x, y, &label_at)
                };
                let l = usize::from(l);
                if l == 0 || l >= cap || tables.total.get(l).copied().unwrap_or(0) < min_trusted {
                    continue;
                }
                let (Some(&median), Some(cell)) = (tables.lo.get(l), disparity.get(x, y)) else {
                    continue;
                };
                let v = match last {
                    Some((k, v)) if k == l => v,
                    _ => {
                        let v = tilts
                            .iter()
                            .find(|(k, _)| *k == l)
                            .map_or(median, |(_, tl)| tl.at(median, y));
                        last = Some((l, v));
                        v
                    }
                };
                if cell.is_on() {
                    report.replaced += 1;
                } else {
                    report.filled += 1;
                }
                disparity.set(x, y, from_pixels(v));
            }
        }
    }
    Ok(report)
}

/// The region an edge cell joins: that of its non-edge neighbour of
/// closest colour within radius 1, else 2 (raster order, first minimum);
/// 0 when none.
fn edge_region<C: SideColour>(
    open: &[u32],
    stride: usize,
    (w, h): (usize, usize),
    colour: &ImageView<'_, C>,
    x: usize,
    y: usize,
    label_at: &impl Fn(usize, usize) -> u16,
) -> u16 {
    let Some(own) = colour.get(x, y) else {
        return 0;
    };
    for r in 1..=2usize {
        let mut best: Option<(u32, u16)> = None;
        for yy in y.saturating_sub(r)..=(y + r).min(h.saturating_sub(1)) {
            let orow = open.get(yy * stride..(yy + 1) * stride).unwrap_or(&[]);
            let crow = colour.row(yy).unwrap_or(&[]);
            for xx in x.saturating_sub(r)..=(x + r).min(w.saturating_sub(1)) {
                if !bit(orow, xx) {
                    continue;
                }
                let Some(&c) = crow.get(xx) else {
                    continue;
                };
                let d = own.dist2(c);
                if best.is_none_or(|(bd, _)| d < bd) {
                    best = Some((d, label_at(xx, yy)));
                }
            }
        }
        if let Some((_, l)) = best {
            return l;
        }
    }
    0
}
