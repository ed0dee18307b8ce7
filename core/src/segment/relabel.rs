//! The band relabelling: a low-contrast object's outline re-decided by
//! colour and stereo matching together, with a smoothness term.
//!
//! A mask the depth pass cuts from the stereo's map follows the map's
//! blur where no colour edge stops it: the outline of a low-contrast
//! object is fattened by a few pixels (docs/RECALL.md). Near that outline
//! neither cue decides a cell alone, the object's colour being close to
//! its surroundings' and the textures smooth, but they err apart. So, for
//! a mask whose outline has an edge of C within 1 px on fewer than
//! [`Relabel::edge_percent`] % of its cells (the outline is not the
//! colour's):
//!
//! 1. the *core* is the mask eroded by [`Relabel::core`] square steps,
//!    the *reach* the mask dilated by [`Relabel::reach`] steps, the *ring*
//!    the reach dilated by [`Relabel::ring`] more, less the reach; the
//!    *band* is the reach less the core;
//! 2. over the core and over the ring, `n` cells, `S` the sum and `Q`
//!    the sum of squares of the left image's R, G and B; per band cell of
//!    colour `c`, `A = Σ (n·c − S)²` (`n²` times its squared distance to
//!    the mean), and `W = (n_o·Q_o − ΣS_o² + n_o²)·n_b² + (n_b·Q_b −
//!    ΣS_b² + n_b²)·n_o²` (o: core, b: ring; `n²·n²` times the sum of
//!    the two variances, each plus 1);
//! 3. the matching cost of a band cell at disparity `d` is the sum over
//!    its 3x3 window of the Hamming distances between the left and the
//!    right 5x5 census at `x` and `x − d` (grey = R + G + B; coordinates
//!    clamped into the frame; 25 for a window cell with `x < d`);
//!    `Δ = min over the background's disparities − min over the
//!    object's`, the object's being the whole pixels from ⌊low⌋ to
//!    ⌈high⌉ of its slice, the background's the row's dominant disparity
//!    (the ground fit's, rounded) ± 1 (no term in a row without one),
//!    less [`Relabel::mismatch_lean`] where the object's minimum is over
//!    [`Relabel::mismatch_cost`]: left of a near object lies a strip the
//!    right eye cannot see, where neither disparity matches and the
//!    difference alone says nothing;
//! 4. a band cell with `m` of its 4 neighbours in the object (none past
//!    the frame's edge) is of the object when
//!    `27·(A_b·n_o² − A_o·n_b²) + (matching·Δ + 9·smooth·(2m − 4))·W > 0`:
//!    the colour's log-likelihood ratio `3 (d_b² − d_o²) / (v_o + v_b + 2)`
//!    plus the matching's and a Potts term, times `9·W` (exact in
//!    `i128`). Each cell's least `m` that passes (0 to 4, or never) is
//!    computed once;
//! 5. [`Relabel::passes`] passes of iterated conditional modes, from the
//!    mask: each band cell takes the decision for the object cells
//!    around it after the pass before;
//! 6. the mask is the largest 4-connected component of the result, holes
//!    filled.
//!
//! A mask of fewer than 5 core or ring cells, or of more than
//! [`MAX_CELLS`] (where the exact `i128` comparison could overflow), or
//! with no outline cell, is left as it is. Integer only; the reference
//! (`protogist_host::reference::relabel::relabel_mask`) decides the same
//! cells (docs/ERROR_BOUNDS.md, bound 0).

use super::bits::{self, Geom};
use super::buffers::SegmentBuffers;
use super::depth::largest_filled;
use super::pipeline::{BoundingBox, Detection};
use super::refine::{each, inside_and_ring, read};
use super::stats::STAT_FRAC_BITS;
use super::SegmentError;
use crate::conspicuity::EdgeCell;
use crate::image::{ImageView, Rgb8, RgbRows};

