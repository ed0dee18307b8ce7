//! The coarse-to-fine engine: the DEM read-out searching a few candidates
//! per pixel, with row-streamed semi-global aggregation, mirroring the f32
//! reference `protogist_host::reference::stereo::c2f::stereo_c2f` with one
//! pyramid level per c2f level (`levels = 1`), no pooling (`pool_radius =
//! 0`) and 5 SGM paths, or 3 ([`C2fParams::paths`]) (docs/STEREO.md). The
//! left-right check ([`LeftRight`]) reads the right eye, derives its map
//! from the left path sums, or is off; the named operating points are
//! [`C2fParams::FULL`], [`C2fParams::FAST`], [`C2fParams::HALF`],
//! [`C2fParams::FAST_LOW_PENALTY`] and [`C2fParams::HALF_LOW_PENALTY`].
//!
//! The code, by concern: `params` (the parameters and the named points),
//! `buffers` (the `const fn` sizes and [`C2fBuffers`]), `rows` (the levels'
//! rows in, the sinks out), `pass` (one level's run), `votes` (cells,
//! votes, costs) and `decision` (argmin, derived right map, OFF tests).
//!
//! ```text
//! level K (w/2^K) ── full search 0..=⌈D/2^K⌉, every cell group ──► lo maps
//! level k < K     ── window lo..lo+n (n = 2R + 1) from the parent pixel,
//!                    groups within `band` px of the window's centre ──► …
//! level 0         ── the same, then the OFF tests ──► sink(x, y, cell)
//! ```
//!
//! **Levels.** Level `k` is the pair halved `k` times by rounded 2x2 means of
//! the RGB pixels (`⌊w/2^k⌋ x ⌊h/2^k⌋`), produced row by row from the frames
//! ([`RgbRows`]), so no level is stored: a level's grey rows go through a
//! ring of `2r + 1` rows. Each level runs the DEM
//! with its own decoder table (`max_disp` = `⌈D/2^k⌉`).
//!
//! **Windows.** A level finer than the coarsest searches, per pixel and
//! eye, `n = min(2R + 1, max_disp + 1)` consecutive candidates from `lo`,
//! where `lo = min(round(2·d_c) − R, max_disp + 1 − n)` (not below 0) from
//! the parent pixel's argmax `d_c` (before the OFF tests), and `lo = 0`
//! where the parent has none. The coarser level stores only these `lo`
//! (one byte per pixel and eye). Candidates beyond the border (`d > x`
//! left-referenced, `d > w − 1 − x` right-referenced) cost the window's
//! worst valid cost; a window wholly beyond the border gives no estimate.
//!
//! **Band.** With `band = Some(b)`, a windowed pixel is decoded only from
//! the cell groups whose shift `s` satisfies `|s − centre| ≤ b`, centre
//! `lo + (n − 1)/2`; the texture test then counts only those groups. Cells
//! are evaluated only where some pixel takes their vote: the left pixel `x`
//! or the right pixel `x − s`.
//!
//! **Finest level.** With [`C2fParams::finest`] `= F > 0` the run stops at
//! level `F`: its OFF tests run there (the left-right check on level `F`'s
//! maps) and each of its cells goes to the sink over its `2^F x 2^F` block
//! of the frame, its disparity times `2^F` (frame pixel `(x, y)` takes level
//! pixel `(min(x >> F, w_F − 1), min(y >> F, h_F − 1))`, so an odd frame's
//! leftover column and row take the last block's), row by row. The levels
//! below `F` are not run, so the operations fall by about `4^F` for a map
//! with `2^F` times coarser steps; it is the same as running the engine
//! on the pair halved `F` times with `F` coarse levels fewer and
//! `⌈D/2^F⌉`, spread (`tests/tests/stereo_c2f_core.rs`). The report counts
//! frame pixels.
//!
//! **Formats.** Cell energies in `Q8` grey² (rounded once), votes and
//! totals in `i64` from the `i16` table. The scores
//! `n(d) = raw(d)·2^bf − bias(d)·T·2^wf` (the Poisson score `raw/T − bias`
//! without a division) give
//! the SGM costs `C(d) = (max n − n(d)) · m / Σ_e (max n − n(e))` over the
//! `m` valid candidates (the reference's gap to the best over the mean
//! gap), in `Q8` (`u16`, at most `256·m`): the gaps are truncated to 15
//! significant bits (block floating point per pixel) and the quotient
//! rounded once. P1 and P2 are in the same `Q8` units; the 5 paths run in
//! [`super::sgm::Sgm`] exactly. Pixels without evidence (below the
//! texture threshold) cost 0 in their window. The decision is the argmin
//! of the path sums in the window, with the parabola through its
//! neighbours (`U8F8`) and the margin to the best sum more than 1 px
//! away, per path, against `min_margin`.
//!
//! **Error bound** against the f32 reference: each cost is within
//! `2^-8·(1/2 + m·2^-14·m)` mean gaps of the reference's (the rounding,
//! and the truncation of each gap to 15 bits against a largest gap of at
//! least `2^14` units), plus the energies' bound (ERROR_BOUNDS.md section
//! 7). Path sums are exact on those costs, so decisions differ only where
//! two candidates' sums are within the accumulated cost error, i.e. at
//! near ties; the proptest of `tests/tests/stereo_c2f_core.rs` requires
//! 99 % of the pixels valid in both to be within 0.25 px of the reference
//! and 99 % of the OFF decisions to agree.

