//! Every core stage's entry point, called with inputs the optimiser cannot
//! see (`core::hint::black_box`): sizes, parameters, pixels and the bytes of
//! the decoder table and the model blob.
//!
//! The firmware application calls the stages at fixed sizes, so the
//! optimiser may drop a panic path that only some other size could reach.
//! Here nothing is known at compile time, so when the `panic-probe` ELF
//! built for thumbv7em links no panic function (`cargo xtask firmware`),
//! no input can make these stages panic, for any size or content the
//! buffers allow. On the desktop the binary runs the same calls once on
//! small inputs, as a smoke test.

use core::hint::black_box;

use crate::pg::complete::{complete_runs, CompleteParams, RegionTables, RowSpan, RunBuffers};
use crate::pg::conspicuity::{edge_conspicuity, EdgeBuffers, EdgeCell, EdgeParams, Luv, LuvTables};
use crate::pg::disparity::DisparityCell;
use crate::pg::image::{ImageError, ImageView, ImageViewMut, Rgb8};
use crate::pg::mlp::{self, blob::Model, MirrorScratch, Ranked, Scratch};
use crate::pg::segment::{segment, SegmentBuffers, SegmentParams};
use crate::pg::shape::{shape_vector, RadialProfile, ShapeVector, SHAPE_LEN};
use crate::pg::stereo::c2f::{C2f, C2fBuffers, C2fParams};
use crate::pg::stereo::phase::PhaseParams;

use crate::pg::stereo::table::DemTable;

/// The stereo engine's parameters in the probe: [`C2fParams::FULL`] with
/// the phase refinement, so that its path runs too.
pub const C2F: C2fParams = C2fParams {
    phase: Some(PhaseParams::DEFAULT),
    ..C2fParams::FULL
};

