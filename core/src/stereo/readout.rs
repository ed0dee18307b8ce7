//! The row-streamed engine and the read-out: responses on demand, energies
//! pooled vertically per group, votes with the integer decoder weights,
//! horizontal pooling of the scores, argmax with parabola sub-pixel
//! refinement and the OFF tests, mirroring
//! `host/src/reference/stereo/readout.rs` and `stereo_grey`.
//!
//! **Scores.** Per pixel and candidate `d`, `raw(d) = Σ_g A·a + X_r·b +
//! X_i·c` (energies in `Q8` grey², weights in `Q(wf)`) and the total
//! `T = Σ_g 4A`, both summed over the pooling box. The reference's
//! normalised score `raw/T − bias(d)` is compared without a division as
//! `n(d) = raw'(d)·2^bf − bias(d)·T'·2^wf` (same positive denominator for
//! every `d`), where `raw'`, `T'` are `raw`, `T` shifted right together
//! until `T' < 2^30` (block floating point per pixel), so `|n| < 2^61`.

use super::filters::{level_size, pyramid_row, Bank, MAX_TAPS, Z};
use super::MAX_LEVELS;
use super::{
    Dem, DemTable, GreyRows, Probe, Step, StereoBuffers, StereoError, StereoReport, CHUNK,
};
use crate::disparity::DisparityCell;
use crate::fixed::{round_shift, U8F8};
use core::num::NonZeroUsize;

/// `n`, which is never 0 here (ring and slot counts are `2k + 1` or a
/// filter's rows), as a [`NonZeroUsize`]: the `%` by it then has no panic
/// path.
fn nonzero(n: usize) -> NonZeroUsize {
    NonZeroUsize::new(n).unwrap_or(NonZeroUsize::MIN)
}

/// One pixel's decision before the OFF tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pick {
    /// Sub-pixel disparity, `U8F8` bits.
    pub disparity: i32,
    /// `n(best) − n(second)`, the best score minus the best score more
    /// than 1 px away, in units of `1 / scale` (`None`: no such candidate).
    pub margin: Option<i128>,
    /// The common denominator of the scores, `T'·2^(wf + bf)`.
    pub scale: i128,
}

/// Argmax over the candidates `lo..=hi` (clipped to the table) of the
/// pooled scores `raw` with pooled total `total`, then the parabola through
/// `d̂ ± 1` when both neighbours are candidates. `None` when `total` is 0.
pub fn pick(raw: &[i64], total: i64, table: &DemTable<'_>, lo: usize, hi: usize) -> Option<Pick> {
    let hi = hi.min(raw.len().checked_sub(1)?);
    if total <= 0 || lo > hi {
        return None;
    }
    let sh = (64 - total.leading_zeros()).saturating_sub(30);
    let t = total >> sh;
    let (wf, bf) = (u32::from(table.weight_frac), u32::from(table.bias_frac));
    let n = |d: usize| -> i64 {
        let r = raw.get(d).copied().unwrap_or(0) >> sh;
        (r << bf).saturating_sub((i64::from(table.bias_at(d)) * t) << wf)
    };
    let (mut best, mut nb) = (lo, n(lo));
    for d in lo + 1..=hi {
        let v = n(d);
        if v > nb {
            (best, nb) = (d, v);
        }
    }
    let second = (lo..=hi).filter(|&d| d.abs_diff(best) > 1).map(n).max();
    let mut disparity = (best as i32) << 8;
    if best > lo && best < hi {
        let (m, c, p) = (
            i128::from(n(best - 1)),
            i128::from(nb),
            i128::from(n(best + 1)),
        );
        let denom = m - 2 * c + p;
        if denom < 0 {
            // δ = 0.5 (m − p) / denom in 1/256 px, rounded, within ±½ px.
            let num = 128 * (p - m);
            let den = -denom;
            let delta = (2 * num + den).div_euclid(2 * den).clamp(-128, 128);
            disparity += delta as i32;
        }
    }
    Some(Pick {
        disparity,
        margin: second.map(|s| i128::from(nb) - i128::from(s)),
        scale: i128::from(t) << (wf + bf),
    })
}

