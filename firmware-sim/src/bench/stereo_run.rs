//! The stereo stage on the board: the demo scene's 160x120 stereo pair,
//! 32 disparities, through the coarse-to-fine engine
//! (`protogist::stereo::c2f`, docs/STEREO.md), at its named points.
//!
//! The simulated stereo camera renders each RGB row when the engine asks
//! for it (`synth::SceneSpec::colour`; the coarse levels ask for 2 and 4
//! rows per level row), and each output row is folded into the checksum as
//! it is produced, so only the engine's scratch ([`c2f::scratch_bytes`]) is
//! in RAM: neither frames nor the map. The decoder tables of the three
//! levels (`data/dem_c2f_l{0,1,2}.bin`, written by `protogist train-dem
//! --levels 1 --max-disp 31 | 16 | 8`) are `const`s in flash.
//!
//! The full-search engine (`stereo::stereo_streamed`) ran here until
//! 2026-11-21 (101,581 instructions/px, `git checkout 05f3e88 && cargo
//! xtask firmware`); it left core at a8b9fbc.

use core::fmt::{self, Write};

use crate::pg::checksum::Fnv1a;
use crate::pg::disparity::DisparityCell;
use crate::pg::image::Rgb8;
use crate::pg::image::RgbRows;
use crate::pg::stereo::c2f::{self, C2f, C2fBuffers, C2fParams, LeftRight};
use crate::pg::stereo::filters::Z;
use crate::pg::stereo::phase::{self, PhaseKernel, PhaseParams};
use crate::pg::stereo::{DemTable, Probe, Step, StereoError, StereoReport};
use crate::pg::synth::SceneSpec;
use crate::{Aligned, Ticks};

/// Frame width.
pub const WIDTH: usize = 160;
/// Frame height.
pub const HEIGHT: usize = 120;
/// The parameters: [`C2fParams::FULL`] (32 disparities, 2 coarse levels,
/// windows of 5, band 2, both eyes read, 5 paths).
pub const PARAMS: C2fParams = C2fParams::FULL;
/// The other named operating points of the same engine
/// ([`C2fParams::NAMED`]), run after [`PARAMS`] to measure what each
/// costs (docs/STEREO.md, "Operating points"): the same tables and levels.
/// Each needs no more scratch than [`PARAMS`] and the phase
/// buffers of [`len`], which the `const` assertion below checks at
/// compile time.
pub const POINTS: [(&str, C2fParams); 3] = [
    ("fast", C2fParams::FAST),
    ("half", C2fParams::HALF),
    ("fast-low-penalty", C2fParams::FAST_LOW_PENALTY),
];

const fn fits(p: &C2fParams) -> bool {
    c2f::grey_len(WIDTH, p) <= len::GREY
        && c2f::rgb_len(WIDTH, p) <= len::RGB
        && c2f::z_len(WIDTH, p) <= len::Z
        && c2f::score_len(WIDTH, p) <= len::SCORES
        && c2f::cost_len(WIDTH, p) <= len::COSTS
        && c2f::sum_len(WIDTH, p) <= len::SUMS
        && c2f::map_len(WIDTH, HEIGHT, p) <= len::MAPS
        && match &p.phase {
            Some(ph) => {
                phase::v_len(WIDTH, ph) <= len::P_V
                    && phase::z_len(WIDTH, ph, p.dem.max_disp) <= len::P_Z
            }
            None => true,
        }
}

const _: () = {
    let mut i = 0;
    while i < POINTS.len() {
        assert!(fits(&POINTS[i].1), "an operating point needs more scratch");
        i += 1;
    }
};

/// The decoder tables of levels 0, 1 and 2 ([`Aligned`]).
pub const TABLES: [&[u8]; 3] = [
    &Aligned(*include_bytes!("../../data/dem_c2f_l0.bin")).0,
    &Aligned(*include_bytes!("../../data/dem_c2f_l1.bin")).0,
    &Aligned(*include_bytes!("../../data/dem_c2f_l2.bin")).0,
];