/// Settings of the band relabelling (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Relabel {
    /// Square erosion steps of the mask giving its core (0 to 8).
    pub core: u8,
    /// Square dilation steps of the mask giving its reach (1 to 8).
    pub reach: u8,
    /// Square dilation steps beyond the reach giving the ring (1 to 8).
    pub ring: u8,
    /// Passes of iterated conditional modes (1 to 16).
    pub passes: u8,
    /// Weight of the matching term (0 to 16).
    pub matching: u8,
    /// Weight of the smoothness term (0 to 64).
    pub smooth: u8,
    /// The mask is relabelled when under this share (%) of its outline
    /// cells have an edge of C within 1 px (0 to 100).
    pub edge_percent: u8,
    /// A band cell whose least census cost at the object's slice is over
    /// this matches badly there, as the strip left of a near object that
    /// the right eye cannot see does (costs are at most 225: 255 never).
    pub mismatch_cost: u8,
    /// What such a cell's matching term leans towards the background, in
    /// census bits before the matching weight (0 to 255).
    pub mismatch_lean: u8,
}

impl Relabel {
    /// A core of 2 steps, a reach of 3, a ring of 4 more, 5 passes,
    /// matching 2, smoothness 6, outlines under 40 % edges
    /// (docs/RECALL.md, "Colour and matching together"); cells costing
    /// over 70 at the slice lean 40 towards the background (docs/RECALL.md,
    /// "After the relabelling").
    pub const DEFAULT: Self = Self {
        core: 2,
        reach: 3,
        ring: 4,
        passes: 5,
        matching: 2,
        smooth: 6,
        edge_percent: 40,
        mismatch_cost: 70,
        mismatch_lean: 40,
    };

    /// Checks the settings.
    ///
    /// # Errors
    /// [`SegmentError::BadParams`] naming the field.
    pub fn validate(&self) -> Result<(), SegmentError> {
        let checks = [
            (self.core <= 8, "relabel.core"),
            ((1..=8).contains(&self.reach), "relabel.reach"),
            ((1..=8).contains(&self.ring), "relabel.ring"),
            ((1..=16).contains(&self.passes), "relabel.passes"),
            (self.matching <= 16, "relabel.matching"),
            (self.smooth <= 64, "relabel.smooth"),
            (self.edge_percent <= 100, "relabel.edge_percent"),
        ];
        match checks.iter().find(|(ok, _)| !ok) {
            Some(&(_, name)) => Err(SegmentError::BadParams(name)),
            None => Ok(()),
        }
    }
}

/// Most cells the core or the ring may hold: with `n ≤ 2^20`, `A·n²` is
/// under 2^98 and `W` times the largest weight sum under 2^112, so the
/// decision's `i128` never overflows.
pub const MAX_CELLS: i128 = 1 << 20;

/// Rows of grey the census reads (5x5).
const GREY_ROWS: usize = 5;
/// Rows of census the costs read (3x3).
const CENSUS_ROWS: usize = 3;
/// The cost of a window cell whose match lies left of the frame.
const OUTSIDE: u32 = 25;

/// `u32` words of the scratch [`relabel_object`] takes at this width:
/// per eye 5 rows of grey and 3 of census, and one RGB row.
pub const fn relabel_len(width: usize) -> usize {
    2 * (GREY_ROWS + CENSUS_ROWS) * width + (3 * width).div_ceil(4)
}

/// One eye's rolling rows: grey (`R + G + B`) and census, each slot
/// tagged with the row it holds.
struct Eye<'a> {
    grey: &'a mut [u32],
    census: &'a mut [u32],
    grey_row: [usize; GREY_ROWS],
    census_row: [usize; CENSUS_ROWS],
}

impl<'a> Eye<'a> {
    fn new(grey: &'a mut [u32], census: &'a mut [u32]) -> Self {
        Self {
            grey,
            census,
            grey_row: [usize::MAX; GREY_ROWS],
            census_row: [usize::MAX; CENSUS_ROWS],
        }
    }

    /// Makes grey row `y` (whole) resident.
    fn grey<S: RgbRows>(&mut self, frame: &S, rgb: &mut [Rgb8], w: usize, y: usize) {
        let slot = y % GREY_ROWS;
        if self.grey_row.get(slot) == Some(&y) {
            return;
        }
        let (Some(out), Some(rgb)) = (
            self.grey.get_mut(slot * w..(slot + 1) * w),
            rgb.get_mut(..w),
        ) else {
            return;
        };
        frame.rgb_row(y, rgb);
        for (o, p) in out.iter_mut().zip(rgb.iter()) {
            *o = u32::from(p.r) + u32::from(p.g) + u32::from(p.b);
        }
        if let Some(t) = self.grey_row.get_mut(slot) {
            *t = y;
        }
    }

