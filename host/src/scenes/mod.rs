//! Seeded stereo scenes with ground truth, for the end-to-end benchmark
//! (`protogist gen-scenes`, issue 20 §1) and their loading ([`load`]).
//!
//! A scene holds 1 to 4 objects, each a silhouette of one `gen-shapes`
//! class (distinct within the scene) at its own size, position and
//! disparity, filled with a texture whose colour contrasts with what
//! surrounds it in four scenes out of five. The background is a textured
//! back wall and a ground plane tilting away, with small clutter blobs of
//! no class. The right eye has a mild gain and offset of its own; both
//! eyes have sensor noise. [`render`] says how the views are made.
//!
//! Layout of `OUT`:
//!
//! ```text
//! index.json                  the set: size, split, seed, classes, scenes
//! scene_0000/left.png         left view
//! scene_0000/right.png        right view
//! scene_0000/disparity.pfm    left-referenced disparity, px (every pixel)
//! scene_0000/mask_0.png       object 0's visible mask, 255 on 0
//! scene_0000/truth.json       per object: class, mask, box, disparity
//! ```
//!
//! **Seeds.** Scene `i` of split `train` or `test` draws from a SplitMix64
//! stream keyed by `(seed, 2·i + split)` (`split` 0 for test, 1 for
//! train), so for one `--seed` no training scene is ever a test scene, and
//! a scene does not depend on `--scenes`. `index.json` is written last: a
//! set without it is incomplete.

pub mod given;
pub mod load;
pub mod render;

/// Test fixtures shared by the generator's modules.
#[cfg(test)]
mod fixtures;

use crate::classify::families::CLASSES;
use crate::classify::shapes::class_dir;
use crate::error::{HostError, Result};
use crate::output::{ensure_dir, write_atomic};
use crate::summary::Summary;
use image::GrayImage;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The `format` of `index.json`.
pub const INDEX_FORMAT: &str = "protogist-scenes-1";
/// The `format` of `truth.json`.
pub const TRUTH_FORMAT: &str = "protogist-scene-truth-1";

/// An axis-aligned box of whole pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct BoxPx {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
}

impl BoxPx {
    /// The box of a mask's non-zero pixels, `None` when there are none.
    pub fn of_mask(mask: &GrayImage) -> Option<Self> {
        let (w, h) = mask.dimensions();
        let on = |x: u32, y: u32| mask.get_pixel(x, y).0[0] != 0;
        Self::of(w, h, on)
    }

    /// The box of the pixels where `on(x, y)` holds in a `w` x `h` frame.
    pub fn of(w: u32, h: u32, on: impl Fn(u32, u32) -> bool) -> Option<Self> {
        let (mut x0, mut y0, mut x1, mut y1) = (u32::MAX, u32::MAX, 0, 0);
        for y in 0..h {
            for x in 0..w {
                if on(x, y) {
                    (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
                }
            }
        }
        (x0 != u32::MAX).then(|| Self {
            x: x0,
            y: y0,
            width: x1 - x0 + 1,
            height: y1 - y0 + 1,
        })
    }

    /// Area, px.
    pub fn area(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }

    /// Intersection over union (0 when both are empty).
    pub fn iou(&self, other: &Self) -> f64 {
        let ix = (self.x + self.width).min(other.x + other.width);
        let iy = (self.y + self.height).min(other.y + other.height);
        let inter = u64::from(ix.saturating_sub(self.x.max(other.x)))
            * u64::from(iy.saturating_sub(self.y.max(other.y)));
        let union = self.area() + other.area() - inter;
        if union == 0 {
            0.0
        } else {
            inter as f64 / union as f64
        }
    }
}

impl std::fmt::Display for BoxPx {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}x{} at ({}, {})",
            self.width, self.height, self.x, self.y
        )
    }
}

/// One object of a scene's truth.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObjectTruth {
    /// Class folder name as `gen-shapes` writes it (`04_circle`).
    pub class: String,
    /// The visible mask's file name in the scene folder.
    pub mask: String,
    /// Box of the visible mask.
    pub bbox: BoxPx,
    /// Disparity, px (the object is fronto-parallel).
    pub disparity: f64,
    /// Visible area, px.
    pub area: usize,
    /// Whether its colour was drawn to contrast with its surroundings.
    pub contrast: bool,
}

/// `truth.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneTruth {
    /// [`TRUTH_FORMAT`].
    pub format: String,
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Objects, in drawing order.
    pub objects: Vec<ObjectTruth>,
}

/// One scene of `index.json`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct IndexEntry {
    /// Folder name.
    pub dir: String,
    /// Objects in the scene.
    pub objects: usize,
}