/// One pooled row of one level pixel pair in the energy stage.
#[derive(Clone, Copy, Default)]
struct Tap {
    /// Weight of column `i0` (units of `4^-level`).
    a: i32,
    /// Weight of column `i1`.
    b: i32,
    /// `a·z_L(i0)`.
    la: [i32; 2],
    /// `b·z_L(i1)`.
    lb: [i32; 2],
    /// Offset of the row in the response ring.
    off: usize,
}

impl Tap {
    /// Adds `w·[|z_R|², X_r, X_i]` with `lw = w·z_L` (exact: `w·z` < 2^25,
    /// every product < 2^40).
    #[inline(always)]
    fn add_right(&self, acc: &mut [i64; 3], w: i32, lw: [i32; 2], r: Z) {
        let (rr, ri) = (i32::from(r[0]), i32::from(r[1]));
        acc[0] += i64::from(w * rr) * i64::from(rr) + i64::from(w * ri) * i64::from(ri);
        acc[1] += i64::from(lw[0]) * i64::from(rr) + i64::from(lw[1]) * i64::from(ri);
        acc[2] += i64::from(lw[1]) * i64::from(rr) - i64::from(lw[0]) * i64::from(ri);
    }
}

/// Moves the first `n` elements of `*s` out ([`StereoError::Buffer`] if
/// there are fewer).
pub(super) fn take<'a, T>(
    s: &mut &'a mut [T],
    n: usize,
    what: &'static str,
) -> Result<&'a mut [T], StereoError> {
    let got = s.len();
    let (head, tail) = core::mem::take(s)
        .split_at_mut_checked(n)
        .ok_or(StereoError::Buffer {
            what,
            needed: n,
            got,
        })?;
    *s = tail;
    Ok(head)
}

/// Rows of the level-0 grey ring (at least 5: the pyramid reads 5 rows).
pub const fn grey_ring_rows(radius: usize) -> usize {
    let n = 2 * radius + 1;
    if n < 5 {
        5
    } else {
        n
    }
}

/// One eye's grey and response storage.
#[derive(Default)]
struct Eye<'a> {
    ring: &'a mut [u16],
    planes: [&'a mut [u16]; MAX_LEVELS],
    z: [&'a mut [Z]; MAX_LEVELS],
}

/// Grey row `j` of `level` of an eye's `ring` and `planes` (level 0: from
/// the ring, which must hold it).
fn grey_of<'g>(
    ring: &'g [u16],
    planes: &'g [&mut [u16]; MAX_LEVELS],
    level: usize,
    j: usize,
    w: usize,
    ring_rows: NonZeroUsize,
) -> &'g [u16] {
    let (buf, lw, row) = if level == 0 {
        (ring, w, j % ring_rows)
    } else {
        let p = planes.get(level).map_or(&[][..], |p| &**p);
        (p, level_size(w, level), j)
    };
    buf.get(row * lw..(row + 1) * lw).unwrap_or(&[])
}

/// The row-streaming state.
struct Engine<'d, 'a> {
    dem: &'d Dem,
    bank: Bank<'d>,
    w: usize,
    h: usize,
    levels: usize,
    carriers: usize,
    ring_rows: NonZeroUsize,
    pool: usize,
    eyes: [Eye<'a>; 2],
    col: &'a mut [[i32; 3]],
    energy: &'a mut [i32],
    left: &'a mut [i64],
    right: &'a mut [i64],
    pooled: &'a mut [i64],
    picks: &'a mut [i32],
    next_grey: usize,
    next_z: [usize; MAX_LEVELS],
}

/// Row weights of one level for one output row: `(level row, weight)`,
/// weights in units of `2^-level` (bilinear, summed over the pooled rows).
#[derive(Clone, Copy, Default)]
struct RowWeights {
    rows: [(usize, u32); 16],
    n: usize,
}

impl RowWeights {
    fn add(&mut self, j: usize, wgt: u32) {
        if wgt == 0 {
            return;
        }
        let n = self.n;
        if let Some(e) = self.rows.iter_mut().take(n).find(|e| e.0 == j) {
            e.1 += wgt;
        } else if let Some(e) = self.rows.get_mut(n) {
            *e = (j, wgt);
            self.n += 1;
        }
    }

