//! Reference of [`protogist::segment`], same names and argument order.
//!
//! The statistics steps (S, mean and σ, the D_fg thresholds, A^C(d), δ, r)
//! are in floating point: disparity maps are `Option<f32>` px (`None` is
//! OFF), sums in f64. The integer mask stages (dilation, erosion, closing,
//! NMS, labelling, hole filling, the area filter, the border refinement) are
//! written the naive way, pixel by pixel with flood fills on `Vec`s, and
//! must agree with core bit for bit.

use protogist::conspicuity::EdgeCell;
use protogist::image::Rgb8;
use protogist::segment::{Connectivity, Disk, Ratio, SegmentParams, NMS_DIRECTIONS};
use std::collections::VecDeque;

/// A disparity cell in px, `None` for OFF.
pub type DispF = Option<f32>;

fn ratio(r: Ratio) -> f64 {
    f64::from(r.num) / f64::from(r.den)
}

/// True when `(x, y)` lies in S: `x > w·left`, `h·tb < y < h·(1 − tb)`.
pub fn in_selected_area(
    params: &SegmentParams,
    width: usize,
    height: usize,
    x: usize,
    y: usize,
) -> bool {
    let (l, tb) = (ratio(params.left_strip), ratio(params.top_bottom_strip));
    let (x, y, w, h) = (x as f64, y as f64, width as f64, height as f64);
    x > w * l && y > h * tb && y < h * (1.0 - tb)
}

/// mean_S and σ_S, px.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SelectedStatsF {
    /// Valid pixels of S.
    pub count: u32,
    /// mean_S.
    pub mean: f32,
    /// σ_S (population).
    pub sigma: f32,
}

/// mean_S and σ_S over the valid disparities of S; `None` when there are none.
pub fn selected_stats(
    params: &SegmentParams,
    disparity: &[DispF],
    width: usize,
    height: usize,
) -> Option<SelectedStatsF> {
    let vals: Vec<f64> = disparity
        .iter()
        .enumerate()
        .filter(|(i, _)| in_selected_area(params, width, height, i % width, i / width))
        .filter_map(|(_, d)| d.map(f64::from))
        .collect();
    if vals.is_empty() {
        return None;
    }
    let n = vals.len() as f64;
    let mean = vals.iter().sum::<f64>() / n;
    let var = vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    Some(SelectedStatsF {
        count: vals.len() as u32,
        mean: mean as f32,
        sigma: var.sqrt() as f32,
    })
}

/// The open D_fg interval, px.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThresholdsF {
    /// mean + 0.1σ.
    pub low: f32,
    /// mean + 2σ.
    pub high: f32,
}

/// The D_fg interval.
pub fn thresholds(params: &SegmentParams, stats: &SelectedStatsF) -> ThresholdsF {
    let (m, s) = (f64::from(stats.mean), f64::from(stats.sigma));
    ThresholdsF {
        low: (m + ratio(params.fg_low) * s) as f32,
        high: (m + ratio(params.fg_high) * s) as f32,
    }
}

/// D_fg: the disparities of S strictly inside `t`.
pub fn foreground(
    params: &SegmentParams,
    disparity: &[DispF],
    width: usize,
    height: usize,
    t: &ThresholdsF,
) -> Vec<DispF> {
    disparity
        .iter()
        .enumerate()
        .map(|(i, d)| {
            d.filter(|&v| {
                t.low < v
                    && v < t.high
                    && in_selected_area(params, width, height, i % width, i / width)
            })
        })
        .collect()
}

/// C_fg: C where D_fg is ON.
pub fn foreground_conspicuity(c: &[EdgeCell], d_fg: &[DispF]) -> Vec<EdgeCell> {
    c.iter()
        .zip(d_fg)
        .map(|(&c, d)| if d.is_some() { c } else { EdgeCell::OFF })
        .collect()
}

/// ON C_fg cells per whole-px plane (rounded half up) and the D_fg plane range.
pub fn slice_counts(c_fg: &[EdgeCell], d_fg: &[DispF]) -> (Vec<u32>, Option<(u16, u16)>) {
    let mut counts = vec![0u32; 257];
    let mut range: Option<(u16, u16)> = None;
    for (c, d) in c_fg.iter().zip(d_fg) {
        if let Some(d) = d {
            let p = (d + 0.5).floor() as u16;
            range = Some(range.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))));
            if c.is_on() {
                counts[usize::from(p)] += 1;
            }
        }
    }
    (counts, range)
}

