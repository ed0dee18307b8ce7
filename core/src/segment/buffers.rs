//! The caller-provided buffers of [`segment`](super::segment), validated once.

use super::label::{label_capacity, Labeller};
use super::SegmentError;
use crate::conspicuity::EdgeCell;
use crate::disparity::DisparityCell;
use crate::image::{ImageError, ImageView, ImageViewMut};

/// Disparity cells [`SegmentBuffers`] needs: D_fg and D_ObjReg.
pub const fn disparity_maps_len(width: usize, height: usize) -> usize {
    2 * width * height
}

/// Conspicuity cells [`SegmentBuffers`] needs: C_fg, ψ, C_ObjReg, C_Obj.
pub const fn edge_maps_len(width: usize, height: usize) -> usize {
    4 * width * height
}

/// Binary cells [`SegmentBuffers`] needs: the refined region, C_Obj^M,
/// F_Obj, the filled map and a morphology scratch.
pub const fn binary_maps_len(width: usize, height: usize) -> usize {
    5 * width * height
}

/// `u16`s [`SegmentBuffers`] needs: the label map plus the label
/// equivalence table ([`label_capacity`] entries).
pub const fn label_maps_len(width: usize, height: usize) -> usize {
    width * height + label_capacity(width, height)
}

/// Bytes of all buffers of [`SegmentBuffers`] at this size (masks excluded:
/// one `bool` per pixel per object).
pub const fn scratch_bytes(width: usize, height: usize) -> usize {
    disparity_maps_len(width, height) * core::mem::size_of::<DisparityCell>()
        + edge_maps_len(width, height) * core::mem::size_of::<EdgeCell>()
        + binary_maps_len(width, height)
        + label_maps_len(width, height) * 2
        + label_capacity(width, height) * 4
}

/// Every intermediate map of the stage, over caller buffers.
#[derive(Debug)]
pub struct SegmentBuffers<'a> {
    pub(super) d_fg: ImageViewMut<'a, DisparityCell>,
    pub(super) d_obj_reg: ImageViewMut<'a, DisparityCell>,
    pub(super) c_fg: ImageViewMut<'a, EdgeCell>,
    pub(super) psi: ImageViewMut<'a, EdgeCell>,
    pub(super) c_obj_reg: ImageViewMut<'a, EdgeCell>,
    pub(super) c_obj: ImageViewMut<'a, EdgeCell>,
    pub(super) region: ImageViewMut<'a, bool>,
    pub(super) nms: ImageViewMut<'a, bool>,
    pub(super) closed: ImageViewMut<'a, bool>,
    pub(super) filled: ImageViewMut<'a, bool>,
    pub(super) scratch: ImageViewMut<'a, bool>,
    pub(super) labeller: Labeller<'a>,
}

/// Splits `n` maps of `len` elements off the front of `buf`.
fn split<'a, P, const N: usize>(
    buf: &'a mut [P],
    len: usize,
) -> Result<([&'a mut [P]; N], &'a mut [P]), SegmentError> {
    let needed = N * len;
    if buf.len() < needed {
        return Err(ImageError::BufferTooSmall {
            needed,
            got: buf.len(),
        }
        .into());
    }
    let mut rest = buf;
    let mut out: [&'a mut [P]; N] = core::array::from_fn(|_| <&mut [P]>::default());
    for o in out.iter_mut() {
        let (head, tail) = core::mem::take(&mut rest).split_at_mut(len);
        *o = head;
        rest = tail;
    }
    Ok((out, rest))
}

impl<'a> SegmentBuffers<'a> {
    /// Checks every buffer against the `width` x `height` working size; the
    /// lengths come from [`disparity_maps_len`], [`edge_maps_len`],
    /// [`binary_maps_len`], [`label_maps_len`] and [`label_capacity`]
    /// (`area`; a shorter table means a smaller label capacity).
    ///
    /// # Errors
    /// [`SegmentError::Image`] for a bad size or a short buffer.
    pub fn new(
        width: usize,
        height: usize,
        disparity: &'a mut [DisparityCell],
        edges: &'a mut [EdgeCell],
        binary: &'a mut [bool],
        labels: &'a mut [u16],
        area: &'a mut [u32],
    ) -> Result<Self, SegmentError> {
        let len = crate::image::buffer_len(width, height, width)?;
        let ([d0, d1], _) = split(disparity, len)?;
        let ([c0, c1, c2, c3], _) = split(edges, len)?;
        let ([b0, b1, b2, b3, b4], _) = split(binary, len)?;
        let ([lm], parent) = split(labels, len)?;
        let p = |s| ImageViewMut::packed(s, width, height);
        let b = |s| ImageViewMut::packed(s, width, height);
        let e = |s| ImageViewMut::packed(s, width, height);
        Ok(Self {
            d_fg: p(d0)?,
            d_obj_reg: p(d1)?,
            c_fg: e(c0)?,
            psi: e(c1)?,
            c_obj_reg: e(c2)?,
            c_obj: e(c3)?,
            region: b(b0)?,
            nms: b(b1)?,
            closed: b(b2)?,
            filled: b(b3)?,
            scratch: b(b4)?,
            labeller: Labeller::new(width, height, lm, parent, area)?,
        })
    }

    /// Sets every map OFF (binary maps false).
    pub fn clear(&mut self) {
        for m in [&mut self.d_fg, &mut self.d_obj_reg] {
            m.fill(DisparityCell::OFF);
        }
        for m in [
            &mut self.c_fg,
            &mut self.psi,
            &mut self.c_obj_reg,
            &mut self.c_obj,
        ] {
            m.fill(EdgeCell::OFF);
        }
        for m in [
            &mut self.region,
            &mut self.nms,
            &mut self.closed,
            &mut self.filled,
            &mut self.scratch,
        ] {
            m.fill(false);
        }
    }

    /// The labeller (label map and tables) of the last labelling.
    pub fn labeller(&self) -> &Labeller<'a> {
        &self.labeller
    }

    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        self.d_fg.size()
    }

    /// D_fg (after [`segment`](super::segment): with the extracted objects
    /// inhibited).
    pub fn d_fg(&self) -> ImageView<'_, DisparityCell> {
        self.d_fg.as_view()
    }

    /// C_fg of the last object search.
    pub fn c_fg(&self) -> ImageView<'_, EdgeCell> {
        self.c_fg.as_view()
    }

    /// D_ObjReg of the last object.
    pub fn d_obj_reg(&self) -> ImageView<'_, DisparityCell> {
        self.d_obj_reg.as_view()
    }

    /// ψ of the last object.
    pub fn psi(&self) -> ImageView<'_, EdgeCell> {
        self.psi.as_view()
    }

    /// C_ObjReg of the last object.
    pub fn c_obj_reg(&self) -> ImageView<'_, EdgeCell> {
        self.c_obj_reg.as_view()
    }

    /// C_Obj of the last object.
    pub fn c_obj(&self) -> ImageView<'_, EdgeCell> {
        self.c_obj.as_view()
    }

    /// The refined region (largest component of the dilated ψ map) of the
    /// last object.
    pub fn region(&self) -> ImageView<'_, bool> {
        self.region.as_view()
    }

    /// C_Obj^M of the last object.
    pub fn nms(&self) -> ImageView<'_, bool> {
        self.nms.as_view()
    }

    /// F_Obj (the closed C_Obj^M) of the last object.
    pub fn closed(&self) -> ImageView<'_, bool> {
        self.closed.as_view()
    }

    /// F_Obj with its holes filled, before the area filter.
    pub fn filled(&self) -> ImageView<'_, bool> {
        self.filled.as_view()
    }
}
