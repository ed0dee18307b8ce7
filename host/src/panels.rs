//! Display panels: turning core maps into images, and the overview montage.
//!
//! Everything here is for display only. The CIELUV to sRGB inverse in
//! [`luv_to_srgb`] is plain f32 and is not part of any stage.

use crate::error::{HostError, Result};
use crate::ground_truth::GtMap;
use embedded_graphics::prelude::*;
use embedded_graphics::primitives::Rectangle;
use image::{DynamicImage, GrayImage, Rgb, RgbImage};
use protogist::conspicuity::{EdgeCell, Luv, SRGB_TO_XYZ, WHITE_U, WHITE_V};
use protogist::disparity::DisparityCell;
use protogist::draw::{caption, CaptionStyle};
use protogist::image::Rgb8;

/// One named output image; it is written as `{name}.png`.
#[derive(Clone, Debug)]
pub struct Panel {
    /// File stem, e.g. `lightness`.
    pub name: String,
    /// The picture.
    pub image: DynamicImage,
}

impl Panel {
    /// A panel from a name and an image.
    pub fn new(name: impl Into<String>, image: impl Into<DynamicImage>) -> Self {
        Self {
            name: name.into(),
            image: image.into(),
        }
    }

    /// The caption the overview shows above the panel, from its name: a
    /// leading letter (and digits) becomes the figure's panel letter, e.g.
    /// `b_disparity` reads "(b) disparity", `b2_completed_disparity` reads
    /// "(b2) completed disparity" and `gt_mask` reads "gt mask".
    pub fn caption(&self) -> String {
        caption_for(&self.name)
    }

    /// The panel encoded as PNG bytes.
    ///
    /// # Errors
    /// [`HostError::Encode`].
    pub fn encode_png(&self) -> Result<Vec<u8>> {
        let mut bytes = std::io::Cursor::new(Vec::new());
        self.image
            .write_to(&mut bytes, image::ImageFormat::Png)
            .map_err(|source| HostError::Encode {
                name: self.name.clone(),
                source,
            })?;
        Ok(bytes.into_inner())
    }
}

/// The caption of a panel named `name` (see [`Panel::caption`]).
pub fn caption_for(name: &str) -> String {
    let spaced = |s: &str| s.replace('_', " ");
    match name.split_once('_') {
        Some((tag, rest)) if is_panel_letter(tag) && !rest.is_empty() => {
            format!("({tag}) {}", spaced(rest))
        }
        _ => spaced(name),
    }
}

/// One lower-case letter, then digits only: `b`, `b2`.
fn is_panel_letter(tag: &str) -> bool {
    let mut chars = tag.chars();
    chars.next().is_some_and(|c| c.is_ascii_lowercase()) && chars.all(|c| c.is_ascii_digit())
}