/// δ, A^C(δ) and the score A^C(δ)·δ^A (f64); the nearest plane wins ties.
pub fn select_slice(
    counts: &(Vec<u32>, Option<(u16, u16)>),
    exponent: u8,
) -> Option<(u16, u32, f64)> {
    let (c, range) = counts;
    let (lo, hi) = (*range)?;
    let mut best: Option<(u16, u32, f64)> = None;
    for d in lo..=hi {
        let cells: u32 = (d.saturating_sub(1).max(lo)..=(d + 1).min(hi))
            .map(|i| c[usize::from(i)])
            .sum();
        let score = f64::from(cells) * f64::from(d).powi(i32::from(exponent));
        if score > 0.0 && best.is_none_or(|b| score >= b.2) {
            best = Some((d, cells, score));
        }
    }
    best
}

/// r = σ_S · range (σ_S / 2.5), at least `min_slice_radius` / 256, px.
pub fn slice_radius(params: &SegmentParams, stats: &SelectedStatsF) -> f32 {
    let r = (f64::from(stats.sigma) * ratio(params.range)) as f32;
    r.max(f32::from(params.min_slice_radius) / 256.0)
}

fn offsets(disk: Disk) -> Vec<(isize, isize)> {
    let mut v = vec![(0, 0), (-1, 0), (1, 0), (0, -1), (0, 1)];
    if disk == Disk::Square {
        v.extend([(-1, -1), (1, -1), (-1, 1), (1, 1)]);
    }
    v
}

fn at<T: Copy>(m: &[T], w: usize, h: usize, x: isize, y: isize) -> Option<T> {
    if x < 0 || y < 0 || x >= w as isize || y >= h as isize {
        None
    } else {
        Some(m[y as usize * w + x as usize])
    }
}

/// One dilation; outside pixels are OFF.
pub fn dilate(disk: Disk, src: &[bool], w: usize, h: usize) -> Vec<bool> {
    let offs = offsets(disk);
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as isize, (i / w) as isize);
            offs.iter()
                .any(|&(dx, dy)| at(src, w, h, x + dx, y + dy).unwrap_or(false))
        })
        .collect()
}

/// One erosion; outside pixels are ON.
pub fn erode(disk: Disk, src: &[bool], w: usize, h: usize) -> Vec<bool> {
    let offs = offsets(disk);
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as isize, (i / w) as isize);
            offs.iter()
                .all(|&(dx, dy)| at(src, w, h, x + dx, y + dy).unwrap_or(true))
        })
        .collect()
}

/// `n` dilations then `n` erosions of the unbounded plane: of `map` padded
/// by `n` OFF pixels on every side, cropped back.
pub fn close(disk: Disk, map: &[bool], w: usize, h: usize, n: u8) -> Vec<bool> {
    let p = usize::from(n);
    let (pw, ph) = (w + 2 * p, h + 2 * p);
    let mut m = vec![false; pw * ph];
    for (y, row) in map.chunks_exact(w.max(1)).take(h).enumerate() {
        m[(y + p) * pw + p..][..w].copy_from_slice(row);
    }
    for _ in 0..n {
        m = dilate(disk, &m, pw, ph);
    }
    for _ in 0..n {
        m = erode(disk, &m, pw, ph);
    }
    (0..h)
        .flat_map(|y| m[(y + p) * pw + p..][..w].to_vec())
        .collect()
}

/// NMS: ON cells that are ≥ both neighbours along at least one direction.
pub fn non_max_suppression(c_obj: &[EdgeCell], w: usize, h: usize) -> Vec<bool> {
    let v = |x: isize, y: isize| {
        at(c_obj, w, h, x, y)
            .and_then(EdgeCell::get)
            .map_or(-1, |c| i32::from(c.to_bits()))
    };
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as isize, (i / w) as isize);
            let c = v(x, y);
            c >= 0
                && NMS_DIRECTIONS
                    .iter()
                    .any(|&(dx, dy)| c >= v(x - dx, y - dy) && c >= v(x + dx, y + dy))
        })
        .collect()
}