/// Caller-owned memory of the probe: one slice per buffer of every stage.
/// Any lengths: the stages check them.
pub struct ProbeBuffers<'a> {
    /// Left and right frames.
    pub rgb: [&'a mut [Rgb8]; 2],
    /// Edge stage: CIELUV, smoothed, row scratch.
    pub luv: [&'a mut [Luv]; 3],
    /// Edge stage: the conspicuity map.
    pub edges: &'a mut [EdgeCell],
    /// Stereo output, and the completion's input and output.
    pub disparity: &'a mut [DisparityCell],
    /// Stereo scratch.
    pub c2f: C2fBuffers<'a>,
    /// Segmentation: bit maps and component table; the completion's
    /// trusted bit map and run-row index.
    pub seg: [&'a mut [u32]; 2],
    /// Segmentation masks (the second is unused).
    pub masks: [&'a mut [bool]; 2],
    /// The completion's label rows and run table.
    pub labels: [&'a mut [u16]; 2],
    /// The completion's edge bit map and tables (total, below).
    pub counts: [&'a mut [u32]; 3],
    /// Completion tables (lo, hi).
    pub bounds: [&'a mut [u8]; 2],
    /// The completion's row spans, for its tilt.
    pub spans: &'a mut [RowSpan],
    /// Shape: the u8 mask.
    pub mask: &'a mut [u8],
    /// Classifier scratch: input, hidden, output.
    pub mlp: Scratch<'a>,
    /// Classifier ranking.
    pub ranked: &'a mut [Ranked],
    /// The mirror check's buffers.
    pub mirror: MirrorScratch<'a>,
}

/// A `w x h` view of `d`, the slice and the stride opaque.
fn view<P>(d: &[P], w: usize, h: usize) -> Result<ImageView<'_, P>, ImageError> {
    ImageView::new(black_box(d), w, h, black_box(w))
}

/// [`view`], mutably.
fn view_mut<P>(d: &mut [P], w: usize, h: usize) -> Result<ImageViewMut<'_, P>, ImageError> {
    ImageViewMut::new(d, w, h, black_box(w))
}

/// One bit per stage result, so that none is optimised away.
fn seen<T, E>(r: &Result<T, E>, bit: u32) -> u32 {
    u32::from(r.is_ok()) << bit
}

/// Runs every stage on `w x h` frames, the decoder tables `tables` (one
/// per level of the stereo engine) and the model blob `model`, each stage on its own buffers, with
/// everything opaque to the optimiser. Returns one bit per stage that
/// succeeded.
#[allow(clippy::too_many_lines)]
pub fn probe(b: ProbeBuffers<'_>, w: usize, h: usize, tables: [&[u8]; 3], model: &[u8]) -> u32 {
    let (w, h) = (black_box(w), black_box(h));
    let (tables, model) = (black_box(tables), black_box(model));
    let ProbeBuffers {
        rgb: [left, right],
        luv: [luv, smoothed, rows],
        edges,
        disparity,
        mut c2f,
        seg: [maps, seg_table],
        masks: [masks, _],
        labels: [labels, parent],
        counts: [area, total, below],
        bounds: [lo, hi],
        spans,
        mask,
        mlp: mut scratch,
        ranked,
        mut mirror,
    } = b;
    let mut bits = 0;

    // Edge conspicuity.
    let luv_tables = LuvTables::new();
    if let (Ok(l), Ok(mut bufs)) = (
        view(left, w, h),
        EdgeBuffers::new(w, h, &mut *luv, smoothed, rows, &mut *edges),
    ) {
        let r = edge_conspicuity(
            &luv_tables,
            &black_box(EdgeParams::default()),
            &l,
            &mut bufs,
        );
        bits |= seen(&r, 0);
    }

    // Stereo: the decoder tables and the engine (bit 2 was the full-search
    // engine's, removed).
    let parsed = tables.map(DemTable::parse);
    bits |= seen(&parsed[0], 1);
    if let (Ok(l), Ok(r)) = (view(left, w, h), view(right, w, h)) {
        if let ([Ok(t0), Ok(t1), Ok(t2)], Ok(engine)) = (&parsed, C2f::new(&black_box(C2F))) {
            let levels = [*t0, *t1, *t2];
            let mut sink = |x: usize, y: usize, d: DisparityCell| {
                if let Some(c) = disparity.get_mut(y * w + x) {
                    *c = d;
                }
            };
            let s = engine.run(&levels, &l, &r, &mut c2f, &mut sink, &mut ());
            bits |= seen(&s, 3);
        }
    }

    // Border completion, on its own inputs (the runs form the pipeline
    // takes, with full colour).
    let edges_v = view(edges, w, h);
    if let (Ok(e), Ok(c), Ok(mut d)) = (&edges_v, view(luv, w, h), view_mut(&mut *disparity, w, h))
    {
        let mut bufs = RunBuffers {
            open: &mut *area,
            trusted: &mut *maps,
            runs: &mut *parent,
            rows: &mut *seg_table,
            labels: &mut *labels,
        };
        let mut t = RegionTables {
            total: &mut *total,
            below: &mut *below,
            lo: &mut *lo,
            hi: &mut *hi,
            tilt: &mut *spans,
        };
        let params = black_box(CompleteParams::default());
        let r = complete_runs(&params, e, &c, &mut d, &mut bufs, &mut t);
        bits |= seen(&r, 4);
    }

    // Figure-ground segmentation.
    if let (Ok(d), Ok(e), Ok(mut bufs)) = (
        view(disparity, w, h),
        &edges_v,
        SegmentBuffers::new(w, h, maps, seg_table),
    ) {
        let params = black_box(SegmentParams::default());
        let r = segment(&params, &d, e, &mut bufs, masks);
        bits |= seen(&r, 5);
    }

    // The shape vector of a mask.
    let mut profile = RadialProfile::new();
    let mut vector: ShapeVector = [crate::pg::shape::ShapeElem::ZERO; SHAPE_LEN];
    if let Ok(m) = view(mask, w, h) {
        let r = shape_vector(&m, &mut profile, &mut vector);
        bits |= seen(&r, 6);
    }

    // The classifier: parse, forward, and every read-out.
    let parsed = Model::parse(model);
    bits |= seen(&parsed, 7);
    if let Ok(m) = &parsed {
        let input = black_box(&vector[..]);
        if let Ok(out) = mlp::forward(m, input, &mut scratch) {
            let out = black_box(out);
            bits |= seen(&mlp::top_k(m, out, ranked), 8);
            bits |= seen(&mlp::identify(m, out), 9);
            bits |= seen(&mlp::verify(m, out, black_box(0)), 10);
        }
        // The mirror check (whatever symmetry the model bytes hold).
        let r = mlp::mirror_check(m, input, &mut scratch, &mut mirror, ranked);
        bits |= seen(&r, 11);
    }
    bits
}
