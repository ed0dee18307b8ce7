//! The cells and votes of a row, and each pixel's normalised costs.

use crate::stereo::filters::Z;
use crate::stereo::DemTable;

/// The cells of one pixel and carrier into `out` (`[A, Xre, Xim]` in `Q8`
/// each, as many as `others` and `out` both have): the pixel's response
/// `own` paired with each of `others` as `pair(own, other) = (left,
/// right)`. Returns the sum of the cells' `A`.
#[inline(always)]
fn cells<'z>(
    out: &mut [[i32; 3]],
    own: Z,
    others: impl Iterator<Item = &'z Z>,
    pair: impl Fn(Z, Z) -> (Z, Z),
) -> i64 {
    let mut sum = 0i64;
    for (cell, &other) in out.iter_mut().zip(others) {
        let (l, r) = pair(own, other);
        let (lr, li) = (i32::from(l[0]), i32::from(l[1]));
        let (rr, ri) = (i32::from(r[0]), i32::from(r[1]));
        // Exact in i32: |z| components below 2^14.01, so A < 2^30.1
        // (`filters`), then Q12 → Q8.
        let q8 = |v: i32| (v + 8) >> 4;
        let a = q8(lr * lr + li * li + rr * rr + ri * ri);
        *cell = [a, q8(lr * rr + li * ri), q8(li * rr - lr * ri)];
        sum += i64::from(a);
    }
    sum
}

/// Adds one cell's votes to a window's scores `win`: `a·wa + xre·wb +
/// xim·wc` per candidate, from the candidates' weight bytes `wts` (6 per
/// candidate: `wa, wb, wc`, little-endian `i16`).
#[inline(always)]
fn vote(win: &mut [i64], wts: &[u8], [a, xre, xim]: [i32; 3]) {
    for (d, c6) in win.iter_mut().zip(wts.chunks_exact(6)) {
        if let [a0, a1, b0, b1, c0, c1] = *c6 {
            let w = |lo: u8, hi: u8| i32::from(i16::from_le_bytes([lo, hi]));
            *d += i64::from(a) * i64::from(w(a0, a1))
                + i64::from(xre) * i64::from(w(b0, b1))
                + i64::from(xim) * i64::from(w(c0, c1));
        }
    }
}

