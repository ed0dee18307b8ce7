//! The hook for a target's own code in the stage's two hot loops.

use super::Luv;
use crate::stereo::phase::SafePhase;

/// The smoothing cell's row and C~'s window, the stage's hot loops
/// (`docs/CONSPICUITY.md`, "Cost"). The default methods are the portable
/// code; a target may override them (the firmware's DSP kernel packs L*
/// and u* into one word) and must return the same bits for every input
/// whose channels are within ±[`LUV_LIMIT_BITS`](super::LUV_LIMIT_BITS),
/// which every [`Luv`] is. The pipeline takes it from the same type as
/// its stereo [`PhaseKernel`](crate::stereo::phase::PhaseKernel).
pub trait ColourKernel {
    /// One row of the smoothing cell ([`snn_row`](super::snn_row)).
    #[inline(always)]
    fn snn_row(prev: &[Luv], cur: &[Luv], next: &[Luv], out: &mut [Luv]) {
        super::snn_row(prev, cur, next, out);
    }

    /// The largest squared distance over the 4 pairs of a 3x3 window
    /// ([`pair_dist2`](super::pair_dist2)).
    #[inline(always)]
    fn pair_dist2(up: &[Luv], mid: &[Luv], down: &[Luv]) -> u32 {
        super::pair_dist2(up, mid, down)
    }
}

/// The portable kernel.
impl ColourKernel for SafePhase {}
