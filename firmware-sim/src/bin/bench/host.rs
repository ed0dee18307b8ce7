//! Desktop run: SimCamera, a logging LED, `std::thread::sleep` delays, wall-clock ticks.

use std::convert::Infallible;
use std::fmt::Write as _;
use std::process::ExitCode;
use std::time::Instant;

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{ErrorType, OutputPin};
use firmware_sim::bench::objects;
use firmware_sim::bench::{App, Buffers, FRAME_SIZES, MAX_HEIGHT, MAX_WIDTH};
use firmware_sim::pg::conspicuity::{luv_len, row_scratch_len, EdgeCell, Luv};
use firmware_sim::pg::disparity::DisparityCell;
use firmware_sim::pg::image::Rgb8;
use firmware_sim::pg::stereo::phase::SafePhase;
use firmware_sim::{SimCamera, Ticks};

/// Counts LED toggles instead of driving hardware.
#[derive(Default)]
struct CountingLed {
    toggles: u32,
}

impl ErrorType for CountingLed {
    type Error = Infallible;
}

impl OutputPin for CountingLed {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.toggles += 1;
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.toggles += 1;
        Ok(())
    }
}

struct SleepDelay;

impl DelayNs for SleepDelay {
    fn delay_ns(&mut self, ns: u32) {
        std::thread::sleep(std::time::Duration::from_nanos(ns.into()));
    }
}

/// Nanoseconds since start.
struct WallTicks(Instant);

impl Ticks for WallTicks {
    fn now(&mut self) -> u64 {
        self.0.elapsed().as_nanos().try_into().unwrap_or(u64::MAX)
    }
}

