//! One level's run: grey rows, filters, cells and votes, costs, SGM,
//! decisions, and the windows of the next finer level or the output.

use super::buffers::{level_len, take, Work};
use super::decision::{decision, right_from_left, OffTests, Verdict};
use super::rows::{level_row, Cells};
use super::votes::{costs_of, Voter};
use super::{C2f, LeftRight, PATHS};
use crate::disparity::DisparityCell;
use crate::fixed::U8F8;
use crate::image::RgbRows;
use crate::stereo::filters::{grey_row, Bank, MAX_TAPS};
use crate::stereo::phase::PhaseKernel;
use crate::stereo::sgm::{self, Sgm};
use crate::stereo::{DemTable, Probe, Step, StereoError, StereoReport};

/// Where a level's result goes.
pub(super) enum Output<'o, F> {
    /// A coarse level: the windows of the next finer level.
    Map(&'o mut [u8]),
    /// The finest level run: the OFF tests, then the sink (at level 0
    /// pixel by pixel, else each row's verdicts spread over their blocks).
    Sink(&'o mut F, &'o mut StereoReport),
}

/// One level's run.
pub(super) struct Pass<'e, K> {
    pub(super) e: &'e C2f<K>,
    pub(super) k: usize,
    pub(super) w: usize,
    pub(super) h: usize,
    /// Frame size.
    pub(super) full: (usize, usize),
    /// Candidates per pixel.
    pub(super) n: usize,
    /// The votes' geometry (shifts, band).
    voter: Voter,
    /// The OFF tests.
    off: OffTests,
}

impl<'e, K> Pass<'e, K> {
    pub(super) fn new(e: &'e C2f<K>, k: usize, full: (usize, usize)) -> Self {
        let p = &e.params;
        let layout = p.level_params(k).layout();
        let windowed = k < usize::from(p.coarse);
        let (w, n) = (level_len(full.0, k), p.candidates(k));
        Self {
            e,
            k,
            w,
            h: level_len(full.1, k),
            full,
            n,
            voter: Voter::new(
                w,
                n,
                (layout.shifts(0), usize::from(layout.shift_step.max(1))),
                p.band.filter(|_| windowed).map(usize::from),
                usize::from(e.dem.params.carriers),
            ),
            off: OffTests::of(e),
        }
    }

