//! The closing of the unbounded plane on bit maps: the frame padded in
//! place by the closing's steps, closed with [`morph_n`], cropped back.

use super::{bit_map_len, morph_n, Disk, Geom};

/// Most steps of a closing ([`SegmentParams::closing_steps`](crate::segment::SegmentParams::closing_steps),
/// [`DepthPass::closing`](crate::segment::DepthPass::closing)): the
/// closing, the unbounded plane's, pads the frame by this many pixels on
/// every side ([`crate::segment::close`]).
pub const MAX_CLOSING_STEPS: u8 = 8;

/// `u32` words of each of the two buffers the closing of
/// [`SegmentBuffers`](crate::segment::SegmentBuffers) works in: a bit map
/// padded by [`MAX_CLOSING_STEPS`] pixels on every side.
pub const fn closing_map_len(width: usize, height: usize) -> usize {
    let p = 2 * MAX_CLOSING_STEPS as usize;
    bit_map_len(width + p, height + p)
}

/// The closing of the unbounded plane: `n` dilations then `n` erosions of
/// `map` padded by `n` OFF pixels on every side, cropped back, in place.
///
/// The pad holds what the dilations grow past the frame, so the erosions
/// take back a shape's growth at the frame's edge as anywhere else: an
/// object near the edge gets no cap up to it, and (the closing being
/// extensive) none is eaten into. `map` and `scratch` are
/// [`closing_map_len`] words: the map in its first [`Geom::len`], padded in
/// place into `Geom::new(width + 2n, height + 2n)` and back. `rows` is
/// [`morph_rows_len`](super::morph_rows_len) of the padded width. `n` is at most
/// [`MAX_CLOSING_STEPS`] (more is taken as that); shorter buffers leave
/// `map` as it is (never the case with [`SegmentBuffers`](crate::segment::SegmentBuffers),
/// which checks them once).
pub(in crate::segment) fn close(
    g: Geom,
    disk: Disk,
    map: &mut [u32],
    scratch: &mut [u32],
    rows: &mut [u32],
    n: u8,
) {
    let n = n.min(MAX_CLOSING_STEPS);
    if n == 0 {
        return;
    }
    let pn = usize::from(n);
    let pg = Geom::new(g.width + 2 * pn, g.height + 2 * pn);
    let (Some(pm), Some(ps)) = (map.get_mut(..pg.len()), scratch.get_mut(..pg.len())) else {
        return;
    };
    pad(g, pg, pn, pm);
    morph_n(pg, disk, pm, ps, rows, n, false);
    morph_n(pg, disk, pm, ps, rows, n, true);
    crop(g, pg, pn, pm);
}

/// Moves the `g` map at the start of `m` into padded geometry `pg`, row
/// `y` to row `y + n` shifted right by `n` bits (`1 <= n < 32`), the pad
/// OFF. Rows go last first and words high first, so no word is written
/// before it is read (each lands at or past where it was).
fn pad(g: Geom, pg: Geom, n: usize, m: &mut [u32]) {
    let (s, ps) = (g.stride, pg.stride);
    let word = |m: &[u32], y: usize, i: usize| -> u32 {
        if i < s {
            m.get(y * s + i).copied().unwrap_or(0)
        } else {
            0
        }
    };
    for y in (0..g.height).rev() {
        for i in (0..ps).rev() {
            let lo = i.checked_sub(1).map_or(0, |j| word(m, y, j) >> (32 - n));
            let v = word(m, y, i) << n | lo;
            if let Some(w) = m.get_mut((y + n) * ps + i) {
                *w = v;
            }
        }
    }
    for r in [0..n * ps, (g.height + n) * ps..pg.len()] {
        if let Some(rows) = m.get_mut(r) {
            rows.fill(0);
        }
    }
}

/// The inverse of [`pad`]: row `y + n` of the padded map, shifted left by
/// `n` bits, back to row `y` of `g` at the start of `m`; the rest of the
/// padded map is cleared. Rows go first first and words low first, so each
/// word is read before it is written.
fn crop(g: Geom, pg: Geom, n: usize, m: &mut [u32]) {
    let (s, ps) = (g.stride, pg.stride);
    for y in 0..g.height {
        for i in 0..s {
            let at = |k: usize| {
                if k < ps {
                    m.get((y + n) * ps + k).copied().unwrap_or(0)
                } else {
                    0
                }
            };
            let v = at(i) >> n | at(i + 1) << (32 - n);
            // The closing stays within the frame's hull, so the right pad
            // is OFF: the mask only keeps the map's invariant explicit.
            let v = if i + 1 == s { v & g.last } else { v };
            if let Some(w) = m.get_mut(y * s + i) {
                *w = v;
            }
        }
    }
    if let Some(rest) = m.get_mut(g.len()..) {
        rest.fill(0);
    }
}

#[cfg(test)]
mod tests {
    use super::{close, closing_map_len, Disk, Geom, MAX_CLOSING_STEPS};
    use crate::image::ImageViewMut;
    use crate::rng::SplitMix64;
    use crate::segment::bits::morph_rows_len;
    use crate::segment::morph::{self, closing_size};

    const W: usize = 70;
    const H: usize = 12;
    const P: usize = 2 * MAX_CLOSING_STEPS as usize;

    /// The bit closing equals the `bool` one on random maps, widths across
    /// the word boundaries and every step count.
    #[test]
    fn bits_match_the_bool_closing() {
        let mut rng = SplitMix64::new(5);
        for case in 0..400 {
            let w = [1, 5, 31, 32, 33, 40, 63, 64, 65, 70][case % 10];
            let h = 1 + rng.below(H as u64) as usize;
            let n = (case / 10 % (usize::from(MAX_CLOSING_STEPS) + 1)) as u8;
            let disk = if case % 2 == 0 {
                Disk::Cross
            } else {
                Disk::Square
            };
            let density = 1 + rng.below(6);
            let mut map = [false; W * H];
            for p in map.iter_mut().take(w * h) {
                *p = rng.below(8) < density;
            }
            let g = Geom::new(w, h);
            let mut bits = [0u32; closing_map_len(W, H)];
            for (i, &on) in map.iter().take(w * h).enumerate() {
                g.set(&mut bits, i % w, i / w, on);
            }
            let mut scratch = [0u32; closing_map_len(W, H)];
            let mut rows = [0u32; morph_rows_len(W + P)];
            close(g, disk, &mut bits, &mut scratch, &mut rows, n);

            let (pw, ph) = closing_size(w, h, n);
            let (mut padded, mut pad_scratch) =
                ([false; (W + P) * (H + P)], [false; (W + P) * (H + P)]);
            morph::close(
                disk,
                &mut ImageViewMut::packed(&mut map[..w * h], w, h).unwrap(),
                &mut ImageViewMut::packed(&mut padded[..pw * ph], pw, ph).unwrap(),
                &mut ImageViewMut::packed(&mut pad_scratch[..pw * ph], pw, ph).unwrap(),
                n,
            )
            .unwrap();
            for (i, &want) in map.iter().take(w * h).enumerate() {
                assert_eq!(
                    g.bit(&bits, i % w, i / w),
                    want,
                    "case {case}: {w}x{h} n {n} pixel {i}"
                );
            }
            // The rest of the padded buffer is left clear.
            assert!(bits[g.len()..].iter().all(|&b| b == 0), "case {case}");
        }
    }
}