/// A copy of `img` with each object's box and label tab drawn on it by
/// `protogist::draw`, as a board would draw them on its frame buffer.
pub fn labelled(img: &RgbImage, labels: &[protogist::draw::ObjectLabel<'_>]) -> RgbImage {
    let mut out = img.clone();
    let style = protogist::draw::LabelStyle {
        font: crate::canvas::font_for(img.width()),
        ..protogist::draw::LabelStyle::default()
    };
    let Ok(()) =
        protogist::draw::draw_objects(&mut crate::canvas::Canvas(&mut out), labels, &style);
    out
}

fn dims(width: usize, height: usize) -> (u32, u32) {
    let c = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
    (c(width), c(height))
}

/// A grey image from a packed row-major map and a per-cell value function.
pub fn grey_from<T: Copy>(
    map: &[T],
    width: usize,
    height: usize,
    f: impl Fn(T) -> u8,
) -> GrayImage {
    let (w, h) = dims(width, height);
    let px = map.iter().map(|&v| f(v)).collect();
    GrayImage::from_raw(w, h, px).unwrap_or_else(|| GrayImage::new(w, h))
}

/// A colour image from packed core pixels.
pub fn rgb_from(px: &[Rgb8], width: usize, height: usize) -> RgbImage {
    let (w, h) = dims(width, height);
    let raw = px.iter().flat_map(|p| [p.r, p.g, p.b]).collect();
    RgbImage::from_raw(w, h, raw).unwrap_or_else(|| RgbImage::new(w, h))
}

fn to_u8(v: f32) -> u8 {
    (v.clamp(0.0, 255.0) + 0.5) as u8
}

/// L* (0..100) as grey 0..255.
pub fn lightness(luv: &[Luv], width: usize, height: usize) -> GrayImage {
    grey_from(luv, width, height, |p| to_u8(p.l().to_num::<f32>() * 2.55))
}

/// C~ scaled so that `max` is white (all black when `max` is 0).
pub fn conspicuity(map: &[EdgeCell], max: f32, width: usize, height: usize) -> GrayImage {
    let scale = if max > 0.0 { 255.0 / max } else { 0.0 };
    grey_from(map, width, height, |c| {
        c.get().map_or(0, |v| to_u8(v.to_num::<f32>() * scale))
    })
}

/// ON cells white, OFF cells black.
pub fn edges(map: &[EdgeCell], width: usize, height: usize) -> GrayImage {
    grey_from(map, width, height, |c| if c.is_on() { 255 } else { 0 })
}

/// A disparity map through the turbo colour map, 0 to `max(d)` (at least 1).
pub fn disparity(d: &[u8], width: usize, height: usize) -> RgbImage {
    let (w, h) = dims(width, height);
    let max = f64::from(d.iter().copied().max().unwrap_or(0).max(1));
    let raw = d
        .iter()
        .flat_map(|&v| {
            let c = colorous::TURBO.eval_continuous(f64::from(v) / max);
            [c.r, c.g, c.b]
        })
        .collect();
    RgbImage::from_raw(w, h, raw).unwrap_or_else(|| RgbImage::new(w, h))
}

/// An OFF-capable disparity map through the turbo colour map, 0 to `max_px`;
/// OFF cells black.
pub fn disparity_cells(d: &[DisparityCell], max_px: f32, width: usize, height: usize) -> RgbImage {
    let (w, h) = dims(width, height);
    let max = f64::from(max_px.max(1.0));
    let raw = d
        .iter()
        .flat_map(|cell| match cell.get() {
            Some(v) => {
                let c = colorous::TURBO.eval_continuous((v.to_num::<f64>() / max).min(1.0));
                [c.r, c.g, c.b]
            }
            None => [0, 0, 0],
        })
        .collect();
    RgbImage::from_raw(w, h, raw).unwrap_or_else(|| RgbImage::new(w, h))
}

/// The image where `mask` is set, black elsewhere (Fig. 2 j).
pub fn masked(px: &[Rgb8], mask: &[bool], width: usize, height: usize) -> RgbImage {
    let kept: Vec<Rgb8> = px
        .iter()
        .zip(mask)
        .map(|(&p, &m)| if m { p } else { Rgb8::default() })
        .collect();
    rgb_from(&kept, width, height)
}

/// The smoothed CIELUV map back in sRGB, for display.
pub fn luv_image(luv: &[Luv], width: usize, height: usize) -> RgbImage {
    let inv = xyz_to_srgb_matrix();
    let px: Vec<Rgb8> = luv.iter().map(|&p| luv_to_srgb(p, &inv)).collect();
    rgb_from(&px, width, height)
}

/// The inverse of [`SRGB_TO_XYZ`] (computed in f64, used in f32).
pub fn xyz_to_srgb_matrix() -> [[f32; 3]; 3] {
    let m = SRGB_TO_XYZ;
    let cof = |r: usize, c: usize| {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
        m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1]
    };
    let det = m[0][0] * cof(0, 0) + m[0][1] * cof(0, 1) + m[0][2] * cof(0, 2);
    // inverse[i][j] = cofactor(j, i) / det
    core::array::from_fn(|i| core::array::from_fn(|j| (cof(j, i) / det) as f32))
}

