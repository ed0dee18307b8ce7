//! f32 reference of [`protogist::conspicuity`].
//!
//! Same step names and argument order as core. The fixed-point-only inputs
//! (the CIELUV tables, the row scratch) have no counterpart here, and maps
//! are plain `f32`: [`LuvF`] is `[L*, u*, v*]` and a conspicuity cell is
//! `Option<f32>` (`None` is OFF). The formulas and constants are core's own
//! ([`SRGB_TO_XYZ`], [`WHITE_U`], ...), evaluated in f32 without tables.

use protogist::conspicuity::{
    ConspicuityError, Luv, SmoothParams, CIE_EPSILON, CIE_KAPPA, SRGB_TO_XYZ, WHITE_U, WHITE_V,
};
use protogist::image::{ImageView, ImageViewMut, Rgb8};

/// A CIELUV pixel `[L*, u*, v*]` in f32.
pub type LuvF = [f32; 3];

/// A conspicuity cell: the value, or `None` for OFF.
pub type EdgeCellF = Option<f32>;

/// The f32 value of a fixed-point CIELUV pixel (exact).
pub fn luv_to_f32(p: Luv) -> LuvF {
    [p.l().to_num(), p.u().to_num(), p.v().to_num()]
}

fn check_size(expected: (usize, usize), got: (usize, usize)) -> Result<(), ConspicuityError> {
    if expected == got {
        Ok(())
    } else {
        Err(ConspicuityError::SizeMismatch { expected, got })
    }
}

/// sRGB decoding of an 8-bit code, in f32.
pub fn srgb_to_linear(code: u8) -> f32 {
    let c = f32::from(code) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// One pixel, by the CIE formulas in f32.
pub fn convert(p: Rgb8) -> LuvF {
    let lin = [p.r, p.g, p.b].map(srgb_to_linear);
    let [x, y, z] =
        SRGB_TO_XYZ.map(|row| row.iter().zip(lin).map(|(&m, c)| m as f32 * c).sum::<f32>());
    let l = if f64::from(y) > CIE_EPSILON {
        116.0 * y.cbrt() - 16.0
    } else {
        CIE_KAPPA as f32 * y
    };
    let d = x + 15.0 * y + 3.0 * z;
    if d == 0.0 {
        return [l, 0.0, 0.0];
    }
    let u = 13.0 * l * (4.0 * x / d - WHITE_U as f32);
    let v = 13.0 * l * (9.0 * y / d - WHITE_V as f32);
    [l, u, v]
}

/// Converts an sRGB image to CIELUV.
///
/// # Errors
/// [`ConspicuityError::SizeMismatch`] when the sizes differ.
pub fn rgb_to_luv(
    src: &ImageView<'_, Rgb8>,
    dst: &mut ImageViewMut<'_, LuvF>,
) -> Result<(), ConspicuityError> {
    check_size(dst.size(), src.size())?;
    for (s, d) in src.rows().zip(dst.rows_mut()) {
        for (p, o) in s.iter().zip(d.iter_mut()) {
            *o = convert(*p);
        }
    }
    Ok(())
}

/// The pixel at `(x, y)` with coordinates clamped into the image (the
/// replicated border of core's row ring).
fn at<P: Copy + Default>(img: &ImageView<'_, P>, x: isize, y: isize) -> P {
    let cx = x.clamp(0, img.width() as isize - 1) as usize;
    let cy = y.clamp(0, img.height() as isize - 1) as usize;
    img.get(cx, cy).unwrap_or_default()
}

/// The symmetric pairs `(p - δ, p + δ)`, δ in (1,0), (1,1), (0,1), (-1,1).
pub const PAIRS: [(isize, isize); 4] = [(1, 0), (1, 1), (0, 1), (-1, 1)];

/// Squared CIELUV distance.
pub fn dist2(a: LuvF, b: LuvF) -> f32 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
}

/// Smooths `img` in place, `params.iterations` times.
pub fn smooth(params: &SmoothParams, img: &mut ImageViewMut<'_, LuvF>) {
    for _ in 0..params.iterations {
        smooth_step(img);
    }
}

