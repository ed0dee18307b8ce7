//! The object stages on the board: figure-ground, the object mask and its
//! shape vector, after the conspicuity stage of the same frame.
//!
//! They run at 160x120 on the conspicuity map of the app's last frame.
//! Disparity comes from the simulated camera's ground truth (a stand-in for
//! a depth source), so these runs measure segmentation and shape alone; the
//! stereo stage is run and measured on its own (`stereo_run`).

use crate::pg::checksum::Fnv1a;
use crate::pg::conspicuity::EdgeCell;
use crate::pg::disparity::{from_pixels, DisparityCell};
use crate::pg::image::{ImageView, ImageViewMut};
use crate::pg::segment::{
    maps_len, segment_timed, table_len, SegmentBuffers, SegmentError, SegmentParams, Step,
};
use crate::pg::shape::{shape_vector_bits, RadialProfile, ShapeElem, ShapeError, SHAPE_LEN};
use crate::pg::synth::{render_disparity, SceneSpec, SynthError};
use crate::Ticks;

/// Frame size of the object stages on the board: the largest frame of the
/// conspicuity stage, whose map they take.
pub const OBJ_WIDTH: usize = 160;
/// See [`OBJ_WIDTH`].
pub const OBJ_HEIGHT: usize = 120;
const N: usize = OBJ_WIDTH * OBJ_HEIGHT;

/// Buffer lengths at [`OBJ_WIDTH`] x [`OBJ_HEIGHT`].
pub mod len {
    use super::*;
    /// Disparity input (and the depth source's bytes).
    pub const INPUT: usize = N;
    /// The segmentation's bit maps and run rows.
    pub const MAPS: usize = maps_len(OBJ_WIDTH, OBJ_HEIGHT);
    /// The segmentation's component table (one entry per run: any input).
    pub const TABLE: usize = table_len(OBJ_WIDTH, OBJ_HEIGHT);
}

/// Caller-owned memory of the object stages.
pub struct ObjectBuffers<'a> {
    /// Whole-pixel disparity from the depth source.
    pub depth: &'a mut [u8],
    /// The disparity map fed to segmentation.
    pub input: &'a mut [DisparityCell],
    /// Segmentation bit maps.
    pub maps: &'a mut [u32],
    /// Segmentation component table.
    pub table: &'a mut [u32],
    /// The object mask (K = 1).
    pub mask: &'a mut [bool],
}

/// The segmentation steps timed one by one, in [`Step`] order.
pub const SEGMENT_STEPS: [(Step, &str); 9] = [
    (Step::Foreground, "seg-foreground"),
    (Step::Slice, "seg-slice"),
    (Step::Region, "seg-region"),
    (Step::Refine, "seg-refine"),
    (Step::Nms, "seg-nms"),
    (Step::Close, "seg-close"),
    (Step::Fill, "seg-fill"),
    (Step::Mask, "seg-mask"),
    (Step::Holes, "seg-holes"),
];

/// What the object stages found in one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ObjectResult {
    /// FNV-1a 32 over the mask and the shape vector.
    pub checksum: u32,
    /// Mask pixels of the most salient object (0: none).
    pub area: u32,
    /// Ticks in segmentation.
    pub segment: u64,
    /// Ticks per segmentation step, [`SEGMENT_STEPS`] order (the rest of
    /// `segment` is setup: parameter and size checks, clearing).
    pub steps: [u64; 8],
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
    let mut seg = SegmentBuffers::new(w, h, bufs.maps, bufs.table).map_err(ObjectError::Segment)?;
    let mut steps = [0u64; 8];
    let mut last = ticks.now();
    let mut probe = |step: Step| {
        let now = ticks.now();
        if let Some((_, t)) = SEGMENT_STEPS
            .iter()
            .zip(steps.iter_mut())
            .find(|((s, _), _)| *s == step)
        {
            *t += now - last;
        }
        last = ticks.now();
    };
    let report = segment_timed(
        &SegmentParams::default(),
        &input,
        &edges,
        &mut seg,
        bufs.mask,
        &mut probe,
    )
    .map_err(ObjectError::Segment)?;
    let t1 = ticks.now();
    let area = report.objects.first().map_or(0, |d| d.area);

    let mut profile = RadialProfile::new();
    let mut vector = [ShapeElem::ZERO; SHAPE_LEN];
    match shape_vector_bits(&seg.mask(), &mut profile, &mut vector) {
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
        steps,
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

// The object stages take the conspicuity map the app computed last.
const _: () = {
    let (w, h) = super::FRAME_SIZES[super::FRAME_SIZES.len() - 1];
    assert!(w == OBJ_WIDTH && h == OBJ_HEIGHT);
};
