//! Image views over caller-provided buffers, and the pixel newtypes.
//!
//! A view is a slice plus `width`, `height` and `stride` (elements from the
//! start of one row to the start of the next). The constructor checks the
//! geometry once; after that no accessor can panic: rows are exactly `width`
//! long, and every out-of-range access returns `None`.
//!
//! ```
//! use protogist::image::{ImageView, Luma8};
//! let px = [Luma8(1), Luma8(2), Luma8(9), Luma8(3), Luma8(4), Luma8(9)];
//! // 2x2 image whose rows are 3 elements apart (one padding element each).
//! let img = ImageView::new(&px, 2, 2, 3).unwrap();
//! assert_eq!(img.get(1, 1), Some(Luma8(4)));
//! assert_eq!(img.get(2, 1), None);
//! assert_eq!(img.row(1), Some(&px[3..5]));
//! ```

use core::fmt;

/// Largest width or height a view accepts. It keeps every per-image count
/// (pixels, sums of 8-bit values) inside `u32` with room to spare.
pub const MAX_DIM: usize = 8192;

/// Why a buffer cannot be viewed as an image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ImageError {
    /// Width or height is zero.
    ZeroSize,
    /// Width or height is above [`MAX_DIM`].
    TooLarge {
        /// The offending width.
        width: usize,
        /// The offending height.
        height: usize,
    },
    /// The stride is shorter than a row.
    StrideTooSmall {
        /// Image width.
        width: usize,
        /// Given stride.
        stride: usize,
    },
    /// The slice cannot hold `height` rows of `stride` elements (the last row
    /// needs only `width`).
    BufferTooSmall {
        /// Elements needed.
        needed: usize,
        /// Elements given.
        got: usize,
    },
    /// Two images that must share a size do not.
    SizeMismatch {
        /// Expected `(width, height)`.
        expected: (usize, usize),
        /// Given `(width, height)`.
        got: (usize, usize),
    },
}

impl fmt::Display for ImageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::ZeroSize => write!(f, "image has zero width or height"),
            Self::TooLarge { width, height } => {
                write!(f, "image {width}x{height} exceeds the {MAX_DIM} px limit")
            }
            Self::StrideTooSmall { width, stride } => {
                write!(f, "stride {stride} is shorter than the width {width}")
            }
            Self::BufferTooSmall { needed, got } => {
                write!(f, "buffer holds {got} elements, the image needs {needed}")
            }
            Self::SizeMismatch { expected, got } => write!(
                f,
                "image is {}x{}, expected {}x{}",
                got.0, got.1, expected.0, expected.1
            ),
        }
    }
}

impl core::error::Error for ImageError {}

/// Elements a buffer needs to hold a `width` x `height` image with `stride`.
///
/// # Errors
/// The geometry errors of [`ImageView::new`], except [`ImageError::BufferTooSmall`].
pub const fn buffer_len(width: usize, height: usize, stride: usize) -> Result<usize, ImageError> {
    if width == 0 || height == 0 {
        return Err(ImageError::ZeroSize);
    }
    if width > MAX_DIM || height > MAX_DIM || stride > MAX_DIM * 4 {
        return Err(ImageError::TooLarge { width, height });
    }
    if stride < width {
        return Err(ImageError::StrideTooSmall { width, stride });
    }
    // Cannot overflow: all three are bounded above.
    Ok((height - 1) * stride + width)
}

/// Checks that two images have the same size: a stereo pair, or an image
/// and a map computed from it.
///
/// # Errors
/// [`ImageError::SizeMismatch`] with `a`'s size as the expected one.
pub fn check_same_size<A, B>(a: &ImageView<'_, A>, b: &ImageView<'_, B>) -> Result<(), ImageError> {
    if a.size() == b.size() {
        Ok(())
    } else {
        Err(ImageError::SizeMismatch {
            expected: a.size(),
            got: b.size(),
        })
    }
}

/// An 8-bit grey pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[repr(transparent)]
pub struct Luma8(pub u8);

/// An 8-bit sRGB pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Rgb8 {
    /// Red.
    pub r: u8,
    /// Green.
    pub g: u8,
    /// Blue.
    pub b: u8,
}

impl Rgb8 {
    /// A pixel from its three channels.
    pub const fn new(r: u8, g: u8, b: u8) -> Self {
        Self { r, g, b }
    }
}

/// The rows of an [`ImageViewMut`], split off one stride at a time: no
/// division (unlike `chunks_mut`, which divides by the stride to size
/// itself), so no panic path.
struct RowsMut<'a, P> {
    rest: &'a mut [P],
    width: usize,
    stride: usize,
    left: usize,
}

impl<'a, P> Iterator for RowsMut<'a, P> {
    type Item = &'a mut [P];

