//! Boxes, category labels and captions on any `embedded-graphics`
//! [`DrawTarget`] (feature `draw`).
//!
//! The same code draws the host's PNG panels (`Rgb888`) and a board's frame
//! buffer or display (`Rgb565`, or any other [`PixelColor`]): colours come
//! from a style struct, text from the crate's built-in mono fonts, and
//! nothing allocates.
//!
//! * [`draw_objects`] outlines each object's box and puts a filled tab with
//!   its category (and score) above the box, or inside it at the top when
//!   there is no room above. Known objects get a solid outline in
//!   [`LabelStyle::known`]; unknown ones a dashed outline in
//!   [`LabelStyle::unknown`], so the two differ even without colour.
//! * [`caption`] fills a target with a caption strip, for panel names.
//!
//! Everything is clipped to the target: boxes partly or wholly outside the
//! frame, huge boxes and zero-size boxes are all fine (a zero-size box draws
//! nothing).
//!
//! ```
//! use embedded_graphics::{mock_display::MockDisplay, pixelcolor::Rgb565};
//! use protogist::draw::{draw_objects, LabelStyle, ObjectLabel};
//!
//! let mut display = MockDisplay::<Rgb565>::new();
//! display.set_allow_overdraw(true);
//! let cup = ObjectLabel::new(8, 20, 30, 20, "cup", true).with_score(87);
//! draw_objects(&mut display, &[cup], &LabelStyle::default()).unwrap();
//! assert_eq!(display.get_pixel((8, 30).into()), Some(Rgb565::GREEN));
//! # use embedded_graphics::prelude::RgbColor;
//! ```

use core::fmt::Write as _;
use embedded_graphics::mono_font::ascii::{FONT_4X6, FONT_5X8, FONT_6X10};
use embedded_graphics::mono_font::{MonoFont, MonoTextStyle};
use embedded_graphics::pixelcolor::RgbColor;
use embedded_graphics::prelude::*;
use embedded_graphics::primitives::{PrimitiveStyle, Rectangle};
use embedded_graphics::text::{Baseline, Text};

/// One object to draw: its box in target pixels and its label.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ObjectLabel<'a> {
    /// Left column of the box (may be negative: clipped).
    pub x: i32,
    /// Top row of the box (may be negative: clipped).
    pub y: i32,
    /// Box width in pixels; 0 draws nothing.
    pub width: u32,
    /// Box height in pixels; 0 draws nothing.
    pub height: u32,
    /// The label, e.g. the top category's name.
    pub text: &'a str,
    /// A score in percent shown after the text (e.g. ` 87%`), if any;
    /// values above 100 show as 100.
    pub score_percent: Option<u8>,
    /// Whether the classifier accepted the object (solid outline) or
    /// rejected it as unknown (dashed outline).
    pub known: bool,
}

impl<'a> ObjectLabel<'a> {
    /// A label without a score.
    pub const fn new(x: i32, y: i32, width: u32, height: u32, text: &'a str, known: bool) -> Self {
        Self {
            x,
            y,
            width,
            height,
            text,
            score_percent: None,
            known,
        }
    }

    /// The same label with a score in percent.
    #[must_use]
    pub const fn with_score(mut self, percent: u8) -> Self {
        self.score_percent = Some(percent);
        self
    }
}

/// Colours and font of [`draw_objects`].
#[derive(Clone, Copy, Debug)]
pub struct LabelStyle<C> {
    /// Outline and tab colour of known objects.
    pub known: C,
    /// Outline and tab colour of unknown objects.
    pub unknown: C,
    /// Text colour inside the tabs.
    pub text: C,
    /// The tab font.
    pub font: &'static MonoFont<'static>,
}

impl<C: RgbColor> Default for LabelStyle<C> {
    /// Green for known, magenta for unknown, black 6x10 text.
    fn default() -> Self {
        Self {
            known: C::GREEN,
            unknown: C::MAGENTA,
            text: C::BLACK,
            font: &FONT_6X10,
        }
    }
}

/// Colours of [`caption`].
#[derive(Clone, Copy, Debug)]
pub struct CaptionStyle<C> {
    /// Strip colour.
    pub background: C,
    /// Text colour.
    pub text: C,
}

impl<C: RgbColor> Default for CaptionStyle<C> {
    /// White text on black.
    fn default() -> Self {
        Self {
            background: C::BLACK,
            text: C::WHITE,
        }
    }
}

