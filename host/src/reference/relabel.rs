//! Reference of the band relabelling ([`protogist::segment::Relabel`],
//! `protogist::segment::relabel_object`) on `bool` maps: the outline's
//! share of edges, the core, band and ring by repeated square steps, the
//! colour moments of the core and the ring, the 5x5 census of both eyes,
//! the 3x3 matching costs at the object's and the background's
//! disparities, a least neighbour count per band cell, iterated
//! conditional modes from the mask, and the largest component, holes
//! filled.
//!
//! Core decides in integers; so does this (`i128`), so the two agree
//! mask for mask (error bound: none, docs/ERROR_BOUNDS.md).

use super::refine::{scaled, steps};
use super::segment::{dilate, erode, largest_filled};
use protogist::conspicuity::EdgeCell;
use protogist::image::Rgb8;
use protogist::segment::{DisparityRange, Relabel, STAT_FRAC_BITS};

/// Most cells the core or the ring may hold (core's `relabel::MAX_CELLS`).
const MAX_CELLS: i128 = 1 << 20;

/// The 4-neighbours of a cell.
const FOUR: [(isize, isize); 4] = [(-1, 0), (1, 0), (0, -1), (0, 1)];

/// The cell `(x + dx, y + dy)` when it lies in the frame.
fn inside(x: usize, y: usize, dx: isize, dy: isize, w: usize, h: usize) -> Option<usize> {
    let (x, y) = (x.checked_add_signed(dx)?, y.checked_add_signed(dy)?);
    (x < w && y < h).then_some(y * w + x)
}

/// The cell `(x + dx, y + dy)` clamped into the frame.
fn clamped(x: usize, y: usize, dx: isize, dy: isize, w: usize, h: usize) -> usize {
    let c = |v: usize, d: isize, n: usize| (v as isize + d).clamp(0, n as isize - 1) as usize;
    c(y, dy, h) * w + c(x, dx, w)
}

/// Whether under `percent` % of the outline cells of `mask` (ON with a
/// 4-neighbour OFF or past the frame) have an ON cell of C in the 3x3
/// square around them; false without an outline.
fn weak_outline(mask: &[bool], edges: &[EdgeCell], percent: u8, w: usize, h: usize) -> bool {
    let (mut outline, mut edged) = (0u64, 0u64);
    for y in 0..h {
        for x in 0..w {
            let on = |dx, dy| inside(x, y, dx, dy, w, h).is_some_and(|i| mask[i]);
            if !on(0, 0) || FOUR.iter().all(|&(dx, dy)| on(dx, dy)) {
                continue;
            }
            outline += 1;
            let near = (-1..=1).any(|dy| {
                (-1..=1).any(|dx| inside(x, y, dx, dy, w, h).is_some_and(|i| edges[i].is_on()))
            });
            edged += u64::from(near);
        }
    }
    outline > 0 && 100 * edged < u64::from(percent) * outline
}

/// Cells, channel sums and the sum of the squares of every channel of
/// `left` over `on`.
struct Moments {
    n: i128,
    s: [i128; 3],
    q: i128,
}

impl Moments {
    fn of(left: &[Rgb8], on: &[bool]) -> Self {
        let mut m = Self {
            n: 0,
            s: [0; 3],
            q: 0,
        };
        for (p, _) in left.iter().zip(on).filter(|(_, &o)| o) {
            m.n += 1;
            for (s, c) in m.s.iter_mut().zip([p.r, p.g, p.b]) {
                *s += i128::from(c);
                m.q += i128::from(c) * i128::from(c);
            }
        }
        m
    }

    /// `Σ (n·c − S)²`: `n²` times the squared distance of `p` to the mean.
    fn dist(&self, p: Rgb8) -> i128 {
        scaled(p, (self.n, self.s))
    }

    /// `n·Q − ΣS² + n²`: `n²` times the summed variance of the channels,
    /// plus 1.
    fn spread(&self) -> i128 {
        self.n * self.q - self.s.iter().map(|s| s * s).sum::<i128>() + self.n * self.n
    }
}

/// The 5x5 census of `img` (grey = R + G + B): per cell, one bit per
/// cell of the square around it (coordinates clamped into the frame),
/// set when that cell's grey is strictly below the centre's.
fn census(img: &[Rgb8], w: usize, h: usize) -> Vec<u32> {
    let grey: Vec<u32> = img
        .iter()
        .map(|p| u32::from(p.r) + u32::from(p.g) + u32::from(p.b))
        .collect();
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let mut bits = 0u32;
            for dy in -2..=2 {
                for dx in -2..=2 {
                    let below = grey[clamped(x, y, dx, dy, w, h)] < grey[i];
                    bits = bits << 1 | u32::from(below);
                }
            }
            bits
        })
        .collect()
}