    #[allow(clippy::too_many_lines)]
    pub(super) fn run<S: RgbRows, F: Cells>(
        &self,
        table: &DemTable<'_>,
        src: [&S; 2],
        bufs: &mut Work<'_, '_>,
        parent: Option<&[u8]>,
        mut out: Output<'_, F>,
        probe: &mut impl Probe,
    ) -> Result<usize, StereoError>
    where
        K: PhaseKernel,
    {
        // `n` is at least 1 (every level has a candidate); `max` shows the
        // compiler, so that the chunk loops below have no panic path.
        let (w, h, n) = (self.w, self.h, self.n.max(1));
        let dem = &self.e.dem;
        let carriers = usize::from(dem.params.carriers);
        let taps = 2 * usize::from(dem.params.radius) + 1;
        let r = taps / 2;
        let bank = Bank::new(dem.kernels.get(..carriers).unwrap_or(&[]));
        // Split the scratch.
        let mut grey = &mut **bufs.grey;
        let rings = [
            take(&mut grey, taps * w, "grey")?,
            take(&mut grey, taps * w, "grey")?,
        ];
        let mut rgb = &mut **bufs.rgb;
        let rgb_out = take(&mut rgb, w, "rgb")?;
        let rgb_scratch = rgb;
        let mut z = &mut **bufs.z;
        let zs = [
            take(&mut z, carriers * w, "z")?,
            take(&mut z, carriers * w, "z")?,
        ];
        let mut col = &mut **bufs.col;
        let col = take(&mut col, w, "col")?;
        let stride = n.saturating_add(1);
        let mut sc = &mut **bufs.scores;
        let (sl, sr) = (
            take(&mut sc, w * stride, "scores")?,
            take(&mut sc, w * stride, "scores")?,
        );
        let mut cs = &mut **bufs.costs;
        let costs = [
            take(&mut cs, w * n, "costs")?,
            take(&mut cs, w * n, "costs")?,
        ];
        let los = [take(&mut cs, w, "costs")?, take(&mut cs, w, "costs")?];
        let voters = [take(&mut cs, w, "costs")?, take(&mut cs, w, "costs")?];
        let state = sgm::scratch_len(w, n);
        let sgm_err = |_| StereoError::BadParams("SGM state");
        let sgms = [
            Sgm::new(
                w,
                n,
                self.e.p1_q8,
                self.e.p2_q8,
                take(&mut cs, state, "costs")?,
            )
            .map_err(sgm_err)?,
            Sgm::new(
                w,
                n,
                self.e.p1_q8,
                self.e.p2_q8,
                take(&mut cs, state, "costs")?,
            )
            .map_err(sgm_err)?,
        ];
        let mut su = &mut **bufs.sums;
        let sums = [take(&mut su, w * n, "sums")?, take(&mut su, w * n, "sums")?];
        let picks = &mut **bufs.picks;
        let (lp, rp) = picks.split_at_mut(w.min(picks.len()));
        let [costs_l, costs_r] = costs;
        let [lo_l, lo_r] = los;
        let [vo_l, vo_r] = voters;
        let [sum_l, sum_r] = sums;
        let [ring_l, ring_r] = rings;
        let [z_l, z_r] = zs;
        let [mut sgm_l, mut sgm_r] = if u32::from(self.e.params.paths) == PATHS {
            sgms
        } else {
            sgms.map(Sgm::without_diagonals)
        };
        let groups = (carriers * self.voter.shifts) as u64;
        let (wc, hc) = (
            level_len(self.full.0, self.k + 1),
            level_len(self.full.1, self.k + 1),
        );
        let lr = self.e.params.left_right;
        let eyes = if lr.reads_right() { 2 } else { 1 };
        let mut next = 0;
        let mut cells = 0;
        for y in 0..h {
            // Grey rows up to y + r, both eyes.
            probe.enter(Step::Pyramid);
            while next <= (y + r).min(h - 1) {
                let slot = next % taps;
                for (ring, s) in [&mut *ring_l, &mut *ring_r].into_iter().zip(src) {
                    level_row(s, self.k, next, rgb_out, rgb_scratch);
                    if let Some(dst) = ring.get_mut(slot * w..(slot + 1) * w) {
                        grey_row(rgb_out, dst);
                    }
                }
                next += 1;
            }
            probe.enter(Step::Filters);
            for (ring, zrow) in [(&*ring_l, &mut *z_l), (&*ring_r, &mut *z_r)] {
                let mut rows: [&[u16]; MAX_TAPS] = [&[]; MAX_TAPS];
                for (t, dst) in rows.iter_mut().enumerate().take(taps) {
                    let j = (y + t).saturating_sub(r).min(h - 1) % taps;
                    *dst = ring.get(j * w..(j + 1) * w).unwrap_or(&[]);
                }
                bank.row(rows.get(..taps).unwrap_or(&[]), col, zrow);
            }
            // Windows of this row.
            probe.enter(Step::Energies);
            for (eye, lo) in [&mut *lo_l, &mut *lo_r].into_iter().enumerate() {
                let row = parent.and_then(|m| {
                    let yc = (y / 2).min(hc.saturating_sub(1));
                    let base = eye * wc * hc + yc * wc;
                    m.get(base..base + wc)
                });
                for (x, v) in lo.iter_mut().enumerate() {
                    *v = row
                        .and_then(|m| m.get((x / 2).min(wc.saturating_sub(1))))
                        .map_or(0, |&b| u16::from(b));
                }
            }
            // Cells and votes: each pixel of each eye takes the votes of the
            // shifts in its band (the cell of left x and right x − s).
            let (z2, lo2) = ([&*z_l, &*z_r], [&*lo_l, &*lo_r]);
            let (sc2, vo2) = ([&mut *sl, &mut *sr], [&mut *vo_l, &mut *vo_r]);
            cells += self
                .voter
                .votes(table, z2, lo2, sc2, vo2, col, lr.reads_right());
            // Costs, aggregation, decisions.
            probe.enter(Step::Readout);
            let need = |total: i64, voters: u16| -> bool {
                let cells = if self.voter.band.is_some() {
                    u64::from(voters)
                } else {
                    groups
                };
                total > 0 && (total as u64) >= dem.min_energy_q8 * 4 * cells
            };
            for (eye, (sc, cost)) in [(&mut *sl, &mut *costs_l), (&mut *sr, &mut *costs_r)]
                .into_iter()
                .enumerate()
                .take(eyes)
            {
                let (lo, vo) = if eye == 0 {
                    (&*lo_l, &*vo_l)
                } else {
                    (&*lo_r, &*vo_r)
                };
                for (x, (raw, ((&lo, &v), dst))) in sc
                    .chunks_exact_mut(stride)
                    .zip(lo.iter().zip(vo).zip(cost.chunks_exact_mut(n)))
                    .enumerate()
                {
                    let top = if eye == 0 { x } else { w - 1 - x };
                    let lo = usize::from(lo);
                    let total = raw.get(n).copied().unwrap_or(0);
                    if !need(total, v) || lo > top {
                        dst.fill(0);
                        continue;
                    }
                    let valid = (top - lo + 1).min(n);
                    if valid == n {
                        K::costs(raw, total, table, lo, dst);
                    } else {
                        costs_of::<0>(raw, total, table, lo, valid, dst);
                    }
                }
            }
            probe.enter(Step::Sgm);
            sgm_l
                .push_row_with::<K>(costs_l, lo_l, sum_l)
                .map_err(sgm_err)?;
            if lr.reads_right() {
                sgm_r
                    .push_row_with::<K>(costs_r, lo_r, sum_r)
                    .map_err(sgm_err)?;
            }
            probe.enter(Step::Readout);
            // Right-referenced decisions first: the left-right check reads
            // them.
            match lr {
                LeftRight::Derived => right_from_left(n, sl, lo_l, sum_l, sum_r, rp),
                // The coarse levels' windows still read `rp`: none.
                LeftRight::Off => rp.fill(-1),
                LeftRight::Read => {
                    for (x, ((pk, raw), (&lo, s))) in rp
                        .iter_mut()
                        .zip(sr.chunks_exact(stride))
                        .zip(lo_r.iter().zip(sum_r.chunks_exact(n)))
                        .enumerate()
                    {
                        *pk = decision(n, raw, lo, s, w - 1 - x).map_or(-1, |d| d.disparity);
                    }
                }
            }
            for (x, ((pk, raw), ((&lo, s), &v))) in lp
                .iter_mut()
                .zip(sl.chunks_exact(stride))
                .zip(lo_l.iter().zip(sum_l.chunks_exact(n)).zip(vo_l.iter()))
                .enumerate()
            {
                let d = decision(n, raw, lo, s, x);
                *pk = d.map_or(-1, |d| d.disparity);
                if let Output::Sink(sink, report) = &mut out {
                    let total = raw.get(n).copied().unwrap_or(0);
                    let verdict = self.off.verdict(x, d, need(total, v), rp);
                    if self.k == 0 {
                        sink.cell(x, y, verdict.count(report));
                    } else if let Some(c) = col.get_mut(x) {
                        // The row's votes are done, so `col` is free.
                        c[0] = verdict.code();
                    }
                }
            }
            match &mut out {
                Output::Map(map) => self.windows_below(y, [&*lp, &*rp], map),
                Output::Sink(sink, report) if self.k > 0 => {
                    self.spread(y, col, &mut **sink, report);
                }
                Output::Sink(..) => {}
            }
        }
        Ok(cells)
    }