    fn iter(&self) -> impl Iterator<Item = &(usize, u32)> {
        self.rows.iter().take(self.n)
    }
}

/// Runs the stage (sizes checked by the caller).
pub(super) fn run<S: GreyRows>(
    dem: &Dem,
    table: &DemTable<'_>,
    rgb: [&S; 2],
    bufs: &mut StereoBuffers<'_>,
    sink: &mut impl FnMut(usize, usize, DisparityCell),
    probe: &mut impl Probe,
) -> Result<StereoReport, StereoError> {
    let (w, h) = rgb[0].size();
    let p = &dem.params;
    let (levels, carriers, pool) = (
        usize::from(p.levels),
        usize::from(p.carriers),
        usize::from(p.pool_radius),
    );
    let ring_rows = grey_ring_rows(usize::from(p.radius));
    let n = table.disparities();
    let max_shift = dem.layout.max_shift();
    let (l_slots, r_slots) = (2 * pool + 1, 2 * pool + max_shift + 1);
    // Split the scratch.
    let (mut grey, mut z) = (&mut *bufs.grey, &mut *bufs.z);
    let mut eyes: [Eye<'_>; 2] = Default::default();
    for eye in &mut eyes {
        eye.ring = take(&mut grey, ring_rows * w, "grey")?;
        for (l, plane) in eye.planes.iter_mut().enumerate().take(levels).skip(1) {
            *plane = take(&mut grey, level_size(w, l) * level_size(h, l), "grey")?;
        }
        for (l, zr) in eye.z.iter_mut().enumerate().take(levels) {
            let len = super::z_ring_rows(pool, l) * carriers * level_size(w, l);
            *zr = take(&mut z, len, "z")?;
        }
    }
    let mut col = &mut *bufs.col;
    let col = take(&mut col, w, "col")?;
    let mut energy = &mut *bufs.energy;
    let energy = take(&mut energy, 3 * CHUNK * dem.layout.groups(), "energy")?;
    let mut scores = &mut *bufs.scores;
    let left = take(&mut scores, l_slots * (n + 1), "scores")?;
    let right = take(&mut scores, r_slots * (n + 1), "scores")?;
    let pooled = take(&mut scores, n + 1, "scores")?;
    let mut picks = &mut *bufs.picks;
    let picks = take(&mut picks, 2 * w, "picks")?;
    let kernels = dem.kernels.get(..carriers).unwrap_or(&[]);
    let mut e = Engine {
        dem,
        bank: Bank::new(kernels),
        w,
        h,
        levels,
        carriers,
        ring_rows: nonzero(ring_rows),
        pool,
        eyes,
        col,
        energy,
        left,
        right,
        pooled,
        picks,
        next_grey: 0,
        next_z: [0; MAX_LEVELS],
    };
    probe.enter(Step::Pyramid);
    e.planes(rgb);
    let mut report = StereoReport::default();
    for y in 0..h {
        e.row(table, rgb, y, sink, &mut report, probe);
    }
    Ok(report)
}

impl Engine<'_, '_> {
    /// Loads level-0 grey rows up to `j` (inclusive) into the rings.
    fn load_grey<S: GreyRows>(&mut self, rgb: [&S; 2], j: usize) {
        while self.next_grey <= j.min(self.h - 1) {
            let row = self.next_grey;
            let slot = row % self.ring_rows;
            for (eye, img) in self.eyes.iter_mut().zip(rgb) {
                if let Some(dst) = eye.ring.get_mut(slot * self.w..(slot + 1) * self.w) {
                    img.grey_row(row, dst);
                }
            }
            self.next_grey += 1;
        }
    }

    /// The pyramid planes of levels 1.. (level 1 from grey rows streamed
    /// through the level-0 ring, which is then reset).
    fn planes<S: GreyRows>(&mut self, rgb: [&S; 2]) {
        let (w, h) = (self.w, self.h);
        // `levels <= MAX_LEVELS` (`DemParams::check`); `min` shows the
        // compiler, so that splitting the planes at `l` has no panic path.
        for l in 1..self.levels.min(MAX_LEVELS) {
            let (lw, lh) = (level_size(w, l), level_size(h, l));
            let (sw, sh) = (level_size(w, l - 1), level_size(h, l - 1));
            for j in 0..lh {
                let src = |t: usize| (2 * j + t).saturating_sub(2).min(sh - 1);
                if l == 1 {
                    self.load_grey(rgb, src(4));
                }
                for eye in &mut self.eyes {
                    let mut tmp: [&[u16]; 5] = [&[]; 5];
                    // Source rows borrow the ring or plane l − 1; the output
                    // row lives in plane l: split the planes array.
                    let (below, above) = eye.planes.split_at_mut(l);
                    let dst = above
                        .first_mut()
                        .and_then(|p| p.get_mut(j * lw..(j + 1) * lw));
                    for (t, row) in tmp.iter_mut().enumerate() {
                        let r = src(t);
                        *row = if l == 1 {
                            let slot = r % self.ring_rows;
                            eye.ring.get(slot * sw..(slot + 1) * sw).unwrap_or(&[])
                        } else {
                            below
                                .get(l - 1)
                                .and_then(|p| p.get(r * sw..(r + 1) * sw))
                                .unwrap_or(&[])
                        };
                    }
                    if let Some(dst) = dst {
                        pyramid_row(tmp, dst);
                    }
                }
            }
        }
        self.next_grey = 0;
    }

    /// Computes response rows of `level` up to `j` (inclusive), both eyes,
    /// every carrier.
    fn responses<S: GreyRows>(
        &mut self,
        rgb: [&S; 2],
        level: usize,
        j: usize,
        probe: &mut impl Probe,
    ) {
        let (lw, lh) = (level_size(self.w, level), level_size(self.h, level));
        let zrows = nonzero(super::z_ring_rows(self.pool, level));
        let Some(next) = self.next_z.get(level).copied() else {
            return;
        };
        for row in next..=j.min(lh - 1) {
            if level == 0 {
                probe.enter(Step::Pyramid);
                self.load_grey(rgb, row + usize::from(self.dem.params.radius));
                probe.enter(Step::Filters);
            }
            let taps = self.bank.taps();
            for eye in &mut self.eyes {
                let mut rows: [&[u16]; MAX_TAPS] = [&[]; MAX_TAPS];
                for (t, dst) in rows.iter_mut().enumerate().take(taps) {
                    let src = (row + t).saturating_sub(taps / 2).min(lh - 1);
                    *dst = grey_of(eye.ring, &eye.planes, level, src, self.w, self.ring_rows);
                }
                let col = self.col.get_mut(..lw).unwrap_or(&mut []);
                let n = self.carriers * lw;
                let off = (row % zrows) * n;
                if let Some(dst) = eye.z.get_mut(level).and_then(|z| z.get_mut(off..off + n)) {
                    self.bank.row(rows.get(..taps).unwrap_or(&[]), col, dst);
                }
            }
        }
        if let Some(nz) = self.next_z.get_mut(level) {
            *nz = (*nz).max(j.min(lh - 1) + 1);
        }
    }

    /// One output row.
    fn row<S: GreyRows>(
        &mut self,
        table: &DemTable<'_>,
        rgb: [&S; 2],
        y: usize,
        sink: &mut impl FnMut(usize, usize, DisparityCell),
        report: &mut StereoReport,
        probe: &mut impl Probe,
    ) {
        let (w, h, pool) = (self.w, self.h, self.pool);
        let (lo_y, hi_y) = (y.saturating_sub(pool), (y + pool).min(h - 1));
        let mut weights = [RowWeights::default(); MAX_LEVELS];
        probe.enter(Step::Filters);
        for (l, rw) in weights.iter_mut().enumerate().take(self.levels) {
            let lh = level_size(h, l);
            let mask = (1usize << l) - 1;
            for yy in lo_y..=hi_y {
                let (j0, f) = (yy >> l, yy & mask);
                rw.add(j0, ((1usize << l) - f) as u32);
                if f > 0 {
                    rw.add((j0 + 1).min(lh - 1), f as u32);
                }
            }
            let top = rw.iter().map(|e| e.0).max().unwrap_or(0);
            self.responses(rgb, l, top, probe);
        }
        let n = table.disparities();
        let max_shift = self.dem.layout.max_shift();
        let (l_slots, r_slots) = (nonzero(2 * pool + 1), nonzero(2 * pool + max_shift + 1));
        let rows_n = (hi_y - lo_y + 1) as u64;
        let cells = 4 * self.dem.layout.groups() as u64;
        let end = w + pool + max_shift;
        let mut x0 = 0;
        while x0 < end {
            let x1 = (x0 + CHUNK).min(end);
            probe.enter(Step::Energies);
            for x in x0..x1.min(w) {
                self.energies(&weights, x, x - x0);
            }
            probe.enter(Step::Readout);
            for x in x0..x1 {
                if x < w {
                    self.votes(table, x, x - x0, n, 0..=n - 1, l_slots, r_slots);
                }
                // Left pixel c = x − pool is complete.
                if let Some(c) = x.checked_sub(pool).filter(|&c| c < w) {
                    let cols = ((c + pool).min(w - 1) - c.saturating_sub(pool) + 1) as u64;
                    let pk = self.pool_pick(table, c, l_slots, false);
                    let code = match pk {
                        None => -1,
                        Some((pk, total)) => {
                            let need = self.dem.min_energy_q8 * cells * rows_n * cols;
                            if (total as u64) < need {
                                -1
                            } else if pk.margin.is_some_and(|m| {
                                (m << 16) < i128::from(self.dem.min_margin_q16) * pk.scale
                            }) {
                                -2
                            } else {
                                pk.disparity
                            }
                        }
                    };
                    if let Some(s) = self.picks.get_mut(c) {
                        *s = code;
                    }
                }
                // Right pixel c = x − pool − max_shift is complete.
                if let Some(c) = x.checked_sub(pool + max_shift).filter(|&c| c < w) {
                    let code = self
                        .pool_pick(table, c, r_slots, true)
                        .map_or(-1, |(pk, _)| pk.disparity);
                    if let Some(s) = self.picks.get_mut(w + c) {
                        *s = code;
                    }
                }
            }
            x0 = x1;
        }
        // The OFF tests and the output row.
        // The picks hold both eyes' rows (`pick_len`).
        let (lp, rp) = self.picks.split_at_checked(w).unwrap_or((&[], &[]));
        for (x, &code) in lp.iter().enumerate() {
            let mut o = DisparityCell::OFF;
            match code {
                -1 => report.off_texture += 1,
                -2 => report.off_ambiguous += 1,
                d => {
                    let ok = self.dem.lr_tolerance_q8.is_none_or(|tol| {
                        let xr = x as i64 - i64::from((d + 128) >> 8);
                        usize::try_from(xr)
                            .ok()
                            .and_then(|xr| rp.get(xr).copied())
                            .is_some_and(|b| b >= 0 && (b - d).abs() <= tol)
                    });
                    if ok {
                        report.on += 1;
                        let q = d.clamp(0, i32::from(u16::MAX - 1)) as u16;
                        o = DisparityCell::from_raw(U8F8::from_bits(q));
                    } else {
                        report.off_inconsistent += 1;
                    }
                }
            }
            sink(x, y, o);
        }
    }

    /// Vertically pooled energies of every group at full-resolution pixel
    /// `x`, into chunk slot `k`, in `Q8` grey² (one rounding each). The
    /// left term `Σ w·|z_L|²` is pooled once per carrier and shared by its
    /// shifts.
    fn energies(&mut self, weights: &[RowWeights; MAX_LEVELS], x: usize, k: usize) {
        let groups = self.dem.layout.groups();
        let base = 3 * k * groups;
        let Some(dst) = self.energy.get_mut(base..base + 3 * groups) else {
            return;
        };
        let mut dst = dst.chunks_exact_mut(3);
        let step = usize::from(self.dem.layout.shift_step);
        let [left, right] = &self.eyes;
        for (l, rw) in weights.iter().enumerate().take(self.levels) {
            let lw = level_size(self.w, l);
            let zrows = nonzero(super::z_ring_rows(self.pool, l));
            let mask = (1usize << l) - 1;
            let (i0, fx) = (x >> l, (x & mask) as i64);
            let i1 = (i0 + 1).min(lw - 1);
            let w0 = (1i64 << l) - fx;
            let sh = 4 + 2 * l as u32;
            let (zl_all, zr_all) = (
                left.z.get(l).map_or(&[][..], |z| &**z),
                right.z.get(l).map_or(&[][..], |z| &**z),
            );
            let shifts = self.dem.layout.shifts(l);
            for c in 0..self.carriers {
                // Per pooled row: the weights of columns i0 and i1 (units of
                // 4^-l, at most (2·7 + 1)·4^3 = 960), the left responses
                // premultiplied by them (< 2^25) and the right response row.
                let mut taps = [Tap::default(); 16];
                let mut n = 0;
                let mut pooled_left = 0i64;
                for (&(j, wj), tap) in rw.iter().zip(taps.iter_mut()) {
                    let off = ((j % zrows) * self.carriers + c) * lw;
                    let zl = zl_all.get(off..off + lw).unwrap_or(&[]);
                    let (a, b) = (wj as i32 * w0 as i32, wj as i32 * fx as i32);
                    let l0 = zl.get(i0).copied().unwrap_or([0; 2]).map(i32::from);
                    let l1 = zl.get(i1).copied().unwrap_or([0; 2]).map(i32::from);
                    let (la, lb) = (l0.map(|v| a * v), l1.map(|v| b * v));
                    pooled_left += i64::from(la[0]) * i64::from(l0[0])
                        + i64::from(la[1]) * i64::from(l0[1])
                        + i64::from(lb[0]) * i64::from(l1[0])
                        + i64::from(lb[1]) * i64::from(l1[1]);
                    *tap = Tap { a, b, la, lb, off };
                    n += 1;
                }
                for k_s in 0..shifts {
                    let s = k_s * step;
                    let mut acc = [0i64; 3];
                    if (s << l) <= x {
                        acc[0] = pooled_left;
                        for t in taps.iter().take(n) {
                            let zr = zr_all.get(t.off..t.off + lw).unwrap_or(&[]);
                            if let Some(r) = i0.checked_sub(s).and_then(|i| zr.get(i)) {
                                t.add_right(&mut acc, t.a, t.la, *r);
                            }
                            if t.b != 0 {
                                if let Some(r) = i1.checked_sub(s).and_then(|i| zr.get(i)) {
                                    t.add_right(&mut acc, t.b, t.lb, *r);
                                }
                            }
                        }
                    }
                    if let Some(d) = dst.next() {
                        for (d, a) in d.iter_mut().zip(acc) {
                            *d = round_shift(a, sh) as i32;
                        }
                    }
                }
            }
        }
    }

    /// Clears the slots of pixel `x` and adds its votes for the candidates
    /// `cand` (the current read-out: all of them): every group's vote goes
    /// to the left-referenced pixel `x` and the right-referenced pixel
    /// `x − s`.
    #[allow(clippy::too_many_arguments)]
    fn votes(
        &mut self,
        table: &DemTable<'_>,
        x: usize,
        k: usize,
        n: usize,
        cand: core::ops::RangeInclusive<usize>,
        l_slots: NonZeroUsize,
        r_slots: NonZeroUsize,
    ) {
        let (lo, count) = (*cand.start(), cand.end().saturating_sub(*cand.start()) + 1);
        let stride = n + 1;
        let li = (x % l_slots) * stride;
        if let Some(s) = self.left.get_mut(li..li + stride) {
            s.fill(0);
        }
        let ri = (x % r_slots) * stride;
        if let Some(s) = self.right.get_mut(ri..ri + stride) {
            s.fill(0);
        }
        let groups = self.dem.layout.groups();
        let base = 3 * k * groups;
        let mut g = 0;
        for l in 0..self.levels {
            let step = usize::from(self.dem.layout.shift_step);
            for _c in 0..self.carriers {
                for k_s in 0..self.dem.layout.shifts(l) {
                    let s = (k_s * step) << l;
                    let gi = g;
                    g += 1;
                    if s > x {
                        continue;
                    }
                    let e = self
                        .energy
                        .get(base + 3 * gi..base + 3 * gi + 3)
                        .unwrap_or(&[]);
                    let [a, xr, xi] = match *e {
                        [a, b, c] => [a, b, c],
                        _ => continue,
                    };
                    let ri = ((x - s) % r_slots) * stride;
                    let (Some(ls), Some(rs)) = (
                        self.left.get_mut(li..li + stride),
                        self.right.get_mut(ri..ri + stride),
                    ) else {
                        continue;
                    };
                    let wb = table
                        .group_bytes(gi)
                        .get(6 * lo..6 * (lo + count))
                        .unwrap_or(&[]);
                    let (Some(lw), Some(rw)) =
                        (ls.get_mut(lo..lo + count), rs.get_mut(lo..lo + count))
                    else {
                        continue;
                    };
                    for ((lv, rv), c) in lw.iter_mut().zip(rw.iter_mut()).zip(wb.chunks_exact(6)) {
                        let v = match *c {
                            [a0, a1, b0, b1, c0, c1] => {
                                i64::from(a) * i64::from(i16::from_le_bytes([a0, a1]))
                                    + i64::from(xr) * i64::from(i16::from_le_bytes([b0, b1]))
                                    + i64::from(xi) * i64::from(i16::from_le_bytes([c0, c1]))
                            }
                            _ => 0,
                        };
                        *lv += v;
                        *rv += v;
                    }
                    if let (Some(lt), Some(rt)) = (ls.get_mut(n), rs.get_mut(n)) {
                        *lt += 4 * i64::from(a);
                        *rt += 4 * i64::from(a);
                    }
                }
            }
        }
    }

    /// Pools the slots of pixels `c − pool ..= c + pool` (clipped) of the
    /// left or right ring and picks: candidates `0..=min(c, max_disp)`
    /// (left) or `0..=min(w − 1 − c, max_disp)` (right).
    fn pool_pick(
        &mut self,
        table: &DemTable<'_>,
        c: usize,
        slots: NonZeroUsize,
        right: bool,
    ) -> Option<(Pick, i64)> {
        let n = table.disparities();
        let stride = n + 1;
        let (lo, hi) = (c.saturating_sub(self.pool), (c + self.pool).min(self.w - 1));
        self.pooled.fill(0);
        let ring = if right { &*self.right } else { &*self.left };
        for xx in lo..=hi {
            let i = (xx % slots) * stride;
            for (p, v) in self
                .pooled
                .iter_mut()
                .zip(ring.get(i..i + stride).unwrap_or(&[]))
            {
                *p += v;
            }
        }
        let total = self.pooled.get(n).copied().unwrap_or(0);
        let top = if right { self.w - 1 - c } else { c };
        pick(self.pooled.get(..n)?, total, table, 0, top).map(|p| (p, total))
    }
}
