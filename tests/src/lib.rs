//! Shared strategies and helpers for the cross-crate tests.

use proptest::prelude::*;
use protogist::image::Rgb8;
use std::path::PathBuf;

pub use protogist_host::storage::{EdgeStorage, SegmentStorage};

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

/// A stereo pair with ground truth: `(left, right, GT)`.
pub type PairFiles = (PathBuf, PathBuf, PathBuf);

/// Middlebury Aloe (`<data root>/aloe/`), as [`data_file`] finds it.
pub fn aloe_files() -> Option<PairFiles> {
    Some((
        data_file("aloe/aloeL.jpg")?,
        data_file("aloe/aloeR.jpg")?,
        data_file("aloe/aloeGT.png")?,
    ))
}

/// Middlebury 2014 Motorcycle (`<data root>/motorcycle/`, scikit-image's
/// copy: 741x500, GT a float32 npz in px), as [`data_file`] finds it.
pub fn motorcycle_files() -> Option<PairFiles> {
    Some((
        data_file("motorcycle/motorcycle_left.png")?,
        data_file("motorcycle/motorcycle_right.png")?,
        data_file("motorcycle/motorcycle_disp.npz")?,
    ))
}

/// The options of `protogist stereo --left L --right R --gt GT --width W
/// --max-disp D --json --out DIR`, every other option at its default.
pub fn stereo_options(
    files: PairFiles,
    width: u32,
    max_disp: u8,
    out: &std::path::Path,
) -> protogist_host::stereo_cmd::StereoOptions {
    let (left, right, gt) = files;
    protogist_host::stereo_cmd::StereoOptions {
        gt: Some(gt),
        width,
        max_disp,
        json: true,
        ..protogist_host::stereo_cmd::StereoOptions::new(left, right, out.to_path_buf())
    }
}

/// bad-2 % (over estimated pixels, over all GT pixels) of the final map of
/// `protogist stereo` with `opts` (which must ask for JSON and give GT).
pub fn stereo_bad2(opts: &protogist_host::stereo_cmd::StereoOptions) -> (f64, f64) {
    let s = protogist_host::stereo_cmd::run_stereo(opts).unwrap();
    let v: serde_json::Value = serde_json::from_str(s.raw.as_deref().unwrap()).unwrap();
    let get = |k: &str| v["final"][k].as_f64().unwrap();
    (get("bad2_estimated"), get("bad2_all"))
}

/// A binary mask (0 or 255), tightly packed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MaskCase {
    /// Pixels, `width * height`.
    pub data: Vec<u8>,
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
}

impl MaskCase {
    /// An empty mask.
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            data: vec![0; width * height],
            width,
            height,
        }
    }

    /// The mask as a view.
    pub fn view(&self) -> protogist::image::ImageView<'_, u8> {
        protogist::image::ImageView::packed(&self.data, self.width, self.height)
            .expect("mask geometry is valid")
    }

    /// Pixel at `(x, y)`; outside is background.
    pub fn on(&self, x: isize, y: isize) -> bool {
        x >= 0
            && y >= 0
            && (x as usize) < self.width
            && (y as usize) < self.height
            && self.data[y as usize * self.width + x as usize] != 0
    }

    /// Sets every pixel where `f(x, y)` holds.
    pub fn paint(&mut self, f: impl Fn(i32, i32) -> bool) {
        for y in 0..self.height {
            for x in 0..self.width {
                if f(x as i32, y as i32) {
                    self.data[y * self.width + x] = 255;
                }
            }
        }
    }

    /// `(x0, y0, x1, y1)` of the object pixels, inclusive, or `None`.
    pub fn bbox(&self) -> Option<(usize, usize, usize, usize)> {
        let mut b: Option<(usize, usize, usize, usize)> = None;
        for y in 0..self.height {
            for x in 0..self.width {
                if self.data[y * self.width + x] != 0 {
                    b = Some(match b {
                        None => (x, y, x, y),
                        Some((a, c, d, e)) => (a.min(x), c.min(y), d.max(x), e.max(y)),
                    });
                }
            }
        }
        b
    }

    /// The same mask moved by `(dx, dy)` (pixels leaving the image are lost).
    pub fn translated(&self, dx: isize, dy: isize) -> Self {
        let mut out = Self::new(self.width, self.height);
        out.paint(|x, y| self.on(x as isize - dx, y as isize - dy));
        out
    }

    /// The 2x nearest-neighbour upscale.
    pub fn upscaled2(&self) -> Self {
        let mut out = Self::new(2 * self.width, 2 * self.height);
        out.paint(|x, y| self.on(x as isize / 2, y as isize / 2));
        out
    }
}

