//! Semi-global aggregation of the read-out's scores (core's engine runs
//! it, `protogist::stereo::sgm`; docs/STEREO.md).
//!
//! The cost of candidate `d` at a pixel is its normalised log-likelihood
//! below the pixel's best one,
//! `C(d) = (max_e s(e) − s(d)) / mean_e (max s − s(e))`,
//! with `s` the read-out's score (`readout::pick`): 0 at the best candidate
//! and 1 on average, so every textured pixel brings the same amount of
//! evidence whatever its contrast, and `P1`, `P2` are in units of that mean
//! gap. Pixels without evidence (no energy, or below `min_energy`) cost 0
//! everywhere and take their disparity from the paths. Candidates beyond
//! the pixel's search window (the image border) cost the pixel's worst valid
//! cost.
//!
//! Along each path direction `r` the standard recurrence
//! `L(p, d) = C(p, d) + min(L(p−r, d), L(p−r, d±1) + P1, min L(p−r) + P2)
//! − min L(p−r)` is run, and the paths are summed.

use super::readout::Scores;

/// How the read-out aggregates the scores over space.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Aggregation {
    /// Box pooling only (`pool_radius`): the model's default.
    #[default]
    Box,
    /// Box pooling (`pool_radius`, 0 for none), then semi-global
    /// aggregation of the normalised costs along `paths` directions.
    Sgm {
        /// Penalty for a 1 px disparity step between neighbours.
        p1: f32,
        /// Penalty for a larger step (`>= p1`).
        p2: f32,
        /// Path set, see [`directions`]: 3 or 5.
        paths: u8,
    },
}

/// The path directions `(dx, dy)` (each path comes from `p − r`):
/// - 3: left→right, right→left, top→bottom;
/// - 5: the 3 plus the two diagonals from above, every path a row-streaming
///   reader can run in one top-to-bottom pass.
///
/// `None` for any other count.
pub fn directions(paths: u8) -> Option<&'static [(isize, isize)]> {
    const ALL: [(isize, isize); 5] = [(1, 0), (-1, 0), (0, 1), (1, 1), (-1, 1)];
    match paths {
        3 => Some(&ALL[..3]),
        5 => Some(&ALL[..5]),
        _ => None,
    }
}

/// One step of the recurrence: `out(d) = c(d) + min(prev(d), prev(d ± 1) +
/// p1, min prev + p2) − min prev`.
pub fn step(c: &[f32], prev: &[f32], p1: f32, p2: f32, out: &mut [f32]) {
    let lo = prev.iter().copied().fold(f32::INFINITY, f32::min);
    let n = prev.len();
    for (d, (o, &cd)) in out.iter_mut().zip(c).enumerate() {
        let mut m = prev[d].min(lo + p2);
        if d > 0 {
            m = m.min(prev[d - 1] + p1);
        }
        if d + 1 < n {
            m = m.min(prev[d + 1] + p1);
        }
        *o = cd + m - lo;
    }
}

/// `L_r` of one path direction `(dx, dy)` over a `[pixel][d]` cost volume
/// of `width x height` pixels and `n` candidates.
pub fn aggregate_path(
    cost: &[f32],
    width: usize,
    height: usize,
    n: usize,
    dir: (isize, isize),
    p1: f32,
    p2: f32,
) -> Vec<f32> {
    let mut l = vec![0.0f32; cost.len()];
    let order = |len: usize, forward: bool| -> Vec<usize> {
        if forward {
            (0..len).collect()
        } else {
            (0..len).rev().collect()
        }
    };
    let (dx, dy) = dir;
    for y in order(height, dy >= 0) {
        for x in order(width, dx >= 0) {
            let p = y * width + x;
            let (px, py) = (x as isize - dx, y as isize - dy);
            let c = &cost[p * n..(p + 1) * n];
            if px < 0 || py < 0 || px >= width as isize || py >= height as isize {
                l[p * n..(p + 1) * n].copy_from_slice(c);
                continue;
            }
            let q = py as usize * width + px as usize;
            // `q` was visited before `p` in this order, and q != p.
            let (head, tail) = l.split_at_mut(p.max(q) * n);
            let (prev, out) = if q < p {
                (&head[q * n..(q + 1) * n], &mut tail[..n])
            } else {
                (&tail[..n], &mut head[p * n..(p + 1) * n])
            };
            step(c, prev, p1, p2, out);
        }
    }
    l
}