/// `index.json`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SceneIndex {
    /// [`INDEX_FORMAT`].
    pub format: String,
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// `train` or `test`.
    pub split: Split,
    /// `--seed`.
    pub seed: u64,
    /// Every class a scene may hold.
    pub classes: Vec<String>,
    /// The scenes.
    pub scenes: Vec<IndexEntry>,
}

/// Which set a scene belongs to; the two never share a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    /// Scenes to measure on.
    Test,
    /// Scenes to train and tune on.
    Train,
}

/// Identifies one scene's random stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneKey {
    /// `--seed`.
    pub seed: u64,
    /// The split.
    pub split: Split,
    /// Scene number.
    pub index: u64,
}

impl SceneKey {
    /// The stream's seed: the set's seed mixed with `2·index + split`.
    pub fn stream(&self) -> u64 {
        let bit = u64::from(self.split == Split::Train);
        render::mix64(render::mix64(self.seed) ^ ((self.index << 1) | bit))
    }
}

/// What every scene of a set shares.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneParams {
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Classes drawn from: the first N of the `gen-shapes` list.
    pub classes: usize,
    /// Least and most objects per scene.
    pub objects: (u8, u8),
}

/// Options of `protogist gen-scenes`.
#[derive(Clone, Debug, PartialEq, Eq, clap::Args)]
pub struct GenScenesOptions {
    /// Output directory (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Number of scenes.
    #[arg(long, default_value_t = 200)]
    pub scenes: u64,
    /// Seed of the set.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Which split: test and train scenes of one seed never coincide.
    #[arg(long, value_enum, default_value = "test")]
    pub split: Split,
    /// Frame width, px.
    #[arg(long, default_value_t = 160)]
    pub width: u32,
    /// Frame height, px.
    #[arg(long, default_value_t = 120)]
    pub height: u32,
    /// Objects per scene: `N` or a range `LO..HI` (inclusive), within 1..4.
    #[arg(long, default_value = "1..4")]
    pub objects: String,
    /// Classes: the first N of the `gen-shapes` list (all 19 by default).
    #[arg(long, default_value_t = CLASSES.len())]
    pub classes: usize,
}

/// Parses `N` or `LO..HI` (also `LO..=HI`) within 1..=4.
///
/// # Errors
/// [`HostError::InvalidArgument`] naming `objects`.
pub fn parse_objects(s: &str) -> Result<(u8, u8)> {
    let bad = || HostError::InvalidArgument {
        name: "objects",
        reason: format!("{s:?} is not N or LO..HI within 1..4"),
    };
    let num = |t: &str| t.trim().parse::<u8>().map_err(|_| bad());
    let (lo, hi) = match s.split_once("..") {
        Some((a, b)) => (num(a)?, num(b.trim_start_matches('='))?),
        None => (num(s)?, num(s)?),
    };
    if (1..=4).contains(&lo) && (lo..=4).contains(&hi) {
        Ok((lo, hi))
    } else {
        Err(bad())
    }
}

/// Checks `opts` and turns them into scene parameters.
///
/// # Errors
/// [`HostError::ZeroDimension`] or [`HostError::InvalidArgument`].
pub fn params(opts: &GenScenesOptions) -> Result<SceneParams> {
    if opts.scenes == 0 {
        return Err(HostError::ZeroDimension { name: "scenes" });
    }
    if opts.classes == 0 || opts.classes > CLASSES.len() {
        return Err(HostError::InvalidArgument {
            name: "classes",
            reason: format!("{} asked, 1..={} available", opts.classes, CLASSES.len()),
        });
    }
    for (name, v, least) in [("width", opts.width, 64), ("height", opts.height, 48)] {
        if !(least..=1024).contains(&v) {
            return Err(HostError::InvalidArgument {
                name,
                reason: format!("{v} px is outside {least}..=1024"),
            });
        }
    }
    let objects = parse_objects(&opts.objects)?;
    if usize::from(objects.1) > opts.classes {
        return Err(HostError::InvalidArgument {
            name: "objects",
            reason: format!(
                "{} distinct classes needed, {} given",
                objects.1, opts.classes
            ),
        });
    }
    Ok(SceneParams {
        width: opts.width,
        height: opts.height,
        classes: opts.classes,
        objects,
    })
}

/// The folder name of scene `i`.
pub fn scene_dir(i: u64) -> String {
    format!("scene_{i:04}")
}