/// Buffer lengths at [`WIDTH`] x [`HEIGHT`] for [`PARAMS`].
pub mod len {
    use super::*;
    /// Grey rings (`u16`).
    pub const GREY: usize = c2f::grey_len(WIDTH, &PARAMS);
    /// RGB rows.
    pub const RGB: usize = c2f::rgb_len(WIDTH, &PARAMS);
    /// Response rows ([`type@Z`]).
    pub const Z: usize = c2f::z_len(WIDTH, &PARAMS);
    /// y-pass row (`[i32; 3]`).
    pub const COL: usize = WIDTH;
    /// Score rows (`i64`).
    pub const SCORES: usize = c2f::score_len(WIDTH, &PARAMS);
    /// Costs, windows, voters, SGM states (`u16`).
    pub const COSTS: usize = c2f::cost_len(WIDTH, &PARAMS);
    /// SGM sums (`u32`).
    pub const SUMS: usize = c2f::sum_len(WIDTH, &PARAMS);
    /// Row picks (`i32`).
    pub const PICKS: usize = c2f::pick_len(WIDTH);
    /// Window maps (`u8`).
    pub const MAPS: usize = c2f::map_len(WIDTH, HEIGHT, &PARAMS);
    /// Phase refinement RGB row.
    pub const P_RGB: usize = WIDTH;
    /// Phase refinement grey row (`i32`), for [`PhaseParams::DEFAULT`].
    pub const P_V: usize = phase::v_len(WIDTH, &PhaseParams::DEFAULT);
    /// Phase refinement response rows (`[i16; 2]`).
    pub const P_Z: usize = phase::z_len(WIDTH, &PhaseParams::DEFAULT, PARAMS.dem.max_disp);
    /// Phase refinement map row.
    pub const P_ROW: usize = WIDTH;
}

/// Scratch bytes of the run.
pub const SCRATCH_BYTES: usize = c2f::scratch_bytes(WIDTH, HEIGHT, &PARAMS);
/// Scratch bytes of the phase refinement's buffers ([`len`]`::P_*`), which
/// the points with `phase` use besides [`SCRATCH_BYTES`].
pub const PHASE_SCRATCH_BYTES: usize =
    phase::scratch_bytes(WIDTH, &PhaseParams::DEFAULT, PARAMS.dem.max_disp);

/// One eye of the demo scene, rendered row by row.
struct SceneEye<'s> {
    spec: &'s SceneSpec,
    right: bool,
}

impl RgbRows for SceneEye<'_> {
    fn size(&self) -> (usize, usize) {
        (WIDTH, HEIGHT)
    }

    fn rgb_row(&self, y: usize, out: &mut [Rgb8]) {
        let y = i32::try_from(y).unwrap_or(i32::MAX);
        for (x, o) in (0i32..).zip(out.iter_mut()) {
            *o = self.spec.colour(self.right, x, y);
        }
    }
}

/// Ticks per step.
struct StepProbe<'t, T: Ticks> {
    ticks: &'t mut T,
    step: Option<Step>,
    since: u64,
    spent: [u64; 5],
}

fn index(s: Step) -> usize {
    match s {
        Step::Pyramid => 0,
        Step::Filters => 1,
        Step::Energies => 2,
        Step::Sgm => 3,
        _ => 4,
    }
}

impl<T: Ticks> StepProbe<'_, T> {
    fn close(&mut self) {
        let now = self.ticks.now();
        if let Some(s) = self.step.and_then(|s| self.spent.get_mut(index(s))) {
            *s += now - self.since;
        }
        self.since = now;
    }
}

impl<T: Ticks> Probe for StepProbe<'_, T> {
    fn enter(&mut self, step: Step) {
        self.close();
        self.step = Some(step);
    }
}

/// What a run measured.
#[derive(Clone, Copy, Debug)]
pub struct StereoResult {
    /// FNV-1a of the map's `U8F8` bits (little endian), row-major.
    pub checksum: u32,
    /// The stage's counts.
    pub report: StereoReport,
    /// Ticks per step: levels and grey, filters, cells and votes, SGM,
    /// costs and decisions.
    pub steps: [u64; 5],
    /// Ticks of setup (kernels, table parse).
    pub setup: u64,
    /// Ticks of the whole stage.
    pub total: u64,
    /// Ticks the simulated camera takes to render the rows the engine asks
    /// for (each frame pixel once per level and eye, and once more per eye
    /// for the phase refinement), measured alone: part of the `levels`
    /// step (and of the output step for the phase refinement's rows), the
    /// camera's cost rather than the engine's.
    pub camera: u64,
}

/// Runs the stage on the demo pair with [`PARAMS`].
///
/// # Errors
/// [`StereoError`] (a bad table or short buffers).
pub fn run<T: Ticks, K: PhaseKernel>(
    bufs: &mut C2fBuffers<'_>,
    ticks: &mut T,
) -> Result<StereoResult, StereoError> {
    run_at::<T, K>(&PARAMS, bufs, ticks)
}

