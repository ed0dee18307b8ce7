//! The engine's parameters and its named operating points.

#[cfg(doc)]
use super::C2f;
use super::PATHS;
use crate::stereo::phase::PhaseParams;
use crate::stereo::DemParams;

/// Largest number of coarse levels.
pub const MAX_COARSE: usize = 3;

/// The left-right check, and where its right-referenced map comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LeftRight {
    /// No left-right check: only the left eye is read out (the right
    /// eye's votes, costs and aggregation are not run), and no pixel is
    /// set OFF as inconsistent.
    Off,
    /// The right eye read out right-referenced (its votes, costs and
    /// aggregation), and the left map checked against it.
    Read,
    /// The right map derived from the left map's path sums, as OpenCV's
    /// SGBM does (`disp2`): the right eye's votes, costs and aggregation
    /// are not run.
    Derived,
}

impl LeftRight {
    /// Whether the right eye is read out.
    pub const fn reads_right(self) -> bool {
        matches!(self, Self::Read)
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
    /// The left-right check ([`LeftRight`]): off, against the right eye
    /// read out, or against a right map derived from the left map's path
    /// sums. [`C2fParams::FULL`]: [`LeftRight::Read`].
    pub left_right: LeftRight,
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
    /// responses ([`crate::stereo::phase`]): with `finest` 1, a map of the frame's
    /// resolution from the half-size level. Default `None`.
    pub phase: Option<PhaseParams>,
}

impl C2fParams {
    /// **Full**: the whole coarse-to-fine search down to the frame's
    /// resolution, both eyes read out for the left-right check, 5 SGM
    /// paths; 32 disparities (`max_disp` 31), 2 coarse levels, windows of
    /// 5 candidates (R 2) decoded from the groups within 2 px of their
    /// centre, P1 0.25, P2 4 (chosen on the held-out Motorcycle pair). The
    /// most accurate estimates (fewest bad pixels among those estimated)
    /// at about 8,700 M4 instructions per pixel (docs/BENCHMARKS.md,
    /// "Stereo operating points").
    pub const FULL: Self = Self {
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
        left_right: LeftRight::Read,
        paths: PATHS as u8,
        finest: 0,
        phase: None,
    };

    /// **Fast**: the search stops at the half-size level, which is then
    /// refined to the frame's resolution by phase ([`PhaseParams::DEFAULT`]);
    /// band 1, 3 SGM paths, the left-right check against a right map
    /// derived from the left ([`LeftRight::Derived`]: no right eye). A map
    /// of the frame's resolution within the 1,500 M4 instructions per
    /// pixel budget (about 1,470), as accurate over all GT pixels as
    /// [`C2fParams::FULL`].
    pub const FAST: Self = Self {
        band: Some(1),
        left_right: LeftRight::Derived,
        paths: 3,
        finest: 1,
        phase: Some(PhaseParams::DEFAULT),
        ..Self::FULL
    };

    /// **Half**: [`C2fParams::FAST`] without the phase refinement: the map
    /// of the half-size pair, each cell spread over its 2x2 block of the
    /// frame with its disparity doubled. The cheapest point (about 1,320
    /// M4 instructions per pixel), for consumers that need only blocks.
    pub const HALF: Self = Self {
        phase: None,
        ..Self::FAST
    };

    /// **Fast, low penalty**: [`C2fParams::FAST`] with one small SGM
    /// penalty for every step, P1 = P2 = 0.25 mean cost gaps, instead of
    /// P2 = 4. The large-step penalty that wins on the Motorcycle pair
    /// smooths a small object's disparity step away, so the object takes
    /// its background's disparity and figure-ground loses it; with the low
    /// penalty the aggregation still votes along 3 paths but keeps those
    /// steps. The same instructions as `fast` (the penalties are values,
    /// not work).
    pub const FAST_LOW_PENALTY: Self = Self {
        p1: 0.25,
        p2: 0.25,
        ..Self::FAST
    };

    /// **Half, low penalty**: [`C2fParams::FAST_LOW_PENALTY`] without the
    /// phase refinement, [`C2fParams::HALF`] with the low penalty: the
    /// half-size map spread over 2x2 blocks. About 2.5 M M4 instructions a
    /// 160x120 frame fewer than `fast-low-penalty` (the phase step's
    /// rows), for the same objects found within a point of recall: the
    /// pipeline's point (`pipeline::STEREO_DEFAULT`, docs/PIPELINE.md,
    /// "The stereo point").
    pub const HALF_LOW_PENALTY: Self = Self {
        phase: None,
        ..Self::FAST_LOW_PENALTY
    };

    /// **Half, narrow filters**: [`C2fParams::HALF_LOW_PENALTY`] with
    /// Gabor kernels of radius 2 (5 taps) instead of 7 (15 taps, ⌈3σ⌉):
    /// the envelope (σ = 2.24 px) is cut at 0.9σ, so each cell sees less
    /// of its neighbourhood and a near object's disparity spreads less
    /// beyond its outline. Its own decoder tables (`protogist train-dem
    /// --radius 2`). The pipeline's point (`pipeline::STEREO_DEFAULT`,
    /// docs/CHOICES.md, "Narrow filters"): more objects found end to end,
    /// and 1.6 M M4 instructions a 160x120 frame fewer than
    /// `half-low-penalty`.
    pub const HALF_NARROW: Self = Self {
        dem: DemParams {
            radius: 2,
            ..Self::HALF_LOW_PENALTY.dem
        },
        ..Self::HALF_LOW_PENALTY
    };

    /// **Fast, narrow filters, full search**: [`C2fParams::HALF_NARROW`]
    /// with one coarse level fewer (`coarse` 1): every disparity is
    /// searched at the half-size level, with no coarser level whose
    /// windows a small object could fall out of; the half-size map is
    /// then refined to the frame's resolution by phase
    /// ([`PhaseParams::DEFAULT`], as [`C2fParams::FAST`] does). Levels 0
    /// and 1 of `half-narrow`'s tables. More objects found end to end,
    /// and named right more often (the pipeline's `accurate` preset,
    /// docs/PIPELINE.md, "The stereo point"), for about twice the host
    /// time of the pipeline at `half-narrow` and about 45 M M4
    /// instructions a 160x120 frame more: a point for boards with several
    /// times the product's 32 M.
    pub const FAST_NARROW_FULL_SEARCH: Self = Self {
        coarse: 1,
        phase: Some(PhaseParams::DEFAULT),
        ..Self::HALF_NARROW
    };

    /// The named points, by the name `protogist stereo --point` takes.
    pub const NAMED: [(&'static str, Self); 7] = [
        ("full", Self::FULL),
        ("fast", Self::FAST),
        ("half", Self::HALF),
        ("fast-low-penalty", Self::FAST_LOW_PENALTY),
        ("half-low-penalty", Self::HALF_LOW_PENALTY),
        ("half-narrow", Self::HALF_NARROW),
        ("fast-narrow-full-search", Self::FAST_NARROW_FULL_SEARCH),
    ];

    /// The named point called `name` ([`C2fParams::NAMED`]).
    pub fn from_name(name: &str) -> Option<Self> {
        crate::named::by_name(&Self::NAMED, name)
    }

    /// The name of these parameters if they are a named point.
    pub fn name(&self) -> Option<&'static str> {
        crate::named::name_of(&Self::NAMED, self)
    }

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
    pub(super) const fn levels(&self) -> usize {
        if self.coarse as usize > MAX_COARSE {
            0
        } else {
            self.coarse as usize + 1
        }
    }
}

impl Default for C2fParams {
    /// [`C2fParams::FULL`].
    fn default() -> Self {
        Self::FULL
    }
}
