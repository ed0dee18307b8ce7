//! Test fixtures shared by the generator's modules.

use super::SceneParams;
use image::{GrayImage, Luma};

pub fn params() -> SceneParams {
    SceneParams {
        width: 160,
        height: 120,
        classes: 19,
        objects: (1, 4),
    }
}

/// A 40x20 bar at (10, 30) in a 64x64 frame.
pub fn bar() -> GrayImage {
    GrayImage::from_fn(64, 64, |x, y| {
        Luma([if (10..50).contains(&x) && (30..50).contains(&y) {
            255
        } else {
            0
        }])
    })
}