/// Runs the stage on the demo pair with `params` (2 coarse levels: the
/// three tables of [`TABLES`]), the phase refinement's step by kernel `K`
/// (the same bits whatever the kernel: the firmware passes its assembly
/// one, the desktop build [`phase::SafePhase`]).
///
/// # Errors
/// [`StereoError`] (bad parameters, a bad table or short buffers).
pub fn run_at<T: Ticks, K: PhaseKernel>(
    params: &C2fParams,
    bufs: &mut C2fBuffers<'_>,
    ticks: &mut T,
) -> Result<StereoResult, StereoError> {
    let spec = SceneSpec::demo(WIDTH, HEIGHT);
    let (left, right) = (
        SceneEye {
            spec: &spec,
            right: false,
        },
        SceneEye {
            spec: &spec,
            right: true,
        },
    );
    let t0 = ticks.now();
    let engine = C2f::<K>::with_kernel(params)?;
    let tables = [
        DemTable::parse(TABLES[0])?,
        DemTable::parse(TABLES[1])?,
        DemTable::parse(TABLES[2])?,
    ];
    let t1 = ticks.now();
    let mut hash = Fnv1a::new();
    let mut sink = |_x: usize, _y: usize, c: DisparityCell| {
        hash.write(&c.raw().to_bits().to_le_bytes());
    };
    let mut probe = StepProbe {
        ticks,
        step: None,
        since: t1,
        spent: [0; 5],
    };
    let report = engine.run(&tables, &left, &right, bufs, &mut sink, &mut probe)?;
    probe.close();
    let t2 = probe.ticks.now();
    // The camera alone: the same row renders, into the RGB scratch.
    // One pass per level run, and one more for the phase refinement.
    let levels = usize::from(params.coarse.saturating_sub(params.finest))
        + 1
        + usize::from(params.phase.is_some());
    let row = bufs.rgb.get_mut(..WIDTH).unwrap_or(&mut []);
    for _ in 0..levels {
        for eye in [&left, &right] {
            for y in 0..HEIGHT {
                eye.rgb_row(y, row);
            }
        }
    }
    let t3 = probe.ticks.now();
    Ok(StereoResult {
        checksum: hash.finish(),
        report,
        steps: probe.spent,
        setup: t1 - t0,
        total: t2 - t0,
        camera: t3 - t2,
    })
}

/// `checksum stereo WxH 0x........ on=N` (compared host vs QEMU) and the
/// OFF counts.
pub fn write_result(out: &mut impl Write, r: &StereoResult) -> fmt::Result {
    writeln!(
        out,
        "checksum stereo {WIDTH}x{HEIGHT} 0x{:08x} on={}",
        r.checksum, r.report.on
    )?;
    writeln!(
        out,
        "stereo off texture={} ambiguous={} inconsistent={}",
        r.report.off_texture, r.report.off_ambiguous, r.report.off_inconsistent
    )?;
    // Tenths of a cell per pixel, in integers (no float formatting).
    let tenths = (r.report.cells * 10 + WIDTH * HEIGHT / 2) / (WIDTH * HEIGHT);
    writeln!(
        out,
        "stereo cells {WIDTH}x{HEIGHT} {} ({}.{} per pixel)",
        r.report.cells,
        tenths / 10,
        tenths % 10
    )
}

/// One operating point's lines: `checksum stereo@NAME WxH 0x........
/// on=N` (compared host vs QEMU), then [`write_point_line`].
pub fn write_point(
    out: &mut impl Write,
    name: &str,
    params: &C2fParams,
    r: &StereoResult,
    to_instructions: impl Fn(u64) -> u64,
) -> fmt::Result {
    writeln!(
        out,
        "checksum stereo@{name} {WIDTH}x{HEIGHT} 0x{:08x} on={}",
        r.checksum, r.report.on
    )?;
    write_point_line(out, name, params, r, to_instructions)?;
    // The refinement's buffers come on top of the engine's.
    if params.phase.is_some() {
        writeln!(
            out,
            "scratch stereo@{name} {WIDTH}x{HEIGHT} {}",
            c2f::scratch_bytes(WIDTH, HEIGHT, params)
        )?;
    }
    Ok(())
}

