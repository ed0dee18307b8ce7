//! Counting a run's steps: a monotonic counter ([`Ticks`]: SysTick on the
//! board, the wall clock or nothing on the desktop) and the
//! instructions-per-pixel report line.

use core::fmt::{self, Write};

/// A monotonic counter read around each step (SysTick on the MCU, nothing on the host).
pub trait Ticks {
    /// Current count; only differences are meaningful.
    fn now(&mut self) -> u64;
}

/// A [`Ticks`] that always reads 0 (no timing).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoTicks;

impl Ticks for NoTicks {
    fn now(&mut self) -> u64 {
        0
    }
}

/// `ipp STEP WxH X.Y`: instructions per pixel with one decimal, without float formatting.
pub fn write_ipp(
    out: &mut impl Write,
    step: &str,
    w: usize,
    h: usize,
    instructions: u64,
) -> fmt::Result {
    let pixels = (w as u64 * h as u64).max(1);
    let tenths = (instructions * 10 + pixels / 2) / pixels;
    writeln!(out, "ipp {step} {w}x{h} {}.{}", tenths / 10, tenths % 10)
}
