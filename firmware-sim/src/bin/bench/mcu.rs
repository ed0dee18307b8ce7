//! The bench firmware on QEMU mps2-an386 (Cortex-M4, 25 MHz SYSCLK): every
//! stage harness of [`firmware_sim::bench`] in turn, counted in
//! instructions by the board's SysTick ([`crate::board`]), with the
//! assembly kernels of [`crate::dsp`].

use core::fmt::Write;

use cortex_m::peripheral::Peripherals;
use cortex_m::singleton;
use cortex_m_rt::entry;
use cortex_m_semihosting::hio;
use embedded_hal::delay::DelayNs;
use firmware_sim::bench::objects::{self, len};
use firmware_sim::bench::{App, Buffers, FRAME_SIZES, MAX_HEIGHT, MAX_WIDTH};
use firmware_sim::pg::conspicuity::{luv_len, row_scratch_len, scratch_bytes, EdgeCell, Luv};
use firmware_sim::pg::disparity::DisparityCell;
use firmware_sim::pg::image::Rgb8;
use firmware_sim::{write_ipp, SimCamera};

use crate::board::{self, Led, SysTicks};

const PIXELS: usize = MAX_WIDTH * MAX_HEIGHT;
const LUV_LEN: usize = luv_len(MAX_WIDTH, MAX_HEIGHT);
const ROWS_LEN: usize = row_scratch_len(MAX_WIDTH);
/// mps2-an386 SYSCLK is 25 MHz: 40 ns per cycle.
const NS_PER_CYCLE: u32 = 40;

/// Busy-wait delay at the 25 MHz core clock.
struct CycleDelay;

impl DelayNs for CycleDelay {
    fn delay_ns(&mut self, ns: u32) {
        cortex_m::asm::delay(ns / NS_PER_CYCLE);
    }
}

fn run(out: &mut impl Write) -> Result<(), &'static str> {
    let mut cp = Peripherals::take().ok_or("core peripherals already taken")?;
    let to_instructions =
        board::start_counting(&mut cp.SYST, out).map_err(|_| "semihosting write failed")?;
    let mut ticks = SysTicks;

    // Working memory lives in .bss, so the linker checks it against memory.x.
    let rgb = singleton!(: [Rgb8; PIXELS] = [Rgb8 { r: 0, g: 0, b: 0 }; PIXELS])
        .ok_or("rgb buffer taken")?;
    let luv = singleton!(: [Luv; LUV_LEN] = [Luv::default(); LUV_LEN]).ok_or("luv buffer taken")?;
    let rows =
        singleton!(: [Luv; ROWS_LEN] = [Luv::default(); ROWS_LEN]).ok_or("row buffer taken")?;
    let conspicuity = singleton!(: [EdgeCell; LUV_LEN] = [EdgeCell::default(); LUV_LEN])
        .ok_or("conspicuity buffer taken")?;
    let mut bufs = Buffers {
        rgb,
        luv,
        rows,
        conspicuity,
    };

    let mut app = App::new(SimCamera::new(), Led, CycleDelay);
    app.run(&FRAME_SIZES, &mut bufs, &mut ticks, out, |r, out| {
        let (w, h) = (r.width, r.height);
        write_ipp(out, "capture", w, h, to_instructions(r.ticks.capture))?;
        write_ipp(
            out,
            "conspicuity",
            w,
            h,
            to_instructions(r.ticks.conspicuity),
        )?;
        for (step, t) in [
            ("luv", r.ticks.luv),
            ("smooth", r.ticks.smooth),
            ("cmap", r.ticks.cmap),
            ("threshold", r.ticks.threshold),
            ("checksum", r.ticks.checksum),
        ] {
            write_ipp(out, step, w, h, to_instructions(t))?;
        }
        writeln!(out, "scratch conspicuity {w}x{h} {}", scratch_bytes(w, h))
    })
    .map_err(|_| "firmware app failed")?;

    // The object stages on the last frame's (160x120) conspicuity map.
    let (ow, oh) = (objects::OBJ_WIDTH, objects::OBJ_HEIGHT);
    let mut obj = objects::ObjectBuffers {
        depth: singleton!(: [u8; len::INPUT] = [0; len::INPUT]).ok_or("depth taken")?,
        input: singleton!(: [DisparityCell; len::INPUT] = [DisparityCell::OFF; len::INPUT])
            .ok_or("input taken")?,
        maps: singleton!(: [u32; len::MAPS] = [0; len::MAPS]).ok_or("maps taken")?,
        table: singleton!(: [u32; len::TABLE] = [0; len::TABLE]).ok_or("table taken")?,
        mask: singleton!(: [bool; len::INPUT] = [false; len::INPUT]).ok_or("mask taken")?,
    };
    let r = objects::detect(bufs.conspicuity, &mut obj, &mut ticks)
        .map_err(|_| "object stages failed")?;
    objects::write_result(out, &r).map_err(|_| "semihosting write failed")?;
    write_ipp(out, "segment", ow, oh, to_instructions(r.segment))
        .and_then(|()| {
            objects::SEGMENT_STEPS
                .iter()
                .zip(r.steps)
                .try_for_each(|((_, name), t)| write_ipp(out, name, ow, oh, to_instructions(t)))
        })
        .and_then(|()| write_ipp(out, "shape", ow, oh, to_instructions(r.shape)))
        .and_then(|()| {
            writeln!(
                out,
                "scratch segment {ow}x{oh} {}",
                firmware_sim::pg::segment::scratch_bytes(ow, oh)
            )
        })
        .map_err(|_| "semihosting write failed")?;
    run_stereo(out, &mut ticks, &to_instructions)?;
    run_mlp(out, &mut ticks, &to_instructions)?;
    writeln!(out, "stack peak {} bytes", board::stack_peak_bytes())
        .map_err(|_| "semihosting write failed")
}

