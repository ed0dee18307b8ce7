//! The read-out (spec §5, §6): Poisson log-likelihood scores, box pooling,
//! argmax with parabola sub-pixel refinement, and the OFF tests.
//!
//! Per pixel and disparity the score is
//! `Σ_j R_j ℓ_j(d) / Σ_j R_j − ΣW(d)/mean ΣW`, the spec's
//! `k·Σ R ℓ − ΣW(d)` divided by the constant `mean_d ΣW(d)`, so that it
//! does not depend on the scale of the energies. Both sums are linear in
//! the responses, so pooling them over a box equals pooling the responses.
//!
//! A binocular cell with left receptive field at `x` and right at `x − s`
//! votes for the left-referenced pixel `x` and for the right-referenced
//! pixel `x − s`: the right-referenced map costs no extra cells.

use super::filters::Response;
use super::population::{energies, groups};
use super::train::Decoder;
use super::DemParams;

/// Raw score sums of one reference eye: `Σ R ℓ(d)` per pixel and `d`
/// (pixel-major) and `Σ R` per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Scores {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// Disparities, `max_disp + 1`.
    pub disparities: usize,
    /// `Σ_j R_j ℓ_j(d)`, `[pixel][d]`.
    pub raw: Vec<f32>,
    /// `Σ_j R_j`, per pixel.
    pub total: Vec<f32>,
}

impl Scores {
    fn new(width: usize, height: usize, disparities: usize) -> Self {
        Self {
            width,
            height,
            disparities,
            raw: vec![0.0; width * height * disparities],
            total: vec![0.0; width * height],
        }
    }
}

/// The left- and right-referenced score sums of the whole population.
pub fn scores(
    params: &DemParams,
    decoder: &Decoder,
    left: &[Vec<Response>],
    right: &[Vec<Response>],
    width: usize,
    height: usize,
) -> (Scores, Scores) {
    let n = decoder.disparities();
    let (mut sl, mut sr) = (Scores::new(width, height, n), Scores::new(width, height, n));
    let mut vote = vec![0.0f32; n];
    for (gi, g) in groups(params).iter().enumerate() {
        let e = energies(left, right, g, width, height);
        let w = decoder.group(gi);
        for y in 0..height {
            for x in g.shift..width {
                let [a, xr, xi] = e[y * width + x];
                for (v, abc) in vote.iter_mut().zip(w) {
                    *v = a * abc[0] + xr * abc[1] + xi * abc[2];
                }
                let (pl, pr) = (y * width + x, y * width + x - g.shift);
                sl.total[pl] += 4.0 * a;
                sr.total[pr] += 4.0 * a;
                for (dst, v) in sl.raw[pl * n..(pl + 1) * n].iter_mut().zip(&vote) {
                    *dst += v;
                }
                for (dst, v) in sr.raw[pr * n..(pr + 1) * n].iter_mut().zip(&vote) {
                    *dst += v;
                }
            }
        }
    }
    (sl, sr)
}

/// Scores for the coarse-to-fine experiment ([`super::c2f`]): each
/// group's energies are box pooled (radius `r`, cells at `x < shift`
/// contributing nothing, as in [`scores`]), and a pixel with a window
/// `lo..=hi` is decoded only from the groups whose shift lies within
/// `band` px of the window's centre `(lo + hi) / 2` (a pixel without a
/// window: every group), as an engine that computes only those groups
/// would. The scores come out already pooled; also returned, per pixel of
/// each map, the number of groups that voted (for the texture test). Up to
/// the clipping of the box at the right border, `band` ≥ `max_disp` gives
/// [`scores`] followed by [`pool`].
#[allow(clippy::too_many_arguments)]
pub fn scores_banded(
    params: &DemParams,
    decoder: &Decoder,
    left: &[Vec<Response>],
    right: &[Vec<Response>],
    width: usize,
    height: usize,
    windows: &super::Windows,
    band: usize,
) -> (Scores, Scores, [Vec<f32>; 2]) {
    let n = decoder.disparities();
    let (mut sl, mut sr) = (Scores::new(width, height, n), Scores::new(width, height, n));
    let mut voters = [vec![0.0f32; width * height], vec![0.0f32; width * height]];
    let mut vote = vec![0.0f32; n];
    let r = usize::from(params.pool_radius);
    let near = |win: &[Option<(usize, usize)>], p: usize, shift: usize| {
        win.get(p)
            .copied()
            .flatten()
            .is_none_or(|(lo, hi)| (shift as f32 - 0.5 * (lo + hi) as f32).abs() <= band as f32)
    };
    for (gi, g) in groups(params).iter().enumerate() {
        let e = energies(left, right, g, width, height);
        let mut flat: Vec<f32> = Vec::with_capacity(3 * width * height);
        for (i, v) in e.iter().enumerate() {
            let keep = i % width >= g.shift;
            flat.extend(v.iter().map(|&c| if keep { c } else { 0.0 }));
        }
        box_sum(&mut flat, width, height, 3, r);
        let w = decoder.group(gi);
        for y in 0..height {
            // Pooled energies reach left pixels x < shift too (from their
            // box neighbours), right pixels only through x ≥ shift.
            for x in 0..width {
                let pl = y * width + x;
                let pr = pl.saturating_sub(g.shift);
                let (a, xr, xi) = (flat[3 * pl], flat[3 * pl + 1], flat[3 * pl + 2]);
                let (in_l, in_r) = (
                    near(&windows.left, pl, g.shift),
                    x >= g.shift && near(&windows.right, pr, g.shift),
                );
                if !(in_l || in_r) {
                    continue;
                }
                for (v, abc) in vote.iter_mut().zip(w) {
                    *v = a * abc[0] + xr * abc[1] + xi * abc[2];
                }
                for (on, s, p, k) in [(in_l, &mut sl, pl, 0), (in_r, &mut sr, pr, 1)] {
                    if on {
                        s.total[p] += 4.0 * a;
                        voters[k][p] += 1.0;
                        for (dst, v) in s.raw[p * n..(p + 1) * n].iter_mut().zip(&vote) {
                            *dst += v;
                        }
                    }
                }
            }
        }
    }
    (sl, sr, voters)
}

