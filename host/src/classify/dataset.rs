//! Image-folder datasets of silhouettes: one subfolder per class (sorted
//! by name; the class index is the position), PNG or JPEG images inside.
//!
//! **Masks.** An image with an alpha channel that is not fully opaque:
//! the pixels of non-zero alpha. Any other image (grey, RGB, or RGBA all
//! opaque): its non-black pixels (any channel non-zero after conversion
//! to 8-bit RGB).
//!
//! **Inputs (section 4.3).** The paper normalises every *vector* (subtract
//! its own mean, divide by its own standard deviation); shape vectors come
//! out of the shape stage already normalised this way (`s^N`, section 4.2)
//! and "are used with all their 720 components". So there is no
//! per-feature standardisation over the training set: the network input is
//! the core `shape_vector` output, converted to float and z-normalised
//! once more with [`rules::z_normalise`] (which only removes the core's
//! fixed-point rounding).
//!
//! Images whose mask is empty or degenerate (zero-variance profile) are
//! skipped and counted.

use super::mlp::SplitMix;
use super::rules;
use crate::error::{HostError, Result};
use protogist::image::ImageView;
use protogist::shape::{shape_vector, RadialProfile, ShapeElem, ShapeError, SHAPE_LEN};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// One usable image.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    /// `class_folder/file_name`, the key of the split.
    pub key: String,
    /// Class index.
    pub label: usize,
    /// The normalised 720-element shape vector.
    pub x: Vec<f32>,
    /// The core shape vector itself (`I4F12` raw bits), the integer
    /// network's input.
    pub shape: Vec<i16>,
}

/// A loaded dataset.
#[derive(Clone, Debug, PartialEq)]
pub struct Dataset {
    /// Class folder names, sorted.
    pub classes: Vec<String>,
    /// Usable images, by class then file name.
    pub samples: Vec<Sample>,
    /// Images skipped for an empty or degenerate mask.
    pub skipped: usize,
}

