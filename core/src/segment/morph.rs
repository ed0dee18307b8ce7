//! Binary morphology with a radius-1 disk, and the non-maximum suppression.
//!
//! Maps are `bool` images. Dilation treats pixels outside the image as OFF,
//! erosion treats them as ON (as `imclose` pads). The closing is the
//! unbounded plane's ([`close`]): it neither eats into a shape at the
//! image's border nor adds a cap up to it.

use super::{check_size, SegmentError};
use crate::conspicuity::EdgeCell;
use crate::image::{ImageView, ImageViewMut};

/// The discrete radius-1 disk used as structuring element.
///
/// The paper says "radius-1 disk" without naming the discrete set. The
/// Euclidean disk `x² + y² ≤ 1` is the 3x3 cross ([`Disk::Cross`], the
/// default; it is also what MATLAB's `strel('disk', 1)` gives). The full 3x3
/// square ([`Disk::Square`]) grows twice as fast along the diagonals.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Disk {
    /// Centre plus its 4 edge neighbours.
    #[default]
    Cross,
    /// The full 3x3 block.
    Square,
}

impl Disk {
    /// The offsets `(dx, dy)` of the element, centre included.
    pub fn offsets(self) -> &'static [(isize, isize)] {
        const CROSS: [(isize, isize); 5] = [(0, 0), (-1, 0), (1, 0), (0, -1), (0, 1)];
        const SQUARE: [(isize, isize); 9] = [
            (0, 0),
            (-1, 0),
            (1, 0),
            (0, -1),
            (0, 1),
            (-1, -1),
            (1, -1),
            (-1, 1),
            (1, 1),
        ];
        match self {
            Self::Cross => &CROSS,
            Self::Square => &SQUARE,
        }
    }
}

/// `img(x + dx, y + dy)`, or `outside` beyond the border.
fn at<P: Copy>(img: &ImageView<'_, P>, x: usize, y: usize, dx: isize, dy: isize) -> Option<P> {
    let xi = x.checked_add_signed(dx)?;
    let yi = y.checked_add_signed(dy)?;
    img.get(xi, yi)
}

/// One step: dilation (`erode == false`: any element pixel ON, outside OFF)
/// or erosion (`erode == true`: all element pixels ON, outside ON).
fn step(
    disk: Disk,
    src: &ImageView<'_, bool>,
    dst: &mut ImageViewMut<'_, bool>,
    erode: bool,
) -> Result<(), SegmentError> {
    check_size(src.size(), dst.size())?;
    let offs = disk.offsets();
    for (y, row) in dst.rows_mut().enumerate() {
        for (x, o) in row.iter_mut().enumerate() {
            // Dilation: any(p); erosion: all(p) = !any(!p).
            *o = erode
                ^ offs
                    .iter()
                    .any(|&(dx, dy)| at(src, x, y, dx, dy).unwrap_or(erode) ^ erode);
        }
    }
    Ok(())
}

/// One binary dilation of `src` into `dst`.
///
/// # Errors
/// [`SegmentError::SizeMismatch`].
pub fn dilate(
    disk: Disk,
    src: &ImageView<'_, bool>,
    dst: &mut ImageViewMut<'_, bool>,
) -> Result<(), SegmentError> {
    step(disk, src, dst, false)
}

/// One binary erosion of `src` into `dst`.
///
/// # Errors
/// [`SegmentError::SizeMismatch`].
pub fn erode(
    disk: Disk,
    src: &ImageView<'_, bool>,
    dst: &mut ImageViewMut<'_, bool>,
) -> Result<(), SegmentError> {
    step(disk, src, dst, true)
}

fn repeat(
    disk: Disk,
    map: &mut ImageViewMut<'_, bool>,
    scratch: &mut ImageViewMut<'_, bool>,
    n: u8,
    erode: bool,
) -> Result<(), SegmentError> {
    check_size(map.size(), scratch.size())?;
    for _ in 0..n {
        scratch.copy_from(&map.as_view())?;
        step(disk, &scratch.as_view(), map, erode)?;
    }
    Ok(())
}