    fn next(&mut self) -> Option<&'a mut [P]> {
        self.left = self.left.checked_sub(1)?;
        let rest = core::mem::take(&mut self.rest);
        // The last row may be shorter than the stride, not than the width.
        let (row, tail) = rest.split_at_mut(self.stride.min(rest.len()));
        self.rest = tail;
        Some(row.get_mut(..self.width).unwrap_or(&mut []))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.left, Some(self.left))
    }
}

impl<P> ExactSizeIterator for RowsMut<'_, P> {}

/// A read-only image over a borrowed slice.
#[derive(Clone, Copy, Debug)]
pub struct ImageView<'a, P> {
    data: &'a [P],
    width: usize,
    height: usize,
    stride: usize,
}

/// A mutable image over a borrowed slice.
#[derive(Debug)]
pub struct ImageViewMut<'a, P> {
    data: &'a mut [P],
    width: usize,
    height: usize,
    stride: usize,
}

/// Checks that `(x, y, w, h)` lies inside a `width` x `height` image.
const fn sub_rect_ok(width: usize, height: usize, x: usize, y: usize, w: usize, h: usize) -> bool {
    w > 0 && h > 0 && x < width && y < height && w <= width - x && h <= height - y
}

impl<'a, P> ImageView<'a, P> {
    /// Views `data` as `width` x `height` pixels, rows `stride` elements apart.
    ///
    /// # Errors
    /// [`ImageError`] when the geometry is invalid or `data` is too short.
    pub const fn new(
        data: &'a [P],
        width: usize,
        height: usize,
        stride: usize,
    ) -> Result<Self, ImageError> {
        match buffer_len(width, height, stride) {
            Err(e) => Err(e),
            Ok(needed) if needed > data.len() => Err(ImageError::BufferTooSmall {
                needed,
                got: data.len(),
            }),
            Ok(_) => Ok(Self {
                data,
                width,
                height,
                stride,
            }),
        }
    }

    /// A tightly packed view (`stride == width`).
    ///
    /// # Errors
    /// As [`ImageView::new`].
    pub const fn packed(data: &'a [P], width: usize, height: usize) -> Result<Self, ImageError> {
        Self::new(data, width, height, width)
    }

    /// Width in pixels.
    pub const fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub const fn height(&self) -> usize {
        self.height
    }

    /// Elements from one row start to the next.
    pub const fn stride(&self) -> usize {
        self.stride
    }

    /// `(width, height)`.
    pub const fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// Number of pixels.
    pub const fn len(&self) -> usize {
        self.width * self.height
    }

    /// Always false: a valid view has at least one pixel.
    pub const fn is_empty(&self) -> bool {
        false
    }

    /// Row `y`, exactly `width` pixels long.
    pub fn row(&self, y: usize) -> Option<&'a [P]> {
        if y >= self.height {
            return None;
        }
        let start = y * self.stride;
        self.data.get(start..start + self.width)
    }

    /// All rows, top to bottom, each exactly `width` pixels long.
    pub fn rows(&self) -> impl ExactSizeIterator<Item = &'a [P]> + DoubleEndedIterator + 'a {
        let (data, width, stride) = (self.data, self.width, self.stride);
        // By row index, not `chunks(stride)`: `chunks` divides by the
        // stride to size itself, a division the compiler cannot prove
        // non-zero, so a panic path. The constructor guarantees every row.
        (0..self.height).map(move |y| {
            let start = y * stride;
            data.get(start..start + width).unwrap_or(&[])
        })
    }

    /// A sub-image of `w` x `h` pixels at `(x, y)`, or `None` if it does not fit.
    pub fn sub_view(&self, x: usize, y: usize, w: usize, h: usize) -> Option<ImageView<'a, P>> {
        if !sub_rect_ok(self.width, self.height, x, y, w, h) {
            return None;
        }
        let data = self.data.get(y * self.stride + x..)?;
        ImageView::new(data, w, h, self.stride).ok()
    }
}

impl<P: Copy> ImageView<'_, P> {
    /// The pixel at `(x, y)`.
    pub fn get(&self, x: usize, y: usize) -> Option<P> {
        self.row(y)?.get(x).copied()
    }

    /// Pixels in row-major order.
    pub fn pixels(&self) -> impl Iterator<Item = P> + '_ {
        self.rows().flat_map(|r| r.iter().copied())
    }
}

/// RGB rows of an input frame, on demand: a frame in memory
/// ([`ImageView`]), or a camera that renders rows as a stage asks for them
/// (the stereo engine, `crate::stereo::c2f`, reads its frames this way).
pub trait RgbRows {
    /// `(width, height)`.
    fn size(&self) -> (usize, usize);
    /// Row `y` (`y < height`) into `out` (`width` long).
    fn rgb_row(&self, y: usize, out: &mut [Rgb8]);