/// Connected components of the pixels equal to `value` by flood fill,
/// labels `1..=n` in raster order of first pixel; returns the labels and `n`.
pub fn label(src: &[bool], w: usize, h: usize, value: bool, conn: Connectivity) -> (Vec<u16>, u16) {
    let mut labels = vec![0u16; w * h];
    let mut n = 0u16;
    let mut nbrs = vec![(-1isize, 0isize), (1, 0), (0, -1), (0, 1)];
    if conn == Connectivity::Eight {
        nbrs.extend([(-1, -1), (1, -1), (-1, 1), (1, 1)]);
    }
    for start in 0..w * h {
        if src[start] != value || labels[start] != 0 {
            continue;
        }
        n += 1;
        labels[start] = n;
        let mut q = VecDeque::from([start]);
        while let Some(i) = q.pop_front() {
            let (x, y) = ((i % w) as isize, (i / w) as isize);
            for &(dx, dy) in &nbrs {
                if at(src, w, h, x + dx, y + dy) == Some(value) {
                    let j = (y + dy) as usize * w + (x + dx) as usize;
                    if labels[j] == 0 {
                        labels[j] = n;
                        q.push_back(j);
                    }
                }
            }
        }
    }
    (labels, n)
}

/// `closed` plus every background pixel not 4-connected to the border.
pub fn fill_holes(closed: &[bool], w: usize, h: usize) -> Vec<bool> {
    let (labels, _) = label(closed, w, h, false, Connectivity::Four);
    let outside: std::collections::HashSet<u16> = (0..w * h)
        .filter(|i| i % w == 0 || i % w == w - 1 || i / w == 0 || i / w == h - 1)
        .map(|i| labels[i])
        .collect();
    (0..w * h)
        .map(|i| closed[i] || !outside.contains(&labels[i]))
        .collect()
}

/// Keeps the 8-connected components of `filled` with area ≥ keep·largest.
pub fn area_filter(filled: &[bool], w: usize, h: usize, keep: Ratio) -> Vec<bool> {
    let (labels, n) = label(filled, w, h, true, Connectivity::Eight);
    let mut area = vec![0u64; usize::from(n) + 1];
    labels.iter().for_each(|&l| area[usize::from(l)] += 1);
    let largest = area.iter().skip(1).copied().max().unwrap_or(0);
    labels
        .iter()
        .map(|&l| {
            l != 0 && area[usize::from(l)] * u64::from(keep.den) >= largest * u64::from(keep.num)
        })
        .collect()
}

/// The region of the border refinement: the largest (first on ties)
/// 8-connected component of the (ψ ≠ OFF) map dilated `n` times.
pub fn refine_region(disk: Disk, psi: &[EdgeCell], w: usize, h: usize, n: u8) -> Vec<bool> {
    let mut m: Vec<bool> = psi.iter().map(|c| c.is_on()).collect();
    for _ in 0..n {
        m = dilate(disk, &m, w, h);
    }
    let (labels, count) = label(&m, w, h, true, Connectivity::Eight);
    let mut area = vec![0u32; usize::from(count) + 1];
    labels.iter().for_each(|&l| area[usize::from(l)] += 1);
    let mut best = (0u16, 0u32);
    for l in 1..=count {
        if area[usize::from(l)] > best.1 {
            best = (l, area[usize::from(l)]);
        }
    }
    labels.iter().map(|&l| l != 0 && l == best.0).collect()
}

/// The fitted ground of [`fit_ground`]: `d_g(y) = slope·y + offset`, px.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundLineF {
    /// px per row.
    pub slope: f64,
    /// px at row 0.
    pub offset: f64,
    /// Rows that lie on the line.
    pub rows: u32,
}

impl GroundLineF {
    /// `d_g(y)`, px.
    pub fn at(&self, y: usize) -> f64 {
        self.slope * y as f64 + self.offset
    }
}

/// Reference of [`protogist::segment::fit_ground`]: each row's dominant
/// disparity (the mean within a plane of its most common whole-px plane,
/// when a quarter of the row agrees, to 1/256 px), a Hough vote of the rows not within
/// 1/64 px of the row above over slopes 1/32 to
/// 1/2 px per row in steps of 1/128 (intercepts at the bottom row in half
/// px, two bins a window), three least-squares refinements over the rows
/// near the line before (within 1/2 px, then 1/4 px), and the checks (a quarter of the rows, slope ≥ 1/32).
/// Each row's dominant disparity as [`fit_ground`] takes it: the mean
/// within a plane of its most common whole-px plane (the lowest on ties),
/// to 1/256 px, when a quarter of the row agrees; `None` otherwise.
pub fn row_disparities(disparity: &[DispF], width: usize, height: usize) -> Vec<Option<f64>> {
    let plane = |v: f64| (v + 0.5).floor() as i64;
    (0..height)
        .map(|y| {
            let row: Vec<f64> = disparity[y * width..(y + 1) * width]
                .iter()
                .filter_map(|d| d.map(f64::from))
                .collect();
            let mut hist = vec![0usize; 257];
            for &v in &row {
                hist[plane(v).clamp(0, 256) as usize] += 1;
            }
            // Most common plane, the lowest on ties.
            let mode = (0..257).rev().max_by_key(|&i| hist[i])? as i64;
            let near: Vec<f64> = row
                .iter()
                .copied()
                .filter(|&v| (plane(v) - mode).abs() <= 1)
                .collect();
            (!near.is_empty() && near.len() >= width.div_ceil(4).max(1))
                // In the disparity's unit, 1/256 px, as core keeps it.
                .then(|| (near.iter().sum::<f64>() / near.len() as f64 * 256.0).round() / 256.0)
        })
        .collect()
}

