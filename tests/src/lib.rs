//! Shared strategies and helpers for the cross-crate tests.

use proptest::prelude::*;
use protogist::image::Rgb8;
use std::path::PathBuf;

/// An RGB image buffer with its geometry; `stride >= width`, and the padding
/// holds random pixels that no stage may read.
#[derive(Clone, Debug)]
pub struct RgbCase {
    /// Pixels, `(height - 1) * stride + width` of them.
    pub data: Vec<Rgb8>,
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// Stride.
    pub stride: usize,
}

impl RgbCase {
    /// The image as a view.
    pub fn view(&self) -> protogist::image::ImageView<'_, Rgb8> {
        protogist::image::ImageView::new(&self.data, self.width, self.height, self.stride)
            .expect("strategy makes valid geometry")
    }
}

fn rgb() -> impl Strategy<Value = Rgb8> {
    any::<[u8; 3]>().prop_map(|[r, g, b]| Rgb8::new(r, g, b))
}

/// Images from 1x1 to `max` x `max`, strides up to 5 wider than the row,
/// either uniform noise or blocks from a small palette (flat regions, exact
/// ties, strong edges).
pub fn rgb_image(max: usize) -> impl Strategy<Value = RgbCase> {
    (1..=max, 1..=max, 0usize..=5, any::<bool>()).prop_flat_map(|(w, h, pad, blocky)| {
        let stride = w + pad;
        let len = (h - 1) * stride + w;
        let noise = proptest::collection::vec(rgb(), len).boxed();
        let pixels = if blocky {
            (
                proptest::collection::vec(rgb(), 3),
                proptest::collection::vec(0usize..3, len),
            )
                .prop_map(|(pal, idx)| idx.into_iter().map(|i| pal[i]).collect())
                .boxed()
        } else {
            noise
        };
        pixels.prop_map(move |data| RgbCase {
            data,
            width: w,
            height: h,
            stride,
        })
    })
}

/// Where fetched data lives: `$PROTOGIST_DATA`, else `<workspace>/.cache/data`.
pub fn data_dir() -> PathBuf {
    std::env::var_os("PROTOGIST_DATA").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../.cache/data"),
        PathBuf::from,
    )
}

/// The path of a fetched file, or `None` when it is missing and data is not
/// required. `cargo xtask ci` sets `PROTOGIST_REQUIRE_DATA=1`, which turns a
/// missing file into a test failure.
pub fn data_file(rel: &str) -> Option<PathBuf> {
    let p = data_dir().join(rel);
    if p.is_file() {
        return Some(p);
    }
    assert!(
        std::env::var_os("PROTOGIST_REQUIRE_DATA").is_none(),
        "{} is missing: run `cargo xtask fetch-data`",
        p.display()
    );
    eprintln!(
        "skipping: {} is missing (run `cargo xtask fetch-data`)",
        p.display()
    );
    None
}

/// Owned storage for [`protogist::conspicuity::EdgeBuffers`] at one size.
pub struct EdgeStorage {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// CIELUV map.
    pub luv: Vec<protogist::conspicuity::Luv>,
    /// Smoothed map.
    pub smoothed: Vec<protogist::conspicuity::Luv>,
    /// Row scratch.
    pub rows: Vec<protogist::conspicuity::Luv>,
    /// Conspicuity map.
    pub cmap: Vec<protogist::conspicuity::EdgeCell>,
}

impl EdgeStorage {
    /// Storage sized by the stage's `const fn`s.
    pub fn new(width: usize, height: usize) -> Self {
        use protogist::conspicuity::{luv_len, row_scratch_len, EdgeCell, Luv};
        Self {
            width,
            height,
            luv: vec![Luv::default(); luv_len(width, height)],
            smoothed: vec![Luv::default(); luv_len(width, height)],
            rows: vec![Luv::default(); row_scratch_len(width)],
            cmap: vec![EdgeCell::OFF; luv_len(width, height)],
        }
    }

    /// The stage's view of the storage.
    pub fn buffers(&mut self) -> protogist::conspicuity::EdgeBuffers<'_> {
        protogist::conspicuity::EdgeBuffers::new(
            self.width,
            self.height,
            &mut self.luv,
            &mut self.smoothed,
            &mut self.rows,
            &mut self.cmap,
        )
        .expect("storage is sized by the stage's const fns")
    }
}

/// Owned storage for [`protogist::segment::SegmentBuffers`] at one size.
pub struct SegmentStorage {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// D_fg, D_ObjReg.
    pub disparity: Vec<protogist::disparity::DisparityCell>,
    /// C_fg, ψ, C_ObjReg, C_Obj.
    pub edges: Vec<protogist::conspicuity::EdgeCell>,
    /// Binary maps.
    pub binary: Vec<bool>,
    /// Label map and parent table.
    pub labels: Vec<u16>,
    /// Area table.
    pub area: Vec<u32>,
}

impl SegmentStorage {
    /// Storage sized by the stage's `const fn`s.
    pub fn new(width: usize, height: usize) -> Self {
        use protogist::segment as s;
        Self {
            width,
            height,
            disparity: vec![Default::default(); s::disparity_maps_len(width, height)],
            edges: vec![Default::default(); s::edge_maps_len(width, height)],
            binary: vec![false; s::binary_maps_len(width, height)],
            labels: vec![0; s::label_maps_len(width, height)],
            area: vec![0; s::label_capacity(width, height)],
        }
    }

    /// The stage's view of the storage.
    pub fn buffers(&mut self) -> protogist::segment::SegmentBuffers<'_> {
        protogist::segment::SegmentBuffers::new(
            self.width,
            self.height,
            &mut self.disparity,
            &mut self.edges,
            &mut self.binary,
            &mut self.labels,
            &mut self.area,
        )
        .expect("storage is sized by the stage's const fns")
    }
}

/// Parses an ASCII picture, rows of `#` (ON) and `.` (OFF); blank
/// characters are ignored. Returns `(pixels, width, height)`.
pub fn parse_mask(rows: &[&str]) -> (Vec<bool>, usize, usize) {
    let rows: Vec<Vec<bool>> = rows
        .iter()
        .map(|r| {
            r.chars()
                .filter(|c| !c.is_whitespace())
                .map(|c| match c {
                    '#' => true,
                    '.' => false,
                    other => panic!("mask pictures use '#' and '.', not {other:?}"),
                })
                .collect()
        })
        .collect();
    let w = rows.first().map_or(0, Vec::len);
    assert!(rows.iter().all(|r| r.len() == w), "ragged mask picture");
    let h = rows.len();
    (rows.into_iter().flatten().collect(), w, h)
}

/// Renders a binary map as rows of `#` and `.`.
pub fn show_mask(px: &[bool], width: usize) -> Vec<String> {
    px.chunks(width)
        .map(|r| r.iter().map(|&b| if b { '#' } else { '.' }).collect())
        .collect()
}

/// `mask![ "#.#", "..#" ]`: an ASCII picture as `(Vec<bool>, width, height)`.
#[macro_export]
macro_rules! mask {
    ($($row:expr),* $(,)?) => {
        $crate::parse_mask(&[$($row),*])
    };
}
