//! Decisions: the argmin of the path sums with its parabola and margin,
//! the right map derived from the left, and the OFF tests.

use super::{C2f, LeftRight};
use crate::disparity::DisparityCell;
use crate::fixed::U8F8;
use crate::stereo::StereoReport;

/// One pixel's decision before the OFF tests.
#[derive(Clone, Copy)]
pub(super) struct Decision {
    /// `U8F8` bits.
    pub(super) disparity: i32,
    /// Best path sum more than 1 px away minus the best (`None`: none).
    pub(super) margin: Option<u32>,
}

/// Argmin of `sums` (a window from `lo`, the first `valid` of them), the
/// parabola through its neighbours in `U8F8`, and the margin.
pub(super) fn decide(sums: &[u32], lo: usize, valid: usize) -> Option<Decision> {
    let s = sums.get(..valid)?;
    // The engine's windows of 5 and 3, unrolled.
    if let Ok(s5) = <&[u32; 5]>::try_from(s) {
        return decide_in(s5, lo);
    }
    if let Ok(s3) = <&[u32; 3]>::try_from(s) {
        return decide_in(s3, lo);
    }
    let (mut best, mut sb) = (0usize, *s.first()?);
    for (i, &v) in s.iter().enumerate().skip(1) {
        if v < sb {
            (best, sb) = (i, v);
        }
    }
    // The best sum more than 1 px away: before `best − 1` or after
    // `best + 1`.
    let before = s.get(..best.saturating_sub(1)).unwrap_or(&[]);
    let after = s.get(best + 2..).unwrap_or(&[]);
    let second = before.iter().chain(after).copied().min();
    let disparity = parabola(s, lo, best, sb);
    Some(Decision {
        disparity,
        margin: second.map(|v| v - sb),
    })
}

/// [`decide`] over a whole window of `N` sums (the same integers; the
/// length known, so the loops unroll).
#[inline(always)]
fn decide_in<const N: usize>(s: &[u32; N], lo: usize) -> Option<Decision> {
    let (mut best, mut sb) = (0usize, *s.first()?);
    for (i, &v) in s.iter().enumerate().skip(1) {
        if v < sb {
            (best, sb) = (i, v);
        }
    }
    let mut second = None::<u32>;
    for (i, &v) in s.iter().enumerate() {
        if i + 1 < best || i > best + 1 {
            second = Some(second.map_or(v, |m| m.min(v)));
        }
    }
    Some(Decision {
        disparity: parabola(s, lo, best, sb),
        margin: second.map(|v| v - sb),
    })
}

/// `U8F8` disparity of candidate `best` (sum `sb`) of the window `s` from
/// `lo`, refined by the parabola through its neighbours where both exist.
#[inline(always)]
fn parabola(s: &[u32], lo: usize, best: usize, sb: u32) -> i32 {
    let mut disparity = ((lo + best) as i32) << 8;
    if let (Some(&m), Some(&p)) = (s.get(best.wrapping_sub(1)), s.get(best + 1)) {
        // Path sums are below 5·65535 < 2^19, so every term fits in i32.
        let (m, c, p) = (m as i32, sb as i32, p as i32);
        // The reference's parabola on −sum: δ = (m − p) / (2 (m − 2c + p)).
        let curv = m - 2 * c + p;
        if curv > 0 {
            let num = 128 * (m - p);
            let delta = (2 * num + curv).div_euclid(2 * curv).clamp(-128, 128);
            disparity += delta;
        }
    }
    disparity
}

/// The right map of the left-right check derived from the left one
/// (OpenCV SGBM's `disp2`): right pixel `x − d` takes the candidate `d`
/// (`U8F8` bits, integer) of least path sum over the left pixels `x`
/// with evidence (`total > 0`) and their valid candidates `d <= x`;
/// the first such (by `x`, then `d`) wins a tie; `-1` where no left
/// pixel maps. `n`: the candidates per pixel; `scores`, `lo`, `sums`:
/// the left row's; `best` is scratch (`w` long).
pub(super) fn right_from_left(
    n: usize,
    scores: &[i64],
    lo: &[u16],
    sums: &[u32],
    best: &mut [u32],
    right: &mut [i32],
) {
    // The engine's windows of 5 and its coarsest level's 9 as constants.
    match n {
        5 => right_from_left_n::<5>(n, scores, lo, sums, best, right),
        9 => right_from_left_n::<9>(n, scores, lo, sums, best, right),
        _ => right_from_left_n::<0>(n, scores, lo, sums, best, right),
    }
}