/// A one-channel little-endian PFM of `data` (row-major, top row first).
pub fn pfm_bytes(data: &[f32], width: u32, height: u32) -> Vec<u8> {
    let mut out = format!("Pf\n{width} {height}\n-1.0\n").into_bytes();
    for row in data.chunks_exact(width as usize).rev() {
        for v in row {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

fn png(img: &image::DynamicImage, name: &str) -> Result<Vec<u8>> {
    let mut buf = std::io::Cursor::new(Vec::new());
    img.write_to(&mut buf, image::ImageFormat::Png)
        .map_err(|source| HostError::Encode {
            name: name.into(),
            source,
        })?;
    Ok(buf.into_inner())
}

/// Renders scene `key` and writes its folder `dir`.
///
/// # Errors
/// Rendering, encoding and I/O errors.
pub fn write_scene(params: &SceneParams, key: SceneKey, dir: &Path) -> Result<usize> {
    let scene = render::render_scene(params, key)?;
    ensure_dir(dir)?;
    let files = [
        ("left.png", png(&scene.left.into(), "left")?),
        ("right.png", png(&scene.right.into(), "right")?),
        (
            "disparity.pfm",
            pfm_bytes(&scene.disparity, params.width, params.height),
        ),
    ];
    for (name, bytes) in files {
        write_atomic(&dir.join(name), &bytes)?;
    }
    for (o, m) in scene.objects.iter().zip(scene.masks) {
        write_atomic(&dir.join(&o.mask), &png(&m.into(), &o.mask)?)?;
    }
    let truth = SceneTruth {
        format: TRUTH_FORMAT.into(),
        width: params.width,
        height: params.height,
        objects: scene.objects,
    };
    write_json(&dir.join("truth.json"), &truth)?;
    Ok(truth.objects.len())
}

/// Writes `value` as pretty JSON, atomically.
///
/// # Errors
/// [`HostError::Io`].
pub fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(|e| HostError::io(path, e.into()))?;
    write_atomic(path, format!("{text}\n").as_bytes())
}

/// `protogist gen-scenes`: renders the scenes in parallel, then writes
/// `index.json` (an older one is removed first, so an interrupted run
/// leaves no index).
///
/// # Errors
/// Bad options (checked before anything is written), rendering, encoding
/// and I/O errors.
pub fn gen_scenes(opts: &GenScenesOptions) -> Result<Summary> {
    let start = std::time::Instant::now();
    let p = params(opts)?;
    ensure_dir(&opts.out)?;
    let index_path = opts.out.join("index.json");
    if index_path.exists() {
        std::fs::remove_file(&index_path).map_err(|e| HostError::io(&index_path, e))?;
    }
    let scenes = (0..opts.scenes)
        .into_par_iter()
        .map(|index| {
            let key = SceneKey {
                seed: opts.seed,
                split: opts.split,
                index,
            };
            let dir = scene_dir(index);
            let objects = write_scene(&p, key, &opts.out.join(&dir))?;
            Ok(IndexEntry { dir, objects })
        })
        .collect::<Result<Vec<_>>>()?;
    let index = SceneIndex {
        format: INDEX_FORMAT.into(),
        width: p.width,
        height: p.height,
        split: opts.split,
        seed: opts.seed,
        classes: (0..p.classes).filter_map(class_dir).collect(),
        scenes,
    };
    write_json(&index_path, &index)?;
    let mut s = Summary::new(format!(
        "protogist gen-scenes: {} {} scenes at {}x{}, seed {}",
        opts.scenes,
        match opts.split {
            Split::Test => "test",
            Split::Train => "train",
        },
        p.width,
        p.height,
        opts.seed
    ));
    for n in p.objects.0..=p.objects.1 {
        let count = index
            .scenes
            .iter()
            .filter(|e| e.objects == usize::from(n))
            .count();
        s.push(format!("scenes with {n} objects"), count);
    }
    s.push("output", opts.out.display());
    s.push("time", format!("{:.1} s", start.elapsed().as_secs_f64()));
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(x: u32, y: u32, width: u32, height: u32) -> BoxPx {
        BoxPx {
            x,
            y,
            width,
            height,
        }
    }

    #[test]
    fn box_iou_edge_cases() {
        let a = b(10, 10, 10, 10);
        assert_eq!(a.iou(&a), 1.0);
        // Touching edges share no pixel.
        assert_eq!(a.iou(&b(20, 10, 10, 10)), 0.0);
        assert_eq!(a.iou(&b(50, 50, 3, 3)), 0.0);
        // Half the width overlapping: 50 / 150.
        assert!((a.iou(&b(15, 10, 10, 10)) - 1.0 / 3.0).abs() < 1e-12);
        // A box inside another: the area ratio, exactly 0.5 here.
        assert_eq!(b(0, 0, 10, 10).iou(&b(0, 0, 10, 5)), 0.5);
        // Empty boxes.
        assert_eq!(b(0, 0, 0, 0).iou(&b(0, 0, 0, 0)), 0.0);
        assert_eq!(b(0, 0, 0, 5).iou(&a), 0.0);
    }

    #[test]
    fn box_of_a_mask() {
        let mut m = GrayImage::new(8, 6);
        assert_eq!(BoxPx::of_mask(&m), None);
        m.put_pixel(2, 1, image::Luma([255]));
        m.put_pixel(5, 4, image::Luma([1]));
        assert_eq!(BoxPx::of_mask(&m), Some(b(2, 1, 4, 4)));
    }

    #[test]
    fn objects_ranges_parse_or_fail() {
        assert_eq!(parse_objects("1..4").unwrap(), (1, 4));
        assert_eq!(parse_objects("2..=3").unwrap(), (2, 3));
        assert_eq!(parse_objects("3").unwrap(), (3, 3));
        for bad in ["0", "5", "3..2", "1..5", "x", "", "1.."] {
            assert!(
                matches!(
                    parse_objects(bad),
                    Err(HostError::InvalidArgument {
                        name: "objects",
                        ..
                    })
                ),
                "{bad}"
            );
        }
    }

    #[test]
    fn bad_options_are_typed_errors() {
        let opts = GenScenesOptions {
            out: PathBuf::from("/nonexistent/never"),
            scenes: 2,
            seed: 1,
            split: Split::Test,
            width: 160,
            height: 120,
            objects: "1..4".into(),
            classes: 19,
        };
        assert!(params(&opts).is_ok());
        let with = |f: &dyn Fn(&mut GenScenesOptions)| {
            let mut o = opts.clone();
            f(&mut o);
            gen_scenes(&o)
                .err()
                .map(|e| e.to_string())
                .unwrap_or_default()
        };
        assert!(with(&|o| o.scenes = 0).contains("--scenes"));
        assert!(with(&|o| o.classes = 0).contains("--classes"));
        assert!(with(&|o| o.classes = 20).contains("--classes"));
        assert!(with(&|o| o.width = 10).contains("--width"));
        assert!(with(&|o| o.height = 5000).contains("--height"));
        assert!(with(&|o| o.objects = "7".into()).contains("--objects"));
        // Four distinct classes need four classes.
        assert!(with(&|o| o.classes = 3).contains("--objects"));
    }

    #[test]
    fn splits_and_indices_draw_apart() {
        let key = |split, index| SceneKey {
            seed: 1,
            split,
            index,
        };
        let mut seen = std::collections::HashSet::new();
        for i in 0..500 {
            assert!(seen.insert(key(Split::Test, i).stream()));
            assert!(seen.insert(key(Split::Train, i).stream()));
        }
    }

    #[test]
    fn pfm_round_trips_through_the_reader() {
        let data: Vec<f32> = (0..12).map(|v| v as f32 * 0.25).collect();
        let gt = crate::ground_truth::parse_pfm(&pfm_bytes(&data, 4, 3)).unwrap();
        assert_eq!((gt.width, gt.height), (4, 3));
        assert_eq!(gt.data, data.iter().map(|&v| Some(v)).collect::<Vec<_>>());
    }

    #[test]
    fn scenes_hold_their_objects_in_front_of_the_background() {
        let p = SceneParams {
            width: 160,
            height: 120,
            classes: 19,
            objects: (1, 4),
        };
        for index in 0..6 {
            let key = SceneKey {
                seed: 3,
                split: Split::Test,
                index,
            };
            let s = render::render_scene(&p, key).unwrap();
            assert!(!s.objects.is_empty() && s.objects.len() <= 4);
            let classes: std::collections::HashSet<_> =
                s.objects.iter().map(|o| &o.class).collect();
            assert_eq!(classes.len(), s.objects.len(), "classes are distinct");
            let max = render::max_disparity(160) as f32;
            assert!(s.disparity.iter().all(|&d| d > 0.0 && d <= max));
            for (o, m) in s.objects.iter().zip(&s.masks) {
                assert_eq!(BoxPx::of_mask(m), Some(o.bbox));
                // Fully inside both views: the right view shifts it left.
                assert!(f64::from(o.bbox.x) >= o.disparity.ceil() - 1.0);
                let inside: Vec<f32> = m
                    .as_raw()
                    .iter()
                    .zip(&s.disparity)
                    .filter(|(&v, _)| v != 0)
                    .map(|(_, &d)| d)
                    .collect();
                assert_eq!(inside.len(), o.area);
                assert!(inside.iter().all(|&d| f64::from(d) == o.disparity));
            }
            assert_ne!(s.left, s.right);
        }
    }
}
