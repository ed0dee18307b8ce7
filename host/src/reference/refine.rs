//! References of the depth pass's colour refinement
//! ([`protogist::segment::Refine`]) and of the holes by colour
//! ([`protogist::segment::Holes`]), on `bool` maps: masks, bands and rings
//! by repeated square steps, mean colours, and each cell given to the
//! nearer mean.
//!
//! Core compares the distances exactly in integers (the holes' to means
//! kept to 1/16 of a level); so do these (`i128`), so the two agree mask
//! for mask (error bound: none, docs/ERROR_BOUNDS.md
//! 8b).

use super::segment::{dilate, erode, label, largest_filled};
use protogist::image::Rgb8;
use protogist::segment::{Connectivity, Disk, Holes, Refine};

/// `n` steps of `step` on `map`.
pub(super) fn steps(
    step: fn(Disk, &[bool], usize, usize) -> Vec<bool>,
    map: &[bool],
    n: u8,
    w: usize,
    h: usize,
) -> Vec<bool> {
    (0..n).fold(map.to_vec(), |m, _| step(Disk::Square, &m, w, h))
}

/// Cells and channel sums of `left` over `on`.
fn sum(left: &[Rgb8], on: &[bool]) -> (i128, [i128; 3]) {
    left.iter()
        .zip(on)
        .filter(|(_, &o)| o)
        .fold((0, [0; 3]), |(n, s), (p, _)| {
            (
                n + 1,
                [
                    s[0] + i128::from(p.r),
                    s[1] + i128::from(p.g),
                    s[2] + i128::from(p.b),
                ],
            )
        })
}

/// `Σ (n·c − S)²` over the channels: `n²` times the squared distance of
/// `p` to the mean.
pub(super) fn scaled(p: Rgb8, (n, s): (i128, [i128; 3])) -> i128 {
    [p.r, p.g, p.b]
        .iter()
        .zip(s)
        .map(|(&c, s)| (n * i128::from(c) - s).pow(2))
        .sum()
}

/// Reference of the refinement of `mask` against the left image `left`
/// (module docs of `protogist::segment::refine`).
pub fn refine_mask(refine: &Refine, mask: &[bool], left: &[Rgb8], w: usize, h: usize) -> Vec<bool> {
    let core = steps(erode, mask, refine.core, w, h);
    let reach = steps(dilate, mask, refine.reach, w, h);
    let outer = steps(dilate, &reach, refine.ring, w, h);
    let ring: Vec<bool> = outer.iter().zip(&reach).map(|(&o, &r)| o && !r).collect();
    let (object, behind) = (sum(left, &core), sum(left, &ring));
    if object.0 == 0 || behind.0 == 0 {
        return mask.to_vec();
    }
    let joined: Vec<bool> = (0..w * h)
        .map(|i| {
            if core[i] || !reach[i] {
                return core[i];
            }
            let to_object = scaled(left[i], object) * behind.0 * behind.0;
            let to_behind = scaled(left[i], behind) * object.0 * object.0;
            to_object < to_behind || (to_object == to_behind && mask[i])
        })
        .collect();
    largest_filled(&joined, w, h)
}

/// Reference of the holes by colour of `mask` against the left image
/// `left` (module docs of `protogist::segment::holes`): `mask` less its
/// holes.
pub fn open_holes(holes: &Holes, mask: &[bool], left: &[Rgb8], w: usize, h: usize) -> Vec<bool> {
    let inside = steps(erode, mask, holes.band, w, h);
    let band: Vec<bool> = mask.iter().zip(&inside).map(|(&m, &i)| m && !i).collect();
    let near = steps(dilate, mask, holes.gap, w, h);
    let outer = steps(dilate, &near, holes.ring, w, h);
    let ring: Vec<bool> = outer.iter().zip(&near).map(|(&o, &n)| o && !n).collect();
    let (object, around) = (sum(left, &band), sum(left, &ring));
    if !inside.contains(&true) || object.0 == 0 || around.0 == 0 {
        return mask.to_vec();
    }
    // Means to 1/16 of a level, rounded half up; distances in sixteenths.
    let mean = |(n, s): (i128, [i128; 3])| s.map(|s| (16 * s + n / 2).div_euclid(n));
    let (object, around) = (mean(object), mean(around));
    let dist = |p: Rgb8, m: [i128; 3]| -> i128 {
        [p.r, p.g, p.b]
            .iter()
            .zip(m)
            .map(|(&c, m)| (16 * i128::from(c) - m).pow(2))
            .sum()
    };
    let candidates: Vec<bool> = (0..w * h)
        .map(|i| inside[i] && 2 * dist(left[i], around) < dist(left[i], object))
        .collect();
    let opened = steps(erode, &candidates, holes.opening, w, h);
    let opened = steps(dilate, &opened, holes.opening, w, h);
    let opened: Vec<bool> = opened.iter().zip(&inside).map(|(&o, &i)| o && i).collect();
    let (labels, n) = label(&opened, w, h, true, Connectivity::Four);
    let mut area = vec![0u64; usize::from(n) + 1];
    labels.iter().for_each(|&l| area[usize::from(l)] += 1);
    let before = mask.iter().filter(|&&m| m).count() as u64;
    let (num, den) = (u64::from(holes.min_area.num), u64::from(holes.min_area.den));
    mask.iter()
        .zip(&labels)
        .map(|(&m, &l)| m && !(l != 0 && area[usize::from(l)] * den >= before * num))
        .collect()
}
