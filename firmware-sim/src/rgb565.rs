//! RGB565, the sensor's pixel format: packing and exact expansion.
//!
//! The build script includes this file too (`build.rs`), to make the
//! CIELUV table of every RGB565 value with the same expansion the frames
//! use (`crate::stereo_camera::luv_of_rgb565`).

use protogist::image::Rgb8;

/// Packs an RGB8 colour as a sensor would deliver it: the top 5, 6 and 5
/// bits of red, green and blue.
pub const fn pack_rgb565(p: Rgb8) -> u16 {
    ((p.r as u16 >> 3) << 11) | ((p.g as u16 >> 2) << 5) | (p.b as u16 >> 3)
}

/// Expands an RGB565 pixel to RGB8 by bit replication: each channel's top
/// bits fill its low bits (`r8 = r5 << 3 | r5 >> 2`, `g8 = g6 << 2 | g6 >>
/// 4`), so 0 stays 0, full scale becomes 255, and the steps are as even as
/// 8 bits allow. [`pack_rgb565`] of the result gives `v` back.
pub const fn expand_rgb565(v: u16) -> Rgb8 {
    let r = ((v >> 11) & 0x1f) as u8;
    let g = ((v >> 5) & 0x3f) as u8;
    let b = (v & 0x1f) as u8;
    Rgb8 {
        r: (r << 3) | (r >> 2),
        g: (g << 2) | (g >> 4),
        b: (b << 3) | (b >> 2),
    }
}