/// The sum over the paths of `paths` (see [`directions`]; an unknown count
/// gives the costs themselves).
pub fn aggregate(
    cost: &[f32],
    width: usize,
    height: usize,
    n: usize,
    paths: u8,
    p1: f32,
    p2: f32,
) -> Vec<f32> {
    let Some(dirs) = directions(paths) else {
        return cost.to_vec();
    };
    let mut sum = vec![0.0f32; cost.len()];
    for &dir in dirs {
        for (s, v) in sum
            .iter_mut()
            .zip(aggregate_path(cost, width, height, n, dir, p1, p2))
        {
            *s += v;
        }
    }
    sum
}

/// Cost of a candidate outside a pixel's search window: large enough that
/// no path goes through it (every step then takes the `P2` branch), small
/// enough that sums over 8 paths stay exact in f32 steps of the costs.
pub const EXCLUDED: f32 = 1.0e6;

/// The normalised cost volume of `scores` (module docs): `evidence(p)`
/// says whether pixel `p` has any, and `top(p)` is its last valid
/// candidate.
pub fn costs(
    scores: &Scores,
    bias: &[f32],
    evidence: impl Fn(usize) -> bool,
    top: impl Fn(usize) -> usize,
) -> Vec<f32> {
    costs_in(scores, bias, evidence, top, |_| None)
}

/// [`costs`] with a search window per pixel: `window(p) = Some((lo, hi))`
/// restricts the candidates to `lo..=hi`, as an engine that stores only
/// the window would (`protogist::stereo::c2f`): candidates outside it cost
/// [`EXCLUDED`]; the valid ones, `lo..=min(hi, top(p))`, are normalised
/// over themselves; the window's candidates beyond `top(p)` cost the worst
/// valid one. A windowed pixel without evidence, or whose window lies
/// wholly beyond `top(p)`, costs 0 in its window.
pub fn costs_in(
    scores: &Scores,
    bias: &[f32],
    evidence: impl Fn(usize) -> bool,
    top: impl Fn(usize) -> usize,
    window: impl Fn(usize) -> Option<(usize, usize)>,
) -> Vec<f32> {
    let n = scores.disparities;
    let mut cost = vec![0.0f32; scores.raw.len()];
    for (p, (c, raw)) in cost
        .chunks_exact_mut(n)
        .zip(scores.raw.chunks_exact(n))
        .enumerate()
    {
        let t = top(p).min(n - 1);
        // The window, and its last valid candidate.
        let (lo, hi) = window(p).map_or((0, n - 1), |(lo, hi)| (lo.min(n - 1), hi.min(n - 1)));
        c[..lo].fill(EXCLUDED);
        c[hi + 1..].fill(EXCLUDED);
        let total = scores.total[p];
        if total <= 0.0 || !evidence(p) || lo > t {
            continue;
        }
        let last = hi.min(t);
        for ((c, &r), &b) in c[lo..=last].iter_mut().zip(&raw[lo..]).zip(&bias[lo..]) {
            *c = -(r / total - b);
        }
        let valid = &mut c[lo..=last];
        let min = valid.iter().copied().fold(f32::INFINITY, f32::min);
        let mean = valid.iter().map(|v| v - min).sum::<f32>() / valid.len() as f32;
        let scale = if mean > 0.0 { 1.0 / mean } else { 0.0 };
        let mut worst = 0.0f32;
        for v in valid.iter_mut() {
            *v = (*v - min) * scale;
            worst = worst.max(*v);
        }
        c[last + 1..=hi].fill(worst);
    }
    cost
}
