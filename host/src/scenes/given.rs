//! Scenes of given silhouettes (`train --through-pipeline`, issue 20 §3):
//! any mask placed as an object of a seeded scene, everything else drawn
//! as [`render_scene`](super::render::render_scene) draws it.

use super::render::RenderedScene;
use super::{BoxPx, SceneParams};
use crate::error::{HostError, Result};
use image::{GrayImage, Luma};

/// A silhouette to place in a scene: its class name and its mask
/// (non-zero = object), of any size.
#[derive(Clone, Copy, Debug)]
pub struct GivenObject<'a> {
    /// Class name, for the truth.
    pub class: &'a str,
    /// The silhouette.
    pub mask: &'a GrayImage,
}

/// Share of its drawn size that a given silhouette's longer side takes:
/// about the share of a `gen-shapes` silhouette in its canvas (55 to 75 %
/// of the diameter).
pub(super) const GIVEN_FILL: f64 = 0.65;

/// Renders a scene of the stream `stream` (any 64-bit seed) whose objects
/// are `given`, in order, in place of drawn classes: background, clutter,
/// sizes, positions, disparities, colours and textures are drawn as
/// [`render_scene`](super::render::render_scene) draws them. Each
/// silhouette is cropped to its box and scaled (area-averaged, then
/// thresholded at half) so that its longer side is 65 % of the drawn size.
/// An object that finds no place (`render_scene`'s rules) is left out:
/// [`RenderedScene::sources`] says which of `given` each object of the
/// scene is; the first one, drawn first, is left out only when it cannot
/// be placed at all.
///
/// # Errors
/// [`HostError::InvalidArgument`] when `given` is empty.
pub fn render_given(
    params: &SceneParams,
    stream: u64,
    given: &[GivenObject<'_>],
) -> Result<RenderedScene> {
    if given.is_empty() {
        return Err(HostError::InvalidArgument {
            name: "objects",
            reason: "a scene of given silhouettes needs at least one".into(),
        });
    }
    super::render::render_stream(params, stream, Some(given))
}

/// `mask` cropped to its box and scaled so that its longer side is
/// `side` px, 255 on 0 (`None` when the mask is empty).
pub(super) fn fit_silhouette(mask: &GrayImage, side: f64) -> Option<GrayImage> {
    let b = BoxPx::of_mask(mask)?;
    let crop = image::imageops::crop_imm(mask, b.x, b.y, b.width, b.height).to_image();
    let binary = GrayImage::from_fn(b.width, b.height, |x, y| {
        Luma([if crop.get_pixel(x, y).0[0] != 0 {
            255
        } else {
            0
        }])
    });
    let k = side / f64::from(b.width.max(b.height));
    let (nw, nh) = (
        ((f64::from(b.width) * k).round() as u32).max(1),
        ((f64::from(b.height) * k).round() as u32).max(1),
    );
    let scaled = image::imageops::resize(&binary, nw, nh, image::imageops::FilterType::Triangle);
    let out = GrayImage::from_fn(nw + 2, nh + 2, |x, y| {
        let on =
            x >= 1 && y >= 1 && x <= nw && y <= nh && scaled.get_pixel(x - 1, y - 1).0[0] >= 128;
        Luma([if on { 255 } else { 0 }])
    });
    BoxPx::of_mask(&out).map(|_| out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes::fixtures::{bar, params};

    #[test]
    fn given_silhouettes_are_placed_first_and_scaled() {
        let (a, b) = (bar(), crate::classify::shapes::render(4, 0, 1, 64).unwrap());
        let given = [
            GivenObject {
                class: "bar",
                mask: &a,
            },
            GivenObject {
                class: "circle",
                mask: &b,
            },
        ];
        let mut placed = 0;
        for stream in 0..8 {
            let s = render_given(&params(), stream, &given).unwrap();
            assert_eq!(s.sources.len(), s.objects.len());
            assert!(s.sources.windows(2).all(|w| w[0] < w[1]));
            let Some(k) = s.sources.iter().position(|&i| i == 0) else {
                continue;
            };
            placed += 1;
            let o = &s.objects[k];
            assert_eq!(o.class, "bar");
            // Longer side 65 % of a size in 36..72 px, aspect 2:1; most of
            // it visible.
            assert!((23..=48).contains(&o.bbox.width), "{}", o.bbox);
            assert!(o.bbox.height * 2 <= o.bbox.width + 2, "{}", o.bbox);
            assert!(s
                .sources
                .iter()
                .zip(&s.objects)
                .all(|(&i, o)| o.class == ["bar", "circle"][i]));
            // Seeded.
            let again = render_given(&params(), stream, &given).unwrap();
            assert_eq!((again.left, again.objects), (s.left, s.objects));
        }
        assert!(placed >= 6, "the first silhouette is placed: {placed} of 8");
    }

    #[test]
    fn given_silhouettes_that_cannot_be_rendered() {
        assert!(matches!(
            render_given(&params(), 1, &[]),
            Err(HostError::InvalidArgument {
                name: "objects",
                ..
            })
        ));
        let empty = GrayImage::new(32, 32);
        let s = render_given(
            &params(),
            1,
            &[GivenObject {
                class: "none",
                mask: &empty,
            }],
        )
        .unwrap();
        assert!(s.objects.is_empty() && s.sources.is_empty());
    }
}