    /// Makes census row `y` resident over columns `xs` (clamped
    /// neighbours); other columns of the slot are left as they were.
    fn census<S: RgbRows>(
        &mut self,
        frame: &S,
        rgb: &mut [Rgb8],
        g: Geom,
        y: usize,
        xs: (usize, usize),
    ) {
        let (w, h) = (g.width, g.height);
        let slot = y % CENSUS_ROWS;
        if self.census_row.get(slot) == Some(&y) {
            return;
        }
        let rows = [0usize, 1, 2, 3, 4].map(|k| (y + k).saturating_sub(2).min(h.saturating_sub(1)));
        for &r in &rows {
            self.grey(frame, rgb, w, r);
        }
        let last = w.saturating_sub(1);
        for x in xs.0..=xs.1.min(last) {
            let centre = self.px(rows[2], x, w);
            let mut bits = 0u32;
            for &r in &rows {
                for dx in 0..5 {
                    let xx = (x + dx).saturating_sub(2).min(last);
                    bits = bits << 1 | u32::from(self.px(r, xx, w) < centre);
                }
            }
            if let Some(c) = self.census.get_mut(slot * w + x) {
                *c = bits;
            }
        }
        if let Some(t) = self.census_row.get_mut(slot) {
            *t = y;
        }
    }

    fn px(&self, y: usize, x: usize, w: usize) -> u32 {
        self.grey.get((y % GREY_ROWS) * w + x).copied().unwrap_or(0)
    }

    fn code(&self, y: usize, x: usize, w: usize) -> u32 {
        self.census
            .get((y % CENSUS_ROWS) * w + x)
            .copied()
            .unwrap_or(0)
    }
}

/// Colour sums over a bit map: cells, channel sums, sum of squares.
#[derive(Clone, Copy, Default)]
struct Moments {
    n: i128,
    s: [i128; 3],
    q: i128,
}

impl Moments {
    fn add(&mut self, c: [i64; 3]) {
        self.n += 1;
        for (s, c) in self.s.iter_mut().zip(c) {
            *s += i128::from(c);
            self.q += i128::from(c) * i128::from(c);
        }
    }

    /// `Σ (n·c − S)²`.
    fn scaled_dist(&self, c: [i64; 3]) -> i128 {
        self.s
            .iter()
            .zip(c)
            .map(|(&s, c)| {
                let e = self.n * i128::from(c) - s;
                e * e
            })
            .sum()
    }

    /// `n·Q − ΣS² + n²`: `n²` times the summed variance plus 1.
    fn spread(&self) -> i128 {
        self.n * self.q - self.s.iter().map(|s| s * s).sum::<i128>() + self.n * self.n
    }
}

/// Whether the outline of the mask `mask` has an edge of C within 1 px
/// on under `percent` % of its cells (an outline cell is ON with a
/// 4-neighbour OFF or past the frame). The outline is found a word at a
/// time.
fn weak_outline(g: Geom, mask: &[u32], edges: &ImageView<'_, EdgeCell>, percent: u8) -> bool {
    let (mut outline, mut edged) = (0u64, 0u64);
    let empty: &[u32] = &[];
    for y in 0..g.height {
        let row = g.row(mask, y).unwrap_or(empty);
        let up = if y > 0 {
            g.row(mask, y - 1).unwrap_or(empty)
        } else {
            empty
        };
        let down = g.row(mask, y + 1).unwrap_or(empty);
        for (i, &m) in row.iter().enumerate() {
            if m == 0 {
                continue;
            }
            let before = if i > 0 {
                row.get(i - 1).copied().unwrap_or(0)
            } else {
                0
            };
            let after = row.get(i + 1).copied().unwrap_or(0);
            let left = m << 1 | before >> 31;
            let right = m >> 1 | after << 31;
            let vertical = up.get(i).copied().unwrap_or(0) & down.get(i).copied().unwrap_or(0);
            let mut edge_cells = m & !(left & right & vertical);
            while edge_cells != 0 {
                let x = i * 32 + edge_cells.trailing_zeros() as usize;
                edge_cells &= edge_cells.wrapping_sub(1);
                outline += 1;
                let near = (y.saturating_sub(1)..=y + 1).any(|yy| {
                    (x.saturating_sub(1)..=x + 1)
                        .any(|xx| edges.get(xx, yy).is_some_and(|e| !e.is_off()))
                });
                edged += u64::from(near);
            }
        }
    }
    outline > 0 && edged * 100 < u64::from(percent) * outline
}

