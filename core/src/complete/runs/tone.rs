//! One byte of smoothed colour per pixel, for the completion's edge cells.

use super::SideColour;
use crate::conspicuity::Luv;

/// A smoothed CIELUV colour in one byte: L* in 16 bins of 6.25 units (bits
/// 7..4), u* in 4 bins over −84..177 (bits 3..2) and v* in 4 bins over
/// −134..108 (bits 1..0); channels past the ends go to the end bins.
///
/// It is what the pipeline keeps per pixel for the completion, which only
/// asks which neighbour of an edge cell looks most like it: on the seeded
/// synthetic scenes this byte gives the full colour's recall, precision
/// and mask IoU (`docs/PIPELINE.md`, "The workspace").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(transparent)]
pub struct Tone(pub u8);

/// `(lowest raw Q6 value, bins, Q6 width of a bin)` of L*, u*, v*.
const BINS: [(i32, i32, i32); 3] = [(0, 16, 401), (-5400, 4, 4176), (-8600, 4, 3876)];

/// The bin of raw Q6 channel `x`.
#[inline(always)]
fn bin(x: i16, (lo, bins, width): (i32, i32, i32)) -> u8 {
    // In 0..bins: a quotient of a value clamped to 0..bins * width.
    ((i32::from(x) - lo).clamp(0, bins * width - 1) / width) as u8
}

impl Tone {
    /// The tone of a CIELUV pixel.
    #[inline]
    pub fn of(p: Luv) -> Self {
        let [l, u, v] = p.to_bits();
        let [bl, bu, bv] = BINS;
        Self(bin(l, bl) << 4 | bin(u, bu) << 2 | bin(v, bv))
    }

    /// The bins `[L*, u*, v*]`.
    pub const fn bins(self) -> [u8; 3] {
        [self.0 >> 4, self.0 >> 2 & 3, self.0 & 3]
    }
}

impl Tone {
    /// The CIELUV colour at the low corner of the tone's bins: CIELUV
    /// distances between such colours are [`SideColour::dist2`] of the
    /// tones.
    pub fn to_luv(self) -> Luv {
        let c = |b: u8, (lo, _, width): (i32, i32, i32)| {
            i16::try_from(lo + i32::from(b) * width).unwrap_or(0)
        };
        let [l, u, v] = self.bins();
        let [bl, bu, bv] = BINS;
        Luv::from_bits(c(l, bl), c(u, bu), c(v, bv))
    }
}

impl SideColour for Tone {
    /// The squared distance between the bins' starts, in raw Q6 units
    /// (below 2^29).
    fn dist2(self, other: Self) -> u32 {
        let sq = |a: u8, b: u8, width: i32| {
            let d = u32::from(a.abs_diff(b)) * width.unsigned_abs();
            d * d
        };
        let ([a0, a1, a2], [b0, b1, b2]) = (self.bins(), other.bins());
        sq(a0, b0, BINS[0].2) + sq(a1, b1, BINS[1].2) + sq(a2, b2, BINS[2].2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_cover_the_gamut_and_clamp_outside_it() {
        assert_eq!(Tone::of(Luv::from_bits(0, -5400, -8600)).bins(), [0, 0, 0]);
        assert_eq!(
            Tone::of(Luv::from_bits(6400, 11300, 6900)).bins(),
            [15, 3, 3]
        );
        assert_eq!(
            Tone::of(Luv::from_bits(-100, i16::MIN, i16::MIN)).bins(),
            [0, 0, 0]
        );
        assert_eq!(
            Tone::of(Luv::from_bits(i16::MAX, i16::MAX, i16::MAX)).bins(),
            [15, 3, 3]
        );
        // Mid grey: L* 50, u* = v* = 0.
        assert_eq!(Tone::of(Luv::from_bits(3200, 0, 0)).bins(), [7, 1, 2]);
    }

    #[test]
    fn distance_grows_with_the_bins_apart() {
        let t = |l: u8, u: u8, v: u8| Tone(l << 4 | u << 2 | v);
        assert_eq!(t(3, 1, 2).dist2(t(3, 1, 2)), 0);
        assert_eq!(t(3, 1, 2).dist2(t(5, 1, 2)), 802 * 802);
        assert!(t(0, 0, 0).dist2(t(0, 3, 0)) > t(0, 0, 0).dist2(t(15, 0, 0)));
        assert_eq!(t(0, 0, 0).dist2(t(15, 3, 3)), t(15, 3, 3).dist2(t(0, 0, 0)));
        for (a, b) in [(t(1, 2, 3), t(9, 0, 1)), (t(15, 3, 3), t(0, 0, 0))] {
            assert_eq!(a.to_luv().dist2(b.to_luv()), a.dist2(b));
            assert_eq!(Tone::of(a.to_luv()), a);
        }
    }
}