/// Height of a caption strip that fits the largest caption font (6x10) with
/// a pixel above and below.
pub const CAPTION_HEIGHT: u32 = 12;

/// Caption fonts, largest first: [`caption`] takes the first that fits.
const CAPTION_FONTS: [&MonoFont<'static>; 3] = [&FONT_6X10, &FONT_5X8, &FONT_4X6];

/// Dash pattern of unknown objects' outlines: `DASH_ON` of every
/// `DASH_PERIOD` pixels are drawn.
const DASH_PERIOD: i64 = 6;
const DASH_ON: i64 = 4;

/// Width in pixels of `chars` characters of `font`.
pub fn text_width(font: &MonoFont<'_>, chars: usize) -> u32 {
    let n = u32::try_from(chars).unwrap_or(u32::MAX);
    let advance = font
        .character_size
        .width
        .saturating_add(font.character_spacing);
    // As embedded-graphics measures it: no spacing after the last.
    n.saturating_mul(advance)
        .saturating_sub(font.character_spacing)
}

/// Draws every object's box and label tab onto `target`.
///
/// Boxes are drawn first and tabs second, both last object first, so that
/// the first object's (the most salient's) tab ends up on top.
///
/// # Errors
/// Only the target's own drawing errors.
pub fn draw_objects<D: DrawTarget>(
    target: &mut D,
    labels: &[ObjectLabel<'_>],
    style: &LabelStyle<D::Color>,
) -> Result<(), D::Error> {
    let area = target.bounding_box();
    let mut clipped = target.clipped(&area);
    for label in labels.iter().rev() {
        draw_box(&mut clipped, area, label, style)?;
    }
    for label in labels.iter().rev() {
        draw_tab(&mut clipped, area, label, style)?;
    }
    Ok(())
}

/// Inclusive pixel bounds of an area or box, in i64 (no overflow).
#[derive(Clone, Copy, Debug)]
struct Bounds {
    x0: i64,
    y0: i64,
    x1: i64,
    y1: i64,
}

impl Bounds {
    fn of(x: i32, y: i32, width: u32, height: u32) -> Option<Self> {
        if width == 0 || height == 0 {
            return None;
        }
        let (x0, y0) = (i64::from(x), i64::from(y));
        Some(Self {
            x0,
            y0,
            x1: x0 + i64::from(width) - 1,
            y1: y0 + i64::from(height) - 1,
        })
    }

    fn of_rect(r: &Rectangle) -> Option<Self> {
        Self::of(r.top_left.x, r.top_left.y, r.size.width, r.size.height)
    }

    fn meets(&self, o: &Self) -> bool {
        self.x0 <= o.x1 && o.x0 <= self.x1 && self.y0 <= o.y1 && o.y0 <= self.y1
    }
}

/// A coordinate already clamped into the target's i32 area.
fn to_i32(v: i64) -> i32 {
    i32::try_from(v).unwrap_or(if v < 0 { i32::MIN } else { i32::MAX })
}

/// One straight edge of a box: `from..=to` along the run at `fixed` across
/// it (a column when `vertical`, else a row).
#[derive(Clone, Copy)]
struct Run {
    from: i64,
    to: i64,
    fixed: i64,
    vertical: bool,
}

fn draw_box<D: DrawTarget>(
    target: &mut D,
    area: Rectangle,
    label: &ObjectLabel<'_>,
    style: &LabelStyle<D::Color>,
) -> Result<(), D::Error> {
    let (Some(b), Some(a)) = (
        Bounds::of(label.x, label.y, label.width, label.height),
        Bounds::of_rect(&area),
    ) else {
        return Ok(());
    };
    if !b.meets(&a) {
        return Ok(());
    }
    let colour = if label.known {
        style.known
    } else {
        style.unknown
    };
    let runs = [
        Run {
            from: b.x0,
            to: b.x1,
            fixed: b.y0,
            vertical: false,
        },
        Run {
            from: b.x0,
            to: b.x1,
            fixed: b.y1,
            vertical: false,
        },
        Run {
            from: b.y0,
            to: b.y1,
            fixed: b.x0,
            vertical: true,
        },
        Run {
            from: b.y0,
            to: b.y1,
            fixed: b.x1,
            vertical: true,
        },
    ];
    for run in runs {
        let (lo, hi, fixed_lo, fixed_hi) = if run.vertical {
            (a.y0, a.y1, a.x0, a.x1)
        } else {
            (a.x0, a.x1, a.y0, a.y1)
        };
        if run.fixed < fixed_lo || run.fixed > fixed_hi {
            continue;
        }
        let (from, to) = (run.from.max(lo), run.to.min(hi));
        let known = label.known;
        let origin = run.from;
        let pixels = (from..=to)
            .filter(move |&t| known || (t - origin).rem_euclid(DASH_PERIOD) < DASH_ON)
            .map(move |t| {
                let (x, y) = if run.vertical {
                    (run.fixed, t)
                } else {
                    (t, run.fixed)
                };
                Pixel(Point::new(to_i32(x), to_i32(y)), colour)
            });
        target.draw_iter(pixels)?;
    }
    Ok(())
}

fn draw_tab<D: DrawTarget>(
    target: &mut D,
    area: Rectangle,
    label: &ObjectLabel<'_>,
    style: &LabelStyle<D::Color>,
) -> Result<(), D::Error> {
    let (Some(b), Some(a)) = (
        Bounds::of(label.x, label.y, label.width, label.height),
        Bounds::of_rect(&area),
    ) else {
        return Ok(());
    };
    if !b.meets(&a) {
        return Ok(());
    }
    let mut score: heapless::String<8> = heapless::String::new();
    if let Some(p) = label.score_percent {
        // At most " 100%": fits the 8 bytes, so the write cannot fail.
        let _ = write!(score, " {}%", p.min(100));
    }
    let font = style.font;
    let chars = label.text.chars().count().saturating_add(score.len());
    let tab_w = i64::from(text_width(font, chars)) + 2;
    let tab_h = i64::from(font.character_size.height) + 2;
    // Left-aligned with the box, pulled back inside the frame's right edge
    // (but never past its left edge).
    let x = b.x0.min(a.x1 + 1 - tab_w).max(a.x0);
    // Above the box if it fits in the frame, else inside the box's top.
    let y = if b.y0 - tab_h >= a.y0 {
        b.y0 - tab_h
    } else {
        b.y0.min(a.y1 + 1 - tab_h).max(a.y0)
    };
    let colour = if label.known {
        style.known
    } else {
        style.unknown
    };
    let (x, y) = (to_i32(x), to_i32(y));
    let size = Size::new(
        u32::try_from(tab_w).unwrap_or(u32::MAX),
        u32::try_from(tab_h).unwrap_or(u32::MAX),
    );
    Rectangle::new(Point::new(x, y), size)
        .into_styled(PrimitiveStyle::with_fill(colour))
        .draw(target)?;
    let text_style = MonoTextStyle::new(font, style.text);
    let at = Point::new(x.saturating_add(1), y.saturating_add(1));
    let next = Text::with_baseline(label.text, at, text_style, Baseline::Top).draw(target)?;
    if !score.is_empty() {
        Text::with_baseline(&score, next, text_style, Baseline::Top).draw(target)?;
    }
    Ok(())
}

/// Fills the whole of `target` with a caption strip: `style.background`,
/// and `text` left-aligned and centred vertically in the largest built-in
/// font (6x10, 5x8 or 4x6) that fits; text that fits in none is cut at the
/// right edge.
///
/// For a strip across the top of a larger picture, pass a cropped target:
/// `caption(&mut t.cropped(&strip), text, &style)` with a strip of
/// [`CAPTION_HEIGHT`] rows.
///
/// # Errors
/// Only the target's own drawing errors.
pub fn caption<D: DrawTarget>(
    target: &mut D,
    text: &str,
    style: &CaptionStyle<D::Color>,
) -> Result<(), D::Error> {
    let area = target.bounding_box();
    target.fill_solid(&area, style.background)?;
    let chars = text.chars().count();
    let fits = |f: &&&MonoFont<'static>| {
        text_width(f, chars).saturating_add(2) <= area.size.width
            && f.character_size.height <= area.size.height
    };
    let font = CAPTION_FONTS
        .iter()
        .find(fits)
        .copied()
        .unwrap_or(&FONT_4X6);
    let spare = area.size.height.saturating_sub(font.character_size.height) / 2;
    let at = area.top_left + Point::new(1, i32::try_from(spare).unwrap_or(0));
    let mut clipped = target.clipped(&area);
    Text::with_baseline(
        text,
        at,
        MonoTextStyle::new(font, style.text),
        Baseline::Top,
    )
    .draw(&mut clipped)?;
    Ok(())
}

#[cfg(test)]
mod tests;