mod buffers;
mod decision;
mod params;
mod pass;
mod rows;
mod votes;

/// The row source of the frames, beside [`crate::image::ImageView`].
pub use crate::image::RgbRows;
pub use buffers::{
    cost_len, grey_len, level_len, map_len, pick_len, rgb_len, score_len, scratch_bytes, sum_len,
    z_len, C2fBuffers,
};
pub use params::{C2fParams, LeftRight, MAX_COARSE};

use super::phase::{Phase, PhaseBuffers, PhaseKernel, Refiner, SafePhase};
use super::{param, Dem, DemTable, Probe, StereoError, StereoReport};
use crate::disparity::DisparityCell;
use crate::image::{ImageError, ImageViewMut};
use buffers::Work;
use core::marker::PhantomData;
use pass::{Output, Pass};
use rows::{Cells, Map, Plain, Refined};

/// The read-out's costs of one pixel whose window's candidates are all
/// valid: the portable [`PhaseKernel::costs`]. `raw` holds the window's
/// scores (`raw[..n]`, overwritten; `n = out.len()`) and `total` (> 0) the
/// sum of its cells' energies; `table` is the level's decoder table and
/// `lo` the window's first candidate; `out` takes the `Q8` costs.
pub fn costs(raw: &mut [i64], total: i64, table: &DemTable<'_>, lo: usize, out: &mut [u16]) {
    match out.len() {
        5 => votes::costs_of::<5>(raw, total, table, lo, 5, out),
        9 => votes::costs_of::<9>(raw, total, table, lo, 9, out),
        3 => votes::costs_of::<3>(raw, total, table, lo, 3, out),
        n => votes::costs_of::<0>(raw, total, table, lo, n, out),
    }
}

/// The number of SGM paths (the 5 of one top-to-bottom pass).
pub const PATHS: u32 = 5;
/// Fraction bits of the SGM costs and penalties.
pub const COST_FRAC: u32 = 8;

/// The set-up engine: checked parameters, kernels, thresholds; `K` is the
/// phase refinement's row step ([`PhaseKernel`]: the portable
/// [`SafePhase`] from [`C2f::new`], a target's own from
/// [`C2f::with_kernel`]; the same bits either way).
#[derive(Clone, Debug, PartialEq)]
pub struct C2f<K = SafePhase> {
    /// The parameters.
    pub params: C2fParams,
    /// The model of level 0 (kernels and thresholds, the same at every
    /// level).
    pub dem: Dem,
    /// P1 in `Q8`.
    pub p1_q8: u16,
    /// P2 in `Q8`.
    pub p2_q8: u16,
    /// Ambiguity threshold on the path-sum margin: OFF when
    /// `margin·2^16 < min_margin_sums`.
    pub min_margin_sums: i64,
    /// The phase refinement, set up.
    pub phase: Option<Phase>,
    /// The phase kernel.
    kernel: PhantomData<fn() -> K>,
}

impl C2f {
    /// Checks `params` and builds the kernels (one-time setup, floats via
    /// `libm`), with the portable phase step [`SafePhase`].
    ///
    /// # Errors
    /// [`StereoError::BadParams`].
    pub fn new(params: &C2fParams) -> Result<Self, StereoError> {
        Self::with_kernel(params)
    }
}