pub fn fit_ground(disparity: &[DispF], width: usize, height: usize) -> Option<GroundLineF> {
    let plane = |v: f64| (v + 0.5).floor() as i64;
    let rows = row_disparities(disparity, width, height);
    let bottom = height as f64 - 1.0;
    let mut best: Option<(usize, f64, f64)> = None;
    for step in 0..=60 {
        let slope = (8 + 2 * step) as f64 / 256.0;
        let mut votes = vec![0usize; 514];
        for (y, r) in rows.iter().enumerate() {
            // Rows within 1/64 px of the row above (a wall) do not vote.
            let flat = y > 0
                && match (rows[y - 1], r) {
                    (Some(a), Some(b)) => (a - b).abs() < 4.0 / 256.0,
                    _ => false,
                };
            if let Some(d) = r.filter(|_| !flat) {
                let bin = plane(2.0 * (d + slope * (bottom - y as f64)));
                if (0..514).contains(&bin) {
                    votes[bin as usize] += 1;
                }
            }
        }
        for bin in 0..513 {
            let n = votes[bin] + votes[bin + 1];
            if best.is_none_or(|b| n > b.0) {
                best = Some((n, slope, (bin as f64 + 0.5) / 2.0));
            }
        }
    }
    let (_, slope, b) = best?;
    let mut line = GroundLineF {
        slope,
        offset: b - slope * bottom,
        rows: 0,
    };
    for band in [0.5, 0.25, 0.25] {
        let on: Vec<(f64, f64)> = rows
            .iter()
            .enumerate()
            .filter_map(|(y, r)| r.map(|d| (y as f64, d)))
            .filter(|&(y, d)| (d - line.at(y as usize)).abs() <= band)
            .collect();
        let n = on.len() as f64;
        let (sy, sd) = on.iter().fold((0.0, 0.0), |a, &(y, d)| (a.0 + y, a.1 + d));
        let (syy, syd) = on
            .iter()
            .fold((0.0, 0.0), |a, &(y, d)| (a.0 + y * y, a.1 + y * d));
        let den = n * syy - sy * sy;
        if on.is_empty() || den == 0.0 {
            return None;
        }
        let slope = (n * syd - sy * sd) / den;
        line = GroundLineF {
            slope,
            offset: (sd - slope * sy) / n,
            rows: on.len() as u32,
        };
    }
    (line.rows as usize >= height.div_ceil(4).max(2) && line.slope >= 1.0 / 32.0).then_some(line)
}

/// Reference of [`protogist::segment::inhibit_ground`]: D_fg without the
/// cells at most `band` px nearer than the ground line.
pub fn inhibit_ground(line: &GroundLineF, band: f32, d_fg: &[DispF], width: usize) -> Vec<DispF> {
    d_fg.iter()
        .enumerate()
        .map(|(i, d)| d.filter(|&v| f64::from(v) > line.at(i / width) + f64::from(band)))
        .collect()
}