/// One object of the synthetic scenes, any of the four shapes, half-sizes in
/// `min_r..=max_r`, centred so that it may touch or cross the border of a
/// `w` x `h` image only when `clip` is set.
pub fn object_spec(
    w: usize,
    h: usize,
    min_r: i32,
    max_r: i32,
    clip: bool,
) -> impl Strategy<Value = protogist::synth::ObjectSpec> {
    use protogist::synth::{ObjectSpec, Shape};
    let shape = prop_oneof![
        Just(Shape::Ellipse),
        Just(Shape::Rectangle),
        Just(Shape::Diamond),
        Just(Shape::Triangle)
    ];
    (
        shape,
        min_r..=max_r,
        min_r..=max_r,
        0.0f64..1.0,
        0.0f64..1.0,
    )
        .prop_map(move |(shape, rx, ry, fx, fy)| {
            let (w, h) = (w as i32, h as i32);
            let (x0, x1, y0, y1) = if clip {
                (0, w - 1, 0, h - 1)
            } else {
                (rx, w - 1 - rx, ry, h - 1 - ry)
            };
            ObjectSpec {
                shape,
                cx: x0 + ((x1 - x0).max(0) as f64 * fx) as i32,
                cy: y0 + ((y1 - y0).max(0) as f64 * fy) as i32,
                rx,
                ry,
                disparity: 8,
                colour: Rgb8::new(200, 60, 40),
            }
        })
}

/// The mask of `objects` rendered by [`protogist::synth::render_mask`] and
/// united: object `i` is rendered as the only object of its scene.
pub fn render_objects(w: usize, h: usize, objects: &[protogist::synth::ObjectSpec]) -> MaskCase {
    use protogist::image::ImageViewMut;
    use protogist::synth::{render_mask, SceneSpec};
    let mut out = MaskCase::new(w, h);
    for o in objects {
        let mut spec = SceneSpec::demo(w, h);
        spec.objects.clear();
        spec.objects.push(*o).expect("capacity");
        let mut m = vec![0u8; w * h];
        render_mask(&spec, 0, &mut ImageViewMut::packed(&mut m, w, h).unwrap()).unwrap();
        out.data.iter_mut().zip(&m).for_each(|(a, b)| *a |= b);
    }
    out
}