    /// Pixels `xs` of row `y` (`y < height`) into the same places of
    /// `out` (`width` long); the rest of `out` may be left as it was. The
    /// default reads the whole row; a frame that converts its pixels (the
    /// firmware's RGB565) converts only these, with the same bits.
    #[inline]
    fn rgb_part(&self, y: usize, xs: core::ops::Range<usize>, out: &mut [Rgb8]) {
        let _ = xs;
        self.rgb_row(y, out);
    }

    /// Row `y` (`y < height`) as CIELUV into `out` (`width` long), for the
    /// conspicuity stage; `rgb` (`width` long) is scratch. The default
    /// reads [`rgb_row`](Self::rgb_row) and converts each pixel with
    /// [`LUV_TABLES`](crate::conspicuity::LUV_TABLES). A frame whose
    /// pixels take few values may look them up in a table instead (the
    /// firmware's RGB565 frames do), and must give the same bits.
    #[inline]
    fn luv_row(&self, y: usize, rgb: &mut [Rgb8], out: &mut [crate::conspicuity::Luv]) {
        self.rgb_row(y, rgb);
        for (o, &px) in out.iter_mut().zip(rgb.iter()) {
            *o = crate::conspicuity::LUV_TABLES.convert(px);
        }
    }

    /// Row `j` of the half-size image (`j < height / 2`) into `out`
    /// (`width / 2` long): the rounded means of the 2x2 blocks of rows
    /// `2j` and `2j + 1`, per channel (`(a + b + c + d + 2) / 4`), the
    /// stereo pyramid's first level. `scratch` holds `2 * out.len()` pixels
    /// twice. The default reads both rows with [`rgb_row`](Self::rgb_row);
    /// a frame may compute the means from its own pixels (the firmware's
    /// RGB565 frames do) and must give the same values.
    #[inline]
    fn half_row(&self, j: usize, out: &mut [Rgb8], scratch: &mut [Rgb8]) {
        let fw = 2 * out.len();
        let (a, rest) = scratch.split_at_mut(fw.min(scratch.len()));
        let (b, _) = rest.split_at_mut(fw.min(rest.len()));
        self.rgb_row(2 * j, a);
        self.rgb_row(2 * j + 1, b);
        mean_2x2_row(a, b, out);
    }

    /// Row `y` (`y < height`) as the phase step's grey into `out` (`width`
    /// long): [`grey8`](crate::stereo::phase::grey8) of each pixel of
    /// [`rgb_row`](Self::rgb_row) (the default), `rgb` (`width` long)
    /// scratch. A frame may compute it from its own pixels (the
    /// firmware's RGB565 frames sum one table entry per channel) and must
    /// give the same values.
    #[inline]
    fn grey8_row(&self, y: usize, rgb: &mut [Rgb8], out: &mut [i32]) {
        self.rgb_row(y, rgb);
        for (o, &px) in out.iter_mut().zip(rgb.iter()) {
            *o = crate::stereo::phase::grey8(px);
        }
    }
}

/// The rounded 2x2 means of rows `a` and `b` (`2 * out.len()` long) into
/// `out`, per channel: `(a0 + a1 + b0 + b1 + 2) / 4`.
#[inline]
pub fn mean_2x2_row(a: &[Rgb8], b: &[Rgb8], out: &mut [Rgb8]) {
    let mean = |p: [u8; 4]| {
        let s: u16 = p.iter().map(|&v| u16::from(v)).sum();
        ((s + 2) / 4) as u8
    };
    for ((o, a), b) in out.iter_mut().zip(a.chunks_exact(2)).zip(b.chunks_exact(2)) {
        if let ([a0, a1], [b0, b1]) = (a, b) {
            *o = Rgb8::new(
                mean([a0.r, a1.r, b0.r, b1.r]),
                mean([a0.g, a1.g, b0.g, b1.g]),
                mean([a0.b, a1.b, b0.b, b1.b]),
            );
        }
    }
}

impl RgbRows for ImageView<'_, Rgb8> {
    fn size(&self) -> (usize, usize) {
        ImageView::size(self)
    }

    fn rgb_row(&self, y: usize, out: &mut [Rgb8]) {
        if let Some(row) = self.row(y) {
            for (o, &p) in out.iter_mut().zip(row) {
                *o = p;
            }
        }
    }

    fn rgb_part(&self, y: usize, xs: core::ops::Range<usize>, out: &mut [Rgb8]) {
        if let (Some(o), Some(r)) = (out.get_mut(xs.clone()), self.row(y).and_then(|r| r.get(xs))) {
            for (o, &p) in o.iter_mut().zip(r) {
                *o = p;
            }
        }
    }
}