/// The normalised `Q8` costs of one pixel (module docs) from its scores
/// `raw` (window candidates, overwritten with the scores `n(d)`) and
/// `total`: `valid` candidates from `lo`, the rest of the window the worst
/// valid cost.
pub(super) fn costs_of<const N: usize>(
    raw: &mut [i64],
    total: i64,
    table: &DemTable<'_>,
    lo: usize,
    valid: usize,
    out: &mut [u16],
) {
    // `N > 0`: the caller's `valid` is `N`, known here, so the loops unroll.
    let valid = if N > 0 { N } else { valid };
    let sh = (64 - total.leading_zeros()).saturating_sub(30);
    // Below 2^30 for the callers' `total > 0`, so `i32`.
    let t32 = i32::try_from(total >> sh).unwrap_or(i32::MAX);
    let t = i64::from(t32);
    // `n(d) = 2^m·u(d)`, `m = min(wf, bf)`: `u(d) = (raw(d) >> sh)·2^(bf −
    // m) − bias(d)·t·2^(wf − m)`. Exact, and far from overflow (so the
    // reference's saturation never acts): `|raw| <= 2^14·total + 2^27`
    // (`|X| <= A/2` per cell, `|w| <= 2^15`), so `|raw >> sh| < 2^44.01`,
    // `|bias·t| < 2^45`, and with `wf, bf <= 15` (`DemTable::parse`)
    // `|n(d)| < 2^61`. The window's bias slice is read directly (the
    // `bias_at` path, 0 beyond the table, only serves a window past it):
    // a shorter chained iterator cost 240 instructions/px on the M4.
    let (wf, bf) = (u32::from(table.weight_frac), u32::from(table.bias_frac));
    let m = wf.min(bf);
    let (kb, kw) = (bf - m, wf - m);
    let scores = raw.get_mut(..valid).unwrap_or(&mut []);
    let bias = table.bias_bytes().get(2 * lo..2 * (lo + valid));
    // One of `2^kb`, `2^kw` is 1. With `kw = 0` (the firmware's tables,
    // `bf > wf`), `(raw >> sh) << kb` is one shift of `raw` with low bits
    // cleared: `(raw >> (sh − kb))` without its low `kb` bits, or `raw`
    // without its low `sh` bits `<< (kb − sh)`, by less than 32 here; and
    // `− bias·t` is one 32x32 multiply-accumulate. The same integers as
    // the general form below, in fewer M4 instructions.
    let nt = i64::from(t32.saturating_neg());
    let (best, worst) = match bias {
        Some(bias) if kw == 0 && sh >= kb && sh - kb < 32 => {
            let (a, keep) = ((sh - kb) & 31, !i64::from((1u32 << kb) - 1));
            fold(scores, bias, |r, b| ((r >> a) & keep) + i64::from(b) * nt)
        }
        Some(bias) if kw == 0 && sh < kb => {
            let (a, keep) = ((kb - sh) & 31, !i64::from((1u32 << sh) - 1));
            fold(scores, bias, |r, b| ((r & keep) << a) + i64::from(b) * nt)
        }
        Some(bias) => fold(scores, bias, |r, b| {
            ((r >> sh) << kb).wrapping_sub((i64::from(b) * t) << kw)
        }),
        None => {
            let (mut best, mut worst) = (i64::MIN, i64::MAX);
            for (d, r) in (lo..).zip(scores.iter_mut()) {
                let bt = i64::from(table.bias_at(d)) * t;
                *r = ((*r >> sh) << kb).wrapping_sub(bt << kw);
                best = best.max(*r);
                worst = worst.min(*r);
            }
            (best, worst)
        }
    };
    // Gaps `best − n(d) = 2^m·(best − u(d))` truncated to 15 significant
    // bits (so they fit `out` until they become costs).
    let span = best.abs_diff(worst);
    let bits = if span == 0 {
        0
    } else {
        64 - span.leading_zeros() + m
    };
    let sh2 = bits.saturating_sub(15);
    // `best >= v`, both within ±2^61: the difference is exact. The
    // shift, by less than 32 in the first two forms (so that the M4 shifts
    // one word pair), is chosen once.
    let total_gap = if sh2 >= m && sh2 - m < 32 {
        let k = (sh2 - m) & 31;
        gaps(out, scores, |v| (best.wrapping_sub(v) as u64 >> k) as u16)
    } else if sh2 < m {
        let k = (m - sh2) & 31;
        gaps(out, scores, |v| {
            (best.wrapping_sub(v) as u64).wrapping_shl(k) as u16
        })
    } else {
        let k = sh2 - m;
        gaps(out, scores, |v| (best.wrapping_sub(v) as u64 >> k) as u16)
    };
    // At most 2^15 · 256 · 256 = 2^31: no overflow.
    let scale = 256 * valid as u32;
    let mut hi = 0u16;
    for o in out.iter_mut().take(valid) {
        let c = (u32::from(*o) * scale + total_gap / 2)
            .checked_div(total_gap)
            .unwrap_or(0);
        *o = c.min(u32::from(u16::MAX)) as u16;
        hi = hi.max(*o);
    }
    for o in out.iter_mut().skip(valid) {
        *o = hi;
    }
}

/// [`costs_of`]'s scores: each `r` of `scores` becomes `score(r, bias)`
/// with its candidate's bias from `bias` (little-endian `i16`); returns
/// their largest and smallest.
#[inline(always)]
fn fold(scores: &mut [i64], bias: &[u8], score: impl Fn(i64, i16) -> i64) -> (i64, i64) {
    let (mut best, mut worst) = (i64::MIN, i64::MAX);
    for (r, b) in scores.iter_mut().zip(bias.chunks_exact(2)) {
        if let [b0, b1] = *b {
            *r = score(*r, i16::from_le_bytes([b0, b1]));
            best = best.max(*r);
            worst = worst.min(*r);
        }
    }
    (best, worst)
}

/// [`costs_of`]'s gaps: `out[d] = gap(score d)`; returns their sum.
#[inline(always)]
fn gaps(out: &mut [u16], scores: &[i64], gap: impl Fn(i64) -> u16) -> u32 {
    let mut total = 0u32;
    for (o, &v) in out.iter_mut().zip(scores) {
        *o = gap(v);
        total += u32::from(*o);
    }
    total
}

