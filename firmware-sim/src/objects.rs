//! The object stages on the board: figure-ground, the object mask and its
//! shape vector, after the conspicuity stage of the same frame.
//!
//! Until the fixed-point disparity energy model is in core, disparity comes
//! from the simulated camera's ground truth (a stand-in for a depth source),
//! so these runs measure segmentation and shape, not stereo.

use crate::pg::checksum::Fnv1a;
use crate::pg::conspicuity::EdgeCell;
use crate::pg::disparity::{from_pixels, DisparityCell};
use crate::pg::image::{ImageView, ImageViewMut};
use crate::pg::segment::{
    binary_maps_len, disparity_maps_len, edge_maps_len, label_capacity, label_maps_len, segment,
    SegmentBuffers, SegmentError, SegmentParams,
};
use crate::pg::shape::{shape_vector, RadialProfile, ShapeElem, ShapeError, SHAPE_LEN};
use crate::pg::synth::{render_disparity, SceneSpec, SynthError};
use crate::Ticks;

/// Frame size of the object stages on the board: segmentation keeps every
/// intermediate map, which at 160x120 would not fit beside the conspicuity
/// buffers in the board's 512 KB (see docs/BENCHMARKS.md).
pub const OBJ_WIDTH: usize = 64;
/// See [`OBJ_WIDTH`].
pub const OBJ_HEIGHT: usize = 48;
const N: usize = OBJ_WIDTH * OBJ_HEIGHT;

/// Buffer lengths at [`OBJ_WIDTH`] x [`OBJ_HEIGHT`].
pub mod len {
    use super::*;
    /// Disparity input.
    pub const INPUT: usize = N;
    /// D_fg and D_ObjReg.
    pub const DISPARITY: usize = disparity_maps_len(OBJ_WIDTH, OBJ_HEIGHT);
    /// C_fg, ψ, C_ObjReg, C_Obj.
    pub const EDGES: usize = edge_maps_len(OBJ_WIDTH, OBJ_HEIGHT);
    /// Binary maps.
    pub const BINARY: usize = binary_maps_len(OBJ_WIDTH, OBJ_HEIGHT);
    /// Labels and parents.
    pub const LABELS: usize = label_maps_len(OBJ_WIDTH, OBJ_HEIGHT);
    /// Component areas.
    pub const AREA: usize = label_capacity(OBJ_WIDTH, OBJ_HEIGHT);
}

/// Caller-owned memory of the object stages.
pub struct ObjectBuffers<'a> {
    /// Whole-pixel disparity from the depth source.
    pub depth: &'a mut [u8],
    /// The disparity map fed to segmentation.
    pub input: &'a mut [DisparityCell],
    /// Segmentation maps.
    pub disparity: &'a mut [DisparityCell],
    /// Segmentation edge maps.
    pub edges: &'a mut [EdgeCell],
    /// Segmentation binary maps.
    pub binary: &'a mut [bool],
    /// Label map and parents.
    pub labels: &'a mut [u16],
    /// Component areas.
    pub area: &'a mut [u32],
    /// The object mask (K = 1).
    pub mask: &'a mut [bool],
    /// The mask as bytes, for the shape stage.
    pub mask_u8: &'a mut [u8],
}

/// What the object stages found in one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ObjectResult {
    /// FNV-1a 32 over the mask and the shape vector.
    pub checksum: u32,
    /// Mask pixels of the most salient object (0: none).
    pub area: u32,
    /// Ticks in segmentation.
    pub segment: u64,
    /// Ticks in the shape stage.
    pub shape: u64,
}

/// Why the object stages failed.
#[derive(Debug)]
pub enum ObjectError {
    /// The depth source.
    Depth(SynthError),
    /// A buffer or size.
    Image(crate::pg::image::ImageError),
    /// Segmentation.
    Segment(SegmentError),
    /// Shape (other than an empty or degenerate mask, which is reported as
    /// area 0).
    Shape(ShapeError),
}

/// Runs segmentation and shape at [`OBJ_WIDTH`] x [`OBJ_HEIGHT`] on the
/// conspicuity map `edges` of the demo scene.
///
/// # Errors
/// [`ObjectError`].
pub fn detect<T: Ticks>(
    edges: &[EdgeCell],
    bufs: &mut ObjectBuffers<'_>,
    ticks: &mut T,
) -> Result<ObjectResult, ObjectError> {
    let (w, h) = (OBJ_WIDTH, OBJ_HEIGHT);
    let spec = SceneSpec::demo(w, h);
    let mut depth = ImageViewMut::packed(&mut *bufs.depth, w, h).map_err(ObjectError::Image)?;
    render_disparity(&spec, &mut depth).map_err(ObjectError::Depth)?;
    for (d, &px) in bufs.input.iter_mut().zip(bufs.depth.iter()) {
        *d = from_pixels(px);
    }
    let edges =
        ImageView::packed(edges.get(..N).unwrap_or(&[]), w, h).map_err(ObjectError::Image)?;
    let input = ImageView::packed(&*bufs.input, w, h).map_err(ObjectError::Image)?;

    let t0 = ticks.now();
    let mut seg = SegmentBuffers::new(
        w,
        h,
        bufs.disparity,
        bufs.edges,
        bufs.binary,
        bufs.labels,
        bufs.area,
    )
    .map_err(ObjectError::Segment)?;
    let report = segment(
        &SegmentParams::default(),
        &input,
        &edges,
        &mut seg,
        bufs.mask,
    )
    .map_err(ObjectError::Segment)?;
    let t1 = ticks.now();
    let area = report.objects.first().map_or(0, |d| d.area);

    for (b, &m) in bufs.mask_u8.iter_mut().zip(bufs.mask.iter()) {
        *b = u8::from(m);
    }
    let mut profile = RadialProfile::new();
    let mut vector = [ShapeElem::ZERO; SHAPE_LEN];
    let mask = ImageView::packed(&*bufs.mask_u8, w, h).map_err(ObjectError::Image)?;
    match shape_vector(&mask, &mut profile, &mut vector) {
        Ok(_) | Err(ShapeError::EmptyMask | ShapeError::ZeroVariance) => {}
        Err(e) => return Err(ObjectError::Shape(e)),
    }
    let t2 = ticks.now();

    let mut hash = Fnv1a::new();
    bufs.mask.iter().for_each(|&m| hash.write(&[u8::from(m)]));
    vector
        .iter()
        .for_each(|e| hash.write(&e.to_bits().to_le_bytes()));
    Ok(ObjectResult {
        checksum: hash.finish(),
        area,
        segment: t1 - t0,
        shape: t2 - t1,
    })
}

/// `checksum objects WxH 0x........ area=N`: compared host vs QEMU.
///
/// # Errors
/// The sink's.
pub fn write_result(out: &mut impl core::fmt::Write, r: &ObjectResult) -> core::fmt::Result {
    writeln!(
        out,
        "checksum objects {OBJ_WIDTH}x{OBJ_HEIGHT} 0x{:08x} area={}",
        r.checksum, r.area
    )
}