fn dataset_error(path: &Path, reason: impl Into<String>) -> HostError {
    HostError::Dataset {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

fn is_image(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| matches!(e.to_ascii_lowercase().as_str(), "png" | "jpg" | "jpeg"))
}

fn sorted_entries(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut v = std::fs::read_dir(dir)
        .map_err(|e| HostError::io(dir, e))?
        .map(|e| e.map(|e| e.path()).map_err(|e| HostError::io(dir, e)))
        .collect::<Result<Vec<_>>>()?;
    v.sort();
    Ok(v)
}

/// The object mask (1 = object) of an image, with its size.
pub fn mask_of(img: &image::DynamicImage) -> (Vec<u8>, usize, usize) {
    let (w, h) = (img.width() as usize, img.height() as usize);
    if img.color().has_alpha() {
        let rgba = img.to_rgba8();
        if rgba.pixels().any(|p| p.0[3] < 255) {
            return (rgba.pixels().map(|p| u8::from(p.0[3] > 0)).collect(), w, h);
        }
    }
    let rgb = img.to_rgb8();
    let m = rgb.pixels().map(|p| u8::from(p.0 != [0; 3])).collect();
    (m, w, h)
}

/// The normalised shape vector of a mask, or `None` when the mask is
/// empty or degenerate.
///
/// # Errors
/// [`HostError::Image`] for a size the core rejects.
pub fn shape_input(mask: &[u8], w: usize, h: usize) -> Result<Option<Vec<f32>>> {
    Ok(shape_inputs(mask, w, h)?.map(|(x, _)| x))
}

/// A normalised float shape vector and the core one (`I4F12` raw bits).
pub type ShapePair = (Vec<f32>, Vec<i16>);

/// [`shape_input`] and the core shape vector (`I4F12` raw bits).
///
/// # Errors
/// As [`shape_input`].
pub fn shape_inputs(mask: &[u8], w: usize, h: usize) -> Result<Option<ShapePair>> {
    let view = ImageView::packed(mask, w, h)?;
    let mut profile = RadialProfile::new();
    let mut v = [ShapeElem::ZERO; SHAPE_LEN];
    match shape_vector(&view, &mut profile, &mut v) {
        Ok(_) => {}
        Err(ShapeError::EmptyMask | ShapeError::ZeroVariance) => return Ok(None),
        Err(e) => return Err(e.into()),
    }
    let mut x: Vec<f32> = v.iter().map(|e| e.to_num::<f32>()).collect();
    let raw = v.iter().map(|e| e.to_bits()).collect();
    Ok(rules::z_normalise(&mut x).ok().map(|()| (x, raw)))
}

/// Loads `dir`: every class folder must hold at least one usable image.
///
/// # Errors
/// [`HostError::Dataset`] for a missing directory, no class folder, a
/// class folder without (usable) images; decoding and I/O errors.
pub fn load_dataset(dir: &Path) -> Result<Dataset> {
    let (classes, class_dirs, files) = dataset_files(dir)?;
    let vectors: Vec<Result<Option<ShapePair>>> = files
        .par_iter()
        .map(|(_, _, p)| {
            let img = crate::io::load_image(p)?;
            let (m, w, h) = mask_of(&img);
            shape_inputs(&m, w, h)
        })
        .collect();
    let mut samples = vec![];
    let mut skipped = 0;
    for ((key, label, _), v) in files.into_iter().zip(vectors) {
        match v? {
            Some((x, shape)) => samples.push(Sample {
                key,
                label,
                x,
                shape,
            }),
            None => skipped += 1,
        }
    }
    for (c, cd) in class_dirs.iter().enumerate() {
        if !samples.iter().any(|s| s.label == c) {
            return Err(dataset_error(cd, "no image with a usable mask"));
        }
    }
    Ok(Dataset {
        classes,
        samples,
        skipped,
    })
}

/// The image files of an image-folder dataset: `(key, label, path)`.
type Files = Vec<(String, usize, PathBuf)>;

/// The class names, class folders and image files of `dir`, without
/// reading any image.
fn dataset_files(dir: &Path) -> Result<(Vec<String>, Vec<PathBuf>, Files)> {
    if !dir.is_dir() {
        return Err(dataset_error(dir, "not a directory"));
    }
    let class_dirs: Vec<PathBuf> = sorted_entries(dir)?
        .into_iter()
        .filter(|p| p.is_dir())
        .collect();
    if class_dirs.is_empty() {
        return Err(dataset_error(dir, "no class subfolder"));
    }
    let mut classes = vec![];
    let mut files = vec![];
    for (label, cd) in class_dirs.iter().enumerate() {
        let name = cd
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        let images: Vec<PathBuf> = sorted_entries(cd)?
            .into_iter()
            .filter(|p| p.is_file() && is_image(p))
            .collect();
        if images.is_empty() {
            return Err(dataset_error(cd, "class folder has no PNG or JPEG image"));
        }
        for p in images {
            let file = p
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            files.push((format!("{name}/{file}"), label, p));
        }
        classes.push(name);
    }
    Ok((classes, class_dirs, files))
}

/// Classes and image files of a dataset folder, from its listing alone
/// (for the memory check before training).
///
/// # Errors
/// As [`load_dataset`] for the folder's layout.
pub fn count_images(dir: &Path) -> Result<(usize, usize)> {
    let (classes, _, files) = dataset_files(dir)?;
    Ok((classes.len(), files.len()))
}

/// A seeded stratified split: for each class, `round(fraction · n_c)` of
/// its samples (at most `n_c − 1`, so every class keeps a training
/// sample), drawn by a seeded shuffle, go to the test set. Returns
/// `is_test` per sample.
pub fn stratified_split(labels: &[usize], classes: usize, fraction: f64, seed: u64) -> Vec<bool> {
    let mut rng = SplitMix::new(seed);
    let mut is_test = vec![false; labels.len()];
    for c in 0..classes {
        let mut idx: Vec<usize> = (0..labels.len()).filter(|&i| labels[i] == c).collect();
        for i in (1..idx.len()).rev() {
            let j = (rng.next_u64() % (i as u64 + 1)) as usize;
            idx.swap(i, j);
        }
        let n = idx.len();
        let k = ((fraction * n as f64).round() as usize).min(n.saturating_sub(1));
        for &i in &idx[..k] {
            is_test[i] = true;
        }
    }
    is_test
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_is_stratified_seeded_and_keeps_a_training_sample() {
        let labels: Vec<usize> = (0..30).map(|i| i % 3).collect();
        let s = stratified_split(&labels, 3, 0.3, 5);
        for c in 0..3 {
            let t = (0..30).filter(|&i| labels[i] == c && s[i]).count();
            assert_eq!(t, 3);
        }
        assert_eq!(s, stratified_split(&labels, 3, 0.3, 5));
        assert_ne!(s, stratified_split(&labels, 3, 0.3, 6));
        let one = stratified_split(&[0], 1, 0.9, 0);
        assert_eq!(one, vec![false]);
    }

    #[test]
    fn masks_from_alpha_or_non_black() {
        let mut rgba = image::RgbaImage::new(2, 1);
        rgba.put_pixel(0, 0, image::Rgba([0, 0, 0, 255]));
        let (m, ..) = mask_of(&image::DynamicImage::ImageRgba8(rgba));
        assert_eq!(m, vec![1, 0]);
        let mut g = image::GrayImage::new(2, 1);
        g.put_pixel(1, 0, image::Luma([7]));
        let (m, ..) = mask_of(&image::DynamicImage::ImageLuma8(g));
        assert_eq!(m, vec![0, 1]);
        assert_eq!(shape_input(&[0; 16], 4, 4).unwrap(), None);
    }
}