impl<K: PhaseKernel> C2f<K> {
    /// [`C2f::new`] with the phase refinement's row step by kernel `K`
    /// (e.g. the firmware's assembly one).
    ///
    /// # Errors
    /// [`StereoError::BadParams`].
    #[allow(
        clippy::float_arithmetic,
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss
    )]
    pub fn with_kernel(params: &C2fParams) -> Result<Self, StereoError> {
        param(params.dem.levels == 1, "coarse to fine needs levels = 1")?;
        param(
            params.dem.pool_radius == 0,
            "coarse to fine needs pool_radius = 0",
        )?;
        param(
            (1..=MAX_COARSE).contains(&usize::from(params.coarse)),
            "coarse levels must be 1..=3",
        )?;
        param(
            params.p1 >= 0.0 && params.p2 >= params.p1 && params.p2 <= 128.0,
            "SGM penalties must satisfy 0 <= p1 <= p2 <= 128",
        )?;
        param(
            params.paths == 3 || u32::from(params.paths) == PATHS,
            "SGM paths must be 3 or 5",
        )?;
        param(
            params.finest <= params.coarse,
            "the finest level must be at most the coarse levels",
        )?;
        let dem = Dem::new(&params.dem)?;
        let q8 = |v: f32| libm::roundf(v * 256.0) as u16;
        let (p1_q8, p2_q8) = (q8(params.p1), q8(params.p2));
        // Costs are at most 256·n: with P2 they must fit the SGM's u16.
        let n_max = (0..params.levels())
            .map(|k| params.candidates(k))
            .max()
            .unwrap_or(1);
        param(
            256 * n_max + usize::from(p2_q8) <= usize::from(u16::MAX),
            "too many candidates per pixel for the SGM costs",
        )?;
        // margin_sums / (256·paths) < min_margin  ⇔  margin_sums·2^16 <
        // q16·256·paths.
        let min_margin_sums = dem
            .min_margin_q16
            .saturating_mul(256 * i64::from(params.paths));
        let phase = match &params.phase {
            Some(ph) => Some(Phase::new(ph, params.dem.max_disp)?),
            None => None,
        };
        Ok(Self {
            params: *params,
            dem,
            p1_q8,
            p2_q8,
            min_margin_sums,
            phase,
            kernel: PhantomData,
        })
    }

    /// Checks the sizes of a run and the tables (one per level, level 0
    /// first).
    ///
    /// # Errors
    /// [`StereoError`]: mismatched sizes, a level below the filter
    /// support, `max_disp` not below a level's width, a table of another
    /// layout, or a table count other than `K + 1`.
    pub fn check(
        &self,
        tables: &[DemTable<'_>],
        left: (usize, usize),
        right: (usize, usize),
    ) -> Result<(), StereoError> {
        if left != right {
            return Err(StereoError::SizeMismatch { left, right });
        }
        if tables.len() != self.params.levels() {
            return Err(StereoError::BadParams("one decoder table per level"));
        }
        let min = self.params.dem.min_size();
        for (k, table) in tables.iter().enumerate() {
            let p = self.params.level_params(k);
            let size = (level_len(left.0, k), level_len(left.1, k));
            if size.0 < min || size.1 < min {
                return Err(StereoError::TooSmall { min, got: size });
            }
            if usize::from(p.max_disp) >= size.0 {
                return Err(StereoError::MaxDispTooLarge {
                    max_disp: p.max_disp,
                    width: size.0,
                });
            }
            let expected = p.layout();
            if table.layout != expected {
                return Err(StereoError::DecoderMismatch {
                    got: table.layout,
                    expected,
                });
            }
        }
        Ok(())
    }

    /// Runs the engine on a pair: every output cell goes to `sink(x, y,
    /// cell)` row by row (left-referenced, `U8F8` px or OFF); `tables[k]` is
    /// level `k`'s decoder. With [`C2fParams::phase`] each output row is
    /// refined ([`Refiner::flush`], the step by `K`) before it goes to
    /// `sink`.
    ///
    /// # Errors
    /// As [`C2f::check`], and [`StereoError::Buffer`] for short buffers,
    /// before any cell is produced.
    pub fn run<S: RgbRows>(
        &self,
        tables: &[DemTable<'_>],
        left: &S,
        right: &S,
        bufs: &mut C2fBuffers<'_>,
        sink: &mut impl FnMut(usize, usize, DisparityCell),
        probe: &mut impl Probe,
    ) -> Result<StereoReport, StereoError> {
        let Some(phase) = &self.phase else {
            return self.run_levels(tables, left, right, bufs, &mut Plain(sink), probe);
        };
        self.check(tables, left.size(), right.size())?;
        let C2fBuffers { phase: pb, .. } = bufs;
        let pb = PhaseBuffers {
            rgb: &mut *pb.rgb,
            v: &mut *pb.v,
            z: &mut *pb.z,
            row: &mut *pb.row,
        };
        let mut refiner = Refiner::<S, K>::with_kernel(phase, left, right, pb)?;
        let mut rest = C2fBuffers {
            grey: &mut *bufs.grey,
            rgb: &mut *bufs.rgb,
            z: &mut *bufs.z,
            col: &mut *bufs.col,
            scores: &mut *bufs.scores,
            costs: &mut *bufs.costs,
            sums: &mut *bufs.sums,
            picks: &mut *bufs.picks,
            maps: &mut *bufs.maps,
            phase: PhaseBuffers {
                rgb: &mut [],
                v: &mut [],
                z: &mut [],
                row: &mut [],
            },
        };
        let mut refined = Refined {
            refiner: &mut refiner,
            sink,
        };
        self.run_levels(tables, left, right, &mut rest, &mut refined, probe)
    }

    /// [`C2f::run`] into a map of the frame's size (every cell written):
    /// the same cells, but a level `k > 0` without the phase refinement
    /// fills each frame row whole instead of cell by cell.
    ///
    /// # Errors
    /// As [`C2f::run`], and [`StereoError::Image`] for a map of another
    /// size than the frames.
    pub fn run_into<S: RgbRows>(
        &self,
        tables: &[DemTable<'_>],
        left: &S,
        right: &S,
        bufs: &mut C2fBuffers<'_>,
        map: &mut ImageViewMut<'_, DisparityCell>,
        probe: &mut impl Probe,
    ) -> Result<StereoReport, StereoError> {
        if map.size() != left.size() {
            return Err(StereoError::Image(ImageError::SizeMismatch {
                expected: left.size(),
                got: map.size(),
            }));
        }
        if self.phase.is_some() {
            return self.run(
                tables,
                left,
                right,
                bufs,
                &mut |x, y, c| {
                    map.set(x, y, c);
                },
                probe,
            );
        }
        self.run_levels(tables, left, right, bufs, &mut Map { map, next: 0 }, probe)
    }

    /// [`C2f::run`] without the phase refinement.
    fn run_levels<S: RgbRows>(
        &self,
        tables: &[DemTable<'_>],
        left: &S,
        right: &S,
        bufs: &mut C2fBuffers<'_>,
        sink: &mut impl Cells,
        probe: &mut impl Probe,
    ) -> Result<StereoReport, StereoError> {
        self.check(tables, left.size(), right.size())?;
        let (w, h) = left.size();
        let p = &self.params;
        let need = [
            ("grey", bufs.grey.len(), grey_len(w, p)),
            ("rgb", bufs.rgb.len(), rgb_len(w, p)),
            ("z", bufs.z.len(), z_len(w, p)),
            ("col", bufs.col.len(), w),
            ("scores", bufs.scores.len(), score_len(w, p)),
            ("costs", bufs.costs.len(), cost_len(w, p)),
            ("sums", bufs.sums.len(), sum_len(w, p)),
            ("picks", bufs.picks.len(), pick_len(w)),
            ("maps", bufs.maps.len(), map_len(w, h, p)),
        ];
        if let Some(&(what, got, needed)) = need.iter().find(|e| e.1 < e.2) {
            return Err(StereoError::Buffer { what, needed, got });
        }
        let mut report = StereoReport::default();
        let levels = p.levels();
        // Maps of odd levels in the first part, of even levels in the
        // second: a level reads its parent's part and writes its own.
        let C2fBuffers {
            grey,
            rgb,
            z,
            col,
            scores,
            costs,
            sums,
            picks,
            maps,
            ..
        } = bufs;
        let mut work = Work {
            grey,
            rgb,
            z,
            col,
            scores,
            costs,
            sums,
            picks,
        };
        let split = 2 * level_len(w, 1) * level_len(h, 1);
        let (odd, even) = maps.split_at_mut(split.min(maps.len()));
        let finest = usize::from(p.finest);
        for k in (finest..levels).rev() {
            let (mine, parent) = if k % 2 == 1 {
                (&mut *odd, &*even)
            } else {
                (&mut *even, &*odd)
            };
            let table = tables.get(k).ok_or(StereoError::BadParams("no table"))?;
            let pass = Pass::new(self, k, (w, h));
            let parent = (k + 1 < levels).then_some(parent);
            let out = if k == finest {
                Output::Sink(&mut *sink, &mut report)
            } else {
                Output::Map(mine)
            };
            report.cells += pass.run(table, [left, right], &mut work, parent, out, probe)?;
        }
        Ok(report)
    }
}