/// Masks of one or two synthetic objects (united) in a `w` x `h` image,
/// half-sizes `min_r..=max_r`; objects may cross the border when `clip`.
pub fn shape_mask(
    w: usize,
    h: usize,
    min_r: i32,
    max_r: i32,
    clip: bool,
) -> impl Strategy<Value = MaskCase> {
    proptest::collection::vec(object_spec(w, h, min_r, max_r, clip), 1..=2)
        .prop_map(move |objs| render_objects(w, h, &objs))
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

/// Random float networks and their int8 blobs, for the classifier tests.
pub mod nets {
    use ndarray::{Array1, Array2};
    use protogist::mlp::blob::{crc32, Model, CRC_LEN, HEADER_LEN, VERSION_1};
    use protogist_host::classify::mlp::{unit, Mlp, SplitMix};
    use protogist_host::classify::quant::{write_blob, BlobExtras, QuantNet};

    /// A version-2 model blob as version 1: the symmetry section (before
    /// the names and the metadata) dropped, the version and the CRC
    /// rewritten.
    pub fn blob_version_1(v2: &[u8]) -> Vec<u8> {
        let m = Model::parse(v2).unwrap();
        assert!(m.has_symmetry_section());
        let le = |at: usize| u32::from_le_bytes(v2[at..at + 4].try_into().unwrap()) as usize;
        let tail = le(32) + le(36) + CRC_LEN;
        let sym = v2.len() - tail - m.classes();
        let mut v1 = v2[..HEADER_LEN].to_vec();
        v1[4..6].copy_from_slice(&VERSION_1.to_le_bytes());
        v1.extend_from_slice(&v2[HEADER_LEN..sym]);
        v1.extend_from_slice(&v2[sym + m.classes()..v2.len() - CRC_LEN]);
        let crc = crc32(&v1);
        v1.extend_from_slice(&crc.to_le_bytes());
        v1
    }

    /// `n` values uniform in `[-a, a)`.
    pub fn uniform(rng: &mut SplitMix, n: usize, a: f64) -> Vec<f64> {
        (0..n).map(|_| a * (2.0 * unit(rng) - 1.0)).collect()
    }

    /// A `d`-`h`-`k` network with weights uniform in `±a1` (layer 1) and
    /// `±a2` (layer 2), biases in `±bias·a`.
    pub fn random_net(
        rng: &mut SplitMix,
        (d, h, k): (usize, usize, usize),
        a1: f64,
        a2: f64,
        bias: f64,
    ) -> Mlp {
        Mlp {
            w1: Array2::from_shape_vec((h, d), uniform(rng, h * d, a1)).expect("h·d values"),
            b1: Array1::from(uniform(rng, h, bias * a1)),
            w2: Array2::from_shape_vec((k, h), uniform(rng, k * h, a2)).expect("k·h values"),
            b2: Array1::from(uniform(rng, k, bias * a2)),
        }
    }

    /// The blob of a quantised network with `k` classes named `c0..`, zero
    /// templates, Δ 0 and no metadata.
    pub fn blob(q: &QuantNet, k: usize) -> Vec<u8> {
        let names: Vec<String> = (0..k).map(|c| format!("c{c}")).collect();
        write_blob(
            q,
            &BlobExtras {
                templates: &vec![0; k * k],
                delta_q16: 0,
                names: &names,
                meta: "",
                symmetry: None,
            },
        )
        .expect("a valid network writes")
    }
}

/// A random-dot stereogram of uniform disparity `d`
/// (`reference::stereo::train::random_dot_pair`, dots 0 or 255) as grey RGB
/// pixels.
pub fn rds_rgb(w: usize, h: usize, d: usize, seed: u64) -> (Vec<Rgb8>, Vec<Rgb8>) {
    let (l, r) = protogist_host::reference::stereo::train::random_dot_pair(w, h, d, seed);
    let rgb = |p: &protogist_host::reference::stereo::filters::Plane| {
        p.data
            .iter()
            .map(|&v| {
                let g = v.round().clamp(0.0, 255.0) as u8;
                Rgb8::new(g, g, g)
            })
            .collect::<Vec<_>>()
    };
    (rgb(&l), rgb(&r))
}

/// Agreement of a fixed-point stereo map with its f32 reference: (% of the
/// pixels ON in both within 0.25 px, % of the pixels whose OFF decision
/// agrees, pixels ON in both), the end-to-end measures.
pub fn stereo_agreement(
    core: &[protogist::disparity::DisparityCell],
    float: &protogist_host::reference::stereo::DisparityMapsF,
) -> (f64, f64, usize) {
    let (mut both, mut close, mut agree) = (0usize, 0usize, 0usize);
    for (c, f) in core.iter().zip(&float.disparity_f32) {
        let c = c.get().map(|v| v.to_num::<f32>());
        agree += usize::from(c.is_some() == f.is_some());
        if let (Some(c), Some(f)) = (c, f) {
            both += 1;
            close += usize::from((c - f).abs() <= 0.25);
        }
    }
    (
        100.0 * close as f64 / both.max(1) as f64,
        100.0 * agree as f64 / core.len().max(1) as f64,
        both,
    )
}

/// The Aloe pair area-downscaled to 160 px wide, as core RGB pixels
/// (`None` without the data; see [`data_file`]).
pub fn aloe_160_rgb() -> Option<(Vec<Rgb8>, Vec<Rgb8>, usize, usize)> {
    use protogist_host::io::{area_downscale, load_rgb, to_core_rgb, working_size};
    let l = load_rgb(&data_file("aloe/aloeL.jpg")?).unwrap();
    let r = load_rgb(&data_file("aloe/aloeR.jpg")?).unwrap();
    let (w, h) = working_size(l.width(), l.height(), 160).unwrap();
    Some((
        to_core_rgb(&area_downscale(&l, w, h)),
        to_core_rgb(&area_downscale(&r, w, h)),
        w as usize,
        h as usize,
    ))
}

/// SGM penalty for a 1 px step of the reference's read-out tests, in
/// units of a pixel's mean cost gap.
pub const SGM_P1: f32 = 0.25;
/// SGM penalty for a larger step of the reference's read-out tests.
pub const SGM_P2: f32 = 16.0;
/// SGM paths of the reference's read-out tests (one top-to-bottom pass).
pub const SGM_PATHS: u8 = 5;

/// The coarse-to-fine engine's shared fixtures: decoder tables trained once
/// per layout, the reference's parameters, and a core run on an RGB pair.
pub mod c2f {
    use protogist::disparity::DisparityCell;
    use protogist::image::{ImageView, Rgb8};
    use protogist::stereo::c2f::{C2f, C2fParams};
    use protogist::stereo::{self as qs, StereoError, StereoReport};
    use protogist_host::reference::stereo::c2f::level_params;
    use protogist_host::reference::stereo::table::DemTable as HostTable;
    use protogist_host::reference::stereo::{self as dem};
    use protogist_host::storage::C2fStorage;
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};

    /// The reference's parameters for `p` (what `protogist stereo --engine
    /// reference` runs).
    pub fn host_params(p: &C2fParams) -> dem::DemParams {
        protogist_host::dem_tables::params_of(p)
    }

    /// Trained tables by largest disparity and kernel radius.
    type TableCache = Mutex<HashMap<(u8, u8), Vec<u8>>>;

    /// The decoder tables of every level of `p` (trained once per layout).
    pub fn tables(p: &C2fParams) -> Vec<Vec<u8>> {
        static CACHE: OnceLock<TableCache> = OnceLock::new();
        let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
        let hp = host_params(p);
        (0..=usize::from(p.coarse))
            .map(|k| {
                let lp = level_params(&hp, k);
                let mut c = cache.lock().unwrap();
                c.entry((lp.max_disp, lp.radius))
                    .or_insert_with(|| HostTable::from_decoder(&dem::train(&lp)).to_bytes())
                    .clone()
            })
            .collect()
    }

    /// Runs core on an RGB pair.
    pub fn run_core(
        p: &C2fParams,
        tables: &[Vec<u8>],
        l: &[Rgb8],
        r: &[Rgb8],
        w: usize,
        h: usize,
    ) -> Result<(Vec<DisparityCell>, StereoReport), StereoError> {
        let e = C2f::new(p)?;
        let ts: Vec<qs::DemTable<'_>> = tables
            .iter()
            .map(|t| qs::DemTable::parse(t))
            .collect::<Result<_, _>>()?;
        let mut st = C2fStorage::new(w, h, p);
        let mut out = vec![DisparityCell::OFF; w * h];
        let rep = e.run(
            &ts,
            &ImageView::packed(l, w, h).unwrap(),
            &ImageView::packed(r, w, h).unwrap(),
            &mut st.buffers(),
            &mut |x, y, c| out[y * w + x] = c,
            &mut (),
        )?;
        Ok((out, rep))
    }

    /// The full engine settings with `max_disp` disparities.
    pub fn params(max_disp: u8) -> C2fParams {
        C2fParams {
            dem: qs::DemParams {
                max_disp,
                ..C2fParams::FULL.dem
            },
            ..C2fParams::FULL
        }
    }
}
