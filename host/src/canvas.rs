//! `embedded-graphics` on [`image::RgbImage`]: the desktop's drawing target,
//! so that panels and plots are labelled with the same code and built-in
//! mono fonts as a board's frame buffer (`protogist::draw`).

use embedded_graphics::mono_font::ascii::{FONT_4X6, FONT_5X8, FONT_6X10};
use embedded_graphics::mono_font::{MonoFont, MonoTextStyle};
use embedded_graphics::pixelcolor::Rgb888;
use embedded_graphics::prelude::*;
use embedded_graphics::text::{Alignment, Baseline, Text, TextStyleBuilder};
use image::{Rgb, RgbImage};
use std::convert::Infallible;

/// An [`RgbImage`] as an `embedded-graphics` [`DrawTarget`] (`Rgb888`).
/// Pixels outside the image are ignored, as the trait requires.
#[derive(Debug)]
pub struct Canvas<'a>(pub &'a mut RgbImage);

impl OriginDimensions for Canvas<'_> {
    fn size(&self) -> Size {
        Size::new(self.0.width(), self.0.height())
    }
}

impl DrawTarget for Canvas<'_> {
    type Color = Rgb888;
    type Error = Infallible;

    fn draw_iter<I>(&mut self, pixels: I) -> Result<(), Infallible>
    where
        I: IntoIterator<Item = Pixel<Rgb888>>,
    {
        let (w, h) = self.0.dimensions();
        for Pixel(p, c) in pixels {
            if let (Ok(x), Ok(y)) = (u32::try_from(p.x), u32::try_from(p.y)) {
                if x < w && y < h {
                    self.0.put_pixel(x, y, Rgb([c.r(), c.g(), c.b()]));
                }
            }
        }
        Ok(())
    }
}

/// An `image` colour as an `embedded-graphics` one.
pub fn rgb888(c: Rgb<u8>) -> Rgb888 {
    Rgb888::new(c.0[0], c.0[1], c.0[2])
}

/// Horizontal anchor of a text: which side of the text `x` names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HAnchor {
    /// `x` is the text's left edge.
    Left,
    /// `x` is the text's centre.
    Centre,
    /// `x` is the text's right edge.
    Right,
}

/// Vertical anchor of a text: which part of the text `y` names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VAnchor {
    /// `y` is the top row.
    Top,
    /// `y` is the middle row.
    Middle,
    /// `y` is the bottom row.
    Bottom,
}

/// One text to put on a picture, in pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct TextMark {
    /// The text (ASCII; other characters show as `?`).
    pub text: String,
    /// Anchor point, x.
    pub x: i32,
    /// Anchor point, y.
    pub y: i32,
    /// What `x` names.
    pub h: HAnchor,
    /// What `y` names.
    pub v: VAnchor,
    /// Text colour.
    pub colour: Rgb<u8>,
}

impl TextMark {
    /// A text mark.
    pub fn new(text: impl Into<String>, (x, y): (i32, i32), h: HAnchor, v: VAnchor) -> Self {
        Self {
            text: text.into(),
            x,
            y,
            h,
            v,
            colour: TEXT,
        }
    }

    /// The same mark in another colour.
    #[must_use]
    pub fn coloured(mut self, colour: Rgb<u8>) -> Self {
        self.colour = colour;
        self
    }
}

/// Default text colour of plots: near-black, so text is told apart from
/// black frames in tests.
pub const TEXT: Rgb<u8> = Rgb([24, 24, 24]);

/// The font for a picture `width` pixels wide: 6x10 from 300 px, 5x8 from
/// 140 px, else 4x6.
pub fn font_for(width: u32) -> &'static MonoFont<'static> {
    match width {
        300.. => &FONT_6X10,
        140.. => &FONT_5X8,
        _ => &FONT_4X6,
    }
}

