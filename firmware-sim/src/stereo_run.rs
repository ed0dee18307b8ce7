//! The stereo stage on the board: the demo scene's 160x120 stereo pair,
//! 32 disparities, row-streamed.
//!
//! The simulated stereo camera renders each grey row when the stage asks
//! for it (`synth::SceneSpec::colour`), and each output row is folded into
//! the checksum as it is produced, so only the stage's own scratch
//! ([`stereo::scratch_bytes`]) is in RAM: neither frames nor the map. The
//! decoder table for D = 32 (`data/dem_d32.bin`, written by
//! `protogist train-dem --max-disp 31`) is a `const` in flash.

use core::fmt::{self, Write};

use crate::pg::checksum::Fnv1a;
use crate::pg::disparity::DisparityCell;
use crate::pg::stereo::filters::{grey, Z};
use crate::pg::stereo::{
    self, col_len, energy_len, grey_len, pick_len, score_len, z_len, Dem, DemParams, DemTable,
    GreyRows, Probe, Step, StereoBuffers, StereoError, StereoReport,
};
use crate::pg::synth::SceneSpec;
use crate::Ticks;

/// Frame width.
pub const WIDTH: usize = 160;
/// Frame height.
pub const HEIGHT: usize = 120;
/// The parameters: the defaults with 32 disparities.
pub const PARAMS: DemParams = DemParams {
    max_disp: 31,
    ..DemParams::DEFAULT
};
/// The decoder table trained for [`PARAMS`].
pub const TABLE: &[u8] = include_bytes!("../data/dem_d32.bin");

/// Buffer lengths at [`WIDTH`] x [`HEIGHT`] for [`PARAMS`].
pub mod len {
    use super::*;
    /// Grey rings and planes (`u16`).
    pub const GREY: usize = grey_len(WIDTH, HEIGHT, &PARAMS);
    /// Response rings ([`Z`]).
    pub const Z: usize = z_len(WIDTH, &PARAMS);
    /// y-pass row (`[i32; 3]`).
    pub const COL: usize = col_len(WIDTH);
    /// Energy chunk (`i32`).
    pub const ENERGY: usize = energy_len(&PARAMS);
    /// Score rings (`i64`).
    pub const SCORES: usize = score_len(&PARAMS);
    /// Row picks (`i32`).
    pub const PICKS: usize = pick_len(WIDTH);
}

/// Scratch bytes of the run.
pub const SCRATCH_BYTES: usize = stereo::scratch_bytes(WIDTH, HEIGHT, PARAMS.max_disp);

/// One eye of the demo scene, rendered row by row.
struct SceneEye<'s> {
    spec: &'s SceneSpec,
    right: bool,
}

impl GreyRows for SceneEye<'_> {
    fn size(&self) -> (usize, usize) {
        (WIDTH, HEIGHT)
    }

    fn grey_row(&self, y: usize, out: &mut [u16]) {
        let y = i32::try_from(y).unwrap_or(i32::MAX);
        for (x, o) in (0i32..).zip(out.iter_mut()) {
            *o = grey(self.spec.colour(self.right, x, y));
        }
    }
}

/// Ticks per step.
struct StepProbe<'t, T: Ticks> {
    ticks: &'t mut T,
    step: Option<Step>,
    since: u64,
    spent: [u64; 4],
}

fn index(s: Step) -> usize {
    match s {
        Step::Pyramid => 0,
        Step::Filters => 1,
        Step::Energies => 2,
        Step::Readout => 3,
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
    /// Ticks per step: grey/pyramid, filters, energies, read-out.
    pub steps: [u64; 4],
    /// Ticks of setup (kernels, table parse).
    pub setup: u64,
    /// Ticks of the whole stage.
    pub total: u64,
}

/// Runs the stage on the demo pair.
///
/// # Errors
/// [`StereoError`] (a bad table or short buffers).
pub fn run<T: Ticks>(
    bufs: &mut StereoBuffers<'_>,
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
    let dem = Dem::new(&PARAMS)?;
    let table = DemTable::parse(TABLE)?;
    let t1 = ticks.now();
    let mut hash = Fnv1a::new();
    let mut sink = |_x: usize, _y: usize, c: DisparityCell| {
        hash.write(&c.raw().to_bits().to_le_bytes());
    };
    let mut probe = StepProbe {
        ticks,
        step: None,
        since: t1,
        spent: [0; 4],
    };
    let report = stereo::stereo_streamed(&dem, &table, &left, &right, bufs, &mut sink, &mut probe)?;
    probe.close();
    let t2 = probe.ticks.now();
    Ok(StereoResult {
        checksum: hash.finish(),
        report,
        steps: probe.spent,
        setup: t1 - t0,
        total: t2 - t0,
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
    )
}

/// The step names of [`StereoResult::steps`], as printed.
pub const STEP_NAMES: [&str; 4] = [
    "stereo-pyramid",
    "stereo-filters",
    "stereo-energies",
    "stereo-readout",
];

/// Keeps the element type of the response ring nameable by callers.
pub type ZCell = Z;

/// The result lines, then `ipp` per step and in total (from ticks, through
/// `to_instructions`) and `scratch stereo WxH BYTES`.
pub fn write_report(
    out: &mut impl Write,
    r: &StereoResult,
    to_instructions: impl Fn(u64) -> u64,
) -> fmt::Result {
    write_result(out, r)?;
    for (name, &t) in STEP_NAMES.iter().zip(&r.steps) {
        crate::app::write_ipp(out, name, WIDTH, HEIGHT, to_instructions(t))?;
    }
    crate::app::write_ipp(out, "stereo-setup", WIDTH, HEIGHT, to_instructions(r.setup))?;
    crate::app::write_ipp(out, "stereo", WIDTH, HEIGHT, to_instructions(r.total))?;
    writeln!(out, "scratch stereo {WIDTH}x{HEIGHT} {SCRATCH_BYTES}")
}
