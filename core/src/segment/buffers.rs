//! The caller-provided buffers of [`segment`](super::segment), validated once.
//!
//! Every map of the stage is a bit map ([`BitView`]): a cell map such as D_fg
//! or ψ is its source (D or C) where the bit is ON, OFF elsewhere
//! ([`BitView::masked`]). Components are labelled by runs, so the label
//! memory is one table entry per run, not a label per pixel.

use super::bits::{
    bit_map_len, closing_map_len, morph_rows_len, row_runs, run_capacity, BitView, Geom,
    MAX_CLOSING_STEPS,
};
use super::ground::ground_rows_len;
use super::SegmentError;
use crate::image::ImageError;

/// Bit maps [`SegmentBuffers`] holds: D_fg, D_ObjReg, C_ObjReg, the refined
/// region, C_Obj, C_Obj^M, F_Obj, the filled map, the mask, the interiors,
/// a scratch map and the depth pass's foreground (written with D_fg, kept
/// for the pass). F_Obj and the scratch map are [`closing_map_len`] words,
/// the closing's padded maps.
pub const BIT_MAPS: usize = 12;

/// Width of the closing's padded maps, the widest the morphology's rows
/// serve.
const fn padded_width(width: usize) -> usize {
    width + 2 * MAX_CLOSING_STEPS as usize
}

/// `u32` words of the `maps` buffer of [`SegmentBuffers`]: [`BIT_MAPS`] bit
/// maps (two of them padded for the closing), two rows of runs for the
/// labelling and two rows of words for the morphology, and one word per row
/// for the ground fit.
pub const fn maps_len(width: usize, height: usize) -> usize {
    (BIT_MAPS - 2) * bit_map_len(width, height)
        + 2 * closing_map_len(width, height)
        + 4 * row_runs(width)
        + morph_rows_len(padded_width(width))
        + ground_rows_len(height)
}

/// Entries of the `table` buffer of [`SegmentBuffers`] that label any map
/// of this size (one per run); a shorter table is a smaller capacity, and
/// running out of it is [`SegmentError::LabelCapacity`].
pub const fn table_len(width: usize, height: usize) -> usize {
    run_capacity(width, height)
}

/// Bytes of all buffers of [`SegmentBuffers`] at this size (the masks,
/// one `bool` per pixel per object, are the caller's output and not
/// counted).
pub const fn scratch_bytes(width: usize, height: usize) -> usize {
    (maps_len(width, height) + table_len(width, height)) * core::mem::size_of::<u32>()
}

/// Every intermediate map of the stage, over caller buffers.
#[derive(Debug)]
pub struct SegmentBuffers<'a> {
    pub(super) g: Geom,
    pub(super) d_fg: &'a mut [u32],
    pub(super) d_obj_reg: &'a mut [u32],
    pub(super) c_obj_reg: &'a mut [u32],
    pub(super) region: &'a mut [u32],
    pub(super) c_obj: &'a mut [u32],
    pub(super) nms: &'a mut [u32],
    pub(super) closed: &'a mut [u32],
    pub(super) filled: &'a mut [u32],
    pub(super) mask: &'a mut [u32],
    pub(super) interiors: &'a mut [u32],
    pub(super) scratch: &'a mut [u32],
    pub(super) rise: &'a mut [u32],
    pub(super) rows: &'a mut [u32],
    pub(super) morph_rows: &'a mut [u32],
    pub(super) ground_rows: &'a mut [u32],
    pub(super) table: &'a mut [u32],
}

impl<'a> SegmentBuffers<'a> {
    /// Checks the buffers against the `width` x `height` working size:
    /// `maps` needs [`maps_len`] words, `table` [`table_len`] entries for
    /// any input (fewer make a smaller label capacity).
    ///
    /// # Errors
    /// [`SegmentError::Image`] for a bad size or a short `maps`.
    pub fn new(
        width: usize,
        height: usize,
        maps: &'a mut [u32],
        table: &'a mut [u32],
    ) -> Result<Self, SegmentError> {
        crate::image::buffer_len(width, height, width)?;
        let g = Geom::new(width, height);
        let needed = maps_len(width, height);
        if maps.len() < needed {
            return Err(ImageError::BufferTooSmall {
                needed,
                got: maps.len(),
            }
            .into());
        }
        let mut rest: &'a mut [u32] = maps;
        let mut take = |n: usize| -> &'a mut [u32] {
            let r = core::mem::take(&mut rest);
            let (head, tail) = r.split_at_mut(n.min(r.len()));
            rest = tail;
            head
        };
        let len = g.len();
        Ok(Self {
            g,
            d_fg: take(len),
            d_obj_reg: take(len),
            c_obj_reg: take(len),
            region: take(len),
            c_obj: take(len),
            nms: take(len),
            closed: take(closing_map_len(width, height)),
            filled: take(len),
            mask: take(len),
            interiors: take(len),
            scratch: take(closing_map_len(width, height)),
            rise: take(len),
            rows: take(4 * row_runs(width)),
            morph_rows: take(morph_rows_len(padded_width(width))),
            ground_rows: take(ground_rows_len(height)),
            table,
        })
    }

    /// Clears every map.
    pub fn clear(&mut self) {
        for m in [
            &mut self.d_fg,
            &mut self.d_obj_reg,
            &mut self.c_obj_reg,
            &mut self.region,
            &mut self.c_obj,
            &mut self.nms,
            &mut self.closed,
            &mut self.filled,
            &mut self.mask,
            &mut self.interiors,
            &mut self.rise,
        ] {
            m.fill(0);
        }
    }

    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        (self.g.width, self.g.height)
    }

    /// Entries of the component table (the label capacity, in runs).
    pub fn label_capacity(&self) -> usize {
        self.table.len()
    }

    fn view<'s>(&'s self, m: &'s [u32]) -> BitView<'s> {
        BitView::with_geom(m, self.g)
    }

    /// D_fg, ON where D is kept as foreground (after
    /// [`segment`](super::segment): with the extracted objects inhibited but
    /// the last). C_fg of the last search is C where it is ON.
    pub fn d_fg(&self) -> BitView<'_> {
        self.view(self.d_fg)
    }

    /// D_ObjReg of the last object; ψ is C where it is ON.
    pub fn d_obj_reg(&self) -> BitView<'_> {
        self.view(self.d_obj_reg)
    }

    /// C_ObjReg of the last object (C where ON).
    pub fn c_obj_reg(&self) -> BitView<'_> {
        self.view(self.c_obj_reg)
    }

    /// The refined region (largest component of the dilated ψ map) of the
    /// last object.
    pub fn region(&self) -> BitView<'_> {
        self.view(self.region)
    }

    /// C_Obj of the last object (C where ON).
    pub fn c_obj(&self) -> BitView<'_> {
        self.view(self.c_obj)
    }

    /// C_Obj^M of the last object.
    pub fn nms(&self) -> BitView<'_> {
        self.view(self.nms)
    }

    /// F_Obj (the closed C_Obj^M) of the last object.
    pub fn closed(&self) -> BitView<'_> {
        self.view(self.closed)
    }

    /// F_Obj with its holes filled, before the area filter.
    pub fn filled(&self) -> BitView<'_> {
        self.view(self.filled)
    }

    /// The mask of the last object (also written to the caller's masks).
    pub fn mask(&self) -> BitView<'_> {
        self.view(self.mask)
    }

    /// The interiors of the last search's mask (its pixels off the closed
    /// contours), with [`SegmentParams::split_interiors`](super::SegmentParams::split_interiors).
    pub fn interiors(&self) -> BitView<'_> {
        self.view(self.interiors)
    }
}
