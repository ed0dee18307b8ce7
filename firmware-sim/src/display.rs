//! An RGB565 frame buffer as an `embedded-graphics` draw target, so that
//! the board draws the pipeline's objects with `protogist::draw` into the
//! memory it sends to its display (or writes to storage).
//!
//! ```
//! use firmware_sim::display::Rgb565Frame;
//! use protogist::draw::{draw_objects, LabelStyle, ObjectLabel};
//!
//! let mut px = [0u16; 160 * 120];
//! let mut frame = Rgb565Frame::new(&mut px, 160, 120).unwrap();
//! let cup = ObjectLabel::new(40, 50, 30, 20, "cup", true).with_score(87);
//! draw_objects(&mut frame, &[cup], &LabelStyle::default()).unwrap();
//! assert_eq!(frame.pixel(40, 60), Some(0x07e0)); // green outline
//! ```

use core::convert::Infallible;
use embedded_graphics::pixelcolor::raw::RawU16;
use embedded_graphics::pixelcolor::Rgb565;
use embedded_graphics::prelude::*;

/// A row-major RGB565 frame over caller memory: pixel `(x, y)` is
/// `buf[y * width + x]`, in `Rgb565`'s raw 5-6-5 bit order.
#[derive(Debug)]
pub struct Rgb565Frame<'a> {
    buf: &'a mut [u16],
    width: usize,
    height: usize,
}

/// Why a frame buffer was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameError {
    /// `buf` holds fewer than `width * height` pixels.
    TooSmall {
        /// Pixels needed.
        needed: usize,
        /// Pixels given.
        len: usize,
    },
    /// `width * height` overflows, or a side exceeds `u32`.
    TooLarge,
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::TooSmall { needed, len } => write!(
                f,
                "frame buffer holds {len} pixels, the frame needs {needed}"
            ),
            Self::TooLarge => f.write_str("frame size overflows"),
        }
    }
}

impl<'a> Rgb565Frame<'a> {
    /// A `width` x `height` frame over `buf` (longer buffers are fine; the
    /// rest is left alone).
    ///
    /// # Errors
    /// [`FrameError`] when `buf` is too short or the size overflows.
    pub fn new(buf: &'a mut [u16], width: usize, height: usize) -> Result<Self, FrameError> {
        let needed = width.checked_mul(height).ok_or(FrameError::TooLarge)?;
        if u32::try_from(width).is_err() || u32::try_from(height).is_err() {
            return Err(FrameError::TooLarge);
        }
        if buf.len() < needed {
            return Err(FrameError::TooSmall {
                needed,
                len: buf.len(),
            });
        }
        Ok(Self { buf, width, height })
    }

    /// The raw RGB565 value at `(x, y)`, or `None` outside the frame.
    pub fn pixel(&self, x: usize, y: usize) -> Option<u16> {
        self.index(x, y).and_then(|i| self.buf.get(i)).copied()
    }

    fn index(&self, x: usize, y: usize) -> Option<usize> {
        (x < self.width && y < self.height).then(|| y * self.width + x)
    }
}

impl OriginDimensions for Rgb565Frame<'_> {
    fn size(&self) -> Size {
        // Both sides fit u32 (checked in `new`).
        let side = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
        Size::new(side(self.width), side(self.height))
    }
}

impl DrawTarget for Rgb565Frame<'_> {
    type Color = Rgb565;
    type Error = Infallible;

    fn draw_iter<I>(&mut self, pixels: I) -> Result<(), Infallible>
    where
        I: IntoIterator<Item = Pixel<Rgb565>>,
    {
        for Pixel(p, c) in pixels {
            let (Ok(x), Ok(y)) = (usize::try_from(p.x), usize::try_from(p.y)) else {
                continue;
            };
            if let Some(slot) = self.index(x, y).and_then(|i| self.buf.get_mut(i)) {
                *slot = RawU16::from(c).into_inner();
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use protogist::draw::{caption, draw_objects, CaptionStyle, LabelStyle, ObjectLabel};

    const GREEN: u16 = 0x07e0;
    const MAGENTA: u16 = 0xf81f;

    #[test]
    fn a_labelled_box_lands_on_the_right_pixels() {
        let (w, h) = (64, 48);
        let mut px = [0u16; 64 * 48];
        let mut f = Rgb565Frame::new(&mut px, w, h).unwrap();
        let label = ObjectLabel::new(10, 20, 20, 10, "ok", true);
        let Ok(()) = draw_objects(&mut f, &[label], &LabelStyle::default());
        for (x, y) in [(10, 20), (29, 20), (10, 29), (29, 29), (20, 29), (10, 25)] {
            assert_eq!(f.pixel(x, y), Some(GREEN), "({x}, {y})");
        }
        for (x, y) in [(9, 25), (30, 25), (20, 30), (11, 21), (20, 25)] {
            assert_eq!(f.pixel(x, y), Some(0), "({x}, {y})");
        }
        // The tab above: rows 8..=19, x 10..=23 ("ok" is 12 px + 2), filled
        // green with black text.
        let tab: [usize; 2] =
            (8..20)
                .flat_map(|y| (10..24).map(move |x| (x, y)))
                .fold([0, 0], |[g, b], (x, y)| match f.pixel(x, y) {
                    Some(GREEN) => [g + 1, b],
                    Some(0) => [g, b + 1],
                    _ => [g, b],
                });
        assert_eq!(tab[0] + tab[1], 12 * 14);
        assert!(tab[1] > 10, "no text pixels: {tab:?}");
        assert_eq!(f.pixel(24, 12), Some(0));
        // Row-major layout in the raw buffer.
        assert_eq!(px[20 * 64 + 10], GREEN);
    }

    #[test]
    fn clipping_at_the_frame_edges_and_unknown_colours() {
        let mut px = [0u16; 32 * 16];
        let mut f = Rgb565Frame::new(&mut px, 32, 16).unwrap();
        let labels = [
            ObjectLabel::new(-5, -5, 100, 100, "big", false),
            ObjectLabel::new(20, 8, 0, 5, "empty", true),
        ];
        let Ok(()) = draw_objects(&mut f, &labels, &LabelStyle::default());
        // Only the unknown tab shows (top-left, magenta); the box's edges
        // are all outside.
        assert_eq!(f.pixel(0, 0), Some(MAGENTA));
        assert_eq!(f.pixel(31, 15), Some(0));
        assert!((0..16).all(|y| f.pixel(20, y) != Some(GREEN)));
    }

    #[test]
    fn a_caption_fills_its_strip() {
        let mut px = [0u16; 40 * 12];
        let mut f = Rgb565Frame::new(&mut px, 40, 12).unwrap();
        let Ok(()) = caption(&mut f, "(a) x", &CaptionStyle::default());
        let white = px.iter().filter(|&&p| p == 0xffff).count();
        assert!(white > 10 && white < px.len() / 2, "{white}");
    }

    #[test]
    fn bad_buffers_get_typed_errors() {
        let mut px = [0u16; 10];
        assert_eq!(
            Rgb565Frame::new(&mut px, 4, 3).unwrap_err(),
            FrameError::TooSmall {
                needed: 12,
                len: 10
            }
        );
        assert_eq!(
            Rgb565Frame::new(&mut px, usize::MAX, 2).unwrap_err(),
            FrameError::TooLarge
        );
        let f = Rgb565Frame::new(&mut px, 0, 0).unwrap();
        assert_eq!(f.size(), Size::zero());
        assert_eq!(f.pixel(0, 0), None);
    }
}