/// One level's geometry of the votes: the row width, the window length,
/// the shifts and the band.
pub(super) struct Voter {
    /// Level width.
    pub(super) w: usize,
    /// Candidates per pixel.
    pub(super) n: usize,
    /// Position shifts.
    pub(super) shifts: usize,
    /// Shift step, px.
    step: usize,
    /// The band, where it applies (a windowed level with a band).
    pub(super) band: Option<usize>,
    /// Carriers.
    carriers: usize,
    /// [`Voter::shift_range`] of every window `lo` (a `u8`), worked out
    /// once: no division per pixel.
    ranges: [[u16; 2]; 256],
}

impl Voter {
    /// The geometry of a level `w` wide with `n` candidates per pixel,
    /// `shifts` shifts `step` px apart, `band` and `carriers`.
    pub(super) fn new(
        w: usize,
        n: usize,
        (shifts, step): (usize, usize),
        band: Option<usize>,
        carriers: usize,
    ) -> Self {
        let mut voter = Self {
            w,
            n,
            shifts,
            step,
            band,
            carriers,
            ranges: [[0; 2]; 256],
        };
        // Shifts are at most 256 (`max_disp` is a `u8`), so `u16` holds them.
        let mut ranges = [[0u16; 2]; 256];
        for (lo, r) in (0u16..).zip(ranges.iter_mut()) {
            let x = voter.shift_range_of(lo);
            *r = [x.start, x.end].map(|v| u16::try_from(v).unwrap_or(u16::MAX));
        }
        voter.ranges = ranges;
        voter
    }

    /// The shift indices whose votes a pixel with window `lo` takes: those
    /// with `|s − centre| <= band` (centre `lo + (n − 1)/2`), or all.
    fn shift_range(&self, lo: u16) -> core::ops::Range<usize> {
        match self.ranges.get(usize::from(lo)) {
            Some(&[a, b]) => usize::from(a)..usize::from(b),
            None => self.shift_range_of(lo),
        }
    }

    /// [`Voter::shift_range`] worked out.
    fn shift_range_of(&self, lo: u16) -> core::ops::Range<usize> {
        let Some(b) = self.band else {
            return 0..self.shifts;
        };
        let centre2 = 2 * usize::from(lo) + self.n - 1;
        // 2s in [centre2 − 2b, centre2 + 2b], s = ks·step.
        let (lo2, hi2) = (centre2.saturating_sub(2 * b), centre2 + 2 * b);
        // Never 0 (`step >= 1`); `max` shows the compiler (no panic path).
        let step2 = (2 * self.step).max(1);
        let first = lo2.div_ceil(step2);
        let last = (hi2 / step2 + 1).min(self.shifts);
        first.min(last)..last
    }