/// The stereo stage on the 160x120 demo pair (row-streamed: only its
/// scratch is in RAM).
fn run_stereo(
    out: &mut impl Write,
    ticks: &mut SysTicks,
    to_instructions: &impl Fn(u64) -> u64,
) -> Result<(), &'static str> {
    use firmware_sim::bench::stereo_run::{self, len, Words, ZCell};
    use firmware_sim::pg::disparity::DisparityCell;
    use firmware_sim::pg::image::Rgb8;
    use firmware_sim::pg::stereo::c2f::C2fBuffers;
    use firmware_sim::pg::stereo::phase::PhaseBuffers;
    const BLACK: Rgb8 = Rgb8::new(0, 0, 0);
    let mut bufs = C2fBuffers {
        grey: singleton!(: [u16; len::GREY] = [0; len::GREY]).ok_or("stereo grey taken")?,
        rgb: singleton!(: [Rgb8; len::RGB] = [BLACK; len::RGB]).ok_or("stereo rgb taken")?,
        z: singleton!(: [ZCell; len::Z] = [[0; 2]; len::Z]).ok_or("stereo z taken")?,
        col: singleton!(: [[i32; 3]; len::COL] = [[0; 3]; len::COL]).ok_or("stereo col taken")?,
        scores: singleton!(: [i64; len::SCORES] = [0; len::SCORES]).ok_or("stereo scores taken")?,
        costs: singleton!(: [u16; len::COSTS] = [0; len::COSTS]).ok_or("stereo costs taken")?,
        sums: singleton!(: [u32; len::SUMS] = [0; len::SUMS]).ok_or("stereo sums taken")?,
        picks: singleton!(: [i32; len::PICKS] = [0; len::PICKS]).ok_or("stereo picks taken")?,
        maps: singleton!(: [u8; len::MAPS] = [0; len::MAPS]).ok_or("stereo maps taken")?,
        phase: PhaseBuffers {
            rgb: singleton!(: [Rgb8; len::P_RGB] = [BLACK; len::P_RGB]).ok_or("phase rgb taken")?,
            v: singleton!(: [i32; len::P_V] = [0; len::P_V]).ok_or("phase v taken")?,
            // Word-aligned: the phase kernel reads the responses with `ldm`.
            z: &mut singleton!(: Words<[ZCell; len::P_Z]> = Words([[0; 2]; len::P_Z]))
                .ok_or("phase z taken")?
                .0,
            row: singleton!(: [DisparityCell; len::P_ROW] = [DisparityCell::OFF; len::P_ROW])
                .ok_or("phase row taken")?,
        },
    };
    let r = stereo_run::run::<_, crate::dsp::PhaseAsm>(&mut bufs, ticks)
        .map_err(|_| "stereo stage failed")?;
    stereo_run::write_report(out, &r, to_instructions).map_err(|_| "semihosting write failed")?;
    for (name, params) in &stereo_run::POINTS {
        let r = stereo_run::run_at::<_, crate::dsp::PhaseAsm>(params, &mut bufs, ticks)
            .map_err(|_| "stereo point failed")?;
        stereo_run::write_point(out, name, params, &r, to_instructions)
            .map_err(|_| "semihosting write failed")?;
    }
    stereo_run::write_kernel_check(out, stereo_run::kernel_check::<crate::dsp::PhaseAsm>())
        .map_err(|_| "semihosting write failed")?;
    stereo_run::write_sgm_kernel_check(out, stereo_run::sgm_kernel_check::<crate::dsp::PhaseAsm>())
        .map_err(|_| "semihosting write failed")?;
    firmware_sim::bench::costs_check::write_costs_kernel_check(
        out,
        firmware_sim::bench::costs_check::costs_kernel_check::<crate::dsp::PhaseAsm>(),
    )
    .map_err(|_| "semihosting write failed")?;
    Ok(())
}