impl<'a, P> ImageViewMut<'a, P> {
    /// Views `data` mutably as `width` x `height` pixels, rows `stride` apart.
    ///
    /// # Errors
    /// [`ImageError`] when the geometry is invalid or `data` is too short.
    pub fn new(
        data: &'a mut [P],
        width: usize,
        height: usize,
        stride: usize,
    ) -> Result<Self, ImageError> {
        let needed = buffer_len(width, height, stride)?;
        if needed > data.len() {
            return Err(ImageError::BufferTooSmall {
                needed,
                got: data.len(),
            });
        }
        Ok(Self {
            data,
            width,
            height,
            stride,
        })
    }

    /// A tightly packed mutable view (`stride == width`).
    ///
    /// # Errors
    /// As [`ImageViewMut::new`].
    pub fn packed(data: &'a mut [P], width: usize, height: usize) -> Result<Self, ImageError> {
        Self::new(data, width, height, width)
    }

    /// Width in pixels.
    pub const fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub const fn height(&self) -> usize {
        self.height
    }

    /// Elements from one row start to the next.
    pub const fn stride(&self) -> usize {
        self.stride
    }

    /// `(width, height)`.
    pub const fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// A read-only view of the same pixels.
    pub fn as_view(&self) -> ImageView<'_, P> {
        ImageView {
            data: self.data,
            width: self.width,
            height: self.height,
            stride: self.stride,
        }
    }

    /// A shorter-lived mutable view of the same pixels.
    pub fn reborrow(&mut self) -> ImageViewMut<'_, P> {
        ImageViewMut {
            data: self.data,
            width: self.width,
            height: self.height,
            stride: self.stride,
        }
    }

    /// Row `y`, exactly `width` pixels long.
    pub fn row(&self, y: usize) -> Option<&[P]> {
        if y >= self.height {
            return None;
        }
        let start = y * self.stride;
        self.data.get(start..start + self.width)
    }

    /// Row `y`, mutably.
    pub fn row_mut(&mut self, y: usize) -> Option<&mut [P]> {
        if y >= self.height {
            return None;
        }
        let start = y * self.stride;
        self.data.get_mut(start..start + self.width)
    }

    /// All rows, mutably, top to bottom.
    pub fn rows_mut(&mut self) -> impl ExactSizeIterator<Item = &mut [P]> + '_ {
        RowsMut {
            rest: &mut *self.data,
            width: self.width,
            stride: self.stride,
            left: self.height,
        }
    }

    /// Row `y` mutably together with row `y + 1` read-only, for in-place
    /// filters that read the next, still unmodified, row.
    pub fn row_and_next_mut(&mut self, y: usize) -> Option<(&mut [P], &[P])> {
        if y + 1 >= self.height {
            return None;
        }
        let (head, tail) = self.data.split_at_mut_checked((y + 1) * self.stride)?;
        let row = head.get_mut(y * self.stride..y * self.stride + self.width)?;
        let next = tail.get(..self.width)?;
        Some((row, next))
    }

    /// A mutable sub-image of `w` x `h` pixels at `(x, y)`.
    pub fn sub_view_mut(
        &mut self,
        x: usize,
        y: usize,
        w: usize,
        h: usize,
    ) -> Option<ImageViewMut<'_, P>> {
        if !sub_rect_ok(self.width, self.height, x, y, w, h) {
            return None;
        }
        let data = self.data.get_mut(y * self.stride + x..)?;
        ImageViewMut::new(data, w, h, self.stride).ok()
    }
}

impl<P: Copy> ImageViewMut<'_, P> {
    /// The pixel at `(x, y)`.
    pub fn get(&self, x: usize, y: usize) -> Option<P> {
        self.row(y)?.get(x).copied()
    }

    /// Sets the pixel at `(x, y)`; returns `false` when it is outside.
    pub fn set(&mut self, x: usize, y: usize, value: P) -> bool {
        match self.row_mut(y).and_then(|r| r.get_mut(x)) {
            Some(p) => {
                *p = value;
                true
            }
            None => false,
        }
    }

    /// Sets every pixel to `value`.
    pub fn fill(&mut self, value: P) {
        self.rows_mut().for_each(|r| r.fill(value));
    }

    /// Copies `src`, which must have the same size.
    ///
    /// # Errors
    /// [`ImageError::SizeMismatch`].
    pub fn copy_from(&mut self, src: &ImageView<'_, P>) -> Result<(), ImageError> {
        if src.size() != self.size() {
            return Err(ImageError::SizeMismatch {
                expected: self.size(),
                got: src.size(),
            });
        }
        // Rows are exactly `width` long; `get` shows the compiler that the
        // lengths match, so `copy_from_slice` has no panic path.
        self.rows_mut().zip(src.rows()).for_each(|(d, s)| {
            if let Some(s) = s.get(..d.len()) {
                d.copy_from_slice(s);
            }
        });
        Ok(())
    }
}

#[cfg(test)]
mod tests;