/// CIELUV (D65) to 8-bit sRGB, clipping out-of-gamut colours.
pub fn luv_to_srgb(p: Luv, xyz_to_rgb: &[[f32; 3]; 3]) -> Rgb8 {
    let (l, u, v) = (
        p.l().to_num::<f32>(),
        p.u().to_num::<f32>(),
        p.v().to_num::<f32>(),
    );
    if l <= 0.0 {
        return Rgb8::new(0, 0, 0);
    }
    let up = u / (13.0 * l) + WHITE_U as f32;
    let vp = v / (13.0 * l) + WHITE_V as f32;
    let y = if l > 8.0 {
        ((l + 16.0) / 116.0).powi(3)
    } else {
        l / protogist::conspicuity::CIE_KAPPA as f32
    };
    let vp = vp.max(1e-6);
    let x = y * 9.0 * up / (4.0 * vp);
    let z = y * (12.0 - 3.0 * up - 20.0 * vp) / (4.0 * vp);
    let enc = |row: &[f32; 3]| {
        let lin = (row[0] * x + row[1] * y + row[2] * z).clamp(0.0, 1.0);
        let s = if lin <= 0.003_130_8 {
            12.92 * lin
        } else {
            1.055 * lin.powf(1.0 / 2.4) - 0.055
        };
        to_u8(s * 255.0)
    };
    let [r, g, b] = xyz_to_rgb;
    Rgb8::new(enc(r), enc(g), enc(b))
}

/// Gap between montage tiles and around the border, px.
pub const GAP: u32 = 4;
/// Montage background.
const BACKGROUND: Rgb<u8> = Rgb([32, 32, 32]);

/// Height of the caption strip above each montage tile, px.
pub const CAPTION: u32 = protogist::draw::CAPTION_HEIGHT;

/// All panels tiled left to right, top to bottom, `columns` per row, with
/// [`GAP`]-pixel gaps, each under a [`CAPTION`]-pixel strip with its
/// [`Panel::caption`] (drawn by `protogist::draw::caption`). Tiles in a row
/// share the row's tallest height.
pub fn montage(panels: &[Panel], columns: usize) -> RgbImage {
    let columns = columns.max(1);
    let rows: Vec<&[Panel]> = panels.chunks(columns).collect();
    let row_h: Vec<u32> = rows
        .iter()
        .map(|r| r.iter().map(|p| p.image.height()).max().unwrap_or(0) + CAPTION)
        .collect();
    let row_w = |r: &[Panel]| r.iter().map(|p| p.image.width() + GAP).sum::<u32>() + GAP;
    let width = rows.iter().map(|r| row_w(r)).max().unwrap_or(GAP).max(1);
    let height = row_h.iter().map(|h| h + GAP).sum::<u32>() + GAP;
    let mut out = RgbImage::from_pixel(width, height, BACKGROUND);
    let style = CaptionStyle {
        background: crate::canvas::rgb888(BACKGROUND),
        text: crate::canvas::rgb888(CAPTION_TEXT),
    };
    let mut y = GAP;
    for (row, h) in rows.iter().zip(&row_h) {
        let mut x = GAP;
        for p in row.iter() {
            let strip = Rectangle::new(
                Point::new(coord(x), coord(y)),
                Size::new(p.image.width(), CAPTION),
            );
            let mut canvas = crate::canvas::Canvas(&mut out);
            let Ok(()) = caption(&mut canvas.cropped(&strip), &p.caption(), &style);
            image::imageops::replace(&mut out, &p.image.to_rgb8(), x.into(), (y + CAPTION).into());
            x += p.image.width() + GAP;
        }
        y += h + GAP;
    }
    out
}

/// Caption text colour.
const CAPTION_TEXT: Rgb<u8> = Rgb([235, 235, 235]);

fn coord(v: u32) -> i32 {
    i32::try_from(v).unwrap_or(i32::MAX)
}

/// Disparity colour-mapped with turbo over `0..=max`, OFF black.
pub fn disparity_panel(d: &[Option<f32>], w: usize, h: usize, max: f32) -> RgbImage {
    RgbImage::from_fn(w as u32, h as u32, |x, y| {
        match d[y as usize * w + x as usize] {
            Some(v) => {
                let c =
                    colorous::TURBO.eval_continuous(f64::from((v / max.max(1.0)).clamp(0.0, 1.0)));
                Rgb([c.r, c.g, c.b])
            }
            None => Rgb([0, 0, 0]),
        }
    })
}

