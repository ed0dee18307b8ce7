//! Ground-truth disparity maps: loading (PNG with a scale factor, Middlebury
//! PFM), bringing them to the working size, and the error metrics.
//!
//! A GT map holds left-referenced disparities in pixels of its own size;
//! `None` is unknown (0 in a PNG, ±inf or NaN in a PFM, non-finite or ≤ 0
//! in a NumPy `.npy`/`.npz` array, [`numpy`]).

pub mod numpy;

use crate::error::{HostError, Result};
use image::{DynamicImage, ImageReader};
use std::path::Path;

/// A disparity map with unknown pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct GtMap {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// Disparity, px (`None`: unknown).
    pub data: Vec<Option<f32>>,
}

fn bad_gt(path: &Path, reason: impl Into<String>) -> HostError {
    HostError::BadGroundTruth {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Loads a GT map, by its magic: PFM (`Pf`, one channel), a NumPy `.npy`
/// or `.npz` float32/float64 2-D array ([`numpy`]; both in px, `scale`
/// unused), else a 8- or 16-bit grey PNG whose values are `scale` times the
/// disparity.
///
/// # Errors
/// [`HostError::Io`] when unreadable, [`HostError::BadGroundTruth`] when
/// malformed or truncated, not single-channel, of another dtype or not 2-D,
/// or `scale` is not positive.
pub fn load_gt(path: &Path, scale: f32) -> Result<GtMap> {
    let bytes = std::fs::read(path).map_err(|e| HostError::io(path, e))?;
    gt_from_bytes(&bytes, path, scale)
}

/// [`load_gt`] on the bytes of a file (`path` names it in errors).
///
/// # Errors
/// As [`load_gt`], but for reading.
pub fn gt_from_bytes(bytes: &[u8], path: &Path, scale: f32) -> Result<GtMap> {
    let gt = parse_gt(bytes, path, scale)?;
    check_values(&gt).map_err(|r| bad_gt(path, r))?;
    Ok(gt)
}

/// Checks what a left-referenced disparity map can hold: every known
/// value in `[0, width)` px (a disparity of the image's width or more
/// would match a pixel outside the other view; a negative one, a point
/// behind the cameras' convergence that a left-referenced map cannot
/// have), not subnormal, and at least one known pixel. Byte-swapped data
/// (values such as 5.7e36, or subnormals such as 4.6e-41) and a wrong
/// `--gt-scale` fail.
///
/// # Errors
/// A one-line reason naming the first bad value, or that no pixel is
/// known.
pub fn check_values(gt: &GtMap) -> std::result::Result<(), String> {
    let max = gt.width as f32;
    let mut known = 0usize;
    for (k, v) in gt.data.iter().enumerate() {
        let Some(v) = *v else { continue };
        let possible = |v: f32| (0.0..max).contains(&v) && !v.is_subnormal();
        if !possible(v) {
            let bad = gt.data.iter().flatten().filter(|&&v| !possible(v)).count();
            return Err(format!(
                "disparity {v:e} px at ({}, {}) is not in [0, {}) for an image {} px wide ({bad} such pixels; byte-swapped data or a wrong --gt-scale?)",
                k % gt.width,
                k / gt.width,
                gt.width,
                gt.width
            ));
        }
        known += 1;
    }
    if known == 0 {
        return Err(format!(
            "no ground-truth pixel: all {} pixels are unknown (0 in a PNG, inf or NaN in a PFM)",
            gt.data.len()
        ));
    }
    Ok(())
}

/// `gt` at the working size (see [`downscale_gt`]), checked to keep at
/// least one known pixel.
///
/// # Errors
/// [`HostError::BadGroundTruth`] when no pixel is known at that size.
pub fn gt_at(gt: &GtMap, width: usize, height: usize, path: &Path) -> Result<GtMap> {
    let small = downscale_gt(gt, width, height);
    if small.data.iter().all(Option::is_none) {
        return Err(bad_gt(
            path,
            format!("no ground-truth pixel is left at the working size {width}x{height}"),
        ));
    }
    Ok(small)
}

/// The map in `bytes`, by its magic (see [`load_gt`]), unchecked.
fn parse_gt(bytes: &[u8], path: &Path, scale: f32) -> Result<GtMap> {
    if bytes.starts_with(b"P") && bytes.get(1).is_some_and(|&b| b == b'f' || b == b'F') {
        return parse_pfm(bytes).map_err(|r| bad_gt(path, r));
    }
    if bytes.starts_with(numpy::NPY_MAGIC) {
        return numpy::parse_npy(bytes).map_err(|r| bad_gt(path, r));
    }
    if numpy::ZIP_MAGICS.iter().any(|m| bytes.starts_with(m)) {
        return numpy::parse_npz(bytes).map_err(|r| bad_gt(path, r));
    }
    if !(scale.is_finite() && scale > 0.0) {
        return Err(bad_gt(
            path,
            format!("--gt-scale must be positive, got {scale}"),
        ));
    }
    let img = ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| HostError::io(path, e))?
        .decode()
        .map_err(|e| bad_gt(path, e.to_string()))?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let data: Vec<u16> = match img {
        DynamicImage::ImageLuma8(g) => g.into_raw().into_iter().map(u16::from).collect(),
        DynamicImage::ImageLuma16(g) => g.into_raw(),
        other => {
            return Err(bad_gt(
                path,
                format!("expected a grey PNG, got {:?}", other.color()),
            ))
        }
    };
    Ok(GtMap {
        width: w,
        height: h,
        data: data
            .into_iter()
            .map(|v| (v != 0).then(|| f32::from(v) / scale))
            .collect(),
    })
}

/// Parses a one-channel PFM (rows stored bottom to top; a negative scale
/// means little-endian); infinite and NaN values are unknown.
///
/// # Errors
/// A one-line reason.
pub fn parse_pfm(bytes: &[u8]) -> std::result::Result<GtMap, String> {
    // Header: three whitespace-separated tokens after the magic, then one
    // whitespace byte.
    let mut tokens = Vec::new();
    let mut i = 0;
    while tokens.len() < 4 {
        while i < bytes.len() && bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        let start = i;
        while i < bytes.len() && !bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        if start == i || i >= bytes.len() {
            return Err("truncated PFM header".into());
        }
        tokens.push(String::from_utf8_lossy(&bytes[start..i]).into_owned());
    }
    i += 1;
    if tokens[0] != "Pf" {
        return Err(format!("PFM type {:?} is not one-channel Pf", tokens[0]));
    }
    let num = |s: &str| s.parse::<usize>().ok().filter(|&v| v > 0 && v <= 1 << 16);
    let (Some(w), Some(h)) = (num(&tokens[1]), num(&tokens[2])) else {
        return Err(format!("bad PFM size {} x {}", tokens[1], tokens[2]));
    };
    let scale: f32 = tokens[3]
        .parse()
        .ok()
        .filter(|s: &f32| s.is_finite() && *s != 0.0)
        .ok_or_else(|| format!("bad PFM scale {:?}", tokens[3]))?;
    let body = &bytes[i.min(bytes.len())..];
    if body.len() < 4 * w * h {
        return Err(format!(
            "PFM data truncated: {} bytes, need {}",
            body.len(),
            4 * w * h
        ));
    }
    if body.len() > 4 * w * h {
        return Err(format!(
            "{} trailing bytes after the {w}x{h} PFM raster",
            body.len() - 4 * w * h
        ));
    }
    let mut data = vec![None; w * h];
    for (k, c) in body.chunks_exact(4).take(w * h).enumerate() {
        let raw = [c[0], c[1], c[2], c[3]];
        let v = if scale < 0.0 {
            f32::from_le_bytes(raw)
        } else {
            f32::from_be_bytes(raw)
        };
        let (x, row) = (k % w, k / w);
        data[(h - 1 - row) * w + x] = v.is_finite().then_some(v);
    }
    Ok(GtMap {
        width: w,
        height: h,
        data,
    })
}

/// The GT at `width` x `height`: per output pixel, the overlap-weighted
/// mean of the known source pixels it covers (unknown when less than half
/// of its area is known), times `width / source width`.
pub fn downscale_gt(gt: &GtMap, width: usize, height: usize) -> GtMap {
    if (width, height) == (gt.width, gt.height) {
        return gt.clone();
    }
    let c = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
    let wx = crate::io::axis_weights(c(gt.width), c(width));
    let wy = crate::io::axis_weights(c(gt.height), c(height));
    let factor = width as f64 / gt.width as f64;
    let total = (gt.width * gt.height) as f64;
    let mut data = vec![None; width * height];
    for (y, ty) in wy.iter().enumerate() {
        for (x, tx) in wx.iter().enumerate() {
            let (mut sum, mut known) = (0.0f64, 0.0f64);
            for &(sy, a) in ty {
                for &(sx, b) in tx {
                    if let Some(v) = gt.data[sy * gt.width + sx] {
                        let wgt = (a * b) as f64;
                        sum += wgt * f64::from(v);
                        known += wgt;
                    }
                }
            }
            if known * 2.0 >= total {
                data[y * width + x] = Some((sum / known * factor) as f32);
            }
        }
    }
    GtMap {
        width,
        height,
        data,
    }
}

/// Error statistics of an estimate against GT.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Metrics {
    /// Pixels with known GT.
    pub gt_pixels: usize,
    /// Of those, pixels with an estimate.
    pub estimated: usize,
    /// % of estimated GT pixels with |err| > 1, 2, 4 px.
    pub bad_estimated: [f64; 3],
    /// % of GT pixels with |err| > 1, 2, 4 px or no estimate.
    pub bad_all: [f64; 3],
    /// Mean |err| over estimated GT pixels, px.
    pub mae: f64,
    /// % of GT pixels with an estimate.
    pub density: f64,
}

