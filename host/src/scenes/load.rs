//! Loading a `gen-scenes` set and checking that its truth agrees with its
//! images: sizes, object counts, classes, mask boxes, and the disparity
//! map inside each mask. Every disagreement is a [`SceneError`] naming the
//! file.

use super::{BoxPx, SceneIndex, SceneTruth, INDEX_FORMAT, TRUTH_FORMAT};
use crate::error::{HostError, Result};
use image::ImageReader;
use protogist::image::Rgb8;
use std::path::{Path, PathBuf};

/// Largest difference between an object's disparity and the disparity
/// map inside its mask, px.
pub const DISPARITY_TOLERANCE: f64 = 1e-3;

pub use crate::error::SceneError;

fn truth_error(path: &Path, reason: impl Into<String>) -> HostError {
    SceneError::Truth {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
    .into()
}

/// One loaded scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Its folder.
    pub dir: PathBuf,
    /// Frame width.
    pub width: usize,
    /// Frame height.
    pub height: usize,
    /// Left view, row-major.
    pub left: Vec<Rgb8>,
    /// Right view, row-major.
    pub right: Vec<Rgb8>,
    /// Ground-truth disparity, px (`None`: unknown).
    pub disparity: Vec<Option<f32>>,
    /// The truth.
    pub truth: SceneTruth,
    /// Each object's visible mask, row-major, non-zero = object.
    pub masks: Vec<Vec<u8>>,
}

/// A loaded, checked set.
#[derive(Clone, Debug)]
pub struct SceneSet {
    /// `index.json`'s path.
    pub index_path: PathBuf,
    /// The index.
    pub index: SceneIndex,
    /// The scenes, in index order.
    pub scenes: Vec<Scene>,
}

fn read(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| HostError::io(path, e))
}

/// Reads `DIR/index.json`.
///
/// # Errors
/// [`HostError::Io`] when missing, [`SceneError::Index`] when malformed.
pub fn load_index(dir: &Path) -> Result<(PathBuf, SceneIndex)> {
    let path = dir.join("index.json");
    let bytes = read(&path)?;
    let bad = |reason: String| SceneError::Index {
        path: path.clone(),
        reason,
    };
    let index: SceneIndex = serde_json::from_slice(&bytes).map_err(|e| bad(e.to_string()))?;
    if index.format != INDEX_FORMAT {
        return Err(bad(format!(
            "format {:?}, expected {INDEX_FORMAT:?}",
            index.format
        ))
        .into());
    }
    if index.scenes.is_empty() {
        return Err(bad("no scenes".into()).into());
    }
    Ok((path, index))
}

fn decode(path: &Path) -> Result<image::DynamicImage> {
    let bytes = read(path)?;
    ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| HostError::io(path, e))?
        .decode()
        .map_err(|source| HostError::Decode {
            path: path.to_path_buf(),
            source,
        })
}

fn check_size(path: &Path, got: (u32, u32), truth: &SceneTruth) -> Result<()> {
    if got == (truth.width, truth.height) {
        Ok(())
    } else {
        Err(truth_error(
            path,
            format!(
                "is {}x{}, truth.json says {}x{}",
                got.0, got.1, truth.width, truth.height
            ),
        ))
    }
}

fn rgb(path: &Path, truth: &SceneTruth) -> Result<Vec<Rgb8>> {
    let img = decode(path)?.into_rgb8();
    check_size(path, img.dimensions(), truth)?;
    Ok(crate::io::to_core_rgb(&img))
}

/// Loads and checks scene folder `dir`, expected to hold `objects`
/// objects of `classes` at the index's size.
///
/// # Errors
/// [`HostError::Io`] or [`HostError::Decode`] for a missing or corrupt
/// file, [`SceneError::Truth`] naming the file that disagrees.
pub fn load_scene(dir: &Path, index: &SceneIndex, objects: usize) -> Result<Scene> {
    let truth_path = dir.join("truth.json");
    let truth: SceneTruth = serde_json::from_slice(&read(&truth_path)?)
        .map_err(|e| truth_error(&truth_path, e.to_string()))?;
    if truth.format != TRUTH_FORMAT {
        return Err(truth_error(
            &truth_path,
            format!("format {:?}, expected {TRUTH_FORMAT:?}", truth.format),
        ));
    }
    if (truth.width, truth.height) != (index.width, index.height) {
        return Err(truth_error(
            &truth_path,
            format!(
                "{}x{}, index.json says {}x{}",
                truth.width, truth.height, index.width, index.height
            ),
        ));
    }
    if truth.objects.len() != objects {
        return Err(truth_error(
            &truth_path,
            format!("{} objects, index.json says {objects}", truth.objects.len()),
        ));
    }
    let left = rgb(&dir.join("left.png"), &truth)?;
    let right = rgb(&dir.join("right.png"), &truth)?;
    let pfm = dir.join("disparity.pfm");
    let gt = crate::ground_truth::load_gt(&pfm, 1.0)?;
    check_size(&pfm, (gt.width as u32, gt.height as u32), &truth)?;
    let (w, h) = (truth.width as usize, truth.height as usize);
    let mut masks = Vec::with_capacity(objects);
    for o in &truth.objects {
        if !index.classes.contains(&o.class) {
            return Err(truth_error(
                &truth_path,
                format!("class {:?} is not one of index.json's", o.class),
            ));
        }
        let path = dir.join(&o.mask);
        let m = decode(&path)?.into_luma8();
        check_size(&path, m.dimensions(), &truth)?;
        let found = BoxPx::of_mask(&m);
        if found != Some(o.bbox) {
            let found = found.map_or_else(|| "empty".into(), |b| format!("{b}"));
            return Err(truth_error(
                &path,
                format!("its box is {found}, truth.json says {}", o.bbox),
            ));
        }
        let off = m
            .as_raw()
            .iter()
            .zip(&gt.data)
            .filter(|(&v, _)| v != 0)
            .find(|(_, d)| {
                d.is_none_or(|d| (f64::from(d) - o.disparity).abs() > DISPARITY_TOLERANCE)
            });
        if let Some((_, d)) = off {
            return Err(truth_error(
                &pfm,
                format!(
                    "disparity {d:?} inside {}, truth.json says {}",
                    o.mask, o.disparity
                ),
            ));
        }
        masks.push(m.into_raw());
    }
    Ok(Scene {
        dir: dir.to_path_buf(),
        width: w,
        height: h,
        left,
        right,
        disparity: gt.data,
        truth,
        masks,
    })
}

/// Loads and checks the whole set under `dir`.
///
/// # Errors
/// As [`load_index`] and [`load_scene`].
pub fn load_set(dir: &Path) -> Result<SceneSet> {
    use rayon::prelude::*;
    let (index_path, index) = load_index(dir)?;
    let scenes = index
        .scenes
        .par_iter()
        .map(|e| load_scene(&dir.join(&e.dir), &index, e.objects))
        .collect::<Result<Vec<_>>>()?;
    Ok(SceneSet {
        index_path,
        index,
        scenes,
    })
}

/// Checks that the model named `model` knows every class of the set.
///
/// # Errors
/// [`SceneError::ModelClasses`] for the first class it lacks.
pub fn check_classes(set: &SceneSet, model: &Path, names: &[String]) -> Result<()> {
    match set.index.classes.iter().find(|c| !names.contains(c)) {
        None => Ok(()),
        Some(class) => Err(SceneError::ModelClasses {
            model: model.to_path_buf(),
            index: set.index_path.clone(),
            class: class.clone(),
        }
        .into()),
    }
}