/// `point stereo NAME WxH radius=R band=B lr=L paths=P finest=F phase=Q
/// engine=E cells=C STEP=I ...`: the window half width, the band (`-`:
/// none), the right map of the left-right check (`off`, `read`, or `derived` from
/// the left sums), the SGM paths, the finest level run and the phase
/// refinement (1: on; its cost is the difference to the same point without
/// it, since it runs inside the output step), then instructions per
/// pixel with one decimal (the engine is the total minus the camera, as
/// `ipp stereo-engine`), the cells evaluated and the steps.
pub fn write_point_line(
    out: &mut impl Write,
    name: &str,
    params: &C2fParams,
    r: &StereoResult,
    to_instructions: impl Fn(u64) -> u64,
) -> fmt::Result {
    let px = (WIDTH * HEIGHT) as u64;
    let tenths = |t: u64| (to_instructions(t) * 10 + px / 2) / px;
    let engine = tenths(r.total.saturating_sub(r.camera));
    write!(
        out,
        "point stereo {name} {WIDTH}x{HEIGHT} radius={} band=",
        params.radius
    )?;
    match params.band {
        Some(b) => write!(out, "{b}")?,
        None => write!(out, "-")?,
    }
    let lr = match params.left_right {
        LeftRight::Off => "off",
        LeftRight::Read => "read",
        LeftRight::Derived => "derived",
    };
    write!(
        out,
        " lr={lr} paths={} finest={} phase={}",
        params.paths,
        params.finest,
        u8::from(params.phase.is_some())
    )?;
    write!(
        out,
        " engine={}.{} cells={}",
        engine / 10,
        engine % 10,
        r.report.cells
    )?;
    for (step, &t) in STEP_NAMES.iter().zip(&r.steps) {
        let v = tenths(t);
        let step = step.strip_prefix("stereo-").unwrap_or(step);
        write!(out, " {step}={}.{}", v / 10, v % 10)?;
    }
    writeln!(out)
}

/// The step names of [`StereoResult::steps`], as printed.
pub const STEP_NAMES: [&str; 5] = [
    "stereo-levels",
    "stereo-filters",
    "stereo-cells-votes",
    "stereo-sgm",
    "stereo-costs-picks",
];

/// Keeps the element type of the response ring nameable by callers.
pub type ZCell = Z;

/// The result lines, then `ipp` per step and in total (from ticks, through
/// `to_instructions`), `scratch stereo WxH BYTES` and the
/// [`write_point_line`] of [`PARAMS`], named `full`.
pub fn write_report(
    out: &mut impl Write,
    r: &StereoResult,
    to_instructions: impl Fn(u64) -> u64,
) -> fmt::Result {
    write_result(out, r)?;
    for (name, &t) in STEP_NAMES.iter().zip(&r.steps) {
        crate::write_ipp(out, name, WIDTH, HEIGHT, to_instructions(t))?;
    }
    crate::write_ipp(out, "stereo-setup", WIDTH, HEIGHT, to_instructions(r.setup))?;
    crate::write_ipp(
        out,
        "stereo-camera-within-levels",
        WIDTH,
        HEIGHT,
        to_instructions(r.camera),
    )?;
    crate::write_ipp(out, "stereo", WIDTH, HEIGHT, to_instructions(r.total))?;
    // The engine alone: the frames are the engine's input, and a camera's
    // DMA would leave them in memory (the renders are deterministic, so the
    // difference is exact).
    crate::write_ipp(
        out,
        "stereo-engine",
        WIDTH,
        HEIGHT,
        to_instructions(r.total.saturating_sub(r.camera)),
    )?;
    writeln!(out, "scratch stereo {WIDTH}x{HEIGHT} {SCRATCH_BYTES}")?;
    write_point_line(out, "full", &PARAMS, r, to_instructions)
}

/// Rows of the phase kernel's self-test ([`kernel_check`]).
pub const KERNEL_ROWS: usize = 256;
/// Cells per self-test row.
pub const KERNEL_W: usize = 48;
/// Largest `max_disp` of the self-test.
const KERNEL_MD: usize = 40;

/// Word-aligned storage (the phase kernel reads its responses with `ldm`).
#[repr(C, align(4))]
pub struct Words<T>(pub T);

