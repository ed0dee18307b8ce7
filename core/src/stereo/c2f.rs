//! The coarse-to-fine engine: the DEM read-out searching a few candidates
//! per pixel, with row-streamed semi-global aggregation, mirroring the f32
//! reference `protogist_host::reference::stereo::c2f::stereo_c2f` with one
//! pyramid level per c2f level (`levels = 1`), no pooling (`pool_radius =
//! 0`) and 5 SGM paths, or 3 ([`C2fParams::paths`]) (docs/STEREO.md, "The
//! coarse-to-fine engine in core"). With [`C2fParams::lr_from_left`] the
//! left-right check's right map comes from the left path sums and the
//! right eye is not run.
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
//! ring of `2r + 1` rows as in [`super::readout`]. Each level runs the DEM
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
//! **Formats.** Energies as the full read-out (`Q8` grey², rounded once),
//! votes and totals in `i64` from the `i16` table. The scores
//! `n(d) = raw(d)·2^bf − bias(d)·T·2^wf` ([`super::readout::pick`]) give
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

use super::filters::{grey_row, Bank, MAX_TAPS, Z};
use super::phase::{self, Phase, PhaseBuffers, PhaseKernel, PhaseParams, Refiner, SafePhase};
use super::readout::take;
use super::sgm::{self, Sgm};
use super::{param, Dem, DemParams, DemTable, Probe, Step, StereoError, StereoReport};
use crate::disparity::DisparityCell;
use crate::fixed::U8F8;
use crate::image::{ImageView, Rgb8};

/// Largest number of coarse levels.
pub const MAX_COARSE: usize = 3;
/// The number of SGM paths (the 5 of one top-to-bottom pass).
pub const PATHS: u32 = 5;
/// Fraction bits of the SGM costs and penalties.
pub const COST_FRAC: u32 = 8;

/// RGB rows of an input frame, on demand: a frame in memory, or a camera
/// that renders rows as the engine asks for them.
pub trait RgbRows {
    /// `(width, height)`.
    fn size(&self) -> (usize, usize);
    /// Row `y` (`y < height`) into `out` (`width` long).
    fn rgb_row(&self, y: usize, out: &mut [Rgb8]);
}

impl RgbRows for ImageView<'_, Rgb8> {
    fn size(&self) -> (usize, usize) {
        ImageView::size(self)
    }

    fn rgb_row(&self, y: usize, out: &mut [Rgb8]) {
        if let Some(row) = self.row(y) {
            for (o, &p) in out.iter_mut().zip(row) {
                *o = p;
            }
        }
    }
}

/// The parameters of the engine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct C2fParams {
    /// The model at every level (`max_disp` is level 0's); `levels` must be
    /// 1 and `pool_radius` 0.
    pub dem: DemParams,
    /// Coarse levels `K` (1..=[`MAX_COARSE`]).
    pub coarse: u8,
    /// Window half width `R`: `2R + 1` candidates at the finer levels.
    pub radius: u8,
    /// Decode a windowed pixel only from the groups within this many px of
    /// its window's centre (`None`: every group).
    pub band: Option<u8>,
    /// SGM penalty for a 1 px step, in mean cost gaps.
    pub p1: f32,
    /// SGM penalty for a larger step (`>= p1`), in mean cost gaps.
    pub p2: f32,
    /// The left-right check against a right map derived from the left
    /// map's path sums, as OpenCV's SGBM does (`Pass::right_from_left`),
    /// instead of the right-referenced read-out: the right eye's votes,
    /// costs and aggregation are not run. Default false.
    pub lr_from_left: bool,
    /// SGM paths: [`PATHS`] (5: left→right, right→left, top→bottom and the
    /// two diagonals from above) or 3 (without the diagonals). Default 5.
    pub paths: u8,
    /// The finest level run, `F` (0..=`coarse`). Default 0. With `F > 0`
    /// the levels below it are not run: level `F`'s map is the output,
    /// each of its cells filling its `2^F x 2^F` block of the frame (the
    /// last row and column of blocks also the frame's leftover rows and
    /// columns) with its disparity times `2^F` (module docs, "Finest
    /// level"). [`C2f::run`] still takes and checks one table per level.
    pub finest: u8,
    /// Refine the output map with the phase of the frame's own 0° Gabor
    /// responses ([`super::phase`]): with `finest` 1, a map of the frame's
    /// resolution from the half-size level. Default `None`.
    pub phase: Option<PhaseParams>,
}

