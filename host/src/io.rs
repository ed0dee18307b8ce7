//! Image loading and exact area-average downscaling (writing is
//! [`crate::output`]'s).
//!
//! The downscaler is written here rather than taken from a resizing crate:
//! the common "box" filters (Pillow's and `fast_image_resize`'s) weight a
//! source pixel 1 or 0 by whether its centre falls in the output footprint,
//! which is not area averaging for non-integer ratios. [`area_downscale`]
//! weights every source pixel by its exact overlap with the output pixel, in
//! integers, and rounds once.

use crate::error::{HostError, Result};
use image::{ImageReader, RgbImage};
use protogist::image::Rgb8;
use std::fs;
use std::path::Path;

/// Largest input image accepted, in pixels (checked from the header,
/// before anything is decoded): 2^26, 67 Mpx, about 200 MB as 8-bit RGB.
pub const MAX_INPUT_PIXELS: u64 = 1 << 26;

/// Whether a damaged JPEG is decoded anyway, with a warning
/// (`--accept-damaged`); off by default.
static ACCEPT_DAMAGED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Accept (`true`) or refuse (`false`, the default) damaged JPEGs in every
/// later load of this process; an accepted one is decoded leniently, with
/// a `warning:` line on stderr. Set once from the command line
/// (`--accept-damaged`).
pub fn set_accept_damaged(accept: bool) {
    ACCEPT_DAMAGED.store(accept, std::sync::atomic::Ordering::Relaxed);
}

/// Loads a PNG or JPEG (the format is sniffed from the bytes) as 8-bit RGB.
///
/// The size in the header is checked against [`MAX_INPUT_PIXELS`] before
/// decoding. A JPEG is first decoded strictly (`zune-jpeg`'s strict mode):
/// a file cut short, or with corrupt entropy-coded data or a marker out of
/// place, is an error, where the lenient decoder would fill the missing
/// part in grey and carry on.
///
/// # Errors
/// [`HostError::Io`] when the file cannot be opened or read,
/// [`HostError::Decode`] when it is not a supported, intact image,
/// [`HostError::DamagedImage`] for a truncated or corrupt JPEG (unless
/// [`set_accept_damaged`]),
/// [`HostError::ImageTooLarge`] above the size limit.
pub fn load_rgb(path: &Path) -> Result<RgbImage> {
    let bytes = fs::read(path).map_err(|e| HostError::io(path, e))?;
    decode_rgb(&bytes, path)
}

/// [`load_rgb`] on the bytes of a file (`path` names it in errors).
///
/// # Errors
/// As [`load_rgb`].
pub fn decode_rgb(bytes: &[u8], path: &Path) -> Result<RgbImage> {
    Ok(decode_image(bytes, path)?.to_rgb8())
}

/// Loads a PNG or JPEG as decoded (grey, RGB, with alpha), with the checks
/// of [`load_rgb`].
///
/// # Errors
/// As [`load_rgb`].
pub fn load_image(path: &Path) -> Result<image::DynamicImage> {
    let bytes = fs::read(path).map_err(|e| HostError::io(path, e))?;
    decode_image(&bytes, path)
}

/// [`load_image`] on the bytes of a file (`path` names it in errors).
///
/// # Errors
/// As [`load_rgb`].
pub fn decode_image(bytes: &[u8], path: &Path) -> Result<image::DynamicImage> {
    let decode = |source| HostError::Decode {
        path: path.to_path_buf(),
        source,
    };
    let reader = || {
        ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| HostError::io(path, e))
    };
    let format = reader()?.format();
    let (w, h) = reader()?.into_dimensions().map_err(decode)?;
    if u64::from(w) * u64::from(h) > MAX_INPUT_PIXELS {
        return Err(HostError::ImageTooLarge {
            path: path.to_path_buf(),
            width: w,
            height: h,
            limit: MAX_INPUT_PIXELS,
        });
    }
    if format == Some(image::ImageFormat::Jpeg) {
        if let Err(reason) = check_jpeg(bytes) {
            let err = HostError::DamagedImage {
                path: path.to_path_buf(),
                reason,
            };
            if !ACCEPT_DAMAGED.load(std::sync::atomic::Ordering::Relaxed) {
                return Err(err);
            }
            eprintln!("warning: {err}; decoded anyway (--accept-damaged)");
        }
    }
    reader()?.decode().map_err(decode)
}