/// [`right_from_left`] with `N = n` known (`N > 0`), or any `n` (`N = 0`).
#[inline(always)]
fn right_from_left_n<const N: usize>(
    n: usize,
    scores: &[i64],
    lo: &[u16],
    sums: &[u32],
    best: &mut [u32],
    right: &mut [i32],
) {
    // At least 1; `max` shows the compiler (no panic path in `chunks`).
    let n = if N > 0 { N } else { n.max(1) };
    right.fill(-1);
    best.fill(u32::MAX);
    for (x, (raw, (&lo, s))) in scores
        .chunks_exact(n.saturating_add(1))
        .zip(lo.iter().zip(sums.chunks_exact(n)))
        .enumerate()
    {
        let lo = usize::from(lo);
        if raw.get(n).copied().unwrap_or(0) <= 0 || lo > x {
            continue;
        }
        let valid = (x - lo + 1).min(n);
        for (d, &c) in (lo..).zip(s.iter().take(valid)) {
            let xr = x - d;
            if let (Some(b), Some(r)) = (best.get_mut(xr), right.get_mut(xr)) {
                if c < *b {
                    *b = c;
                    *r = (d as i32) << 8;
                }
            }
        }
    }
}

/// The decision of one pixel with `n` candidates: its scores row `raw`
/// (for the total), window `lo`, path sums `sums`, last valid candidate
/// `top`.
pub(super) fn decision(
    n: usize,
    raw: &[i64],
    lo: u16,
    sums: &[u32],
    top: usize,
) -> Option<Decision> {
    let lo = usize::from(lo);
    let total = raw.get(n).copied().unwrap_or(0);
    if total <= 0 || lo > top {
        return None;
    }
    decide(sums, lo, (top - lo + 1).min(n))
}

/// The OFF tests' thresholds, in the engine's integers.
#[derive(Clone, Copy)]
pub(super) struct OffTests {
    /// OFF when `margin·2^16` is below this.
    min_margin_sums: i64,
    /// The left-right tolerance in `U8F8` (`None`: no check).
    check: Option<i32>,
}

impl OffTests {
    /// The tests of `e`.
    pub(super) fn of<K>(e: &C2f<K>) -> Self {
        let check = match e.params.left_right {
            LeftRight::Off => None,
            LeftRight::Read | LeftRight::Derived => e.dem.lr_tolerance_q8,
        };
        Self {
            min_margin_sums: e.min_margin_sums,
            check,
        }
    }

    /// The OFF tests of left pixel `x` (texture, ambiguity, left-right
    /// against the right decisions `right`).
    pub(super) fn verdict(
        &self,
        x: usize,
        d: Option<Decision>,
        textured: bool,
        right: &[i32],
    ) -> Verdict {
        let Some(d) = d.filter(|_| textured) else {
            return Verdict::Texture;
        };
        if d.margin
            .is_some_and(|m| (i64::from(m) << 16) < self.min_margin_sums)
        {
            return Verdict::Ambiguous;
        }
        let v = d.disparity;
        let ok = self.check.is_none_or(|tol| {
            let xr = x as i64 - i64::from((v + 128) >> 8);
            usize::try_from(xr)
                .ok()
                .and_then(|xr| right.get(xr).copied())
                .is_some_and(|b| b >= 0 && (b - v).abs() <= tol)
        });
        if !ok {
            return Verdict::Inconsistent;
        }
        Verdict::On(v.clamp(0, i32::from(u16::MAX - 1)) as u16)
    }
}

/// The OFF tests' result for one pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Verdict {
    /// A disparity, `U8F8` bits below `U8F8::MAX`.
    On(u16),
    /// OFF: too little evidence.
    Texture,
    /// OFF: the margin test.
    Ambiguous,
    /// OFF: the left-right check.
    Inconsistent,
}

impl Verdict {
    /// As an `i32` (a disparity's bits, or −1, −2, −3 for the OFFs).
    pub(super) fn code(self) -> i32 {
        match self {
            Self::On(v) => i32::from(v),
            Self::Texture => -1,
            Self::Ambiguous => -2,
            Self::Inconsistent => -3,
        }
    }

    /// The inverse of [`Verdict::code`] (anything else reads as no
    /// evidence).
    pub(super) fn from_code(c: i32) -> Self {
        match c {
            -2 => Self::Ambiguous,
            -3 => Self::Inconsistent,
            _ => u16::try_from(c).map_or(Self::Texture, Self::On),
        }
    }

