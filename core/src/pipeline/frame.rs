//! What a run returns: the objects found and views of its maps.

use crate::conspicuity::EdgeCell;
use crate::disparity::DisparityCell;
use crate::image::ImageView;
use crate::mlp::{Identity, Ranked};
use crate::segment::{BitView, BoundingBox, DisparityRange};
use crate::shape::{Centroid, ShapeElem, SHAPE_LEN};

use super::{MAX_OBJECTS, TOP_K};

/// A categorised proto-object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Object {
    /// Rank among the frame's objects: 0 is the most salient.
    pub rank: usize,
    /// The figure-ground search that found it (its mask's slot).
    pub search: usize,
    /// Bounding box of the mask.
    pub bbox: BoundingBox,
    /// Centroid of the mask (Q8) and its area.
    pub centroid: Centroid,
    /// Mask pixels.
    pub area: u32,
    /// δ, the object's disparity, whole px.
    pub delta: u16,
    /// The disparity slice `[δ − r, δ + r]`.
    pub range: DisparityRange,
    /// Saliency A^C(δ)·δ^A.
    pub score: u64,
    /// The best classes by cosine with their templates, best first
    /// (`top_len` of them).
    pub top: [Ranked; TOP_K],
    /// Valid entries of `top`.
    pub top_len: u8,
    /// Known (the best class reaches Δ) or unknown.
    pub identity: Identity,
}

impl Object {
    /// The ranked classes.
    pub fn top(&self) -> &[Ranked] {
        self.top.get(..usize::from(self.top_len)).unwrap_or(&[])
    }

    /// The object as [`crate::draw::draw_objects`] draws it: its box, `name`
    /// (e.g. the best class's), the best cosine in percent, and the verdict.
    #[cfg(feature = "draw")]
    pub fn label<'a>(&self, name: &'a str) -> crate::draw::ObjectLabel<'a> {
        let c = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
        let i = |v: usize| i32::try_from(v).unwrap_or(i32::MAX);
        crate::draw::ObjectLabel {
            x: i(self.bbox.x),
            y: i(self.bbox.y),
            width: c(self.bbox.width),
            height: c(self.bbox.height),
            text: name,
            score_percent: self
                .top()
                .first()
                .map(|r| u8::try_from((u64::from(r.score) * 100 + 32768) >> 16).unwrap_or(100)),
            known: matches!(self.identity, Identity::Known(_)),
        }
    }
}

/// What a run found; its maps live in the workspace.
#[derive(Debug)]
pub struct Frame<'w> {
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) objects: heapless::Vec<Object, MAX_OBJECTS>,
    pub(super) searches: usize,
    pub(super) masks: &'w [u32],
    pub(super) vectors: &'w [ShapeElem],
    pub(super) edges: ImageView<'w, EdgeCell>,
    pub(super) disparity: ImageView<'w, DisparityCell>,
}

impl<'w> Frame<'w> {
    /// `(width, height)` of the frames.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The objects, most salient first. Searches whose mask came out
    /// empty or degenerate are not objects.
    pub fn objects(&self) -> &[Object] {
        &self.objects
    }

    /// Figure-ground searches run (at most K; fewer when the foreground
    /// ran out).
    pub fn searches(&self) -> usize {
        self.searches
    }

    /// The object's mask.
    pub fn mask(&self, o: &Object) -> Option<BitView<'w>> {
        let n = crate::segment::bit_map_len(self.width, self.height);
        let words = self.masks.get(o.search * n..(o.search + 1) * n)?;
        BitView::new(words, self.width, self.height).ok()
    }

    /// The object's shape vector.
    pub fn shape(&self, o: &Object) -> Option<&'w [ShapeElem]> {
        self.vectors
            .get(o.search * SHAPE_LEN..(o.search + 1) * SHAPE_LEN)
    }

    /// The edge map C.
    pub fn edges(&self) -> ImageView<'w, EdgeCell> {
        self.edges
    }

    /// The completed disparity map segmentation took.
    pub fn disparity(&self) -> ImageView<'w, DisparityCell> {
        self.disparity
    }
}
