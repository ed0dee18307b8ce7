//! Reference of the hole by disparity ([`protogist::segment::DepthHole`],
//! `protogist::segment::open_depth_hole`) on `bool` maps: the mask's cells
//! behind the object's slice, opened by repeated square steps, and the
//! 8-connected component of them that holds the centre of the object's
//! box, found by a flood fill.
//!
//! Core decides in integers on the same disparity bits, so the two agree
//! mask for mask (error bound: none, docs/ERROR_BOUNDS.md).

use super::refine::steps;
use super::segment::{dilate, erode};
use protogist::disparity::DisparityCell;
use protogist::segment::{DepthHole, DisparityRange, STAT_FRAC_BITS};

/// Takes the hole by disparity out of `mask` (`w x h`, row-major), the
/// mask of an object of slice `range` whose box is `(x, y, width,
/// height)`, against `disparity` (the same size). Returns whether the
/// mask changed.
pub fn depth_hole(
    p: &DepthHole,
    mask: &mut [bool],
    disparity: &[DisparityCell],
    range: DisparityRange,
    (bx, by, bw, bh): (usize, usize, usize, usize),
    w: usize,
    h: usize,
) -> bool {
    let low = (range.low >> (STAT_FRAC_BITS - 8)) - i64::from(p.margin);
    let behind: Vec<bool> = mask
        .iter()
        .zip(disparity)
        .map(|(&m, d)| m && d.get().is_some_and(|d| i64::from(d.to_bits()) < low))
        .collect();
    let opened = steps(
        dilate,
        &steps(erode, &behind, p.opening, w, h),
        p.opening,
        w,
        h,
    );
    let (cx, cy) = (bx + bw / 2, by + bh / 2);
    if cx >= w || cy >= h || !opened[cy * w + cx] {
        return false;
    }
    let mut hole = vec![false; w * h];
    let mut todo = vec![(cx, cy)];
    hole[cy * w + cx] = true;
    while let Some((x, y)) = todo.pop() {
        for dy in -1isize..=1 {
            for dx in -1isize..=1 {
                let (Some(nx), Some(ny)) = (x.checked_add_signed(dx), y.checked_add_signed(dy))
                else {
                    continue;
                };
                if nx < w && ny < h && opened[ny * w + nx] && !hole[ny * w + nx] {
                    hole[ny * w + nx] = true;
                    todo.push((nx, ny));
                }
            }
        }
    }
    for (m, &o) in mask.iter_mut().zip(&hole) {
        *m &= !o;
    }
    true
}
