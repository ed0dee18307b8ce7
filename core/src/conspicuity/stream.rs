//! The whole stage on a rolling window of rows: CIELUV, the smoothing
//! passes and C~, with no full-frame CIELUV map.
//!
//! Every step reads a 3x3 neighbourhood, so each keeps a ring of three
//! edge-padded rows of its input: the CIELUV rows for the first smoothing
//! pass, that pass's output for the next, and the last pass's output for
//! C~. Row `r` of a ring sits in slot `r % 3`; the rows above the top and
//! below the bottom are the outermost rows, read again (the border rule
//! of [`smooth`](super::smooth) and [`conspicuity`](super::conspicuity)).
//! Step `k` writes its output row `y` straight into ring `k + 1` once its
//! input row `y + 1` has arrived, so each output is the full-frame
//! functions' output bit for bit.

use super::ring::row_scratch_len;
use super::smooth::SmoothParams;
use super::{threshold, to_conspicuity, ColourKernel, ConspicuityError, EdgeCell, EdgeReport, Luv};
use crate::fixed::U10F6;
use crate::image::ImageViewMut;
use crate::off::MaybeOff;
use crate::stereo::phase::SafePhase;

/// [`Luv`] elements of row scratch [`stream`] needs: one ring of three
/// padded rows per smoothing pass, and one for C~.
pub const fn stream_scratch_len(width: usize, smooth: &SmoothParams) -> usize {
    (smooth.iterations as usize + 1) * row_scratch_len(width)
}

/// Replicates the end pixels of a padded slot's body into its pads.
fn pad(slot: &mut [Luv]) {
    let n = slot.len();
    if n < 3 {
        return;
    }
    if let (Some(&a), Some(&b)) = (slot.get(1), slot.get(n - 2)) {
        if let Some(d) = slot.first_mut() {
            *d = a;
        }
        if let Some(d) = slot.last_mut() {
            *d = b;
        }
    }
}

/// Slot of row `r` in a ring (its three rows of `pw` pixels).
fn slot(ring: &[Luv], r: usize, pw: usize) -> &[Luv] {
    let s = (r % 3) * pw;
    ring.get(s..s + pw).unwrap_or(&[])
}

fn slot_mut(ring: &mut [Luv], r: usize, pw: usize) -> &mut [Luv] {
    let s = (r % 3) * pw;
    ring.get_mut(s..s + pw).unwrap_or(&mut [])
}

/// Runs CIELUV, `smooth.iterations` smoothing passes, C~ and the
/// threshold over a frame given row by row: `source(y, row)` fills CIELUV
/// row `y` (`width` pixels), `smoothed(y, row)` sees each smoothed row (for
/// an observer or a compact copy), and C goes to `dst`. The result is
/// [`smooth`](super::smooth), [`conspicuity`](super::conspicuity) and
/// [`threshold`](super::threshold) on the whole frame, bit for bit. A cell
/// whose distance is at most `percent` % of the largest C~ so far, which
/// the threshold would turn OFF whatever comes after, is written OFF
/// without its square root.
///
/// # Errors
/// [`ConspicuityError::ScratchTooSmall`] when `rows` is shorter than
/// [`stream_scratch_len`], [`ConspicuityError::BadThreshold`] for a
/// `percent` above 100.
pub fn stream(
    smooth: &SmoothParams,
    percent: u8,
    rows: &mut [Luv],
    dst: &mut ImageViewMut<'_, EdgeCell>,
    source: impl FnMut(usize, &mut [Luv]),
    smoothed: impl FnMut(usize, &[Luv]),
) -> Result<EdgeReport, ConspicuityError> {
    stream_with::<SafePhase>(smooth, percent, rows, dst, source, smoothed)
}

