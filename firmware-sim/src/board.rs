//! The board support of the product binary (`src/bin/product.rs`) on QEMU
//! mps2-an386: SysTick instruction counting, the FPGAIO LED, the stack
//! high-water mark, the panic handler. `src/mcu.rs` has the same for the
//! bench firmware.

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
    writeln!(
        out,
        "calib instructions={CAL_INSTRUCTIONS} ticks={cal_ticks}"
    )?;
    Ok(move |t: u64| t * CAL_INSTRUCTIONS / cal_ticks)
}

/// mps2 FPGAIO LED0 (bit 0 of the LED register at 0x4002_8000).
pub struct Mps2Led;

const FPGAIO_LED: *mut u32 = 0x4002_8000 as *mut u32;

impl Mps2Led {
    #[allow(unsafe_code)]
    fn write(on: bool) {
        // SAFETY: FPGAIO LED register of mps2-an385/an386, a plain R/W MMIO word.
        unsafe { core::ptr::write_volatile(FPGAIO_LED, u32::from(on)) }
    }
}

impl ErrorType for Mps2Led {
    type Error = core::convert::Infallible;
}

impl OutputPin for Mps2Led {
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