/// The classifier: checksums, then instructions per multiply-accumulate of
/// the two benchmark networks (`ipm mlp 720xHxK <instr/MAC> ...`).
fn run_mlp(
    out: &mut impl Write,
    ticks: &mut SysTicks,
    to_instructions: &dyn Fn(u64) -> u64,
) -> Result<(), &'static str> {
    use firmware_sim::bench::mlp_run::{self, len, macs, MlpBuffers};
    let mut bufs = MlpBuffers {
        mask: singleton!(: [u8; len::MASK] = [0; len::MASK]).ok_or("mlp mask taken")?,
        input: singleton!(: [u32; len::INPUT] = [0; len::INPUT]).ok_or("mlp input taken")?,
        hidden: singleton!(: [u8; len::HIDDEN] = [0; len::HIDDEN]).ok_or("mlp hidden taken")?,
        output: singleton!(: [u16; len::OUTPUT] = [0; len::OUTPUT]).ok_or("mlp output taken")?,
    };
    let r = mlp_run::run::<crate::dsp::SmladKernel, _>(&mut bufs, ticks)
        .map_err(|_| "classifier failed")?;
    mlp_run::write_checksums(out, &r).map_err(|_| "semihosting write failed")?;
    for b in &r.bench {
        let instructions = to_instructions(b.ticks);
        let m = macs(b.hidden, b.classes);
        let hundredths = (instructions * 100 + m / 2) / m.max(1);
        writeln!(
            out,
            "ipm mlp 720x{}x{} {}.{:02} instructions={instructions} macs={m} flash={}",
            b.hidden,
            b.classes,
            hundredths / 100,
            hundredths % 100,
            b.bytes
        )
        .map_err(|_| "semihosting write failed")?;
    }
    Ok(())
}

#[entry]
fn main() -> ! {
    let ok = match hio::hstdout() {
        Ok(mut out) => match run(&mut out) {
            Ok(()) => true,
            Err(e) => {
                let _ = writeln!(out, "error: {e}");
                false
            }
        },
        Err(()) => false,
    };
    board::exit(ok)
}
