//! The RGB-D Object Dataset's cropped release, as the paper uses it.
//!
//! **Layout.** `rgbd-dataset/<category>/<instance>/` holds, per video frame,
//! `<instance>_<video>_<frame>_crop.png` (RGB), `..._depthcrop.png` (16-bit
//! grey, depth in mm, 0 = unknown), `..._maskcrop.png` (the dataset's object
//! mask) and `..._loc.txt` (the crop's position in the full frame; not
//! needed here). [`scan`] takes either the `rgbd-dataset` folder itself or a
//! folder holding it. Category and instance names come from the folders;
//! an instance folder must be named `<category>_<number>`.
//!
//! **Sampling and split (section 4.2, Lai et al. 2011).** Only every 5th
//! video frame: frames `1, 6, 11, ...` of each video ([`SAMPLE_EVERY`]). In
//! every category the first instance (lowest number: `apple_1` before
//! `apple_10`) is the test set and all others train. The paper counts
//! 34,921 training and 7,021 test images.
//!
//! [`scan`] checks the layout and that every sampled crop has its depth and
//! mask; [`load_frame`] reads one frame and checks sizes and the 16-bit
//! depth. Every failure is an [`RgbdError`].

use super::RgbdError;
use std::path::{Path, PathBuf};

/// Keep one video frame in this many.
pub const SAMPLE_EVERY: u32 = 5;

/// One sampled frame of the dataset.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Item {
    /// Category index (position in [`Index::categories`]).
    pub category: usize,
    /// Instance folder name, e.g. `apple_1`.
    pub instance: String,
    /// Video number.
    pub video: u32,
    /// Frame number within the video.
    pub frame: u32,
    /// The RGB crop.
    pub crop: PathBuf,
    /// Its depth crop.
    pub depth: PathBuf,
    /// Its mask crop.
    pub mask: PathBuf,
    /// In the test split (the category's first instance).
    pub test: bool,
}

/// The sampled frames of a dataset, with its categories.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Index {
    /// The `rgbd-dataset` folder.
    pub root: PathBuf,
    /// Category folder names, sorted.
    pub categories: Vec<String>,
    /// Sampled frames, by category, instance, video and frame.
    pub items: Vec<Item>,
    /// Crops seen before sampling.
    pub frames_seen: usize,
}

impl Index {
    /// `(training, test)` counts.
    pub fn counts(&self) -> (usize, usize) {
        let test = self.items.iter().filter(|i| i.test).count();
        (self.items.len() - test, test)
    }
}

/// One frame read from disk.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// RGB crop.
    pub rgb: image::RgbImage,
    /// Depth in mm, row-major, 0 = unknown.
    pub depth: Vec<u16>,
    /// The dataset's object mask (non-zero = object), row-major.
    pub mask: Vec<u8>,
}

