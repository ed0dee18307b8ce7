//! firmware-sim's default binary, the protogist product on the board: one
//! frame of the simulated stereo camera through core's pipeline
//! ([`firmware_sim::product`]), at 160x120 (QEMU mps2-an386) or, with the
//! `f405` feature, at 128x96 (the STM32F405 of QEMU netduinoplus2).
//!
//! On a Cortex-M (`target_os = "none"`) the pair and the workspace are
//! statics in `.bss`, the stereo phase step is the assembly kernel
//! ([`dsp::PhaseAsm`]), and the stages are counted in instructions
//! (`instr stage NAME N`, `instr total N`); on the desktop they are heap
//! buffers, the phase step is the portable one (the same bits), and the
//! stages are timed in nanoseconds. Both print the same `product`,
//! `object` and `objects-checksum` lines.
#![cfg_attr(target_os = "none", no_std, no_main)]
#![deny(unsafe_code)]

#[cfg(target_os = "none")]
mod board;
#[cfg(target_os = "none")]
// The classifier's SMLAD kernel is the bench's: the pipeline's classifier
// takes no kernel.
#[allow(dead_code)]
mod dsp;
#[cfg(target_os = "none")]
mod dsp_colour;

#[cfg(target_os = "none")]
mod mcu {
    use core::fmt::Write;

    use cortex_m::singleton;
    use cortex_m_rt::entry;
    use cortex_m_semihosting::hio;
    use firmware_sim::pg::pipeline::Pipeline;
    use firmware_sim::product::{
        write_pipeline_error, write_ram_plans, Product, FRAME_LEN, HEIGHT, MODEL, PARAMS, STAGES,
        STEPS, TABLES, WIDTH, WORKSPACE_WORDS,
    };
    use firmware_sim::stereo_camera::SimStereoCamera;
    use firmware_sim::write_ipp;

    use super::board::{self, Led, SysTicks};
    use super::dsp::PhaseAsm;

    /// Writes the report; false after writing an `error:` line.
    fn run(out: &mut impl Write) -> Result<bool, core::fmt::Error> {
        let Some(mut cp) = cortex_m::Peripherals::take() else {
            return writeln!(out, "error: core peripherals already taken").map(|()| false);
        };
        let to_instructions = board::start_counting(&mut cp.SYST, out)?;
        // The pair and the workspace live in .bss, so the linker checks
        // them against memory.x.
        let (Some(frame), Some(workspace)) = (
            singleton!(: [u16; FRAME_LEN] = [0; FRAME_LEN]),
            singleton!(: [u64; WORKSPACE_WORDS] = [0; WORKSPACE_WORDS]),
        ) else {
            return writeln!(out, "error: frame buffers already taken").map(|()| false);
        };
        let pipeline = match Pipeline::<PhaseAsm>::with_kernel(&PARAMS, &TABLES, MODEL) {
            Ok(p) => p,
            Err(e) => {
                out.write_str("error: ")?;
                write_pipeline_error(out, &e)?;
                return writeln!(out).map(|()| false);
            }
        };
        let mut product = Product::new(SimStereoCamera::new(), Led, pipeline);
        let s = match product.frame((WIDTH, HEIGHT), frame, workspace, &mut SysTicks, out) {
            Ok(s) => s,
            Err(e) => {
                out.write_str("error: ")?;
                e.write_plain(out)?;
                return writeln!(out).map(|()| false);
            }
        };
        for (name, t) in STAGES.iter().zip(s.ticks.0) {
            writeln!(out, "instr stage {name} {}", to_instructions(t))?;
        }
        for (name, t) in STEPS.iter().zip(s.steps.0) {
            writeln!(out, "instr step {name} {}", to_instructions(t))?;
        }
        let total = to_instructions(s.total);
        writeln!(out, "instr total {total}")?;
        write_ipp(out, "frame", WIDTH, HEIGHT, total)?;
        write_ram_plans(out)?;
        writeln!(out, "stack peak {} bytes", board::stack_peak_bytes())?;
        Ok(true)
    }

    #[entry]
    fn main() -> ! {
        let ok = match hio::hstdout() {
            Ok(mut out) => run(&mut out).unwrap_or(false),
            Err(()) => false,
        };
        board::exit(ok)
    }
}

#[cfg(not(target_os = "none"))]
fn main() -> std::process::ExitCode {
    host::run()
}

#[cfg(not(target_os = "none"))]
mod host {
    use std::convert::Infallible;
    use std::fmt::Write as _;
    use std::process::ExitCode;
    use std::time::Instant;

    use embedded_hal::digital::{ErrorType, OutputPin};
    use firmware_sim::pg::pipeline::Pipeline;
    use firmware_sim::product::{
        write_ram_plans, Product, FRAME_LEN, HEIGHT, MODEL, PARAMS, STAGES, STEPS, TABLES, WIDTH,
        WORKSPACE_WORDS,
    };
    use firmware_sim::stereo_camera::SimStereoCamera;
    use firmware_sim::Ticks;

    /// An LED that goes nowhere.
    struct NoLed;

    impl ErrorType for NoLed {
        type Error = Infallible;
    }

    impl OutputPin for NoLed {
        fn set_low(&mut self) -> Result<(), Infallible> {
            Ok(())
        }
        fn set_high(&mut self) -> Result<(), Infallible> {
            Ok(())
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
        let mut frame = vec![0u16; FRAME_LEN];
        let mut workspace = vec![0u64; WORKSPACE_WORDS];
        let pipeline = match Pipeline::new(&PARAMS, &TABLES, MODEL) {
            Ok(p) => p,
            Err(e) => {
                eprintln!("product: {e}");
                return ExitCode::FAILURE;
            }
        };
        let mut product = Product::new(SimStereoCamera::new(), NoLed, pipeline);
        let mut out = String::new();
        let ticks = &mut WallTicks(Instant::now());
        let s = match product.frame((WIDTH, HEIGHT), &mut frame, &mut workspace, ticks, &mut out) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("product: {e}");
                return ExitCode::FAILURE;
            }
        };
        // Writing into a String cannot fail.
        for (name, t) in STAGES.iter().zip(s.ticks.0) {
            let _ = writeln!(out, "host-ns stage {name} {t}");
        }
        for (name, t) in STEPS.iter().zip(s.steps.0) {
            let _ = writeln!(out, "host-ns step {name} {t}");
        }
        let _ = writeln!(out, "host-ns total {}", s.total);
        let _ = write_ram_plans(&mut out);
        print!("{out}");
        ExitCode::SUCCESS
    }
}