/// Error map: black no GT, blue no estimate, green ≤ 1 px, yellow ≤ 2,
/// orange ≤ 4, red above.
pub fn error_panel(est: &[Option<f32>], gt: &GtMap) -> RgbImage {
    RgbImage::from_fn(gt.width as u32, gt.height as u32, |x, y| {
        let p = y as usize * gt.width + x as usize;
        Rgb(match (est[p], gt.data[p]) {
            (_, None) => [0, 0, 0],
            (None, Some(_)) => [0, 0, 160],
            (Some(e), Some(g)) => match (e - g).abs() {
                v if v <= 1.0 => [0, 190, 0],
                v if v <= 2.0 => [230, 210, 0],
                v if v <= 4.0 => [240, 120, 0],
                _ => [220, 0, 0],
            },
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use protogist::conspicuity::LuvTables;

    #[test]
    fn luv_round_trips_to_srgb_within_one_level() {
        let tables = LuvTables::new();
        let inv = xyz_to_srgb_matrix();
        for &(r, g, b) in &[
            (0, 0, 0),
            (255, 255, 255),
            (196, 64, 48),
            (10, 200, 90),
            (3, 4, 250),
        ] {
            let back = luv_to_srgb(tables.convert(Rgb8::new(r, g, b)), &inv);
            for (a, e) in [(back.r, r), (back.g, g), (back.b, b)] {
                assert!(a.abs_diff(e) <= 1, "{r},{g},{b} -> {back:?}");
            }
        }
    }

    #[test]
    fn montage_holds_every_tile_with_gaps_and_captions() {
        let tile = |name, v| Panel::new(name, GrayImage::from_pixel(60, 5, image::Luma([v])));
        let m = montage(&[tile("a_left", 100), tile("b", 200), tile("c_x", 250)], 2);
        let c = CAPTION;
        assert_eq!(m.dimensions(), (4 + 2 * 64, 4 + 2 * (9 + c)));
        assert_eq!(m.get_pixel(4, 4 + c).0, [100; 3]);
        assert_eq!(m.get_pixel(68, 4 + c).0, [200; 3]);
        assert_eq!(m.get_pixel(4, 13 + 2 * c).0, [250; 3]);
        assert_eq!(m.get_pixel(2, 2).0, BACKGROUND.0);
        // Caption text in each tile's strip, and only there.
        let ink = |x0: u32, y0: u32| {
            (y0..y0 + c)
                .flat_map(|y| (x0..x0 + 60).map(move |x| (x, y)))
                .filter(|&(x, y)| m.get_pixel(x, y).0 == CAPTION_TEXT.0)
                .count()
        };
        assert!(ink(4, 4) > 20, "(a) left");
        assert!(ink(68, 4) > 5, "b");
        assert!(ink(4, 13 + c) > 10, "(c) x");
        assert!(ink(4, 4) > ink(68, 4), "a longer caption, more ink");
        assert_eq!(ink(68, 13 + c), 0, "no fourth tile");
    }

    #[test]
    fn captions_read_as_panel_letters() {
        for (name, caption) in [
            ("b_disparity", "(b) disparity"),
            ("b2_completed_disparity", "(b2) completed disparity"),
            (
                "g_object_region_conspicuity",
                "(g) object region conspicuity",
            ),
            ("gt_mask", "gt mask"),
            ("left", "left"),
            ("shape_vector_0", "shape vector 0"),
            ("a_", "a "),
            ("B_x", "B x"),
        ] {
            assert_eq!(caption_for(name), caption, "{name}");
        }
    }

    #[test]
    fn labelled_draws_boxes_on_a_copy() {
        let img = RgbImage::new(160, 120);
        let boxes = [protogist::draw::ObjectLabel::new(
            20, 40, 50, 30, "ball", true,
        )];
        let out = labelled(&img, &boxes);
        assert_eq!(out.get_pixel(20, 69).0, [0, 255, 0]);
        assert_eq!(out.get_pixel(69, 40).0, [0, 255, 0]);
        assert_eq!(img.get_pixel(20, 69).0, [0, 0, 0]);
    }
}
