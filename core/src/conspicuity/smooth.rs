//! Edge-preserving colour smoothing: a symmetric-nearest-neighbour cell.
//!
//! For each of the 4 symmetric pairs of the 3x3 window (the conspicuity
//! pairs, offsets (1,0), (1,1), (0,1), (-1,1)), the cell keeps the member
//! nearer to the centre in CIELUV distance (the `p - δ` member on a tie). The
//! output is the mean of the centre and the 4 kept pixels, rounded by
//! `div5_round`. Across an edge the kept members lie on the centre's side,
//! so the edge is not blurred; inside a region the cell averages, like the
//! centre of a difference-of-Gaussians. [`SmoothParams::iterations`] repeats
//! it; each repetition widens the smoothing while edges stay put.
//! Image borders replicate the outermost pixels.

use super::ring::Ring;
use super::{ConspicuityError, Luv};
use crate::image::ImageViewMut;

/// Largest error of one [`smooth_step`] against its f32 reference given the
/// same input, in output LSBs, at pixels where the float and integer
/// distance comparisons agree: the exact mean is rounded once (0.5 LSB) and
/// the f32 mean is off by under 0.01 LSB.
pub const MAX_ERR_SMOOTH_STEP_LSB: f32 = 0.51;

/// Parameters of [`smooth`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SmoothParams {
    /// Number of passes of the cell; 0 leaves the image unchanged.
    pub iterations: u8,
}

impl Default for SmoothParams {
    /// One pass: see `docs/CONSPICUITY.md` for the choice.
    fn default() -> Self {
        Self { iterations: 1 }
    }
}

/// Smooths `img` in place, `params.iterations` times.
///
/// # Errors
/// [`ConspicuityError::ScratchTooSmall`] when `rows` is shorter than
/// [`row_scratch_len`](super::row_scratch_len)`(width)`.
pub fn smooth(
    params: &SmoothParams,
    img: &mut ImageViewMut<'_, Luv>,
    rows: &mut [Luv],
) -> Result<(), ConspicuityError> {
    for _ in 0..params.iterations {
        smooth_step(img, rows)?;
    }
    Ok(())
}

/// One pass of the cell, in place.
///
/// # Errors
/// As [`smooth`].
pub fn smooth_step(
    img: &mut ImageViewMut<'_, Luv>,
    rows: &mut [Luv],
) -> Result<(), ConspicuityError> {
    let (w, h) = img.size();
    let mut ring = Ring::new(rows, w)?;
    ring.start(img.row(0).unwrap_or(&[]));
    for y in 0..h {
        ring.load_next(img.row((y + 1).min(h - 1)).unwrap_or(&[]));
        if let Some(out) = img.row_mut(y) {
            snn_row(ring.prev, ring.cur, ring.next, out);
        }
        ring.advance();
    }
    Ok(())
}

#[inline(always)]
pub(crate) fn bits(p: Luv) -> [i32; 3] {
    p.to_bits().map(i32::from)
}

/// Squared CIELUV distance in Q12, exact: [`Luv`] channels lie within
/// ±16 383, so each difference is below 2^15, each square below 2^30 and
/// the sum below 3 · 2^30 < 2^32.
#[inline(always)]
pub(crate) fn dist2(a: [i32; 3], b: [i32; 3]) -> u32 {
    let sq = |x: i32, y: i32| {
        let d = x - y;
        (d * d) as u32
    };
    sq(a[0], b[0]) + sq(a[1], b[1]) + sq(a[2], b[2])
}

/// The pair member nearer to `c`; `minus` on a tie.
#[inline(always)]
fn nearer(c: [i32; 3], minus: [i32; 3], plus: [i32; 3]) -> [i32; 3] {
    if dist2(c, minus) <= dist2(c, plus) {
        minus
    } else {
        plus
    }
}

