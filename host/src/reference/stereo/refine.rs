//! Colour-guided border refinement and fill (dem-spec §6, our reading).
//!
//! Energy models are weak at depth borders: pooled responses spread the
//! nearer surface's disparity across the border, and the left-right check
//! turns occlusions OFF. Within `refine_radius` px of a colour edge (the
//! conspicuity map C), and at every OFF pixel, the estimate is replaced by
//! the median disparity of the `refine_k` trusted pixels (ON and away from
//! edges) of the `(2·refine_window + 1)²` window whose CIELUV colour is
//! nearest to the pixel's own: a border pixel takes the disparity of the
//! side it looks like. A pixel with fewer than `refine_k` trusted
//! candidates keeps its estimate (or stays OFF).

use super::{DemParams, DisparityMapsF};
use crate::reference::conspicuity::{self as cons, dist2, LuvF};
use protogist::conspicuity::EdgeParams;
use protogist::disparity::{Disparity, DisparityCell};
use protogist::image::{ImageView, Rgb8};

/// What [`refine_borders`] changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RefineReport {
    /// Pixels near an edge whose estimate was replaced.
    pub borders: usize,
    /// OFF pixels that received an estimate.
    pub filled: usize,
}

/// Refines `maps` in place against the colours and edges of `left`.
pub fn refine_borders(
    params: &DemParams,
    left: &ImageView<'_, Rgb8>,
    maps: &mut DisparityMapsF,
) -> RefineReport {
    let mut report = RefineReport::default();
    let (w, h) = (maps.width, maps.height);
    let (r, k) = (
        isize::from(params.refine_radius),
        usize::from(params.refine_k),
    );
    if r == 0 || k == 0 || left.size() != (w, h) {
        return report;
    }
    let Ok(edges) = cons::edge_conspicuity(&EdgeParams::default(), left) else {
        return report;
    };
    let luv: &[LuvF] = &edges.luv;
    let near_edge = dilate(&edges.conspicuity, w, h, r);
    let d = maps.disparity_f32.clone();
    let trusted = |i: usize| !near_edge[i] && d[i].is_some();
    let win = isize::from(params.refine_window);
    let mut cands: Vec<(f32, f32)> = Vec::new();
    for y in 0..h as isize {
        for x in 0..w as isize {
            let p = y as usize * w + x as usize;
            if !near_edge[p] && d[p].is_some() {
                continue;
            }
            cands.clear();
            for yy in (y - win).max(0)..=(y + win).min(h as isize - 1) {
                for xx in (x - win).max(0)..=(x + win).min(w as isize - 1) {
                    let q = yy as usize * w + xx as usize;
                    if let (true, Some(v)) = (trusted(q), d[q]) {
                        cands.push((dist2(luv[p], luv[q]), v));
                    }
                }
            }
            if cands.len() < k {
                continue;
            }
            cands.select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0));
            let mut nearest: Vec<f32> = cands[..k].iter().map(|c| c.1).collect();
            nearest.sort_by(f32::total_cmp);
            let v = nearest[k / 2];
            if d[p].is_some() {
                report.borders += 1;
            } else {
                report.filled += 1;
            }
            maps.disparity_f32[p] = Some(v);
            maps.disparity[p] = DisparityCell::on(
                Disparity::saturating_from_num(v).min(Disparity::from_bits(u16::MAX - 1)),
            )
            .unwrap_or(DisparityCell::OFF);
        }
    }
    report
}

/// Cells within Chebyshev distance `r` of an ON cell.
fn dilate(map: &[Option<f32>], w: usize, h: usize, r: isize) -> Vec<bool> {
    let mut out = vec![false; w * h];
    for (i, c) in map.iter().enumerate() {
        if c.is_none() {
            continue;
        }
        let (x, y) = ((i % w) as isize, (i / w) as isize);
        for yy in (y - r).max(0)..=(y + r).min(h as isize - 1) {
            for xx in (x - r).max(0)..=(x + r).min(w as isize - 1) {
                out[yy as usize * w + xx as usize] = true;
            }
        }
    }
    out
}