impl C2fParams {
    /// `--levels 1 --pool 0 --sgm --paths 5 --c2f 2 --c2f-radius 2
    /// --c2f-band 2 --p2 4` of the reference with `max_disp` 31 (the
    /// firmware's 32 disparities) and P1 0.25: P2 and the margin (0) chosen
    /// on the held-out Motorcycle pair (docs/STEREO.md, "The coarse-to-fine
    /// engine in core").
    pub const DEFAULT: Self = Self {
        dem: DemParams {
            max_disp: 31,
            levels: 1,
            pool_radius: 0,
            ..DemParams::DEFAULT
        },
        coarse: 2,
        radius: 2,
        band: Some(2),
        p1: 0.25,
        p2: 4.0,
        lr_from_left: false,
        paths: PATHS as u8,
        finest: 0,
        phase: None,
    };

    /// `max_disp` of level `k`: `⌈D / 2^k⌉`.
    pub const fn level_max_disp(&self, k: usize) -> u8 {
        let d = self.dem.max_disp as usize;
        let m = d.div_ceil(1 << k);
        if m > 255 {
            255
        } else {
            m as u8
        }
    }

    /// The model of level `k`.
    pub const fn level_params(&self, k: usize) -> DemParams {
        let mut p = self.dem;
        p.max_disp = self.level_max_disp(k);
        p
    }

    /// Candidates per pixel at level `k`: all of them at the coarsest,
    /// `min(2R + 1, max_disp + 1)` below.
    pub const fn candidates(&self, k: usize) -> usize {
        let all = self.level_max_disp(k) as usize + 1;
        let win = 2 * self.radius as usize + 1;
        if k >= self.coarse as usize || win > all {
            all
        } else {
            win
        }
    }

    /// Levels, `K + 1` (0 for bad parameters).
    const fn levels(&self) -> usize {
        if self.coarse as usize > MAX_COARSE {
            0
        } else {
            self.coarse as usize + 1
        }
    }
}

impl Default for C2fParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Width of level `k`: `⌊w / 2^k⌋`.
pub const fn level_len(n: usize, k: usize) -> usize {
    n >> k
}

/// `u16` elements of the grey rings: `2r + 1` rows of level 0 per eye.
pub const fn grey_len(w: usize, p: &C2fParams) -> usize {
    2 * (2 * p.dem.radius as usize + 1) * w
}

/// `Rgb8` elements of the row scratch: the longest chain of 2x2 means,
/// `⌊w/2^k⌋ + Σ_{i<k} 2·⌊w/2^i⌋` over the levels.
pub const fn rgb_len(w: usize, p: &C2fParams) -> usize {
    let mut best = 0;
    let mut k = 0;
    while k < p.levels() {
        let mut n = level_len(w, k);
        let mut i = 0;
        while i < k {
            n += 2 * level_len(w, i);
            i += 1;
        }
        if n > best {
            best = n;
        }
        k += 1;
    }
    best
}

/// [`Z`] elements of the response rows: per eye and carrier, one row.
pub const fn z_len(w: usize, p: &C2fParams) -> usize {
    2 * p.dem.carriers as usize * w
}

/// Largest `width · candidates` over the levels.
const fn row_cells(w: usize, p: &C2fParams) -> usize {
    let mut best = 0;
    let mut k = 0;
    while k < p.levels() {
        let n = level_len(w, k) * p.candidates(k);
        if n > best {
            best = n;
        }
        k += 1;
    }
    best
}

/// `i64` elements of the score rows: per eye, pixel and candidate, plus
/// each pixel's total.
pub const fn score_len(w: usize, p: &C2fParams) -> usize {
    let mut best = 0;
    let mut k = 0;
    while k < p.levels() {
        let n = level_len(w, k) * (p.candidates(k) + 1);
        if n > best {
            best = n;
        }
        k += 1;
    }
    2 * best
}

/// `u16` elements of the cost rows, the windows and the voter counts of
/// both eyes, and of the two SGM states.
pub const fn cost_len(w: usize, p: &C2fParams) -> usize {
    let mut state = 0;
    let mut k = 0;
    while k < p.levels() {
        let n = sgm::scratch_len(level_len(w, k), p.candidates(k));
        if n > state {
            state = n;
        }
        k += 1;
    }
    2 * row_cells(w, p) + 4 * w + 2 * state
}