/// One pass of the symmetric-nearest-neighbour cell, in place.
pub fn smooth_step(img: &mut ImageViewMut<'_, LuvF>) {
    let (w, h) = img.size();
    let src: Vec<LuvF> = img.as_view().pixels().collect();
    let Ok(src) = ImageView::packed(&src, w, h) else {
        return;
    };
    for y in 0..h as isize {
        for x in 0..w as isize {
            let c = at(&src, x, y);
            let mut sum = c;
            for (dx, dy) in PAIRS {
                let minus = at(&src, x - dx, y - dy);
                let plus = at(&src, x + dx, y + dy);
                let k = if dist2(c, minus) <= dist2(c, plus) {
                    minus
                } else {
                    plus
                };
                sum = [sum[0] + k[0], sum[1] + k[1], sum[2] + k[2]];
            }
            img.set(x as usize, y as usize, sum.map(|s| s / 5.0));
        }
    }
}

/// C~ at one pixel: the largest distance over the 4 symmetric pairs.
pub fn conspicuity_at(src: &ImageView<'_, LuvF>, x: usize, y: usize) -> f32 {
    let (x, y) = (x as isize, y as isize);
    PAIRS
        .iter()
        .map(|&(dx, dy)| dist2(at(src, x - dx, y - dy), at(src, x + dx, y + dy)).sqrt())
        .fold(0.0, f32::max)
}

/// Computes C~ into `dst` (every cell ON) and returns max C~.
///
/// # Errors
/// [`ConspicuityError::SizeMismatch`] when the sizes differ.
pub fn conspicuity(
    src: &ImageView<'_, LuvF>,
    dst: &mut ImageViewMut<'_, EdgeCellF>,
) -> Result<f32, ConspicuityError> {
    check_size(dst.size(), src.size())?;
    let mut max = 0.0f32;
    for (y, row) in dst.rows_mut().enumerate() {
        for (x, cell) in row.iter_mut().enumerate() {
            let c = conspicuity_at(src, x, y);
            max = max.max(c);
            *cell = Some(c);
        }
    }
    Ok(max)
}

/// Keeps C~ where C~ > `percent`/100 · max, else OFF; returns the ON count.
///
/// # Errors
/// [`ConspicuityError::BadThreshold`] when `percent > 100`.
pub fn threshold(
    map: &mut ImageViewMut<'_, EdgeCellF>,
    max: f32,
    percent: u8,
) -> Result<u32, ConspicuityError> {
    if percent > 100 {
        return Err(ConspicuityError::BadThreshold(percent));
    }
    let limit = f32::from(percent) / 100.0 * max;
    let mut on = 0;
    for row in map.rows_mut() {
        for cell in row.iter_mut() {
            *cell = cell.filter(|&c| c > limit);
            on += u32::from(cell.is_some());
        }
    }
    Ok(on)
}

/// The maps of the whole stage, owned.
#[derive(Clone, Debug)]
pub struct EdgeMapsF {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// CIELUV of the input.
    pub luv: Vec<LuvF>,
    /// Smoothed CIELUV.
    pub smoothed: Vec<LuvF>,
    /// C after the threshold.
    pub conspicuity: Vec<EdgeCellF>,
    /// max C~.
    pub max: f32,
    /// ON cells.
    pub on_count: u32,
}

/// Runs the whole stage in f32.
///
/// # Errors
/// As the steps.
pub fn edge_conspicuity(
    params: &protogist::conspicuity::EdgeParams,
    rgb: &ImageView<'_, Rgb8>,
) -> Result<EdgeMapsF, ConspicuityError> {
    let (w, h) = rgb.size();
    let mut luv = vec![[0.0; 3]; w * h];
    rgb_to_luv(rgb, &mut ImageViewMut::packed(&mut luv, w, h)?)?;
    let mut smoothed = luv.clone();
    smooth(
        &params.smooth,
        &mut ImageViewMut::packed(&mut smoothed, w, h)?,
    );
    let mut cons = vec![None; w * h];
    let mut view = ImageViewMut::packed(&mut cons, w, h)?;
    let max = conspicuity(&ImageView::packed(&smoothed, w, h)?, &mut view)?;
    let on_count = threshold(&mut view, max, params.threshold_percent)?;
    Ok(EdgeMapsF {
        width: w,
        height: h,
        luv,
        smoothed,
        conspicuity: cons,
        max,
        on_count,
    })
}