/// Width of `text` in `font`, px.
pub fn text_width(font: &MonoFont<'_>, text: &str) -> i32 {
    i32::try_from(protogist::draw::text_width(font, text.chars().count())).unwrap_or(i32::MAX)
}

/// Draws every mark onto `img` in `font` (clipped at the edges).
pub fn draw_marks(img: &mut RgbImage, marks: &[TextMark], font: &MonoFont<'_>) {
    let mut canvas = Canvas(img);
    for m in marks {
        let style = TextStyleBuilder::new()
            .alignment(match m.h {
                HAnchor::Left => Alignment::Left,
                HAnchor::Centre => Alignment::Center,
                HAnchor::Right => Alignment::Right,
            })
            .baseline(match m.v {
                VAnchor::Top => Baseline::Top,
                VAnchor::Middle => Baseline::Middle,
                VAnchor::Bottom => Baseline::Bottom,
            })
            .build();
        let chars = MonoTextStyle::new(font, rgb888(m.colour));
        let Ok(()) = Text::with_text_style(&m.text, Point::new(m.x, m.y), chars, style)
            .draw(&mut canvas)
            .map(|_| ());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use protogist::draw::{draw_objects, LabelStyle, ObjectLabel};

    #[test]
    fn the_canvas_writes_pixels_and_ignores_those_outside() {
        let mut img = RgbImage::new(20, 10);
        let mut c = Canvas(&mut img);
        let px = [(-1, 0), (0, -1), (20, 0), (0, 10), (3, 4)];
        let Ok(()) = c.draw_iter(px.map(|(x, y)| Pixel(Point::new(x, y), Rgb888::RED)));
        assert_eq!(img.get_pixel(3, 4).0, [255, 0, 0]);
        assert_eq!(img.pixels().filter(|p| p.0 != [0, 0, 0]).count(), 1);
    }

    #[test]
    fn core_draws_labelled_boxes_on_an_rgb_image() {
        let mut img = RgbImage::new(80, 60);
        let label = ObjectLabel::new(10, 20, 30, 20, "cup", true).with_score(90);
        let Ok(()) = draw_objects(&mut Canvas(&mut img), &[label], &LabelStyle::default());
        assert_eq!(img.get_pixel(10, 39).0, [0, 255, 0]);
        assert_eq!(img.get_pixel(39, 20).0, [0, 255, 0]);
        assert_eq!(img.get_pixel(20, 30).0, [0, 0, 0]);
        // The tab above the box: green fill with black text.
        let tab = (8..20).flat_map(|y| (10..50).map(move |x| (x, y)));
        let (fill, text): (Vec<_>, Vec<_>) = tab
            .map(|(x, y)| img.get_pixel(x, y).0)
            .filter(|p| *p == [0, 255, 0] || *p == [0, 0, 0])
            .partition(|p| *p == [0, 255, 0]);
        assert!(
            fill.len() > 100 && text.len() > 30,
            "{} {}",
            fill.len(),
            text.len()
        );
    }

    #[test]
    fn marks_are_anchored_where_asked() {
        let font = font_for(400);
        let mut img = RgbImage::from_pixel(100, 40, Rgb([255; 3]));
        let marks = [
            TextMark::new("right", (50, 5), HAnchor::Right, VAnchor::Top),
            TextMark::new("left", (50, 25), HAnchor::Left, VAnchor::Top),
        ];
        draw_marks(&mut img, &marks, font);
        let ink = |x0: u32, x1: u32, y0: u32, y1: u32| {
            (y0..y1)
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .filter(|&(x, y)| img.get_pixel(x, y).0 == TEXT.0)
                .count()
        };
        // "right" ends at x = 50 (30 px wide), "left" starts there.
        assert!(ink(20, 50, 5, 15) > 20 && ink(50, 100, 5, 15) == 0);
        assert!(ink(50, 74, 25, 35) > 20 && ink(0, 50, 25, 35) == 0);
        assert_eq!(text_width(font, "right"), 30);
    }
}