/// `u32` elements of the SGM sums of both eyes.
pub const fn sum_len(w: usize, p: &C2fParams) -> usize {
    2 * row_cells(w, p)
}

/// `i32` elements of the per-row picks (left and right).
pub const fn pick_len(w: usize) -> usize {
    2 * w
}

/// `u8` elements of the window maps: levels 1 and 2 (both eyes), the
/// coarser ones reusing them.
pub const fn map_len(w: usize, h: usize, p: &C2fParams) -> usize {
    let mut n = 0;
    let mut k = 1;
    while k <= 2 && k < p.levels() {
        n += 2 * level_len(w, k) * level_len(h, k);
        k += 1;
    }
    n
}

/// Scratch bytes of the engine at `w` x `h`, beyond the two input frames
/// and the output (the phase refinement's included).
pub const fn scratch_bytes(w: usize, h: usize, p: &C2fParams) -> usize {
    let phase = match &p.phase {
        Some(ph) => phase::scratch_bytes(w, ph, p.dem.max_disp),
        None => 0,
    };
    phase
        + 2 * grey_len(w, p)
        + 3 * rgb_len(w, p)
        + 4 * z_len(w, p)
        + 12 * w
        + 8 * score_len(w, p)
        + 2 * cost_len(w, p)
        + 4 * sum_len(w, p)
        + 4 * pick_len(w)
        + map_len(w, h, p)
}

/// Caller-provided scratch, sized by the `const fn`s of this module.
pub struct C2fBuffers<'a> {
    /// Grey rings ([`grey_len`]).
    pub grey: &'a mut [u16],
    /// RGB rows ([`rgb_len`]).
    pub rgb: &'a mut [Rgb8],
    /// Response rows ([`z_len`]).
    pub z: &'a mut [Z],
    /// y-pass row (`w`), then one pixel's cells while voting.
    pub col: &'a mut [[i32; 3]],
    /// Score rows ([`score_len`]).
    pub scores: &'a mut [i64],
    /// Costs, windows, voters, SGM states ([`cost_len`]).
    pub costs: &'a mut [u16],
    /// SGM sums ([`sum_len`]).
    pub sums: &'a mut [u32],
    /// Row picks ([`pick_len`]).
    pub picks: &'a mut [i32],
    /// Window maps ([`map_len`]).
    pub maps: &'a mut [u8],
    /// The phase refinement's ([`super::phase`]; empty slices without
    /// [`C2fParams::phase`]).
    pub phase: PhaseBuffers<'a>,
}

/// The set-up engine: checked parameters, kernels, thresholds.
#[derive(Clone, Debug, PartialEq)]
pub struct C2f {
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
}

impl C2f {
    /// Checks `params` and builds the kernels (one-time setup, floats via
    /// `libm`).
    ///
    /// # Errors
    /// [`StereoError::BadParams`].
    #[allow(
        clippy::float_arithmetic,
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss
    )]
    pub fn new(params: &C2fParams) -> Result<Self, StereoError> {
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
    /// refined ([`Refiner::flush`]) before it goes to `sink`.
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
        self.run_with::<S, SafePhase>(tables, left, right, bufs, sink, probe)
    }

    /// [`C2f::run`] with the phase refinement's step by kernel `K`
    /// ([`PhaseKernel`]; the same bits as [`SafePhase`]).
    ///
    /// # Errors
    /// As [`C2f::run`].
    pub fn run_with<S: RgbRows, K: PhaseKernel>(
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
        let mut refiner = Refiner::new(phase, left, right, pb)?;
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
            kernel: core::marker::PhantomData::<K>,
        };
        self.run_levels(tables, left, right, &mut rest, &mut refined, probe)
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

/// The scratch of one level's run (the maps aside).
struct Work<'b, 'a> {
    grey: &'b mut &'a mut [u16],
    rgb: &'b mut &'a mut [Rgb8],
    z: &'b mut &'a mut [Z],
    col: &'b mut &'a mut [[i32; 3]],
    scores: &'b mut &'a mut [i64],
    costs: &'b mut &'a mut [u16],
    sums: &'b mut &'a mut [u32],
    picks: &'b mut &'a mut [i32],
}