/// [`stream`] with the hot loops by kernel `K` (the same bits).
///
/// # Errors
/// As [`stream`].
pub fn stream_with<K: ColourKernel>(
    smooth: &SmoothParams,
    percent: u8,
    rows: &mut [Luv],
    dst: &mut ImageViewMut<'_, EdgeCell>,
    mut source: impl FnMut(usize, &mut [Luv]),
    mut smoothed: impl FnMut(usize, &[Luv]),
) -> Result<EdgeReport, ConspicuityError> {
    if percent > 100 {
        return Err(ConspicuityError::BadThreshold(percent));
    }
    let (w, h) = dst.size();
    let needed = stream_scratch_len(w, smooth);
    let got = rows.len();
    let rows = rows
        .get_mut(..needed)
        .ok_or(ConspicuityError::ScratchTooSmall { needed, got })?;
    let pw = w + 2;
    let ring_len = 3 * pw;
    let passes = usize::from(smooth.iterations);
    // The largest squared distance so far, and the squared distances at
    // or below which a cell is surely OFF: C~ = round(sqrt(d)) <= k for
    // d <= k² + k, and C~ <= k = ⌊percent · max so far / 100⌋ fails the
    // threshold of any final max.
    let (mut dmax, mut bound) = (0u32, 0u32);
    // Ring k receives its row r at time r + k; step k (a smoothing pass,
    // or C~ for k = passes) makes its output row t - 1 - k at time t.
    for t in 0..h + passes + 1 {
        if t < h {
            let ring0 = rows.get_mut(..ring_len).unwrap_or(&mut []);
            let s = slot_mut(ring0, t, pw);
            if let Some(body) = s.get_mut(1..=w) {
                source(t, body);
            }
            pad(s);
            if passes == 0 {
                smoothed(t, slot(ring0, t, pw).get(1..=w).unwrap_or(&[]));
            }
        }
        for k in 0..=passes {
            let Some(y) = t.checked_sub(1 + k).filter(|&y| y < h) else {
                continue;
            };
            let (this, rest) = rows
                .split_at_mut_checked((k + 1) * ring_len)
                .unwrap_or((&mut [], &mut []));
            let ring = this.get(k * ring_len..).unwrap_or(&[]);
            let (prev, cur, next) = (
                slot(ring, y.saturating_sub(1), pw),
                slot(ring, y, pw),
                slot(ring, (y + 1).min(h - 1), pw),
            );
            if k < passes {
                let s = slot_mut(rest, y, pw);
                if let Some(body) = s.get_mut(1..=w) {
                    K::snn_row(prev, cur, next, body);
                }
                pad(s);
                if k + 1 == passes {
                    smoothed(y, slot(rest, y, pw).get(1..=w).unwrap_or(&[]));
                }
            } else if let Some(out) = dst.row_mut(y) {
                let cells = prev.windows(3).zip(cur.windows(3)).zip(next.windows(3));
                for (((up, mid), down), o) in cells.zip(out.iter_mut()) {
                    let d = K::pair_dist2(up, mid, down);
                    dmax = dmax.max(d);
                    *o = if d <= bound {
                        EdgeCell::OFF
                    } else {
                        MaybeOff::from_raw(U10F6::from_bits(to_conspicuity(d)))
                    };
                }
                let k = u64::from(percent) * u64::from(to_conspicuity(dmax)) / 100;
                bound = u32::try_from(k * k + k).unwrap_or(u32::MAX);
            }
        }
    }
    let max = U10F6::from_bits(to_conspicuity(dmax));
    let on_count = threshold(dst, max, percent)?;
    Ok(EdgeReport { max, on_count })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::conspicuity::{conspicuity, smooth, threshold};
    use crate::rng::SplitMix64;

    /// The streamed stage against the full-frame functions on random
    /// frames of every small size and pass count.
    #[test]
    fn streaming_is_the_full_frame_stage_bit_for_bit() {
        let mut rng = SplitMix64::new(7);
        for (w, h) in [(1, 1), (1, 4), (5, 1), (2, 2), (7, 3), (9, 6)] {
            for (iterations, percent) in [(0u8, 10u8), (1, 0), (2, 10), (2, 60), (3, 100)] {
                let p = SmoothParams { iterations };
                let mut luv = [Luv::default(); 54];
                for px in luv.iter_mut().take(w * h) {
                    let r = rng.next_u64();
                    let c = |s: u32| ((r >> s) & 0x3fff) as i16 - 8192;
                    *px = Luv::from_bits(c(0), c(16), c(32));
                }
                let original = luv;
                let mut full = ImageViewMut::packed(&mut luv[..w * h], w, h).unwrap();
                let mut scratch = [Luv::default(); 4 * row_scratch_len(9)];
                smooth(&p, &mut full, &mut scratch).unwrap();
                let mut c_full = [EdgeCell::OFF; 54];
                let mut c_full_v = ImageViewMut::packed(&mut c_full[..w * h], w, h).unwrap();
                let max_full = conspicuity(&full.as_view(), &mut c_full_v, &mut scratch).unwrap();
                let on_full = threshold(&mut c_full_v, max_full, percent).unwrap();

                let mut c = [EdgeCell::OFF; 54];
                let mut c_v = ImageViewMut::packed(&mut c[..w * h], w, h).unwrap();
                let mut seen = [Luv::default(); 54];
                let report = stream(
                    &p,
                    percent,
                    &mut scratch,
                    &mut c_v,
                    |y, row| row.copy_from_slice(&original[y * w..(y + 1) * w]),
                    |y, row| seen[y * w..(y + 1) * w].copy_from_slice(row),
                )
                .unwrap();
                assert_eq!(report.max, max_full, "{w}x{h}, {iterations} passes");
                assert_eq!(report.on_count, on_full, "{w}x{h}, {iterations} passes");
                assert_eq!(c, c_full, "{w}x{h}, {iterations} passes");
                assert_eq!(&seen[..w * h], &luv[..w * h], "{w}x{h}");
            }
        }
    }

    #[test]
    fn short_scratch_is_a_typed_error() {
        let mut c = [EdgeCell::OFF; 6];
        let mut c_v = ImageViewMut::packed(&mut c, 3, 2).unwrap();
        let mut rows = [Luv::default(); 20];
        let p = SmoothParams { iterations: 2 };
        assert_eq!(
            stream(&p, 10, &mut rows, &mut c_v, |_, _| {}, |_, _| {}),
            Err(ConspicuityError::ScratchTooSmall {
                needed: 45,
                got: 20
            })
        );
        let mut rows = [Luv::default(); 45];
        assert_eq!(
            stream(&p, 101, &mut rows, &mut c_v, |_, _| {}, |_, _| {}),
            Err(ConspicuityError::BadThreshold(101))
        );
    }
}