    /// The cells and votes of one row: for each pixel of each eye (left,
    /// right), its window's scores and total (`n + 1` per pixel, in
    /// `scores`) from the cells of the shifts [`Voter::shift_range`] of its
    /// window `lo` (the cell of left `x` and right `x − s`), and with a
    /// band the number of groups voting (`voters`); `cells` is scratch for
    /// one pixel's cells (`w` long); `right`: the right eye's too (else
    /// only the left's). Returns the number of cells evaluated.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn votes(
        &self,
        table: &DemTable<'_>,
        z: [&[Z]; 2],
        lo: [&[u16]; 2],
        scores: [&mut [i64]; 2],
        voters: [&mut [u16]; 2],
        cells: &mut [[i32; 3]],
        right: bool,
    ) -> usize {
        let [lo_l, lo_r] = lo;
        let [sc_l, sc_r] = scores;
        let [vo_l, vo_r] = voters;
        // Windows of the radii 2 and 1, and the coarsest level of 32
        // disparities (9 candidates), as constants: unrolled votes.
        let left = match self.n {
            5 => self.votes_eye::<true, 5>(table, z, lo_l, sc_l, vo_l, cells),
            3 => self.votes_eye::<true, 3>(table, z, lo_l, sc_l, vo_l, cells),
            9 => self.votes_eye::<true, 9>(table, z, lo_l, sc_l, vo_l, cells),
            _ => self.votes_eye::<true, 0>(table, z, lo_l, sc_l, vo_l, cells),
        };
        if !right {
            return left;
        }
        left + match self.n {
            5 => self.votes_eye::<false, 5>(table, z, lo_r, sc_r, vo_r, cells),
            3 => self.votes_eye::<false, 3>(table, z, lo_r, sc_r, vo_r, cells),
            9 => self.votes_eye::<false, 9>(table, z, lo_r, sc_r, vo_r, cells),
            _ => self.votes_eye::<false, 0>(table, z, lo_r, sc_r, vo_r, cells),
        }
    }

    /// [`Voter::votes`] of one eye (`LEFT`: left-referenced), pixel by
    /// pixel, then carrier by carrier: first the cells, then their votes.
    /// `N` is the window length `self.n` where the caller knows it as a
    /// constant, 0 otherwise.
    fn votes_eye<const LEFT: bool, const N: usize>(
        &self,
        table: &DemTable<'_>,
        [z_l, z_r]: [&[Z]; 2],
        lo: &[u16],
        scores: &mut [i64],
        voters: &mut [u16],
        cells_buf: &mut [[i32; 3]],
    ) -> usize {
        // None of `n`, `w`, `step` is 0 (`Pass::new`); `max` shows the
        // compiler, so that the divisions and chunk loops have no panic path.
        let n = if N == 0 { self.n.max(1) } else { N };
        let (w, step) = (self.w.max(1), self.step.max(1));
        let (step_pow2, step_log) = (step.is_power_of_two(), step.trailing_zeros());
        let carriers = self.carriers;
        let bytes = table.weight_bytes();
        // Group `c·shifts + ks` starts at `6N·(c·shifts + ks)`.
        let n6 = 6 * table.disparities();
        let (own_z, other_z) = if LEFT { (z_l, z_r) } else { (z_r, z_l) };
        let mut evaluated = 0;
        scores.fill(0);
        for (px, ((dst, &lo), v)) in scores
            .chunks_exact_mut(n.saturating_add(1))
            .zip(lo)
            .zip(voters.iter_mut())
            .enumerate()
        {
            let range = self.shift_range(lo);
            // The shifts whose cell lies inside the row: `s <= x` (left),
            // `x + s < w` (right).
            let room = if LEFT { px } else { w - 1 - px };
            let last = if step_pow2 {
                room >> step_log
            } else {
                room / step
            };
            let count = (last + 1).min(range.end).saturating_sub(range.start);
            // The groups voting: `carriers` per shift whose cell is inside
            // (every shift of the range left-referenced).
            *v = if self.band.is_some() {
                let inside = if LEFT { range.len() } else { count };
                (inside * carriers) as u16
            } else {
                0
            };
            evaluated += count * carriers;
            let (win, total) = dst.split_at_mut(n);
            let cells_px = cells_buf.get_mut(..count).unwrap_or(&mut []);
            // The other eye's pixel of the first shift: `x − s` left, `x +
            // s` right; `count` keeps the shifts' pixels inside the row, so
            // `others` has at least `count` and every cell is made.
            let first = range.start * step;
            let mut sum = 0i64;
            for (c, (own_plane, other_plane)) in own_z
                .chunks_exact(w)
                .zip(other_z.chunks_exact(w))
                .take(carriers)
                .enumerate()
            {
                let Some(&own) = own_plane.get(px) else {
                    continue;
                };
                sum += if LEFT {
                    let others = other_plane
                        .get(..(px + 1).saturating_sub(first))
                        .unwrap_or(&[])
                        .iter()
                        .rev()
                        .step_by(step);
                    cells(cells_px, own, others, |o, t| (o, t))
                } else {
                    let others = other_plane
                        .get(px + first..)
                        .unwrap_or(&[])
                        .iter()
                        .step_by(step);
                    cells(cells_px, own, others, |o, t| (t, o))
                };
                // The shift's groups, `n6` apart from the first one.
                let mut g = (c * self.shifts + range.start) * n6 + 6 * usize::from(lo);
                for &cell in cells_px.iter() {
                    let Some(wts) = bytes.get(g..g + 6 * n) else {
                        break;
                    };
                    vote(win, wts, cell);
                    g += n6;
                }
            }
            // The total, `4A` per cell. Like the scores, exact integer sums
            // (far from overflow), so their order does not matter.
            if let Some(t) = total.first_mut() {
                *t = 4 * sum;
            }
        }
        evaluated
    }
}

#[cfg(test)]
mod tests {
    use super::costs_of;
    use crate::rng::SplitMix64;
    use crate::stereo::DemTable;