/// Where the finest level's cells go, in row-major order.
trait Cells {
    /// Cell `(x, y)`.
    fn cell(&mut self, x: usize, y: usize, c: DisparityCell);
    /// A frame row to fill before [`Cells::row_done`], for a consumer that
    /// works on rows (the spread of a level `k > 0` then fills it instead
    /// of calling [`Cells::cell`]).
    fn row(&mut self) -> Option<&mut [DisparityCell]> {
        None
    }
    /// Frame row `y` of [`Cells::row`] is filled.
    fn row_done(&mut self, _y: usize) {}
}

/// A sink of cells.
struct Plain<'f, F>(&'f mut F);

impl<F: FnMut(usize, usize, DisparityCell)> Cells for Plain<'_, F> {
    #[inline(always)]
    fn cell(&mut self, x: usize, y: usize, c: DisparityCell) {
        (self.0)(x, y, c);
    }
}

/// A sink behind the phase refinement (phase step of kernel `K`): each
/// output row is refined, then passed on cell by cell.
struct Refined<'r, 'p, 'b, S: RgbRows, F, K> {
    refiner: &'r mut Refiner<'p, 'b, S>,
    sink: &'r mut F,
    kernel: core::marker::PhantomData<K>,
}

impl<S: RgbRows, F: FnMut(usize, usize, DisparityCell), K: PhaseKernel> Cells
    for Refined<'_, '_, '_, S, F, K>
{
    #[inline(always)]
    fn cell(&mut self, x: usize, y: usize, c: DisparityCell) {
        self.refiner.push_with::<K>(x, y, c, self.sink);
    }
    fn row(&mut self) -> Option<&mut [DisparityCell]> {
        Some(self.refiner.row_mut())
    }
    fn row_done(&mut self, y: usize) {
        self.refiner.flush_with::<K>(y, self.sink);
    }
}

/// Where a level's result goes.
enum Output<'o, F> {
    /// A coarse level: the windows of the next finer level.
    Map(&'o mut [u8]),
    /// The finest level run: the OFF tests, then the sink (at level 0
    /// pixel by pixel, else each row's verdicts spread over their blocks).
    Sink(&'o mut F, &'o mut StereoReport),
}

/// One level's run.
struct Pass<'e> {
    e: &'e C2f,
    k: usize,
    w: usize,
    h: usize,
    /// Frame size.
    full: (usize, usize),
    /// Candidates per pixel.
    n: usize,
    shifts: usize,
    step: usize,
    /// Whether the band applies (a windowed level with a band).
    band: Option<usize>,
    /// [`Pass::shift_range`] of every window `lo` (a `u8`), worked out
    /// once: no division per pixel.
    ranges: [[u16; 2]; 256],
}

/// Level-`k` RGB row `j` of `src` (rounded 2x2 means, `k` times) into
/// `out` (`⌊w/2^k⌋` long), with `scratch` for the finer rows.
fn level_row<S: RgbRows>(src: &S, k: usize, j: usize, out: &mut [Rgb8], scratch: &mut [Rgb8]) {
    if k == 0 {
        src.rgb_row(j, out);
        return;
    }
    let fw = 2 * out.len();
    let (a, rest) = scratch.split_at_mut(fw.min(scratch.len()));
    let (b, rest) = rest.split_at_mut(fw.min(rest.len()));
    level_row(src, k - 1, 2 * j, a, rest);
    level_row(src, k - 1, 2 * j + 1, b, rest);
    let mean = |p: [u8; 4]| {
        let s: u16 = p.iter().map(|&v| u16::from(v)).sum();
        ((s + 2) / 4) as u8
    };
    for ((o, a), b) in out.iter_mut().zip(a.chunks_exact(2)).zip(b.chunks_exact(2)) {
        if let ([a0, a1], [b0, b1]) = (a, b) {
            *o = Rgb8::new(
                mean([a0.r, a1.r, b0.r, b1.r]),
                mean([a0.g, a1.g, b0.g, b1.g]),
                mean([a0.b, a1.b, b0.b, b1.b]),
            );
        }
    }
}

/// One pixel's decision before the OFF tests.
#[derive(Clone, Copy)]
struct Decision {
    /// `U8F8` bits.
    disparity: i32,
    /// Best path sum more than 1 px away minus the best (`None`: none).
    margin: Option<u32>,
}