/// The thresholds of [`Metrics`]' bad-pixel rates, px.
pub const BAD_THRESHOLDS: [f32; 3] = [1.0, 2.0, 4.0];

/// Compares `est` with `gt`, pixel by pixel (same length).
pub fn metrics(est: &[Option<f32>], gt: &[Option<f32>]) -> Metrics {
    let mut m = Metrics::default();
    let mut bad = [0usize; 3];
    let mut abs = 0.0f64;
    for (e, g) in est.iter().zip(gt) {
        let Some(g) = g else { continue };
        m.gt_pixels += 1;
        let Some(e) = e else { continue };
        m.estimated += 1;
        let err = (e - g).abs();
        abs += f64::from(err);
        for (b, t) in bad.iter_mut().zip(BAD_THRESHOLDS) {
            *b += usize::from(err > t);
        }
    }
    let pct = |a: usize, b: usize| {
        if b == 0 {
            0.0
        } else {
            100.0 * a as f64 / b as f64
        }
    };
    let missing = m.gt_pixels - m.estimated;
    m.bad_estimated = bad.map(|b| pct(b, m.estimated));
    m.bad_all = bad.map(|b| pct(b + missing, m.gt_pixels));
    m.mae = if m.estimated == 0 {
        0.0
    } else {
        abs / m.estimated as f64
    };
    m.density = pct(m.estimated, m.gt_pixels);
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pfm_round_trip_with_unknowns_and_bottom_up_rows() {
        let mut b = b"Pf\n2 2\n-1.0\n".to_vec();
        for v in [1.0f32, f32::INFINITY, 3.0, 4.5] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let g = parse_pfm(&b).unwrap();
        assert_eq!(g.data, [Some(3.0), Some(4.5), Some(1.0), None]);
        assert!(parse_pfm(&b[..b.len() - 1]).is_err());
        assert!(parse_pfm(b"PF\n2 2\n-1.0\n").is_err());
        assert!(parse_pfm(b"Pf\n0 2\n-1.0\n").is_err());
    }

    fn pfm(w: usize, h: usize, values: &[f32]) -> Vec<u8> {
        let mut b = format!("Pf\n{w} {h}\n-1.0\n").into_bytes();
        for v in values {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b
    }

    fn load(bytes: &[u8], scale: f32) -> Result<GtMap> {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("gt");
        std::fs::write(&p, bytes).unwrap();
        load_gt(&p, scale)
    }

    fn reason(r: Result<GtMap>) -> String {
        match r {
            Err(HostError::BadGroundTruth { reason, .. }) => reason,
            other => panic!("not BadGroundTruth: {other:?}"),
        }
    }

    #[test]
    fn impossible_disparities_and_empty_maps_are_errors() {
        assert!(load(&pfm(4, 1, &[0.0, 1.5, 3.9, f32::NAN]), 1.0).is_ok());
        for (values, needle) in [
            ([-1.0, 1.0, 1.0, 1.0], "-1e0 px"),
            ([1.0, 1e30, 1.0, 1.0], "1e30 px at (1, 0) is not in [0, 4)"),
            ([1.0, 1.0, 4.0, 1.0], "4e0 px"),
            (
                [f32::NAN, f32::INFINITY, f32::NAN, f32::NEG_INFINITY],
                "no ground-truth pixel",
            ),
        ] {
            let r = reason(load(&pfm(4, 1, &values), 1.0));
            assert!(r.contains(needle), "{r}");
        }
        // Byte-swapped data (a big-endian scale on little-endian floats).
        let mut swapped = b"Pf\n4 1\n1.0\n".to_vec();
        for v in [1.0f32, 2.0, 3.0, 2.5] {
            swapped.extend_from_slice(&v.to_le_bytes());
        }
        let r = reason(load(&swapped, 1.0));
        assert!(r.contains("byte-swapped"), "{r}");
        // Trailing bytes after the raster.
        let mut long = pfm(4, 1, &[1.0; 4]);
        long.push(0);
        assert!(reason(load(&long, 1.0)).contains("1 trailing bytes"));
        // An all-zero PNG: every pixel unknown.
        let mut png = std::io::Cursor::new(Vec::new());
        image::GrayImage::new(4, 2)
            .write_to(&mut png, image::ImageFormat::Png)
            .unwrap();
        let r = reason(load(png.get_ref(), 1.0));
        assert!(r.contains("no ground-truth pixel"), "{r}");
        // A PNG scaled for 256 read at scale 1: values past the width.
        let mut png = std::io::Cursor::new(Vec::new());
        image::ImageBuffer::<image::Luma<u16>, _>::from_pixel(4, 2, image::Luma([512u16]))
            .write_to(&mut png, image::ImageFormat::Png)
            .unwrap();
        assert!(load(png.get_ref(), 256.0).is_ok());
        assert!(reason(load(png.get_ref(), 1.0)).contains("--gt-scale"));
    }

    #[test]
    fn metrics_count_missing_estimates_as_errors_over_all() {
        let gt = [Some(2.0), Some(2.0), Some(2.0), None];
        let est = [Some(2.5), Some(5.0), None, Some(9.0)];
        let m = metrics(&est, &gt);
        assert_eq!((m.gt_pixels, m.estimated), (3, 2));
        assert_eq!(m.bad_estimated, [50.0, 50.0, 0.0]);
        assert!((m.bad_all[2] - 100.0 / 3.0).abs() < 1e-9);
        assert!((m.mae - 1.75).abs() < 1e-9);
    }

    #[test]
    fn downscaling_halves_disparities_and_skips_unknown() {
        let gt = GtMap {
            width: 4,
            height: 2,
            data: vec![
                Some(8.0),
                Some(8.0),
                None,
                None,
                Some(8.0),
                Some(4.0),
                None,
                Some(6.0),
            ],
        };
        let d = downscale_gt(&gt, 2, 1);
        assert_eq!(d.data, [Some(3.5), None]);
    }
}