    /// The output rows of level row `y` at a finest level `k > 0`: frame
    /// rows `y·2^k ..` (to the frame's last row after the level's last
    /// row), each level pixel's verdict in `col` (its disparity times
    /// `2^k`) over frame columns `x·2^k ..` (to the frame's last column
    /// after the level's last pixel). Each verdict is counted once for its
    /// whole block and its cell kept in `col` (`[1]`, the bits), so that
    /// each frame row is only filled.
    fn spread(
        &self,
        y: usize,
        col: &mut [[i32; 3]],
        sink: &mut impl Cells,
        report: &mut StereoReport,
    ) {
        let (fw, fh) = self.full;
        let k = self.k;
        let step = 1usize << k;
        let first = y << k;
        let end = if y + 1 >= self.h { fh } else { first + step };
        let rows = end.saturating_sub(first);
        let last = self.w.saturating_sub(1);
        let col = col.get_mut(..self.w).unwrap_or(&mut []);
        for (x, c) in col.iter_mut().enumerate() {
            let cols = if x == last {
                fw.saturating_sub(x << k)
            } else {
                step
            };
            let cell = Verdict::from_code(c[0])
                .scaled(k)
                .count_n(report, cols * rows);
            c[1] = i32::from(cell.raw().to_bits());
        }
        let cell = |c: &[i32; 3]| DisparityCell::from_raw(U8F8::from_bits(c[1] as u16));
        // The level's last pixel also takes the frame's leftover columns.
        let body = (last << k).min(fw);
        for fy in first..end {
            if let Some(row) = sink.row() {
                let (head, tail) = row.split_at_mut(body.min(row.len()));
                for (dst, c) in head.chunks_exact_mut(step).zip(col.iter()) {
                    dst.fill(cell(c));
                }
                if let (Some(c), Some(dst)) = (col.last(), tail.get_mut(..fw - body)) {
                    dst.fill(cell(c));
                }
                sink.row_done(fy);
            } else {
                for (x, c) in col.iter().enumerate() {
                    let end = if x == last { fw } else { (x + 1) << k };
                    for fx in x << k..end {
                        sink.cell(fx, fy, cell(c));
                    }
                }
            }
        }
    }

    /// Stores the next finer level's window `lo` for row `y` of both eyes'
    /// decisions `picks` (`U8F8` bits, negative: none).
    fn windows_below(&self, y: usize, picks: [&[i32]; 2], map: &mut [u8]) {
        let p = &self.e.params;
        let k = self.k.saturating_sub(1);
        let (all_f, n_f) = (usize::from(p.level_max_disp(k)) + 1, p.candidates(k));
        let radius = usize::from(p.radius);
        for (eye, picks) in picks.into_iter().enumerate() {
            let base = eye * self.w * self.h + y * self.w;
            let Some(dst) = map.get_mut(base..base + self.w) else {
                continue;
            };
            for (m, &d) in dst.iter_mut().zip(picks) {
                let lo = usize::try_from((d + 64) >> 7).map_or(0, |c| {
                    c.saturating_sub(radius).min(all_f.saturating_sub(n_f))
                });
                *m = lo.min(255) as u8;
            }
        }
    }
}