/// Reference of the relabelling of `mask` (module docs of
/// `protogist::segment::relabel`) against the `left` and `right` images,
/// C (`edges`), each row's dominant disparity in px (`ground`, as
/// [`super::segment::row_disparities`] gives it) and the object's slice
/// `range`: `None` where core leaves the mask as it is (the outline
/// follows C, the core or the ring has under 5 cells, or the band is
/// empty), else the new mask.
#[allow(clippy::too_many_arguments)]
pub fn relabel_mask(
    relabel: &Relabel,
    mask: &[bool],
    left: &[Rgb8],
    right: &[Rgb8],
    edges: &[EdgeCell],
    ground: &[Option<f64>],
    range: DisparityRange,
    w: usize,
    h: usize,
) -> Option<Vec<bool>> {
    if !weak_outline(mask, edges, relabel.edge_percent, w, h) {
        return None;
    }
    // Core, reach, ring and band.
    let core = steps(erode, mask, relabel.core, w, h);
    let reach = steps(dilate, mask, relabel.reach, w, h);
    let outer = steps(dilate, &reach, relabel.ring, w, h);
    let ring: Vec<bool> = outer.iter().zip(&reach).map(|(&o, &r)| o && !r).collect();
    let (object, behind) = (Moments::of(left, &core), Moments::of(left, &ring));
    if object.n < 5 || behind.n < 5 || object.n > MAX_CELLS || behind.n > MAX_CELLS {
        return None;
    }
    let band: Vec<bool> = reach.iter().zip(&core).map(|(&r, &c)| r && !c).collect();
    if !band.contains(&true) {
        return None;
    }
    let (no2, nb2) = (object.n * object.n, behind.n * behind.n);
    let weight = object.spread() * nb2 + behind.spread() * no2;

    // The matching cost of cell `(x, y)` at disparity `d`: its 3x3 window
    // (clamped into the frame), a cell of it 25 when its match lies left
    // of the frame.
    let (lc, rc) = (census(left, w, h), census(right, w, h));
    let cost = |x: usize, y: usize, d: usize| -> i128 {
        let mut sum = 0;
        for dy in -1..=1 {
            for dx in -1..=1 {
                let i = clamped(x, y, dx, dy, w, h);
                let xx = i % w;
                sum += if xx < d {
                    25
                } else {
                    (lc[i] ^ rc[i - d]).count_ones()
                };
            }
        }
        i128::from(sum)
    };
    let unit = 1i64 << STAT_FRAC_BITS;
    let (low, high) = (range.low.max(0), range.high.max(0));
    let objects = (low / unit) as usize..=((high + unit - 1) / unit) as usize;
    let least_cost =
        |x, y, ds: std::ops::RangeInclusive<usize>| ds.map(|d| cost(x, y, d)).min().unwrap_or(0);

    // Each band cell's least count of object 4-neighbours that makes it
    // the object's (`None`: never).
    let (matching, smooth) = (i128::from(relabel.matching), i128::from(relabel.smooth));
    let least: Vec<Option<i128>> = (0..w * h)
        .map(|i| {
            if !band[i] {
                return None;
            }
            let (x, y) = (i % w, i / w);
            let delta = match ground[y] {
                Some(v) => {
                    // The row's disparity bits (1/256 px), rounded to a
                    // whole pixel.
                    let bits = (v * 256.0).round() as i64;
                    let db = ((bits + 128) >> 8) as usize;
                    let bg = least_cost(x, y, db.saturating_sub(1)..=db + 1);
                    let object = least_cost(x, y, objects.clone());
                    // A cell that matches badly at the slice leans to
                    // the background.
                    let lean = if object > i128::from(relabel.mismatch_cost) {
                        i128::from(relabel.mismatch_lean)
                    } else {
                        0
                    };
                    bg - object - lean
                }
                None => 0,
            };
            let colour = 27 * (behind.dist(left[i]) * no2 - object.dist(left[i]) * nb2);
            (0..=4).find(|&m| colour + (matching * delta + 9 * smooth * (2 * m - 4)) * weight > 0)
        })
        .collect();

    // Iterated conditional modes from the mask: each pass reads the
    // labels of the pass before; past the frame is background.
    let mut labels = mask.to_vec();
    for _ in 0..relabel.passes {
        let prev = labels.clone();
        for (i, label) in labels.iter_mut().enumerate() {
            if !band[i] {
                continue;
            }
            let (x, y) = (i % w, i / w);
            let m = FOUR
                .iter()
                .filter(|&&(dx, dy)| inside(x, y, dx, dy, w, h).is_some_and(|j| prev[j]))
                .count() as i128;
            *label = least[i].is_some_and(|k| m >= k);
        }
    }
    Some(largest_filled(&labels, w, h))
}