fn not_dataset(path: &Path, reason: impl Into<String>) -> RgbdError {
    RgbdError::NotDataset {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

fn entries(dir: &Path) -> Result<Vec<PathBuf>, RgbdError> {
    let rd = std::fs::read_dir(dir).map_err(|e| not_dataset(dir, e.to_string()))?;
    let mut v = rd
        .map(|e| e.map(|e| e.path()))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| not_dataset(dir, e.to_string()))?;
    v.sort();
    Ok(v)
}

fn name(p: &Path) -> String {
    p.file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
}

/// `(video, frame)` of `<instance>_<video>_<frame>_crop.png`.
fn parse_crop(instance: &str, file: &str) -> Option<(u32, u32)> {
    let rest = file.strip_prefix(instance)?.strip_prefix('_')?;
    let rest = rest.strip_suffix("_crop.png")?;
    let (v, f) = rest.split_once('_')?;
    Some((v.parse().ok()?, f.parse().ok()?))
}

/// The number of an instance folder `<category>_<number>`.
fn instance_number(category: &str, instance: &str) -> Option<u32> {
    instance
        .strip_prefix(category)?
        .strip_prefix('_')?
        .parse()
        .ok()
}

/// Reads the layout of `dir` (the `rgbd-dataset` folder or its parent).
///
/// # Errors
/// [`RgbdError::NotDataset`] for a missing folder, no category folder, an
/// instance folder not named `<category>_<number>`, one without any crop,
/// or files inside an instance that are not the dataset's;
/// [`RgbdError::EmptyCategory`] for a category without a sampled frame;
/// [`RgbdError::MissingCompanion`] for a sampled crop without depth or mask.
pub fn scan(dir: &Path) -> Result<Index, RgbdError> {
    let nested = dir.join("rgbd-dataset");
    let root = if nested.is_dir() {
        nested
    } else {
        dir.to_path_buf()
    };
    let cats: Vec<PathBuf> = entries(&root)?.into_iter().filter(|p| p.is_dir()).collect();
    if cats.is_empty() {
        return Err(not_dataset(&root, "no category folder"));
    }
    let mut index = Index {
        root: root.clone(),
        categories: cats.iter().map(|p| name(p)).collect(),
        items: vec![],
        frames_seen: 0,
    };
    for (ci, cat_dir) in cats.iter().enumerate() {
        let cat = name(cat_dir);
        let mut instances = vec![];
        let listing = entries(cat_dir)?;
        if listing.iter().all(|p| !p.is_dir()) && !listing.is_empty() {
            return Err(not_dataset(cat_dir, "files but no instance folder"));
        }
        for p in listing {
            if !p.is_dir() {
                continue;
            }
            let inst = name(&p);
            let num = instance_number(&cat, &inst).ok_or_else(|| {
                not_dataset(&p, format!("instance folder is not named {cat}_<number>"))
            })?;
            instances.push((num, p, inst));
        }
        instances.sort();
        let before = index.items.len();
        for (k, (_, inst_dir, inst)) in instances.iter().enumerate() {
            let mut crops = 0;
            for f in entries(inst_dir)? {
                let file = name(&f);
                if !file.ends_with("_crop.png") {
                    continue;
                }
                let (video, frame) = parse_crop(inst, &file).ok_or_else(|| {
                    not_dataset(&f, format!("not named {inst}_<video>_<frame>_crop.png"))
                })?;
                crops += 1;
                index.frames_seen += 1;
                if frame % SAMPLE_EVERY != 1 % SAMPLE_EVERY {
                    continue;
                }
                let stem = f.to_string_lossy();
                let stem = stem.strip_suffix("_crop.png").unwrap_or(&stem);
                let depth = PathBuf::from(format!("{stem}_depthcrop.png"));
                let mask = PathBuf::from(format!("{stem}_maskcrop.png"));
                for (kind, p) in [("depth", &depth), ("mask", &mask)] {
                    if !p.is_file() {
                        return Err(RgbdError::MissingCompanion {
                            crop: f.clone(),
                            kind,
                            missing: p.clone(),
                        });
                    }
                }
                index.items.push(Item {
                    category: ci,
                    instance: inst.clone(),
                    video,
                    frame,
                    crop: f,
                    depth,
                    mask,
                    test: k == 0,
                });
            }
            if crops == 0 {
                return Err(not_dataset(
                    inst_dir,
                    "no <instance>_<video>_<frame>_crop.png",
                ));
            }
        }
        if index.items.len() == before {
            return Err(RgbdError::EmptyCategory { category: cat });
        }
        index.items[before..].sort_by(|a, b| {
            (!a.test, &a.instance, a.video, a.frame).cmp(&(!b.test, &b.instance, b.video, b.frame))
        });
    }
    Ok(index)
}

fn decode(path: &Path) -> Result<image::DynamicImage, RgbdError> {
    image::ImageReader::open(path)
        .map_err(|e| RgbdError::Decode {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?
        .with_guessed_format()
        .map_err(|e| RgbdError::Decode {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?
        .decode()
        .map_err(|e| RgbdError::Decode {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })
}

/// Reads one frame: RGB crop, 16-bit depth and mask, all the same size.
///
/// # Errors
/// [`RgbdError::Decode`] for an unreadable crop or mask,
/// [`RgbdError::BadDepth`] for a depth file that is not a 16-bit grey PNG,
/// [`RgbdError::SizeMismatch`] when depth or mask is not the crop's size.
pub fn load_frame(item: &Item) -> Result<Frame, RgbdError> {
    let rgb = decode(&item.crop)?.to_rgb8();
    let size = rgb.dimensions();
    let bad = |reason: String| RgbdError::BadDepth {
        path: item.depth.clone(),
        reason,
    };
    let depth = match decode(&item.depth) {
        Ok(image::DynamicImage::ImageLuma16(d)) => d,
        Ok(other) => return Err(bad(format!("{:?}, not 16-bit grey", other.color()))),
        Err(e) => return Err(bad(e.to_string())),
    };
    if depth.dimensions() != size {
        return Err(RgbdError::SizeMismatch {
            path: item.depth.clone(),
            kind: "depth",
            crop_size: size,
            got: depth.dimensions(),
        });
    }
    let mask = decode(&item.mask)?.to_luma8();
    if mask.dimensions() != size {
        return Err(RgbdError::SizeMismatch {
            path: item.mask.clone(),
            kind: "mask",
            crop_size: size,
            got: mask.dimensions(),
        });
    }
    Ok(Frame {
        rgb,
        depth: depth.into_raw(),
        mask: mask.into_raw(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse() {
        assert_eq!(
            parse_crop("apple_1", "apple_1_4_16_crop.png"),
            Some((4, 16))
        );
        assert_eq!(parse_crop("apple_1", "apple_10_4_16_crop.png"), None);
        assert_eq!(parse_crop("apple_1", "apple_1_4_crop.png"), None);
        assert_eq!(instance_number("food_can", "food_can_12"), Some(12));
        assert_eq!(instance_number("food_can", "food_cup_1"), None);
    }
}