/// `round(s / 5)`, ties toward +∞, for `|s| <= 5 · 2^15`: a bias makes the
/// dividend non-negative so the division is an unsigned multiply-shift.
#[inline(always)]
fn div5_round(s: i32) -> i16 {
    // floor((2s + 5) / 10) = floor((2s + 5 + 327 680) / 10) - 32 768.
    let biased = (2 * s + 5 + 327_680) as u32;
    ((biased / 10) as i32 - 32_768) as i16
}

/// One output row of the cell: `out[x]` from the 3x3 window of columns
/// `x..x + 3` of `prev`, `cur` and `next` (rows padded by one pixel on each
/// side, so `out` is 2 shorter; extra pixels are ignored). The portable
/// [`ColourKernel::snn_row`](super::ColourKernel::snn_row).
pub fn snn_row(prev: &[Luv], cur: &[Luv], next: &[Luv], out: &mut [Luv]) {
    let cells = prev.windows(3).zip(cur.windows(3)).zip(next.windows(3));
    for (((up, mid), down), o) in cells.zip(out.iter_mut()) {
        let (&[a0, a1, a2], &[b0, b1, b2], &[c0, c1, c2]) = (up, mid, down) else {
            continue;
        };
        let c = bits(b1);
        let kept = [
            nearer(c, bits(b0), bits(b2)), // (1, 0)
            nearer(c, bits(a0), bits(c2)), // (1, 1)
            nearer(c, bits(a1), bits(c1)), // (0, 1)
            nearer(c, bits(a2), bits(c0)), // (-1, 1)
        ];
        let mut sum = c;
        for k in kept {
            sum[0] += k[0];
            sum[1] += k[1];
            sum[2] += k[2];
        }
        // The mean of 5 in-range values is in range.
        let [l, u, v] = sum.map(div5_round);
        *o = Luv::in_range(l, u, v);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::conspicuity::row_scratch_len;

    fn lum(l: &[i16]) -> [Luv; 8] {
        core::array::from_fn(|i| Luv::from_bits(*l.get(i).unwrap_or(&0), 0, 0))
    }

    fn run(px: &mut [Luv], w: usize, h: usize, iterations: u8) {
        let mut rows = [Luv::default(); row_scratch_len(8)];
        let mut img = ImageViewMut::packed(px, w, h).unwrap();
        smooth(&SmoothParams { iterations }, &mut img, &mut rows).unwrap();
    }

    #[test]
    fn a_tie_keeps_the_minus_member() {
        // 3x1: centre 10 between 0 and 20; the horizontal pair ties.
        let mut px = lum(&[0, 10, 20]);
        run(&mut px[..3], 3, 1, 1);
        // (10 + 0 + 10 + 10 + 10) / 5: the three other pairs replicate the centre.
        assert_eq!(px[1].to_bits(), [8, 0, 0]);
    }

    #[test]
    fn a_step_edge_stays_sharp_and_noise_is_averaged() {
        let mut step = lum(&[0, 0, 0, 0, 640, 640, 640, 640]);
        run(&mut step, 8, 1, 3);
        assert_eq!(
            step.map(|p| p.l().to_bits()),
            [0, 0, 0, 0, 640, 640, 640, 640]
        );
        let mut spike = lum(&[100, 100, 100, 160, 100, 100, 100, 100]);
        run(&mut spike, 8, 1, 1);
        // Three pairs keep a 100; the vertical pair replicates the centre
        // in a one-row image: (160 + 100 + 100 + 160 + 100) / 5.
        assert_eq!(spike[3].l().to_bits(), 124);
    }

    #[test]
    fn zero_iterations_change_nothing_and_short_scratch_is_an_error() {
        let mut px = lum(&[1, 2, 3, 4, 5, 6, 7, 8]);
        let before = px;
        run(&mut px, 4, 2, 0);
        assert_eq!(px, before);
        let mut rows = [Luv::default(); 5];
        let mut img = ImageViewMut::packed(&mut px, 4, 2).unwrap();
        assert_eq!(
            smooth_step(&mut img, &mut rows),
            Err(ConspicuityError::ScratchTooSmall { needed: 18, got: 5 })
        );
    }
}
