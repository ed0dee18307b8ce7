//! Touching objects of one slice
//! ([`SegmentParams::split_interiors`](super::SegmentParams::split_interiors)).
//!
//! Objects at about one disparity that touch fall into one slice, and the
//! closing joins their contours into one component, so the paper's mask
//! holds them all. Each contour still encloses its own object: the mask's
//! *interiors* (its pixels off the closed contours, 4-connected) that are
//! *solid* are the objects, each given back its contour.

use super::bits::{self, Components};
use super::buffers::SegmentBuffers;
use super::label::Connectivity;
use super::{SegmentError, SegmentParams, MAX_OBJECTS};

/// Dilations that give a part back the contour its interior leaves out.
const PART_DILATIONS: u8 = 2;

/// The interiors of this search's mask that are solid: at least an
/// object's least area ([`SegmentParams::large_enough`]), at least
/// `min_area` of the largest interior's area, and half of them in the
/// object's slice (a ring's hole or the gap between touching objects is
/// not). Writes their roots into `parts`, largest first; `bufs.interiors`
/// holds the interiors, labelled in `bufs.table` as the components
/// returned. Returns how many.
pub(super) fn solid_interiors(
    params: &SegmentParams,
    bufs: &mut SegmentBuffers<'_>,
    parts: &mut [u32; MAX_OBJECTS],
) -> Result<(usize, Components), SegmentError> {
    let g = bufs.g;
    for ((n, &m), &c) in bufs
        .interiors
        .iter_mut()
        .zip(bufs.mask.iter())
        .zip(bufs.closed.iter())
    {
        *n = m & !c;
    }
    let ic = bits::components(g, bufs.interiors, Connectivity::Four, bufs.rows, bufs.table)?;
    let largest = ic.largest.map_or(0, |(_, a)| a);
    let keep = params.min_area;
    let big = |area: u32| {
        params.large_enough(u64::from(area), g.width, g.height)
            && u64::from(area) * u64::from(keep.den) >= u64::from(largest) * u64::from(keep.num)
    };
    let mut cand = [(0u32, 0u32); 2 * MAX_OBJECTS];
    let n = ic.largest_roots(bufs.table, big, &mut cand);
    let mut solid = 0;
    for &(root, area) in cand.iter().take(n) {
        ic.select(g, bufs.interiors, bufs.table, bufs.scratch, |r, _| {
            r == root
        });
        // Only the words the interior touches (the M4 counts bits in
        // software).
        let inside: u32 = bufs
            .scratch
            .iter()
            .zip(bufs.d_obj_reg.iter())
            .filter(|(&c, _)| c != 0)
            .map(|(&c, &d)| (c & d).count_ones())
            .sum();
        if 2 * inside >= area {
            if let Some(p) = parts.get_mut(solid) {
                *p = root;
                solid += 1;
            }
        }
    }
    Ok((solid, ic))
}

/// Writes part `root` of [`solid_interiors`]' labelling into `bufs.mask`:
/// its interior given back its contour, within the filled map. Returns its
/// area.
pub(super) fn part_mask(
    params: &SegmentParams,
    bufs: &mut SegmentBuffers<'_>,
    ic: &Components,
    root: u32,
) -> u32 {
    let g = bufs.g;
    ic.select(g, bufs.interiors, bufs.table, bufs.mask, |r, _| r == root);
    bits::morph_n(
        g,
        params.disk,
        bufs.mask,
        bufs.scratch,
        bufs.morph_rows,
        PART_DILATIONS,
        false,
    );
    let mut area = 0;
    for (m, &f) in bufs.mask.iter_mut().zip(bufs.filled.iter()) {
        *m &= f;
        if *m != 0 {
            area += m.count_ones();
        }
    }
    area
}
