//! How the workspace is laid out, in bytes, by `const fn`.
//!
//! ```text
//! ┌ kept for the frame's result ─────────────┬ one region, reused by phase ─────────────┐
//! │ edges C │ disparity │ K masks │ K vectors │ stereo scratch                          │
//! │         │           │ (bits)  │           │ or: row rings + tones + completion      │
//! │         │           │         │           │ or: segmentation maps, then classifier  │
//! └─────────┴───────────┴─────────┴───────────┴──────────────────────────────────────────┘
//! ```
//!
//! The stages reuse each other's scratch: stereo's is free once its map is
//! written, the colour phase's (conspicuity on a rolling window of rows,
//! one [`Tone`] byte per pixel, the completion by runs) once the completion
//! is done, segmentation's maps once the masks are written. Each buffer is
//! rounded up to whole 8-byte words (the private `arena` module).

use super::arena::bytes;
use super::PipelineParams;
use crate::complete::{
    pipeline_run_capacity, run_rows_len, RowSpan, Tone, DEFAULT_REGION_CAPACITY, LABEL_ROWS,
    PIPELINE_TILT_REGIONS,
};
use crate::conspicuity::{stream_scratch_len, EdgeCell, Luv};
use crate::disparity::DisparityCell;
use crate::image::Rgb8;
use crate::mlp;
use crate::segment::{bit_map_len, maps_len, relabel_len, table_len};
use crate::shape::{ShapeElem, SHAPE_LEN};
use crate::stereo::c2f;
use crate::stereo::filters::Z;
use crate::stereo::phase;
use core::mem::size_of;

/// Bytes kept for the result: the edge map C, the completed disparity, and
/// per object a bit mask and a shape vector.
pub const fn kept_bytes(width: usize, height: usize, params: &PipelineParams) -> usize {
    let n = width * height;
    let k = params.segment.max_objects as usize;
    bytes(n, size_of::<EdgeCell>())
        + bytes(n, size_of::<DisparityCell>())
        + k * bytes(bit_map_len(width, height), 4)
        + k * bytes(SHAPE_LEN, size_of::<ShapeElem>())
}

/// Bytes of the stereo engine's buffers (the phase refinement's included).
pub const fn stereo_bytes(width: usize, height: usize, params: &PipelineParams) -> usize {
    let p = &params.stereo;
    let w = width;
    let phase = match &p.phase {
        Some(ph) => {
            bytes(w, size_of::<Rgb8>())
                + bytes(phase::v_len(w, ph), 4)
                + bytes(phase::z_len(w, ph, p.dem.max_disp), size_of::<[i16; 2]>())
                + bytes(w, size_of::<DisparityCell>())
        }
        None => 0,
    };
    bytes(c2f::grey_len(w, p), 2)
        + bytes(c2f::rgb_len(w, p), size_of::<Rgb8>())
        + bytes(c2f::z_len(w, p), size_of::<Z>())
        + bytes(w, size_of::<[i32; 3]>())
        + bytes(c2f::score_len(w, p), 8)
        + bytes(c2f::cost_len(w, p), 2)
        + bytes(c2f::sum_len(w, p), 4)
        + bytes(c2f::pick_len(w), 4)
        + bytes(c2f::map_len(w, height, p), 1)
        + phase
}

/// Bytes of the streamed conspicuity stage: the row rings
/// ([`stream_scratch_len`]), one RGB row and one [`Tone`] per pixel.
pub const fn colour_stream_bytes(width: usize, height: usize, params: &PipelineParams) -> usize {
    bytes(
        stream_scratch_len(width, &params.edges.smooth),
        size_of::<Luv>(),
    ) + bytes(width, size_of::<Rgb8>())
        + bytes(width * height, size_of::<Tone>())
}

/// Bytes of the completion's two bit maps (non-edge and trusted cells).
pub const fn colour_bit_map_bytes(width: usize, height: usize) -> usize {
    2 * bytes(bit_map_len(width, height), 4)
}

/// Bytes of the colour phase: [`colour_stream_bytes`], then the
/// completion's [`colour_bit_map_bytes`], run table, two rows of runs, five
/// label rows and the region tables.
pub const fn colour_bytes(width: usize, height: usize, params: &PipelineParams) -> usize {
    let regions = DEFAULT_REGION_CAPACITY;
    colour_stream_bytes(width, height, params)
        + colour_bit_map_bytes(width, height)
        + bytes(pipeline_run_capacity(width, height), 2)
        + bytes(run_rows_len(width), 4)
        + bytes(LABEL_ROWS * width, 2)
        + 2 * bytes(regions, 4)
        + 2 * bytes(regions, 1)
        + if params.complete.tilt_rows > 0 {
            bytes(PIPELINE_TILT_REGIONS, core::mem::size_of::<RowSpan>())
        } else {
            0
        }
}

/// Bytes of the object phase: segmentation's maps, then, in their place,
/// the classifier's buffers ([`classify_bytes`]).
pub const fn object_bytes(width: usize, height: usize, params: &PipelineParams) -> usize {
    max(
        segment_bytes(width, height) + relabel_bytes(width, params),
        classify_bytes(params),
    )
}

/// Bytes of the band relabelling's rows ([`relabel_len`]; 0 when
/// [`PipelineParams::relabel`] is off).
pub const fn relabel_bytes(width: usize, params: &PipelineParams) -> usize {
    if params.relabel.is_some() {
        bytes(relabel_len(width), 4)
    } else {
        0
    }
}

/// Bytes of segmentation's maps and label table.
pub const fn segment_bytes(width: usize, height: usize) -> usize {
    bytes(maps_len(width, height), 4) + bytes(table_len(width, height), 4)
}

/// Bytes of the classifier's activations, with the mirror check's
/// [`mirror_bytes`].
pub const fn classify_bytes(params: &PipelineParams) -> usize {
    let m = &params.model;
    bytes(mlp::packed_len(SHAPE_LEN, m.hidden as usize), 4)
        + bytes(mlp::hidden_len(m.hidden as usize), 1)
        + bytes(mlp::output_len(m.classes as usize), 2)
        + mirror_bytes(params)
}

/// Bytes of the mirror check's buffers ([`mlp::MirrorScratch`]; 0 when
/// [`PipelineParams::mirror_check`] is off).
pub const fn mirror_bytes(params: &PipelineParams) -> usize {
    let k = params.model.classes as usize;
    if params.mirror_check {
        bytes(SHAPE_LEN, size_of::<ShapeElem>())
            + bytes(mlp::mirror_outputs_len(k), 2)
            + bytes(mlp::mirror_mean_len(k), 2)
    } else {
        0
    }
}

const fn max(a: usize, b: usize) -> usize {
    if a > b {
        a
    } else {
        b
    }
}

/// Bytes of the region the phases share.
pub const fn shared_bytes(width: usize, height: usize, params: &PipelineParams) -> usize {
    max(
        stereo_bytes(width, height, params),
        max(
            colour_bytes(width, height, params),
            object_bytes(width, height, params),
        ),
    )
}