/// Decodes a JPEG in strict mode, for its errors only.
fn check_jpeg(bytes: &[u8]) -> std::result::Result<(), String> {
    use zune_core::bytestream::ZCursor;
    use zune_core::options::DecoderOptions;
    let opts = DecoderOptions::default()
        .set_strict_mode(true)
        .set_max_width(usize::MAX)
        .set_max_height(usize::MAX);
    let mut d = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(bytes), opts);
    d.decode().map(|_| ()).map_err(|e| format!("{e:?}"))
}

/// The working size for a `width` x `height` input and a target width:
/// `max_width` wide with the aspect ratio kept (height rounded, at least 1),
/// or the input size when it is not wider than `max_width` (never upscale).
///
/// # Errors
/// [`HostError::ZeroDimension`] when `max_width` is 0.
pub fn working_size(width: u32, height: u32, max_width: u32) -> Result<(u32, u32)> {
    if max_width == 0 {
        return Err(HostError::ZeroDimension { name: "width" });
    }
    if width <= max_width {
        return Ok((width, height));
    }
    let h = (u64::from(height) * u64::from(max_width) + u64::from(width) / 2) / u64::from(width);
    Ok((max_width, u32::try_from(h.max(1)).unwrap_or(u32::MAX)))
}

/// For each of `dst` output cells along one axis of `src` input pixels, the
/// source pixels it overlaps and their integer overlap weights.
///
/// In units of `1 / dst` source pixel, output `o` covers `[o·src, (o+1)·src)`
/// and source `i` covers `[i·dst, (i+1)·dst)`; the overlaps are integers and
/// each output's weights sum to `src`.
pub(crate) fn axis_weights(src: u32, dst: u32) -> Vec<Vec<(usize, u64)>> {
    let (src, dst) = (u64::from(src), u64::from(dst));
    (0..dst)
        .map(|o| {
            let (lo, hi) = (o * src, (o + 1) * src);
            (lo / dst..hi.div_ceil(dst))
                .filter_map(|i| {
                    let overlap = hi.min((i + 1) * dst).saturating_sub(lo.max(i * dst));
                    let i = usize::try_from(i).ok()?;
                    (overlap > 0).then_some((i, overlap))
                })
                .collect()
        })
        .collect()
}

/// Resizes `src` to `dst_w` x `dst_h` by exact area averaging: each output
/// pixel is the mean of the source area it covers, every source pixel
/// weighted by its overlap, rounded to nearest once. Meant for downscaling;
/// upscaling works too (as area sampling). A zero target size gives an
/// empty image.
pub fn area_downscale(src: &RgbImage, dst_w: u32, dst_h: u32) -> RgbImage {
    let (sw, sh) = src.dimensions();
    if dst_w == 0 || dst_h == 0 || sw == 0 || sh == 0 {
        return RgbImage::new(dst_w, dst_h);
    }
    let (wx, wy) = (axis_weights(sw, dst_w), axis_weights(sh, dst_h));
    // Horizontal pass: per source row, weighted channel sums (<= 255 · sw).
    let mut rows = vec![[0u64; 3]; wx.len() * sh as usize];
    for (y, out_row) in rows.chunks_mut(wx.len()).enumerate() {
        let y = y as u32;
        for (acc, taps) in out_row.iter_mut().zip(&wx) {
            for &(x, w) in taps {
                let p = src.get_pixel(x as u32, y).0;
                for (a, c) in acc.iter_mut().zip(p) {
                    *a += w * u64::from(c);
                }
            }
        }
    }
    // Vertical pass, then one rounded division by the total weight sw · sh.
    let total = u64::from(sw) * u64::from(sh);
    RgbImage::from_fn(dst_w, dst_h, |x, y| {
        let mut acc = [0u64; 3];
        for &(sy, w) in &wy[y as usize] {
            let row = &rows[sy * wx.len() + x as usize];
            for (a, r) in acc.iter_mut().zip(row) {
                *a += w * r;
            }
        }
        image::Rgb(acc.map(|a| ((a + total / 2) / total).min(255) as u8))
    })
}