    /// A level-`k` disparity in frame pixels: times `2^k`, saturating below
    /// OFF.
    pub(super) fn scaled(self, k: usize) -> Self {
        match self {
            Self::On(v) => Self::On(
                u32::from(v)
                    .checked_shl(k as u32)
                    .map_or(u16::MAX - 1, |s| s.min(u32::from(u16::MAX - 1)) as u16),
            ),
            other => other,
        }
    }

    /// Counts the verdict in `report` and makes it a cell.
    pub(super) fn count(self, report: &mut StereoReport) -> DisparityCell {
        self.count_n(report, 1)
    }

    /// Counts the verdict `n` times in `report` and makes it a cell.
    pub(super) fn count_n(self, report: &mut StereoReport, n: usize) -> DisparityCell {
        match self {
            Self::On(v) => {
                report.on += n;
                DisparityCell::from_raw(U8F8::from_bits(v))
            }
            Self::Texture => {
                report.off_texture += n;
                DisparityCell::OFF
            }
            Self::Ambiguous => {
                report.off_ambiguous += n;
                DisparityCell::OFF
            }
            Self::Inconsistent => {
                report.off_inconsistent += n;
                DisparityCell::OFF
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{decide, right_from_left, right_from_left_n};
    use crate::rng::SplitMix64;

    /// The decision written plainly: the first smallest sum, the smallest
    /// sum more than 1 px from it, and the parabola through the best and
    /// its two neighbours, `δ = (m − p) / (2 (m − 2c + p))` in `U8F8`
    /// rounded half up, within ±0.5 px.
    fn plain(s: &[u32], lo: usize) -> Option<(i32, Option<u32>)> {
        let sb = *s.iter().min()?;
        let best = s.iter().position(|&v| v == sb)?;
        let second = (0..s.len())
            .filter(|&i| i + 1 < best || i > best + 1)
            .map(|i| s[i])
            .min();
        let mut d = ((lo + best) as i32) << 8;
        if best > 0 && best + 1 < s.len() {
            let (m, c, p) = (
                i64::from(s[best - 1]),
                i64::from(sb),
                i64::from(s[best + 1]),
            );
            let curv = m - 2 * c + p;
            if curv > 0 {
                // floor(256 (m − p) / (2 curv) + 1/2)
                let delta = (256 * (m - p) + curv).div_euclid(2 * curv);
                d += delta.clamp(-128, 128) as i32;
            }
        }
        Some((d, second.map(|v| v - sb)))
    }

    #[test]
    fn decisions_equal_the_plain_rule_for_every_window_length() {
        let mut rng = SplitMix64::new(0xdec1de);
        for case in 0..20_000 {
            let n = 1 + (case % 9);
            // Small ranges make ties and flat neighbourhoods common.
            let top = [4, 40, 5 * 65_535][case % 3];
            let mut buf = [0u32; 9];
            for v in buf.iter_mut().take(n) {
                *v = rng.below(top + 1) as u32;
            }
            let s = &buf[..n];
            let lo = rng.below(30) as usize;
            let got = decide(s, lo, n).map(|d| (d.disparity, d.margin));
            assert_eq!(got, plain(s, lo), "sums {s:?} lo {lo}");
        }
        assert!(decide(&[], 0, 0).is_none());
        assert!(decide(&[1, 2], 0, 3).is_none(), "valid beyond the sums");
    }

    /// The specialised derived right maps equal the general one on random
    /// rows (windows anywhere, totals of both signs, ties).
    #[test]
    fn derived_right_maps_equal_the_general_rule() {
        const W: usize = 40;
        let mut rng = SplitMix64::new(0xd15c);
        for case in 0..2_000 {
            let n = if case % 2 == 0 { 5 } else { 9 };
            let mut scores = [0i64; W * 10];
            for t in scores.chunks_exact_mut(n + 1) {
                t[n] = rng.below(3) as i64 - 1;
            }
            let lo: [u16; W] = core::array::from_fn(|_| rng.below(40) as u16);
            let mut sums = [0u32; W * 9];
            for s in &mut sums {
                *s = rng.below(if case % 3 == 0 { 4 } else { 1 << 19 }) as u32;
            }
            let run = |general: bool| {
                let (mut best, mut right) = ([0u32; W], [0i32; W]);
                let (sc, su) = (&scores[..W * (n + 1)], &sums[..W * n]);
                if general {
                    right_from_left_n::<0>(n, sc, &lo, su, &mut best, &mut right);
                } else {
                    right_from_left(n, sc, &lo, su, &mut best, &mut right);
                }
                right
            };
            let want = run(true);
            assert_eq!(run(false), want, "case {case}");
            assert!(case > 0 || want.iter().any(|&r| r >= 0));
        }
    }
}
