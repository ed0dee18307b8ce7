//! A stereo pair from image files at the working size, with its optional
//! ground truth: what `run`, `stereo` and the evaluations load.

use crate::error::{HostError, Result};
use crate::ground_truth::{gt_at, load_gt, GtMap};
use crate::io;
use crate::reference::stereo::StereoError;
use std::path::Path;

/// A stereo pair (and its optional ground truth) at the working size.
#[derive(Clone, Debug)]
pub struct Pair {
    /// Input size `(width, height)`.
    pub input_size: (u32, u32),
    /// Working width.
    pub width: usize,
    /// Working height.
    pub height: usize,
    /// Left view, packed.
    pub left: Vec<protogist::image::Rgb8>,
    /// Right view, packed.
    pub right: Vec<protogist::image::Rgb8>,
    /// Ground-truth disparity in px of the working size, when given.
    pub gt: Option<GtMap>,
}

/// Loads a pair and optional GT, checks their sizes, and area-downscales all
/// to `max_width` (GT disparities scale with the images).
///
/// # Errors
/// [`HostError`] for unreadable files, a pair of different sizes, GT of
/// another size, or a zero width.
pub fn load_pair(
    left: &Path,
    right: &Path,
    gt: Option<&Path>,
    gt_scale: f32,
    max_width: u32,
) -> Result<Pair> {
    if max_width == 0 {
        return Err(HostError::ZeroDimension { name: "width" });
    }
    let (left, right) = (io::load_rgb(left)?, io::load_rgb(right)?);
    let (ow, oh) = left.dimensions();
    if right.dimensions() != (ow, oh) {
        let (rw, rh) = right.dimensions();
        return Err(StereoError::SizeMismatch {
            left: (ow as usize, oh as usize),
            right: (rw as usize, rh as usize),
        }
        .into());
    }
    let gt_full = match gt {
        Some(path) => {
            let g = load_gt(path, gt_scale)?;
            if (g.width, g.height) != (ow as usize, oh as usize) {
                return Err(HostError::GroundTruthSize {
                    path: path.to_path_buf(),
                    expected: (ow as usize, oh as usize),
                    got: (g.width, g.height),
                });
            }
            Some(g)
        }
        None => None,
    };
    let (w, h) = io::working_size(ow, oh, max_width)?;
    let scale = |img: image::RgbImage| {
        if (w, h) == (ow, oh) {
            img
        } else {
            io::area_downscale(&img, w, h)
        }
    };
    let (lp, rp) = (
        io::to_core_rgb(&scale(left)),
        io::to_core_rgb(&scale(right)),
    );
    let (w, h) = (w as usize, h as usize);
    Ok(Pair {
        input_size: (ow, oh),
        width: w,
        height: h,
        left: lp,
        right: rp,
        gt: match (gt_full, gt) {
            (Some(g), Some(path)) => Some(gt_at(&g, w, h, path)?),
            _ => None,
        },
    })
}