/// The pixels of `img` as core [`Rgb8`]s, row-major and packed.
pub fn to_core_rgb(img: &RgbImage) -> Vec<Rgb8> {
    img.pixels()
        .map(|p| Rgb8::new(p.0[0], p.0[1], p.0[2]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A seeded textured JPEG.
    pub(crate) fn jpeg(w: u32, h: u32) -> Vec<u8> {
        let img = RgbImage::from_fn(w, h, |x, y| {
            let v = (x * 7 + y * 13 + (x * y) % 17) as u8;
            image::Rgb([v, v.wrapping_mul(3), 255 - v])
        });
        let mut out = std::io::Cursor::new(Vec::new());
        img.write_to(&mut out, image::ImageFormat::Jpeg).unwrap();
        out.into_inner()
    }

    #[test]
    fn truncated_and_corrupt_jpegs_are_errors() {
        let p = Path::new("x.jpg");
        let good = jpeg(64, 48);
        assert_eq!(decode_rgb(&good, p).unwrap().dimensions(), (64, 48));
        let half = &good[..good.len() / 2];
        let e = decode_rgb(half, p).unwrap_err();
        assert!(matches!(e, HostError::DamagedImage { .. }), "{e}");
        // One flipped bit in the entropy-coded data: a stuffed 0xFF 0x00
        // becomes 0xFF 0x01, a marker where none can be. (Corruption that
        // still decodes cannot be told from an image.)
        let mut flipped = good.clone();
        let sos = good.windows(2).position(|w| w == [0xff, 0xda]).unwrap();
        let k = sos
            + good[sos..]
                .windows(2)
                .position(|w| w == [0xff, 0x00])
                .unwrap();
        flipped[k + 1] = 0x01;
        let e = decode_rgb(&flipped, p).unwrap_err();
        assert!(matches!(e, HostError::DamagedImage { .. }), "{e}");
    }
    use image::Rgb;

    fn mean(img: &RgbImage) -> [f64; 3] {
        let n = f64::from(img.width() * img.height());
        let mut m = [0.0; 3];
        for p in img.pixels() {
            for (a, c) in m.iter_mut().zip(p.0) {
                *a += f64::from(c) / n;
            }
        }
        m
    }

    #[test]
    fn four_by_four_to_two_by_two_is_the_exact_block_mean() {
        let src = RgbImage::from_fn(4, 4, |x, y| {
            let v = (y * 4 + x) as u8 * 16;
            Rgb([v, 255 - v, (x * 60) as u8])
        });
        let out = area_downscale(&src, 2, 2);
        for (ox, oy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let mut sum = [0u32; 3];
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let p = src.get_pixel(2 * ox + dx, 2 * oy + dy).0;
                for (s, c) in sum.iter_mut().zip(p) {
                    *s += u32::from(c);
                }
            }
            let expected = sum.map(|s| ((s + 2) / 4) as u8);
            assert_eq!(out.get_pixel(ox, oy).0, expected, "({ox}, {oy})");
        }
    }

    #[test]
    fn a_constant_image_stays_constant() {
        let src = RgbImage::from_pixel(97, 61, Rgb([13, 200, 77]));
        for (w, h) in [(40, 25), (33, 7), (1, 1), (97, 61)] {
            let out = area_downscale(&src, w, h);
            assert_eq!(out.dimensions(), (w, h));
            assert!(out.pixels().all(|p| p.0 == [13, 200, 77]), "{w}x{h}");
        }
    }

    #[test]
    fn odd_ratios_preserve_the_mean() {
        let src = RgbImage::from_fn(101, 67, |x, y| {
            Rgb([(x * 7 + y * 3) as u8, (x * y) as u8, ((x ^ y) * 5) as u8])
        });
        for (w, h) in [(33, 22), (50, 31), (7, 5), (100, 66)] {
            let (a, b) = (mean(&src), mean(&area_downscale(&src, w, h)));
            for c in 0..3 {
                // Every output pixel covers the same area; only rounding differs.
                assert!((a[c] - b[c]).abs() <= 0.5, "{w}x{h} ch{c}: {a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn weights_cover_each_output_with_the_whole_source_ratio() {
        for (src, dst) in [(10, 3), (7, 7), (160, 160), (1000, 160), (3, 10)] {
            let w = axis_weights(src, dst);
            assert_eq!(w.len(), dst as usize);
            for taps in &w {
                assert_eq!(taps.iter().map(|t| t.1).sum::<u64>(), u64::from(src));
            }
        }
    }

    #[test]
    fn working_size_keeps_the_aspect_and_never_upscales() {
        assert_eq!(working_size(640, 480, 160).unwrap(), (160, 120));
        assert_eq!(working_size(100, 50, 160).unwrap(), (100, 50));
        assert_eq!(working_size(1000, 1, 160).unwrap(), (160, 1));
        assert_eq!(working_size(333, 250, 160).unwrap(), (160, 120));
        assert!(matches!(
            working_size(10, 10, 0),
            Err(HostError::ZeroDimension { name: "width" })
        ));
    }
}