/// Argmin of `sums` (a window from `lo`, the first `valid` of them), the
/// parabola through its neighbours in `U8F8`, and the margin.
fn decide(sums: &[u32], lo: usize, valid: usize) -> Option<Decision> {
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
fn costs_of<const N: usize>(
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
    let t = i64::from(i32::try_from(total >> sh).unwrap_or(i32::MAX));
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
    let (pb, pw) = (i64::from(1u32 << (bf - m)), i64::from(1u32 << (wf - m)));
    let scores = raw.get_mut(..valid).unwrap_or(&mut []);
    if sh > 0 {
        for r in scores.iter_mut() {
            *r >>= sh;
        }
    }
    let (mut best, mut worst) = (i64::MIN, i64::MAX);
    let mut fold = |r: &mut i64, bias: i16| {
        *r = r
            .wrapping_mul(pb)
            .wrapping_sub((i64::from(bias) * t).wrapping_mul(pw));
        best = best.max(*r);
        worst = worst.min(*r);
    };
    match table.bias_bytes().get(2 * lo..2 * (lo + valid)) {
        Some(bias) => {
            for (r, b) in scores.iter_mut().zip(bias.chunks_exact(2)) {
                if let [b0, b1] = *b {
                    fold(r, i16::from_le_bytes([b0, b1]));
                }
            }
        }
        None => {
            for (d, r) in (lo..).zip(scores.iter_mut()) {
                fold(r, table.bias_at(d));
            }
        }
    }
    // Gaps `best − n(d) = 2^m·(best − u(d))` truncated to 15 significant
    // bits (so they fit `out` until they become costs).
    let span = best.abs_diff(worst);
    let bits = if span == 0 {
        0
    } else {
        64 - span.leading_zeros() + m
    };
    let sh2 = bits.saturating_sub(15);
    let mut total_gap = 0u32;
    for (o, &v) in out.iter_mut().zip(scores.iter()) {
        // `best >= v`, both within ±2^61: the difference is exact.
        let du = best.wrapping_sub(v) as u64;
        let gap = if sh2 >= m {
            du >> (sh2 - m)
        } else {
            du << (m - sh2)
        } as u16;
        *o = gap;
        total_gap += u32::from(gap);
    }
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

impl<'e> Pass<'e> {
    fn new(e: &'e C2f, k: usize, full: (usize, usize)) -> Self {
        let p = &e.params;
        let layout = p.level_params(k).layout();
        let windowed = k < usize::from(p.coarse);
        let mut pass = Self {
            e,
            k,
            w: level_len(full.0, k),
            h: level_len(full.1, k),
            full,
            n: p.candidates(k),
            shifts: layout.shifts(0),
            step: usize::from(layout.shift_step.max(1)),
            band: p.band.filter(|_| windowed).map(usize::from),
            ranges: [[0; 2]; 256],
        };
        // Shifts are at most 256 (`max_disp` is a `u8`), so `u16` holds them.
        let mut ranges = [[0u16; 2]; 256];
        for (lo, r) in (0u16..).zip(ranges.iter_mut()) {
            let x = pass.shift_range_of(lo);
            *r = [x.start, x.end].map(|v| u16::try_from(v).unwrap_or(u16::MAX));
        }
        pass.ranges = ranges;
        pass
    }

    /// The shift indices whose votes a pixel with window `lo` takes: those
    /// with `|s − centre| <= band` (centre `lo + (n − 1)/2`), or all.
    fn shift_range(&self, lo: u16) -> core::ops::Range<usize> {
        match self.ranges.get(usize::from(lo)) {
            Some(&[a, b]) => usize::from(a)..usize::from(b),
            None => self.shift_range_of(lo),
        }
    }

    /// [`Pass::shift_range`] worked out.
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

    #[allow(clippy::too_many_lines)]
    fn run<S: RgbRows, F: Cells>(
        &self,
        table: &DemTable<'_>,
        src: [&S; 2],
        bufs: &mut Work<'_, '_>,
        parent: Option<&[u8]>,
        mut out: Output<'_, F>,
        probe: &mut impl Probe,
    ) -> Result<usize, StereoError> {
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
        let groups = (carriers * self.shifts) as u64;
        let (wc, hc) = (
            level_len(self.full.0, self.k + 1),
            level_len(self.full.1, self.k + 1),
        );
        let from_left = self.e.params.lr_from_left;
        let eyes = if from_left { 1 } else { 2 };
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
            cells += self.votes(table, z2, lo2, sc2, vo2, col, !from_left);
            // Costs, aggregation, decisions.
            probe.enter(Step::Readout);
            let need = |total: i64, voters: u16| -> bool {
                let cells = if self.band.is_some() {
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
                    match (valid, n) {
                        (5, 5) => costs_of::<5>(raw, total, table, lo, valid, dst),
                        (3, 3) => costs_of::<3>(raw, total, table, lo, valid, dst),
                        _ => costs_of::<0>(raw, total, table, lo, valid, dst),
                    }
                }
            }
            probe.enter(Step::Sgm);
            sgm_l.push_row(costs_l, lo_l, sum_l).map_err(sgm_err)?;
            if !from_left {
                sgm_r.push_row(costs_r, lo_r, sum_r).map_err(sgm_err)?;
            }
            probe.enter(Step::Readout);
            // Right-referenced decisions first: the left-right check reads
            // them.
            if from_left {
                self.right_from_left(sl, lo_l, sum_l, sum_r, rp);
            } else {
                for (x, ((pk, raw), (&lo, s))) in rp
                    .iter_mut()
                    .zip(sr.chunks_exact(stride))
                    .zip(lo_r.iter().zip(sum_r.chunks_exact(n)))
                    .enumerate()
                {
                    *pk = self
                        .decision(raw, lo, s, w - 1 - x)
                        .map_or(-1, |d| d.disparity);
                }
            }
            for (x, ((pk, raw), ((&lo, s), &v))) in lp
                .iter_mut()
                .zip(sl.chunks_exact(stride))
                .zip(lo_l.iter().zip(sum_l.chunks_exact(n)).zip(vo_l.iter()))
                .enumerate()
            {
                let d = self.decision(raw, lo, s, x);
                *pk = d.map_or(-1, |d| d.disparity);
                if let Output::Sink(sink, report) = &mut out {
                    let total = raw.get(n).copied().unwrap_or(0);
                    let verdict = self.off_tests(x, d, need(total, v), rp);
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
    /// after the level's last pixel).
    fn spread(&self, y: usize, col: &[[i32; 3]], sink: &mut impl Cells, report: &mut StereoReport) {
        let (fw, fh) = self.full;
        let first = y << self.k;
        let end = if y + 1 >= self.h {
            fh
        } else {
            first + (1 << self.k)
        };
        for fy in first..end {
            // Each level pixel's cell, counted once for its columns.
            let mut cells = col.iter().take(self.w).enumerate().map(|(x, c)| {
                let cols = if x + 1 == self.w {
                    (x << self.k)..fw
                } else {
                    (x << self.k)..(x + 1) << self.k
                };
                let verdict = Verdict::from_code(c[0]).scaled(self.k);
                (verdict.count_n(report, cols.len()), cols)
            });
            if let Some(row) = sink.row() {
                for (cell, cols) in &mut cells {
                    row.get_mut(cols)
                        .into_iter()
                        .flatten()
                        .for_each(|c| *c = cell);
                }
                sink.row_done(fy);
            } else {
                for (cell, cols) in cells {
                    for fx in cols {
                        sink.cell(fx, fy, cell);
                    }
                }
            }
        }
    }

    /// The cells and votes of one row: for each pixel of each eye (left,
    /// right), its window's scores and total (`n + 1` per pixel, in
    /// `scores`) from the cells of the shifts [`Pass::shift_range`] of its
    /// window `lo` (the cell of left `x` and right `x − s`), and with a
    /// band the number of groups voting (`voters`); `cells` is scratch for
    /// one pixel's cells (`w` long); `right`: the right eye's too (else
    /// only the left's). Returns the number of cells evaluated.
    #[allow(clippy::too_many_arguments)]
    fn votes(
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

    /// The right map of the left-right check derived from the left one
    /// (OpenCV SGBM's `disp2`): right pixel `x − d` takes the candidate `d`
    /// (`U8F8` bits, integer) of least path sum over the left pixels `x`
    /// with evidence (`total > 0`) and their valid candidates `d <= x`;
    /// the first such (by `x`, then `d`) wins a tie; `-1` where no left
    /// pixel maps. `scores`, `lo`, `sums`: the left row's; `best` is
    /// scratch (`w` long).
    fn right_from_left(
        &self,
        scores: &[i64],
        lo: &[u16],
        sums: &[u32],
        best: &mut [u32],
        right: &mut [i32],
    ) {
        // At least 1; `max` shows the compiler (no panic path in `chunks`).
        let n = self.n.max(1);
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

    /// [`Pass::votes`] of one eye (`LEFT`: left-referenced), pixel by
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
        let carriers = usize::from(self.e.dem.params.carriers);
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

    /// The decision of one pixel: its scores row `raw` (for the total),
    /// window `lo`, path sums `sums`, last valid candidate `top`.
    fn decision(&self, raw: &[i64], lo: u16, sums: &[u32], top: usize) -> Option<Decision> {
        let lo = usize::from(lo);
        let total = raw.get(self.n).copied().unwrap_or(0);
        if total <= 0 || lo > top {
            return None;
        }
        decide(sums, lo, (top - lo + 1).min(self.n))
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

    /// The OFF tests of left pixel `x` (texture, ambiguity, left-right
    /// against the right decisions `right`).
    fn off_tests(&self, x: usize, d: Option<Decision>, textured: bool, right: &[i32]) -> Verdict {
        let Some(d) = d.filter(|_| textured) else {
            return Verdict::Texture;
        };
        if d.margin
            .is_some_and(|m| (i64::from(m) << 16) < self.e.min_margin_sums)
        {
            return Verdict::Ambiguous;
        }
        let v = d.disparity;
        let ok = self.e.dem.lr_tolerance_q8.is_none_or(|tol| {
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
enum Verdict {
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
    fn code(self) -> i32 {
        match self {
            Self::On(v) => i32::from(v),
            Self::Texture => -1,
            Self::Ambiguous => -2,
            Self::Inconsistent => -3,
        }
    }

    /// The inverse of [`Verdict::code`] (anything else reads as no
    /// evidence).
    fn from_code(c: i32) -> Self {
        match c {
            -2 => Self::Ambiguous,
            -3 => Self::Inconsistent,
            _ => u16::try_from(c).map_or(Self::Texture, Self::On),
        }
    }

    /// A level-`k` disparity in frame pixels: times `2^k`, saturating below
    /// OFF.
    fn scaled(self, k: usize) -> Self {
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
    fn count(self, report: &mut StereoReport) -> DisparityCell {
        self.count_n(report, 1)
    }

    /// Counts the verdict `n` times in `report` and makes it a cell.
    fn count_n(self, report: &mut StereoReport, n: usize) -> DisparityCell {
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
    use super::{costs_of, decide};
    use crate::rng::SplitMix64;
    use crate::stereo::DemTable;

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
        let bytes = include_bytes!("../../../firmware-sim/data/dem_c2f_l0.bin");
        let table = DemTable::parse(bytes).unwrap();
        let mut rng = SplitMix64::new(0xc057);
        for case in 0..20_000u64 {
            let total = 1 + rng.below(1 << (1 + case % 40)) as i64;
            // |raw| <= 2^14·total + 2^27 (the engine's bound).
            let bound = (total << 14) + (1 << 27);
            let mut raw = [0i64; 9];
            for r in &mut raw {
                *r = rng.below(2 * bound as u64 + 1) as i64 - bound;
            }
            let (n, valid) = [(5, 5), (3, 3), (5, 2), (9, 9), (3, 1)][(case % 5) as usize];
            let lo = rng.below(30 - n as u64) as usize;
            let want = plain_costs(&raw, total, &table, lo, valid);
            let mut out = [0u16; 9];
            let mut r = raw;
            match (valid, n) {
                (5, 5) => costs_of::<5>(&mut r, total, &table, lo, valid, &mut out[..n]),
                (3, 3) => costs_of::<3>(&mut r, total, &table, lo, valid, &mut out[..n]),
                _ => costs_of::<0>(&mut r, total, &table, lo, valid, &mut out[..n]),
            }
            assert_eq!(out[..n], want[..n], "case {case}: total {total} lo {lo}");
            let mut general = [0u16; 9];
            costs_of::<0>(&mut raw, total, &table, lo, valid, &mut general[..n]);
            assert_eq!(general[..n], want[..n], "case {case}, general path");
        }
    }
}