    /// The costs written plainly in `i128`: `n(d) = (raw >> sh)·2^bf −
    /// bias(d)·(total >> sh)·2^wf`, gaps to the best truncated to 15
    /// significant bits of the span, `C = round(256·m·g / Σ g)`, the rest
    /// of the window the worst valid cost.
    fn plain_costs(raw: &[i64], total: i64, t: &DemTable<'_>, lo: usize, valid: usize) -> [u16; 9] {
        let sh = (64 - total.leading_zeros()).saturating_sub(30);
        let (wf, bf) = (u32::from(t.weight_frac), u32::from(t.bias_frac));
        let n: [i128; 9] = core::array::from_fn(|i| {
            let r = i128::from(raw.get(i).copied().unwrap_or(0) >> sh);
            (r << bf) - ((i128::from(t.bias_at(lo + i)) * i128::from(total >> sh)) << wf)
        });
        let n = &n[..valid];
        let (best, worst) = (*n.iter().max().unwrap(), *n.iter().min().unwrap());
        let bits = 128 - (best - worst).leading_zeros();
        let sh2 = bits.saturating_sub(15);
        let gaps: [u32; 9] =
            core::array::from_fn(|i| n.get(i).map_or(0, |&v| ((best - v) >> sh2) as u32));
        let total_gap: u32 = gaps.iter().sum();
        let mut out = [0u16; 9];
        for (o, &g) in out.iter_mut().zip(&gaps).take(valid) {
            *o = (g * 256 * valid as u32 + total_gap / 2)
                .checked_div(total_gap)
                .map_or(0, |c| c as u16);
        }
        let hi = out.iter().take(valid).copied().max().unwrap_or(0);
        for o in out.iter_mut().skip(valid) {
            *o = hi;
        }
        out
    }

    #[test]
    fn costs_equal_the_plain_rule_with_and_without_a_known_length() {
        // The firmware's level-0 table (32 candidates).
        let bytes = include_bytes!("../../../../firmware-sim/data/dem_c2f_l0.bin");
        let product = DemTable::parse(bytes).unwrap();
        let mut rng = SplitMix64::new(0xc057);
        for case in 0..25_000u64 {
            // The table's own fractions (weights 11, bias 14 bits) and
            // the other orders and ends of `0..=15`.
            let mut table = product;
            let fr = [[11, 14], [14, 11], [12, 12], [0, 15], [15, 0]];
            let [wf, bf] = fr[(case / 5 % 5) as usize];
            (table.weight_frac, table.bias_frac) = (wf, bf);
            let total = 1 + rng.below(1 << (1 + case % 40)) as i64;
            // |raw| <= 2^14·total + 2^27 (the engine's bound).
            let bound = (total << 14) + (1 << 27);
            let mut raw = [0i64; 9];
            for r in &mut raw {
                *r = rng.below(2 * bound as u64 + 1) as i64 - bound;
            }
            // Now and then scores within a few units of each other: gaps
            // of fewer than 15 bits (shifted left).
            if case % 7 == 3 {
                let (spread, base) = (1 << rng.below(12), raw[0]);
                for r in &mut raw[1..] {
                    *r = base + rng.below(spread) as i64;
                }
            }
            let (n, valid) = [(5, 5), (3, 3), (5, 2), (9, 9), (3, 1)][(case % 5) as usize];
            let lo = rng.below(30 - n as u64) as usize;
            let want = plain_costs(&raw, total, &table, lo, valid);
            let mut out = [0u16; 9];
            let mut r = raw;
            match (valid, n) {
                (5, 5) => costs_of::<5>(&mut r, total, &table, lo, valid, &mut out[..n]),
                (3, 3) => costs_of::<3>(&mut r, total, &table, lo, valid, &mut out[..n]),
                (9, 9) => costs_of::<9>(&mut r, total, &table, lo, valid, &mut out[..n]),
                _ => costs_of::<0>(&mut r, total, &table, lo, valid, &mut out[..n]),
            }
            assert_eq!(
                out[..n],
                want[..n],
                "case {case}: total {total} lo {lo} fractions {wf} {bf}"
            );
            let mut general = [0u16; 9];
            costs_of::<0>(&mut raw, total, &table, lo, valid, &mut general[..n]);
            assert_eq!(general[..n], want[..n], "case {case}, general path");
        }
    }
}