/// Box sums over `(2r + 1)²` windows clipped to the image, of `k`
/// interleaved channels per pixel, in place (separable running sums).
pub fn box_sum(data: &mut [f32], width: usize, height: usize, k: usize, r: usize) {
    if r == 0 || width == 0 || height == 0 {
        return;
    }
    let mut line = vec![0.0f32; width.max(height) * k];
    // Rows.
    for y in 0..height {
        let row = &mut data[y * width * k..(y + 1) * width * k];
        line[..width * k].copy_from_slice(row);
        for x in 0..width {
            let (lo, hi) = (x.saturating_sub(r), (x + r).min(width - 1));
            for c in 0..k {
                row[x * k + c] = (lo..=hi).map(|i| line[i * k + c]).sum();
            }
        }
    }
    // Columns.
    for x in 0..width {
        for y in 0..height {
            let src = (y * width + x) * k;
            line[y * k..(y + 1) * k].copy_from_slice(&data[src..src + k]);
        }
        for y in 0..height {
            let (lo, hi) = (y.saturating_sub(r), (y + r).min(height - 1));
            for c in 0..k {
                data[(y * width + x) * k + c] = (lo..=hi).map(|i| line[i * k + c]).sum();
            }
        }
    }
}

/// Pools `scores` over `(2r + 1)²` boxes; also returns, per pixel, the
/// number of pixels in its (clipped) box.
pub fn pool(scores: &mut Scores, r: usize) -> Vec<f32> {
    let (w, h, n) = (scores.width, scores.height, scores.disparities);
    box_sum(&mut scores.raw, w, h, n, r);
    box_sum(&mut scores.total, w, h, 1, r);
    let mut count = vec![1.0f32; w * h];
    box_sum(&mut count, w, h, 1, r);
    count
}

/// The decision at one pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pick {
    /// Sub-pixel disparity of the best score.
    pub disparity: f32,
    /// Best score minus the best score more than 1 px away (∞ if none).
    pub margin: f32,
}

/// Argmax over the candidates `0..=max_d` of the normalised scores of one
/// pixel, with the parabola through `d̂ ± 1`; `None` when `total` is 0.
pub fn pick(raw: &[f32], total: f32, bias: &[f32], max_d: usize) -> Option<Pick> {
    if total <= 0.0 || raw.is_empty() {
        return None;
    }
    Some(pick_by(raw.len(), max_d, |d| raw[d] / total - bias[d]))
}

/// Argmax of the scores `s(d)` over `0..=min(max_d, n − 1)` (`n >= 1`), with
/// the parabola through `d̂ ± 1` and the margin to the best score more than
/// 1 px away.
pub fn pick_by(n: usize, max_d: usize, s: impl Fn(usize) -> f32) -> Pick {
    pick_in(0, max_d.min(n.saturating_sub(1)), s)
}

/// Argmax of the scores `s(d)` over the window `lo..=top` (`lo <= top`),
/// with the parabola through `d̂ ± 1` when both are in the window and the
/// margin to the best score more than 1 px away within it.
pub fn pick_in(lo: usize, top: usize, s: impl Fn(usize) -> f32) -> Pick {
    let best = (lo..=top).fold(lo, |b, d| if s(d) > s(b) { d } else { b });
    let second = (lo..=top)
        .filter(|&d| d.abs_diff(best) > 1)
        .map(&s)
        .fold(f32::NEG_INFINITY, f32::max);
    let mut disparity = best as f32;
    if best > lo && best < top {
        let (m, c, p) = (s(best - 1), s(best), s(best + 1));
        let denom = m - 2.0 * c + p;
        if denom < 0.0 {
            disparity += (0.5 * (m - p) / denom).clamp(-0.5, 0.5);
        }
    }
    Pick {
        disparity,
        margin: s(best) - second,
    }
}