/// `n` dilations of `map`, in place (`scratch` is overwritten).
///
/// # Errors
/// [`SegmentError::SizeMismatch`].
pub fn dilate_n(
    disk: Disk,
    map: &mut ImageViewMut<'_, bool>,
    scratch: &mut ImageViewMut<'_, bool>,
    n: u8,
) -> Result<(), SegmentError> {
    repeat(disk, map, scratch, n, false)
}

/// `n` erosions of `map`, in place (`scratch` is overwritten).
///
/// # Errors
/// [`SegmentError::SizeMismatch`].
pub fn erode_n(
    disk: Disk,
    map: &mut ImageViewMut<'_, bool>,
    scratch: &mut ImageViewMut<'_, bool>,
    n: u8,
) -> Result<(), SegmentError> {
    repeat(disk, map, scratch, n, true)
}

/// `(width, height)` of the two buffers [`close`] works in: the map padded
/// by `n` pixels on every side.
pub const fn closing_size(width: usize, height: usize, n: u8) -> (usize, usize) {
    let p = 2 * n as usize;
    (width + p, height + p)
}

/// The paper's closing, `n` dilations then `n` erosions, of the unbounded
/// plane, in place: `map` is copied into `padded` with `n` OFF pixels on
/// every side, closed there (`scratch` is overwritten) and cropped back.
///
/// Closing the frame itself, with the erosions' outside ON, would keep
/// what the dilations grow towards the frame's edge wherever a shape comes
/// within `n` pixels of it: a cap from the shape to the edge. In the pad
/// the growth is eroded away as anywhere else. `padded` and `scratch` are
/// [`closing_size`].
///
/// # Errors
/// [`SegmentError::SizeMismatch`].
pub fn close(
    disk: Disk,
    map: &mut ImageViewMut<'_, bool>,
    padded: &mut ImageViewMut<'_, bool>,
    scratch: &mut ImageViewMut<'_, bool>,
    n: u8,
) -> Result<(), SegmentError> {
    let (w, h) = map.size();
    let size = closing_size(w, h, n);
    check_size(size, padded.size())?;
    let p = usize::from(n);
    padded.fill(false);
    let mismatch = SegmentError::SizeMismatch {
        expected: size,
        got: padded.size(),
    };
    padded
        .sub_view_mut(p, p, w, h)
        .ok_or(mismatch)?
        .copy_from(&map.as_view())?;
    dilate_n(disk, padded, scratch, n)?;
    erode_n(disk, padded, scratch, n)?;
    let view = padded.as_view();
    map.copy_from(&view.sub_view(p, p, w, h).ok_or(mismatch)?)?;
    Ok(())
}

/// The four NMS directions: horizontal, vertical and the two diagonals.
pub const NMS_DIRECTIONS: [(isize, isize); 4] = [(1, 0), (0, 1), (1, 1), (1, -1)];

/// Non-maximum suppression, C_Obj^M: an ON cell survives when, along at
/// least one of [`NMS_DIRECTIONS`], it is not below either neighbour
/// (`c ≥ c(p − δ)` and `c ≥ c(p + δ)`); OFF and outside neighbours count
/// as below every value.
///
/// Our reading of the paper: "four oriented cell clusters plus one grouping
/// cell at the output" is one local-maximum detector per direction, OR-ed by
/// the grouping cell. Ties survive, so a two-cell-wide ridge of equal values
/// (the conspicuity of a step edge) is kept whole. Returns the survivors.
///
/// # Errors
/// [`SegmentError::SizeMismatch`].
pub fn non_max_suppression(
    c_obj: &ImageView<'_, EdgeCell>,
    dst: &mut ImageViewMut<'_, bool>,
) -> Result<u32, SegmentError> {
    check_size(c_obj.size(), dst.size())?;
    let val = |x, y, dx, dy| {
        at(c_obj, x, y, dx, dy)
            .and_then(EdgeCell::get)
            .map_or(-1, |c| i32::from(c.to_bits()))
    };
    let mut n = 0;
    for (y, row) in dst.rows_mut().enumerate() {
        for (x, o) in row.iter_mut().enumerate() {
            let c = val(x, y, 0, 0);
            *o = c >= 0
                && NMS_DIRECTIONS
                    .iter()
                    .any(|&(dx, dy)| c >= val(x, y, -dx, -dy) && c >= val(x, y, dx, dy));
            n += u32::from(*o);
        }
    }
    Ok(n)
}
