//! The overview picture of `gist-eval`: example scenes with their
//! ground-truth boxes (green, class name below) and the detections
//! (magenta when the claim is right, red otherwise; best class and score
//! above, `?` for unknown), drawn with `embedded-graphics` mono fonts.

use super::detect::Detection;
use crate::panels::{montage, Panel};
use crate::scenes::load::Scene;
use crate::scenes::BoxPx;
use embedded_graphics::mono_font::{ascii::FONT_6X10, MonoTextStyleBuilder};
use embedded_graphics::pixelcolor::Rgb888;
use embedded_graphics::prelude::*;
use embedded_graphics::primitives::{PrimitiveStyle, Rectangle};
use embedded_graphics::text::{Baseline, Text};
use image::{Rgb, RgbImage};
use std::convert::Infallible;

/// Upscaling of the scenes in the overview.
const ZOOM: u32 = 2;
/// Columns of the overview.
const COLUMNS: usize = 4;
/// Ground-truth colour.
const GT: Rgb888 = Rgb888::new(40, 230, 60);
/// A detection whose claim is its matched object's class.
const RIGHT: Rgb888 = Rgb888::new(255, 60, 255);
/// Any other detection.
const WRONG: Rgb888 = Rgb888::new(255, 50, 40);

/// An `embedded-graphics` target over an [`RgbImage`]; pixels outside are
/// dropped.
pub struct Canvas<'a>(pub &'a mut RgbImage);

impl OriginDimensions for Canvas<'_> {
    fn size(&self) -> Size {
        Size::new(self.0.width(), self.0.height())
    }
}

impl DrawTarget for Canvas<'_> {
    type Color = Rgb888;
    type Error = Infallible;

    fn draw_iter<I>(&mut self, pixels: I) -> Result<(), Self::Error>
    where
        I: IntoIterator<Item = Pixel<Self::Color>>,
    {
        for Pixel(p, c) in pixels {
            if let (Ok(x), Ok(y)) = (u32::try_from(p.x), u32::try_from(p.y)) {
                if x < self.0.width() && y < self.0.height() {
                    self.0.put_pixel(x, y, Rgb([c.r(), c.g(), c.b()]));
                }
            }
        }
        Ok(())
    }
}

/// The class name without its `NN_` folder prefix.
fn short(class: &str) -> &str {
    class.split_once('_').map_or(class, |(_, n)| n)
}

fn frame(canvas: &mut Canvas<'_>, b: &BoxPx, colour: Rgb888) {
    let r = Rectangle::new(
        Point::new((b.x * ZOOM) as i32, (b.y * ZOOM) as i32),
        Size::new(b.width * ZOOM, b.height * ZOOM),
    );
    let Ok(()) = r
        .into_styled(PrimitiveStyle::with_stroke(colour, 1))
        .draw(canvas);
}

fn label(canvas: &mut Canvas<'_>, text: &str, at: Point, colour: Rgb888, baseline: Baseline) {
    let style = MonoTextStyleBuilder::new()
        .font(&FONT_6X10)
        .text_color(colour)
        .background_color(Rgb888::BLACK)
        .build();
    let Ok(_) = Text::with_baseline(text, at, style, baseline).draw(canvas);
}

/// One tile: the left view, twice the size, with boxes and labels.
pub fn tile(scene: &Scene, dets: &[Detection], gist: bool) -> RgbImage {
    let (w, h) = (scene.width as u32, scene.height as u32);
    let mut img = RgbImage::from_fn(w * ZOOM, h * ZOOM, |x, y| {
        let p = scene.left[((y / ZOOM) * w + x / ZOOM) as usize];
        Rgb([p.r, p.g, p.b])
    });
    let mut c = Canvas(&mut img);
    for o in &scene.truth.objects {
        frame(&mut c, &o.bbox, GT);
        let at = Point::new(
            (o.bbox.x * ZOOM) as i32,
            ((o.bbox.y + o.bbox.height) * ZOOM) as i32,
        );
        label(&mut c, short(&o.class), at, GT, Baseline::Top);
    }
    for d in dets {
        let right = scene.truth.objects.iter().any(|o| {
            d.category() == Some(o.class.as_str()) && d.bbox.iou(&o.bbox) >= super::score::MIN_IOU
        });
        let colour = if right { RIGHT } else { WRONG };
        frame(&mut c, &d.bbox, colour);
        let text = match d.top5.first() {
            Some((class, score)) if d.known => format!("{} {score:.2}", short(class)),
            Some((class, score)) => format!("?{} {score:.2}", short(class)),
            None => "no shape".into(),
        };
        let at = Point::new((d.bbox.x * ZOOM) as i32, (d.bbox.y * ZOOM) as i32 - 1);
        label(&mut c, &text, at, colour, Baseline::Bottom);
    }
    let name = scene
        .dir
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let caption = format!("{name}  gist {}", if gist { "right" } else { "wrong" });
    label(
        &mut c,
        &caption,
        Point::new(2, 2),
        Rgb888::WHITE,
        Baseline::Top,
    );
    img
}

/// The montage of `tiles`.
pub fn overview(tiles: Vec<(String, RgbImage)>) -> RgbImage {
    let panels: Vec<Panel> = tiles
        .into_iter()
        .map(|(name, img)| Panel::new(name, img))
        .collect();
    montage(&panels, COLUMNS)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes::{ObjectTruth, SceneTruth};
    use protogist::image::Rgb8;

    #[test]
    fn tiles_frame_truth_and_detections_in_their_colours() {
        let (w, h) = (40usize, 30usize);
        let gt = BoxPx {
            x: 5,
            y: 6,
            width: 10,
            height: 8,
        };
        let scene = Scene {
            dir: "scene_0001".into(),
            width: w,
            height: h,
            left: vec![Rgb8 { r: 1, g: 2, b: 3 }; w * h],
            right: vec![],
            disparity: vec![],
            truth: SceneTruth {
                format: String::new(),
                width: w as u32,
                height: h as u32,
                objects: vec![ObjectTruth {
                    class: "04_circle".into(),
                    mask: String::new(),
                    bbox: gt,
                    disparity: 1.0,
                    area: 80,
                    contrast: true,
                }],
            },
            masks: vec![],
        };
        let det = |known| Detection {
            bbox: BoxPx { x: 22, ..gt },
            mask: vec![],
            top5: vec![("04_circle".into(), 0.9)],
            known,
        };
        let colour = |c: Rgb888| Rgb([c.r(), c.g(), c.b()]);
        let img = tile(&scene, &[det(true)], false);
        assert_eq!(img.dimensions(), (80, 60));
        // Box corners, at twice the scale.
        assert_eq!(*img.get_pixel(10, 12), colour(GT));
        assert_eq!(*img.get_pixel(29, 27), colour(GT));
        // The detection is elsewhere: its claim is wrong.
        assert_eq!(*img.get_pixel(44, 27), colour(WRONG));
        // Inside the boxes the scene shows through.
        assert_eq!(*img.get_pixel(20, 20), Rgb([1, 2, 3]));
        let on_top = Detection {
            bbox: gt,
            ..det(true)
        };
        assert_eq!(
            *tile(&scene, &[on_top], true).get_pixel(29, 27),
            colour(RIGHT)
        );
        assert!(overview(vec![("a".into(), img.clone()), ("b".into(), img)]).width() > 160);
    }
}