pub fn run() -> ExitCode {
    let (w, h) = (MAX_WIDTH, MAX_HEIGHT);
    let mut rgb = vec![Rgb8::default(); w * h];
    let mut luv = vec![Luv::default(); luv_len(w, h)];
    let mut rows = vec![Luv::default(); row_scratch_len(w)];
    let mut conspicuity = vec![EdgeCell::default(); luv_len(w, h)];
    let mut bufs = Buffers {
        rgb: &mut rgb,
        luv: &mut luv,
        rows: &mut rows,
        conspicuity: &mut conspicuity,
    };

    let mut app = App::new(SimCamera::new(), CountingLed::default(), SleepDelay);
    let mut out = String::new();
    let result = app.run(
        &FRAME_SIZES,
        &mut bufs,
        &mut WallTicks(Instant::now()),
        &mut out,
        |r, out| {
            let px = (r.width * r.height) as f64;
            writeln!(
                out,
                "host-ns-per-pixel conspicuity {}x{} {:.1}",
                r.width,
                r.height,
                r.ticks.conspicuity as f64 / px
            )
        },
    );
    // The object stages run on the last frame's (160x120) conspicuity map.
    let objects = result.as_ref().ok().map(|()| run_objects(&conspicuity));
    print!("{out}");
    if let Some(r) = objects {
        match r {
            Ok(line) => print!("{line}"),
            Err(e) => {
                eprintln!("bench: object stages: {e:?}");
                return ExitCode::FAILURE;
            }
        }
    }
    if result.is_ok() {
        if let Err(e) = run_stereo() {
            eprintln!("bench: stereo stage: {e}");
            return ExitCode::FAILURE;
        }
    }
    match run_mlp() {
        Ok(lines) => print!("{lines}"),
        Err(e) => {
            eprintln!("bench: classifier: {e:?}");
            return ExitCode::FAILURE;
        }
    }
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("bench: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The object stages on the 160x120 conspicuity map; the line to print.
fn run_objects(edges: &[EdgeCell]) -> Result<String, objects::ObjectError> {
    use objects::len;
    let mut depth = vec![0u8; len::INPUT];
    let mut input = vec![DisparityCell::OFF; len::INPUT];
    let mut maps = vec![0u32; len::MAPS];
    let mut table = vec![0u32; len::TABLE];
    let mut mask = vec![false; len::INPUT];
    let mut bufs = objects::ObjectBuffers {
        depth: &mut depth,
        input: &mut input,
        maps: &mut maps,
        table: &mut table,
        mask: &mut mask,
    };
    let r = objects::detect(edges, &mut bufs, &mut WallTicks(Instant::now()))?;
    let mut line = String::new();
    // Writing into a String cannot fail.
    let _ = objects::write_result(&mut line, &r);
    Ok(line)
}

/// The stereo stage on the 160x120 demo pair, as on the board.
fn run_stereo() -> Result<(), firmware_sim::pg::stereo::StereoError> {
    use firmware_sim::bench::stereo_run::{self, len};
    use firmware_sim::pg::image::Rgb8;
    let (mut grey, mut rgb, mut z, mut col) = (
        vec![0u16; len::GREY],
        vec![Rgb8::new(0, 0, 0); len::RGB],
        vec![[0i16; 2]; len::Z],
        vec![[0i32; 3]; len::COL],
    );
    let (mut scores, mut costs, mut sums, mut picks, mut maps) = (
        vec![0i64; len::SCORES],
        vec![0u16; len::COSTS],
        vec![0u32; len::SUMS],
        vec![0i32; len::PICKS],
        vec![0u8; len::MAPS],
    );
    let mut bufs = firmware_sim::pg::stereo::c2f::C2fBuffers {
        grey: &mut grey,
        rgb: &mut rgb,
        z: &mut z,
        col: &mut col,
        scores: &mut scores,
        costs: &mut costs,
        sums: &mut sums,
        picks: &mut picks,
        maps: &mut maps,
        phase: firmware_sim::pg::stereo::phase::PhaseBuffers {
            rgb: &mut vec![Rgb8::new(0, 0, 0); len::P_RGB],
            v: &mut vec![0i32; len::P_V],
            z: &mut vec![[0i16; 2]; len::P_Z],
            row: &mut vec![firmware_sim::pg::disparity::DisparityCell::OFF; len::P_ROW],
        },
    };
    let r = stereo_run::run::<_, SafePhase>(&mut bufs, &mut WallTicks(Instant::now()))?;
    let mut out = String::new();
    // Writing into a String cannot fail.
    let _ = stereo_run::write_result(&mut out, &r);
    let px = (stereo_run::WIDTH * stereo_run::HEIGHT) as f64;
    let _ = writeln!(
        out,
        "host-ns-per-pixel stereo {}x{} {:.1}",
        stereo_run::WIDTH,
        stereo_run::HEIGHT,
        r.total as f64 / px
    );
    for (name, params) in &stereo_run::POINTS {
        let r =
            stereo_run::run_at::<_, SafePhase>(params, &mut bufs, &mut WallTicks(Instant::now()))?;
        // Host ticks are nanoseconds: only the checksum line is compared.
        let mut line = String::new();
        let _ = stereo_run::write_point(&mut line, name, params, &r, |t| t);
        if let Some(c) = line.lines().next() {
            let _ = writeln!(out, "{c}");
        }
    }
    let _ = stereo_run::write_kernel_check(&mut out, stereo_run::kernel_check::<SafePhase>());
    let _ =
        stereo_run::write_sgm_kernel_check(&mut out, stereo_run::sgm_kernel_check::<SafePhase>());
    let _ = firmware_sim::bench::costs_check::write_costs_kernel_check(
        &mut out,
        firmware_sim::bench::costs_check::costs_kernel_check::<SafePhase>(),
    );
    print!("{out}");
    Ok(())
}

/// The classifier's checksum lines and host nanoseconds per inference.
fn run_mlp() -> Result<String, firmware_sim::bench::mlp_run::MlpRunError> {
    use firmware_sim::bench::mlp_run::{self, len, MlpBuffers};
    let (mut mask, mut input) = (vec![0u8; len::MASK], vec![0u32; len::INPUT]);
    let (mut hidden, mut output) = (vec![0u8; len::HIDDEN], vec![0u16; len::OUTPUT]);
    let mut bufs = MlpBuffers {
        mask: &mut mask,
        input: &mut input,
        hidden: &mut hidden,
        output: &mut output,
    };
    let r = mlp_run::run::<firmware_sim::pg::mlp::SafeKernel, _>(
        &mut bufs,
        &mut WallTicks(Instant::now()),
    )?;
    let mut lines = String::new();
    // Writing into a String cannot fail.
    let _ = mlp_run::write_checksums(&mut lines, &r);
    for b in &r.bench {
        let _ = writeln!(
            lines,
            "host-ns mlp 720x{}x{} {}",
            b.hidden, b.classes, b.ticks
        );
    }
    Ok(lines)
}
