//! The disparity cell shared by the stereo stage (which writes it) and the
//! segmentation stage (which reads it).
//!
//! Disparity is left-referenced, `d = x_left - x_right >= 0`, in pixels of
//! the working image, in [`U8F8`] (LSB 1/256 px, range 0..256). OFF (no
//! estimate: no texture, ambiguous, or inconsistent left-right) is
//! `U8F8::MAX`, which no real disparity reaches.
//!
//! ```
//! use protogist::disparity::{Disparity, DisparityCell};
//! let d = DisparityCell::on(Disparity::from_num(12.5)).unwrap();
//! assert_eq!(d.get().map(|v| v.to_bits()), Some(3200));
//! assert!(DisparityCell::OFF.is_off());
//! ```

pub use crate::fixed::U8F8;
use crate::off::{MaybeOff, OffValue};

/// A disparity in pixels, [`U8F8`].
pub type Disparity = U8F8;

/// One cell of a disparity map: a disparity or OFF.
pub type DisparityCell = MaybeOff<Disparity>;

impl OffValue for U8F8 {
    /// `U8F8::MAX` (255.996 px).
    const OFF: Self = U8F8::MAX;
}

/// A whole-pixel disparity as a cell (saturating below OFF).
pub fn from_pixels(d: u8) -> DisparityCell {
    MaybeOff::from_raw(U8F8::from_bits(u16::from(d) << 8).min(U8F8::from_bits(u16::MAX - 1)))
}