/// The phase kernel's self-test: [`KERNEL_ROWS`] random rows through
/// `K::phase_row3` (responses anywhere in `±2^13`, some small or zero, OFF
/// cells, disparities beyond `max_disp`, λ from 2 to 64 px), folded into
/// `(checksum, cells refined)`. The firmware runs it with its assembly
/// kernel and the desktop build with [`phase::SafePhase`]; xtask requires
/// the two `checksum phase-kernel` lines to be equal, so every branch of
/// the assembly is held to the portable step's bits on every CI run.
pub fn kernel_check<K: PhaseKernel>() -> (u32, usize) {
    let mut rng = crate::pg::rng::SplitMix64::new(0x9e37_79b9_7f4a_7c15);
    let mut zl = Words([[0i16; 2]; KERNEL_W + 2]);
    let mut zr = Words([[0i16; 2]; KERNEL_W + 2 + KERNEL_MD]);
    let mut cells = [DisparityCell::OFF; KERNEL_W];
    let (mut hash, mut refined) = (Fnv1a::new(), 0);
    for _ in 0..KERNEL_ROWS {
        // Response scale: full range, small, or tiny (P = 0 happens).
        let scale = match rng.below(3) {
            0 => 8191,
            1 => 300,
            _ => 2,
        };
        for z in zl.0.iter_mut().chain(zr.0.iter_mut()) {
            *z = [
                rng.range(-scale, scale) as i16,
                rng.range(-scale, scale) as i16,
            ];
        }
        let md = rng.below(KERNEL_MD as u64 + 1) as u8;
        for c in &mut cells {
            *c = if rng.below(8) == 0 {
                DisparityCell::OFF
            } else {
                // Up to md + 2 px, and now and then anything below OFF.
                let top = if rng.below(16) == 0 {
                    0xfffe
                } else {
                    (i32::from(md) + 2) << 8
                };
                DisparityCell::from_raw(crate::pg::fixed::U8F8::from_bits(rng.range(0, top) as u16))
            };
        }
        let lambda = rng.range(2 * 256, 64 * 256);
        let zr_used = zr.0.get(..KERNEL_W + 2 + usize::from(md)).unwrap_or(&[]);
        refined += K::phase_row3(md, lambda, &zl.0, zr_used, &mut cells);
        for c in &cells {
            hash.write(&c.raw().to_bits().to_le_bytes());
        }
    }
    (hash.finish(), refined)
}

/// `checksum phase-kernel ROWSxW 0x........ refined=N` (compared host vs
/// QEMU).
pub fn write_kernel_check(out: &mut impl Write, (sum, refined): (u32, usize)) -> fmt::Result {
    writeln!(
        out,
        "checksum phase-kernel {KERNEL_ROWS}x{KERNEL_W} 0x{sum:08x} refined={refined}"
    )
}

/// Steps of the SGM kernel's self-test ([`sgm_kernel_check`]).
pub const SGM_STEPS: usize = 20_000;

/// The SGM kernel's self-test: [`SGM_STEPS`] random steps through
/// `K::sgm_step9` and `K::sgm_step5` within its contract and at its edges (`P2` up to 65535,
/// costs up to `65535 − P2`, states up to 65535, both pads, `P1` from 0
/// to `P2`), the states and sums folded into a checksum. The firmware runs
/// it with its assembly kernel and the desktop build with the portable
/// step; xtask requires the two `checksum sgm-kernel` lines to be equal.
pub fn sgm_kernel_check<K: PhaseKernel>() -> u32 {
    let mut rng = crate::pg::rng::SplitMix64::new(0x5a5a_0005_d00d_f00d);
    let mut hash = Fnv1a::new();
    let pick = |rng: &mut crate::pg::rng::SplitMix64, top: i32| match rng.below(4) {
        0 => 0,
        1 => top,
        _ => rng.range(0, top),
    };
    for _ in 0..SGM_STEPS {
        let p2 = pick(&mut rng, 0xffff);
        let p1 = pick(&mut rng, p2);
        let c: [u16; 9] = core::array::from_fn(|_| pick(&mut rng, 0xffff - p2) as u16);
        let p: [u16; 9] = core::array::from_fn(|_| pick(&mut rng, 0xffff) as u16);
        let pad = if rng.below(2) == 0 { 0 } else { 1 << 30 };
        let mut acc: [u32; 9] = core::array::from_fn(|_| rng.below(1 << 31) as u32);
        let pen = (p1 as u32, p2 as u32);
        let s9 = K::sgm_step9(&c, &p, pad, pen, &mut acc);
        let (c5, p5) = (first5(&c), first5(&p));
        let mut acc5 = first5(&acc);
        let s5 = K::sgm_step5(&c5, &p5, pad, pen, &mut acc5);
        for v in s9.iter().chain(&s5) {
            hash.write(&v.to_le_bytes());
        }
        for v in acc.iter().chain(&acc5) {
            hash.write(&v.to_le_bytes());
        }
    }
    hash.finish()
}

/// The first five of `v`.
fn first5<T: Copy + Default>(v: &[T; 9]) -> [T; 5] {
    core::array::from_fn(|i| v.get(i).copied().unwrap_or_default())
}

/// `checksum sgm-kernel STEPS 0x........` (compared host vs QEMU).
pub fn write_sgm_kernel_check(out: &mut impl Write, sum: u32) -> fmt::Result {
    writeln!(out, "checksum sgm-kernel {SGM_STEPS} 0x{sum:08x}")
}