/// The object cells among the 4 neighbours of `(x, y)` in `m`.
fn neighbours(g: Geom, m: &[u32], x: usize, y: usize) -> u32 {
    let left = x > 0 && g.bit(m, x - 1, y);
    let up = y > 0 && g.bit(m, x, y - 1);
    u32::from(left) + u32::from(up) + u32::from(g.bit(m, x + 1, y)) + u32::from(g.bit(m, x, y + 1))
}

/// Relabels object `det`'s mask (slot `det.index` of `masks`, bit maps of
/// the frame's size) as the module docs say, against the `left` and
/// `right` frames and C (`edges`); updates its area and box. `scratch`
/// holds [`relabel_len`] words. Returns whether the mask was relabelled.
///
/// # Errors
/// [`SegmentError::Image`] for short scratch;
/// [`SegmentError::SizeMismatch`] for frames or a C map of another size;
/// [`SegmentError::LabelCapacity`] from the labelling.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub fn relabel_object<S: RgbRows>(
    p: &Relabel,
    left: &S,
    right: &S,
    edges: &ImageView<'_, EdgeCell>,
    det: &mut Detection,
    masks: &mut [u32],
    bufs: &mut SegmentBuffers<'_>,
    scratch: &mut [u32],
) -> Result<bool, SegmentError> {
    let g = bufs.g;
    let (w, h) = (g.width, g.height);
    for got in [left.size(), right.size(), edges.size()] {
        if got != (w, h) {
            return Err(SegmentError::SizeMismatch {
                expected: (w, h),
                got,
            });
        }
    }
    let needed = relabel_len(w);
    let short = SegmentError::Image(crate::image::ImageError::BufferTooSmall {
        needed,
        got: scratch.len(),
    });
    let scratch = scratch.get_mut(..needed).ok_or(short)?;
    let chunk = g.len();
    let Some(slot) = masks.get_mut(det.index * chunk..(det.index + 1) * chunk) else {
        return Ok(false);
    };
    bits::copy_map(bufs.mask, slot);
    if w == 0 || h == 0 || !weak_outline(g, bufs.mask, edges, p.edge_percent) {
        return Ok(false);
    }
    // closed = core, filled = reach, region = ring.
    inside_and_ring(bufs, p.core, p.reach, p.ring);
    // `scratch` holds `needed` words: the splits below cannot fail
    // (`split_at_mut` would link a panic path).
    let Some((eyes, rgb_words)) = scratch.split_at_mut_checked(2 * (GREY_ROWS + CENSUS_ROWS) * w)
    else {
        return Ok(false);
    };
    let Some(rgb) = super::refine::rgb_row(rgb_words, w) else {
        return Ok(false);
    };
    let (mut o, mut b) = (Moments::default(), Moments::default());
    for y in 0..h {
        let (ro, rb) = (
            g.row(bufs.closed, y).unwrap_or(&[]),
            g.row(bufs.region, y).unwrap_or(&[]),
        );
        if let Some(px) = read(left, rgb, y, &[ro, rb]) {
            each(px, ro, |_, c| o.add(c));
            each(px, rb, |_, c| b.add(c));
        }
    }
    if o.n < 5 || b.n < 5 || o.n > MAX_CELLS || b.n > MAX_CELLS {
        return Ok(false);
    }
    let (no2, nb2) = (o.n * o.n, b.n * b.n);
    let wt = o.spread() * nb2 + b.spread() * no2;
    // The band (reach less core) in `filled`; its rows and columns.
    for (f, c) in bufs.filled.iter_mut().zip(bufs.closed.iter()) {
        *f &= !*c;
    }
    let Some((x0, y0, x1, y1)) = bits::bbox(g, bufs.filled) else {
        return Ok(false);
    };
    let frac = STAT_FRAC_BITS;
    let d_lo = usize::try_from(det.range.low.max(0) >> frac).unwrap_or(0);
    let d_hi = usize::try_from((det.range.high.max(0) + (1 << frac) - 1) >> frac).unwrap_or(0);
    let ground_max = bufs
        .ground_rows
        .iter()
        .take(h)
        .map(|&r| (r.saturating_sub(1) + 128) >> 8)
        .max()
        .unwrap_or(0) as usize;
    let d_max = d_hi.max(ground_max + 1);
    let Some((eye_l, eye_r)) = eyes.split_at_mut_checked((GREY_ROWS + CENSUS_ROWS) * w) else {
        return Ok(false);
    };
    let (Some((gl, cl)), Some((gr, cr))) = (
        eye_l.split_at_mut_checked(GREY_ROWS * w),
        eye_r.split_at_mut_checked(GREY_ROWS * w),
    ) else {
        return Ok(false);
    };
    let (mut el, mut er) = (Eye::new(gl, cl), Eye::new(gr, cr));
    let last = w.saturating_sub(1);
    let (lx, rx) = (
        (x0.saturating_sub(1), (x1 + 1).min(last)),
        (
            (x0.saturating_sub(1)).saturating_sub(d_max),
            (x1 + 1).min(last),
        ),
    );
    // Each band cell's least neighbour count, in three bit planes.
    let (k0, k1, k2) = (&mut *bufs.d_obj_reg, &mut *bufs.c_obj_reg, &mut *bufs.c_obj);
    k0.fill(0);
    k1.fill(0);
    k2.fill(0);
    let band: &[u32] = bufs.filled;
    let matching = i128::from(p.matching);
    let smooth = i128::from(p.smooth);
    for y in y0..=y1 {
        let rows = [y.saturating_sub(1), y, (y + 1).min(h.saturating_sub(1))];
        for &r in &rows {
            el.census(left, rgb, g, r, lx);
            er.census(right, rgb, g, r, rx);
        }
        let bg = bufs.ground_rows.get(y).copied().unwrap_or(0);
        let row_band = g.row(band, y).unwrap_or(&[]);
        let Some(px) = read(left, rgb, y, &[row_band]) else {
            continue;
        };
        each(px, row_band, |x, c| {
            let cost = |d: usize| -> u32 {
                let mut sum = 0;
                for &yy in &rows {
                    for xx in [x.saturating_sub(1), x, (x + 1).min(last)] {
                        sum += if xx < d {
                            OUTSIDE
                        } else {
                            (el.code(yy, xx, w) ^ er.code(yy, xx.saturating_sub(d), w)).count_ones()
                        };
                    }
                }
                sum
            };
            let delta = if bg == 0 {
                0
            } else {
                let db = ((bg - 1 + 128) >> 8) as usize;
                let c_in = (d_lo..=d_hi).map(cost).min().unwrap_or(0);
                let c_bg = (db.saturating_sub(1)..=db + 1).map(cost).min().unwrap_or(0);
                let lean = if c_in > u32::from(p.mismatch_cost) {
                    i128::from(p.mismatch_lean)
                } else {
                    0
                };
                i128::from(c_bg) - i128::from(c_in) - lean
            };
            let colour = 27 * (b.scaled_dist(c) * no2 - o.scaled_dist(c) * nb2);
            let k = (0..=4i128)
                .find(|&m| colour + (matching * delta + 9 * smooth * (2 * m - 4)) * wt > 0)
                .map_or(5, |m| m as u32);
            g.set(k0, x, y, k & 1 != 0);
            g.set(k1, x, y, k & 2 != 0);
            g.set(k2, x, y, k & 4 != 0);
        });
    }
    // Iterated conditional modes from the mask, in `interiors`.
    let (lab, prev) = (&mut *bufs.interiors, &mut *bufs.scratch);
    bits::copy_map(lab, bufs.mask);
    for _ in 0..p.passes {
        bits::copy_map(prev, lab);
        bits::for_each_on(g, band, |x, y| {
            let k = u32::from(g.bit(k0, x, y))
                | u32::from(g.bit(k1, x, y)) << 1
                | u32::from(g.bit(k2, x, y)) << 2;
            g.set(lab, x, y, neighbours(g, prev, x, y) >= k);
        });
    }
    // closed = the result within the reach (core ∪ band).
    for ((c, l), f) in bufs.closed.iter_mut().zip(lab.iter()).zip(band.iter()) {
        *c |= *l & *f;
    }
    largest_filled(bufs)?;
    let area = bufs.mask.iter().map(|w| w.count_ones()).sum::<u32>();
    bits::copy_map(slot, bufs.mask);
    det.area = area;
    det.bbox = BoundingBox::of_bits(g, bufs.mask);
    Ok(true)
}