/// Reference of the depth pass of
/// [`protogist::segment::segment_with_depth_pass`], after the colour
/// searches found `colour` (their masks): the masks of the objects it
/// adds, in order. Its foreground is every ON cell of S at least `rise`
/// px above its row's dominant disparity ([`row_disparities`]), less the
/// colour masks grown by `clearance` square dilations; each search takes
/// the whole-px plane δ with the most foreground cells in planes δ − 1 to
/// δ + 1, δ's own counted twice (the lowest on a tie), the foreground within `radius` px of δ,
/// closes it by `closing` square steps, keeps its largest 4-connected
/// component (the first in raster order on a tie) with holes filled, and
/// takes the slice grown by one square step out of the foreground; with
/// the pass's `refine` and a left image, the mask is refined by colour
/// ([`super::refine::refine_mask`]). A mask is kept when it is an object ([`SegmentParams::is_object`]), of
/// at least the pass's least area, and touches no colour mask.
pub fn depth_pass(
    params: &SegmentParams,
    disparity: &[DispF],
    colour: &[Vec<bool>],
    left: Option<&[Rgb8]>,
    w: usize,
    h: usize,
) -> Vec<Vec<bool>> {
    let Some(pass) = params.depth_pass else {
        return Vec::new();
    };
    let k = usize::from(params.max_objects);
    let rows = row_disparities(disparity, w, h);
    let rise = f64::from(pass.rise) / 256.0;
    let mut fg: Vec<bool> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            in_selected_area(params, w, h, x, y)
                && matches!((disparity[i], rows[y]), (Some(d), Some(r)) if f64::from(d) >= r + rise)
        })
        .collect();
    let mut taken = vec![false; w * h];
    for m in colour {
        taken.iter_mut().zip(m).for_each(|(t, &c)| *t |= c);
    }
    for _ in 0..pass.clearance {
        taken = dilate(Disk::Square, &taken, w, h);
    }
    fg.iter_mut().zip(&taken).for_each(|(f, &t)| *f &= !t);
    let least = pass.least_area(w, h) as usize;
    let plane = |v: f32| (f64::from(v) + 0.5).floor() as i64;
    let mut out = Vec::new();
    for _ in 0..pass.searches {
        if colour.len() + out.len() >= k {
            break;
        }
        let mut counts = vec![0usize; 258];
        for (i, &on) in fg.iter().enumerate() {
            if let (true, Some(d)) = (on, disparity[i]) {
                counts[plane(d).clamp(0, 256) as usize] += 1;
            }
        }
        // Planes δ − 1 to δ + 1, δ's own twice; the first (lowest) best wins.
        let window = |p: usize| {
            let below = if p == 0 { 0 } else { counts[p - 1] };
            below + 2 * counts[p] + counts[p + 1]
        };
        let best = (0..257).fold((0, 0), |b, p| {
            let n = window(p);
            if n > b.1 {
                (p, n)
            } else {
                b
            }
        });
        if best.1 == 0 || best.1 < least {
            break;
        }
        let (delta, r) = (best.0 as f64, f64::from(pass.radius) / 256.0);
        let slice: Vec<bool> = (0..w * h)
            .map(|i| fg[i] && disparity[i].is_some_and(|d| (f64::from(d) - delta).abs() <= r))
            .collect();
        let closed = close(Disk::Square, &slice, w, h, pass.closing);
        let mut mask = largest_filled(&closed, w, h);
        let grown = dilate(Disk::Square, &slice, w, h);
        fg.iter_mut().zip(&grown).for_each(|(f, &g)| *f &= !g);
        if let (Some(r), Some(l)) = (&pass.refine, left) {
            mask = super::refine::refine_mask(r, &mask, l, w, h);
        }
        let a = mask.iter().filter(|&&m| m).count();
        let (xs, ys): (Vec<usize>, Vec<usize>) = (0..w * h)
            .filter(|&i| mask[i])
            .map(|i| (i % w, i / w))
            .unzip();
        let box_size = match (
            xs.iter().min(),
            xs.iter().max(),
            ys.iter().min(),
            ys.iter().max(),
        ) {
            (Some(x0), Some(x1), Some(y0), Some(y1)) => (x1 + 1 - x0, y1 + 1 - y0),
            _ => (0, 0),
        };
        let clash = colour
            .iter()
            .any(|c| c.iter().zip(&mask).any(|(&a, &b)| a && b));
        if params.is_object(a as u32, box_size, (w, h)) && a >= least && !clash {
            out.push(mask);
        }
    }
    out
}

/// The largest 4-connected component of `map` (the first label, in raster
/// order, on a tie), holes filled; all OFF for an empty map.
pub fn largest_filled(map: &[bool], w: usize, h: usize) -> Vec<bool> {
    let (labels, n) = label(map, w, h, true, Connectivity::Four);
    let mut area = vec![0usize; usize::from(n) + 1];
    labels.iter().for_each(|&l| area[usize::from(l)] += 1);
    area[0] = 0;
    let top = (1..=n).fold(0u16, |b, l| {
        if area[usize::from(l)] > area[usize::from(b)] {
            l
        } else {
            b
        }
    });
    let comp: Vec<bool> = labels.iter().map(|&l| top != 0 && l == top).collect();
    fill_holes(&comp, w, h)
}
