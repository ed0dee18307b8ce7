//! The board support of both firmware binaries (the product,
//! `src/main.rs`, and the bench, `src/bin/bench/`): SysTick instruction
//! counting, the status LED, the stack high-water mark, the exit and the
//! panic handler.
//!
//! Two machines: QEMU mps2-an386 (`memory.x`; LED0 of the FPGAIO) and,
//! with the `f405` feature, the STM32F405 of QEMU netduinoplus2
//! (`memory-f405-qemu.x`; the Netduino Plus 2's LED on PA10). SysTick runs
//! on the core clock on both: under `-icount shift=0` QEMU retires one
//! instruction per virtual nanosecond, so [`start_counting`] measures the
//! ticks per instruction with a delay loop of known length instead of
//! trusting a clock rate.

use core::fmt::Write;
use core::num::NonZeroU64;
use core::panic::PanicInfo;
use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::exception;
use cortex_m_semihosting::{debug, hio};
use embedded_hal::digital::{ErrorType, OutputPin};
use firmware_sim::Ticks;

/// SysTick is 24 bits wide.
const RELOAD: u32 = 0x00FF_FFFF;
/// `asm::delay(n)` runs n + 1 iterations of `subs; bne`: 2n + 2 instructions.
const CAL_DELAY: u32 = 2_000_000;
const CAL_INSTRUCTIONS: u64 = 2 * CAL_DELAY as u64 + 2;

static WRAPS: AtomicU32 = AtomicU32::new(0);

#[exception]
fn SysTick() {
    WRAPS.fetch_add(1, Ordering::Relaxed);
}

/// 64-bit SysTick count (wraps are counted by the exception).
pub struct SysTicks;

impl Ticks for SysTicks {
    fn now(&mut self) -> u64 {
        loop {
            let before = WRAPS.load(Ordering::Acquire);
            let current = SYST::get_current();
            if WRAPS.load(Ordering::Acquire) == before {
                return u64::from(before) * (u64::from(RELOAD) + 1) + u64::from(RELOAD - current);
            }
        }
    }
}

/// Starts SysTick on the core clock and measures instructions per tick
/// with a delay loop of known length; gives the converter from ticks to
/// instructions and writes the `calib` line.
pub fn start_counting(
    syst: &mut SYST,
    out: &mut impl Write,
) -> Result<impl Fn(u64) -> u64, core::fmt::Error> {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(RELOAD);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
    // The current value reads 0 until the first reload; start from a loaded counter.
    while SYST::get_current() == 0 {}
    let mut ticks = SysTicks;
    let t0 = ticks.now();
    cortex_m::asm::delay(CAL_DELAY);
    // Non-zero by type: the conversion divides by it.
    let cal_ticks = NonZeroU64::new(ticks.now() - t0).unwrap_or(NonZeroU64::MIN);
    let per_tick_x100 = CAL_INSTRUCTIONS * 100 / cal_ticks;
    writeln!(
        out,
        "calib instructions={CAL_INSTRUCTIONS} ticks={cal_ticks} instructions_per_tick={}.{:02}",
        per_tick_x100 / 100,
        per_tick_x100 % 100
    )?;
    Ok(move |t: u64| t * CAL_INSTRUCTIONS / cal_ticks)
}

/// The status LED: LED0 of the mps2 FPGAIO (bit 0 of the register at
/// 0x4002_8000), or with `f405` the Netduino Plus 2's LED on PA10 (GPIOA's
/// BSRR at 0x4002_0018; QEMU 7.2 does not model the F405's GPIO and
/// ignores the write).
pub struct Led;

#[cfg(not(feature = "f405"))]
impl Led {
    #[allow(unsafe_code)]
    fn write(on: bool) {
        const FPGAIO_LED: *mut u32 = 0x4002_8000 as *mut u32;
        // SAFETY: FPGAIO LED register of mps2-an385/an386, a plain R/W MMIO word.
        unsafe { core::ptr::write_volatile(FPGAIO_LED, u32::from(on)) }
    }
}

#[cfg(feature = "f405")]
impl Led {
    #[allow(unsafe_code)]
    fn write(on: bool) {
        const GPIOA_BSRR: *mut u32 = 0x4002_0018 as *mut u32;
        const PA10: u32 = 1 << 10;
        // SAFETY: GPIOA's bit set/reset register of the STM32F405, a
        // write-only MMIO word: bit n sets pin n, bit n + 16 resets it.
        unsafe { core::ptr::write_volatile(GPIOA_BSRR, if on { PA10 } else { PA10 << 16 }) }
    }
}

impl ErrorType for Led {
    type Error = core::convert::Infallible;
}

impl OutputPin for Led {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        Self::write(false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Self::Error> {
        Self::write(true);
        Ok(())
    }
}

/// Deepest stack use so far: cortex-m-rt (`paint-stack`) fills the stack region
/// with 0xCCCC_CCCC at reset; count the words from the top that were overwritten.
#[allow(unsafe_code)]
pub fn stack_peak_bytes() -> usize {
    extern "C" {
        static _stack_start: u32;
        static _stack_end: u32;
    }
    // Taking the address of an extern static needs no `unsafe`.
    let (top, bottom) = (
        core::ptr::addr_of!(_stack_start) as usize,
        core::ptr::addr_of!(_stack_end) as usize,
    );
    let mut addr = bottom;
    // SAFETY: [_stack_end, _stack_start) is RAM reserved for the stack; reads are aligned words.
    while addr < top
        && unsafe { core::ptr::read_volatile(addr as *const u32) } == cortex_m_rt::STACK_PAINT_VALUE
    {
        addr += 4;
    }
    top - addr
}

/// Exits QEMU with semihosting success or failure.
pub fn exit(ok: bool) -> ! {
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}

/// Required by `no_std`, and never linked in: `cargo xtask firmware` fails
/// if the ELF contains it or any of `core`'s panic functions.
#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    if let Ok(mut err) = hio::hstderr() {
        let _ = writeln!(err, "panic: {info}");
    }
    exit(false)
}
