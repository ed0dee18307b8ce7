//! Reference of `protogist::complete` (disparity completion over
//! conspicuity regions), written independently of it: breadth-first region
//! labelling and sorted medians instead of two-pass labelling and bisection.
//! Its inputs are the core's integer maps, so the two agree bit for bit.

use protogist::complete::{CompleteParams, CompleteReport};
use protogist::conspicuity::{EdgeCell, Luv};
use protogist::disparity::{from_pixels, DisparityCell};

/// [`protogist::complete::complete_runs`] on packed maps; returns the completed
/// disparity and the report (regions skipped is always 0: no capacity).
pub fn complete(
    params: &CompleteParams,
    edges: &[EdgeCell],
    colour: &[Luv],
    disparity: &[DisparityCell],
    width: usize,
    height: usize,
) -> (Vec<DisparityCell>, CompleteReport) {
    let (w, h) = (width, height);
    let edge: Vec<bool> = edges.iter().map(|c| c.is_on()).collect();
    // Regions: 4-connected non-edge components, labelled 1.. in raster
    // order of first cell.
    let mut label = vec![0u32; w * h];
    let mut regions = 0u32;
    let mut queue = std::collections::VecDeque::new();
    for s in 0..w * h {
        if edge[s] || label[s] != 0 {
            continue;
        }
        regions += 1;
        label[s] = regions;
        queue.push_back(s);
        while let Some(p) = queue.pop_front() {
            let (x, y) = (p % w, p / w);
            let mut nbs = Vec::with_capacity(4);
            if x > 0 {
                nbs.push(p - 1);
            }
            if x + 1 < w {
                nbs.push(p + 1);
            }
            if y > 0 {
                nbs.push(p - w);
            }
            if y + 1 < h {
                nbs.push(p + w);
            }
            for q in nbs {
                if !edge[q] && label[q] == 0 {
                    label[q] = regions;
                    queue.push_back(q);
                }
            }
        }
    }
    let g = usize::from(params.guard);
    let near = |x: usize, y: usize| {
        (y.saturating_sub(g)..=(y + g).min(h - 1))
            .any(|yy| (x.saturating_sub(g)..=(x + g).min(w - 1)).any(|xx| edge[yy * w + xx]))
    };
    let whole = |c: DisparityCell| {
        c.get()
            .map(|d| ((u32::from(d.to_bits()) + 128) >> 8).min(255) as u8)
    };
    let mut values: Vec<Vec<u8>> = vec![Vec::new(); regions as usize + 1];
    // The trusted cells' (row, bits), per region, for the tilt.
    let mut cells: Vec<Vec<(i128, i128)>> = vec![Vec::new(); regions as usize + 1];
    for p in 0..w * h {
        if let Some(v) = whole(disparity[p]) {
            if label[p] != 0 && !near(p % w, p / w) {
                values[label[p] as usize].push(v);
                if let Some(d) = disparity[p].get() {
                    cells[label[p] as usize].push(((p / w) as i128, i128::from(d.to_bits())));
                }
            }
        }
    }
    let median: Vec<Option<u8>> = values
        .iter_mut()
        .map(|v| {
            v.sort_unstable();
            if v.len() < params.min_trusted.max(1) as usize {
                return None;
            }
            v.get(v.len().saturating_sub(1) / 2).copied()
        })
        .collect();
    // Tall regions (trusted rows at least `tilt_rows` apart), the first
    // MAX_TILTED with a median in label order; each fitted to its trusted
    // cells within `tilt_band` bits of its median in every TILT_ROW_STEP-th
    // row, when they span two such rows or more: the least-squares slope and the mean row, Q16, floor
    // divisions.
    let mut tilt: Vec<Option<(i128, i128)>> = vec![None; regions as usize + 1];
    let mut tall = 0;
    let mut tilted = 0;
    for l in 1..=regions as usize {
        if params.tilt_rows == 0 || tall >= protogist::complete::MAX_TILTED {
            break;
        }
        let c = &cells[l];
        let Some(m) = median[l] else { continue };
        if c.is_empty() {
            continue;
        }
        let rows = c.iter().map(|&(y, _)| y);
        let span = rows.clone().max().unwrap_or(0) - rows.min().unwrap_or(0);
        if span < i128::from(params.tilt_rows) {
            continue;
        }
        tall += 1;
        let m = i128::from(m) << 8;
        let c: Vec<(i128, i128)> = c
            .iter()
            .copied()
            .filter(|&(y, b)| {
                y % protogist::complete::TILT_ROW_STEP as i128 == 0
                    && (b - m).abs() <= i128::from(params.tilt_band)
            })
            .collect();
        let rows = c.iter().map(|&(y, _)| y);
        if rows.clone().max().unwrap_or(0) - rows.min().unwrap_or(0) < 1 {
            continue;
        }
        let n = c.len() as i128;
        let sy: i128 = c.iter().map(|&(y, _)| y).sum();
        let syy: i128 = c.iter().map(|&(y, _)| y * y).sum();
        let sb: i128 = c.iter().map(|&(_, b)| b).sum();
        let syb: i128 = c.iter().map(|&(y, b)| y * b).sum();
        let den = n * syy - sy * sy;
        if den <= 0 {
            continue;
        }
        tilt[l] = Some((
            ((n * syb - sy * sb) << 16).div_euclid(den),
            (sy << 16).div_euclid(n),
        ));
        tilted += 1;
    }
    let value = |l: usize, y: usize, m: u8| -> u8 {
        match tilt[l] {
            Some((slope, ybar)) => {
                let b = (i128::from(m) << 8) + ((slope * (((y as i128) << 16) - ybar)) >> 32);
                ((b + 128) >> 8).clamp(0, 255) as u8
            }
            None => m,
        }
    };
    let dist2 = |a: Luv, b: Luv| -> u64 {
        a.to_bits()
            .iter()
            .zip(b.to_bits())
            .map(|(&p, q)| (i64::from(p) - i64::from(q)).pow(2) as u64)
            .sum()
    };
    let mut out = disparity.to_vec();
    let mut report = CompleteReport {
        regions: regions as u16,
        regions_with_median: median.iter().skip(1).filter(|m| m.is_some()).count() as u16,
        tilted: tilted as u16,
        ..CompleteReport::default()
    };
    for y in 0..h {
        for x in 0..w {
            let p = y * w + x;
            if disparity[p].is_on() && !near(x, y) {
                continue;
            }
            let l = if edge[p] {
                // The closest-coloured non-edge neighbour, radius 1 then 2.
                let mut pick = 0;
                for r in 1..=2 {
                    let mut best: Option<u64> = None;
                    for yy in y.saturating_sub(r)..=(y + r).min(h - 1) {
                        for xx in x.saturating_sub(r)..=(x + r).min(w - 1) {
                            let q = yy * w + xx;
                            if edge[q] {
                                continue;
                            }
                            let d = dist2(colour[p], colour[q]);
                            if best.is_none_or(|b| d < b) {
                                best = Some(d);
                                pick = label[q];
                            }
                        }
                    }
                    if best.is_some() {
                        break;
                    }
                }
                pick
            } else {
                label[p]
            };
            let Some(v) = median[l as usize] else {
                continue;
            };
            if l == 0 {
                continue;
            }
            if disparity[p].is_on() {
                report.replaced += 1;
            } else {
                report.filled += 1;
            }
            out[p] = from_pixels(value(l as usize, y, v));
        }
    }
    (out, report)
}
