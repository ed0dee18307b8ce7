//! Deterministic synthetic stereo scenes with ground truth, integer only.
//!
//! A scene is a textured background plane at one disparity and up to
//! [`MAX_OBJECTS`] flat objects in front of it, each at its own disparity.
//! Textures are pure functions of the surface point, so the left and right
//! images agree exactly: the right pixel `(x, y)` shows the surface that the
//! left image shows at `(x + d, y)`. Disparity is left-referenced, `d ≥ 0`,
//! and a larger disparity is nearer. The same code runs on the host (demo,
//! tests) and on the firmware (the simulated camera), so both see the same
//! pixels.
//!
//! ```
//! use protogist::image::{ImageViewMut, Rgb8};
//! use protogist::synth::{render_disparity, render_left, SceneSpec};
//! let spec = SceneSpec::demo(32, 24);
//! let mut px = [Rgb8::default(); 32 * 24];
//! render_left(&spec, &mut ImageViewMut::packed(&mut px, 32, 24).unwrap()).unwrap();
//! let mut d = [0u8; 32 * 24];
//! render_disparity(&spec, &mut ImageViewMut::packed(&mut d, 32, 24).unwrap()).unwrap();
//! // The object, centred, is nearer than the background.
//! assert!(d[12 * 32 + 17] > d[0]);
//! ```

use crate::image::{ImageError, ImageViewMut, Rgb8};
use crate::rng::SplitMix64;
use core::fmt;

/// Most objects a scene holds.
pub const MAX_OBJECTS: usize = 4;

/// The outline of an object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// An axis-aligned ellipse with half-axes `rx`, `ry`.
    Ellipse,
    /// An axis-aligned rectangle with half-sizes `rx`, `ry`.
    Rectangle,
    /// A rhombus with half-diagonals `rx`, `ry`.
    Diamond,
    /// An isosceles triangle, apex up, base `2 rx`, height `2 ry`.
    Triangle,
}

/// One object of a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ObjectSpec {
    /// Outline.
    pub shape: Shape,
    /// Centre column in the left image.
    pub cx: i32,
    /// Centre row.
    pub cy: i32,
    /// Horizontal half-size, px (at least 1).
    pub rx: i32,
    /// Vertical half-size, px (at least 1).
    pub ry: i32,
    /// Disparity, px.
    pub disparity: u8,
    /// Base colour; a texture of ±24 grey levels is added.
    pub colour: Rgb8,
}

impl ObjectSpec {
    /// True when the left-image point `(x, y)` lies on the object.
    pub fn contains(&self, x: i32, y: i32) -> bool {
        let (rx, ry) = (i64::from(self.rx.max(1)), i64::from(self.ry.max(1)));
        let (dx, dy) = (i64::from(x - self.cx), i64::from(y - self.cy));
        match self.shape {
            Shape::Ellipse => (dx * ry).pow(2) + (dy * rx).pow(2) <= (rx * ry).pow(2),
            Shape::Rectangle => dx.abs() <= rx && dy.abs() <= ry,
            Shape::Diamond => dx.abs() * ry + dy.abs() * rx <= rx * ry,
            Shape::Triangle => dy.abs() <= ry && 2 * dx.abs() * ry <= rx * (dy + ry),
        }
    }
}

/// A whole scene.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneSpec {
    /// Seed of every texture.
    pub seed: u64,
    /// Background plane disparity, px.
    pub background_disparity: u8,
    /// Objects; a nearer (larger disparity) object hides a farther one.
    pub objects: heapless::Vec<ObjectSpec, MAX_OBJECTS>,
    /// Base colour of the background plane.
    pub background_colour: Rgb8,
    /// Texture amplitude of the background, grey levels.
    pub background_texture: i32,
}

/// Errors of the generator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum SynthError {
    /// The output buffer is not a valid image.
    Image(ImageError),
    /// [`render_mask`] was asked for an object the scene does not have.
    NoSuchObject(usize),
}

impl fmt::Display for SynthError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Image(e) => write!(f, "synthetic scene: {e}"),
            Self::NoSuchObject(i) => write!(f, "the scene has no object {i}"),
        }
    }
}

impl core::error::Error for SynthError {}

impl From<ImageError> for SynthError {
    fn from(e: ImageError) -> Self {
        Self::Image(e)
    }
}

impl SceneSpec {
    /// The built-in demo scene for a `width` x `height` frame: a reddish
    /// ellipse, right of centre, at disparity `width / 16` in front of a
    /// textured plane at disparity `width / 80`.
    pub fn demo(width: usize, height: usize) -> SceneSpec {
        let (w, h) = (clamp_i32(width), clamp_i32(height));
        let mut objects = heapless::Vec::new();
        // Capacity is MAX_OBJECTS >= 1: the push cannot fail.
        let _ = objects.push(ObjectSpec {
            shape: Shape::Ellipse,
            cx: w * 9 / 16,
            cy: h / 2,
            rx: (w / 6).max(1),
            ry: (h * 2 / 7).max(1),
            disparity: clamp_u8(width / 16),
            colour: Rgb8::new(196, 64, 48),
        });
        SceneSpec {
            seed: 0x5eed_0001,
            background_disparity: clamp_u8(width / 80),
            objects,
            background_colour: Rgb8::new(120, 124, 112),
            background_texture: 40,
        }
    }

    /// A seeded random scene for a `width` x `height` frame, for accuracy
    /// tests with variety: 1 object (6 seeds in 10), 2 (3 in 10) or 3; every
    /// shape; a main object covering 22 % to 45 % of the segmentation's
    /// selected area S (aspect ratio free) and smaller others (1/14 to 1/8
    /// of the width by 1/10 to 1/6 of the height); disparities 5 to `width / 10` px above a
    /// background plane of 1 to `width / 40` px, at least 3 px apart; a
    /// background of random colour and texture amplitude (20 to 60); object
    /// colours at least 80 RGB levels (L1) from the background's. Objects
    /// are centred so they fit inside the segmentation's selected area
    /// (away from the top, bottom and left strips) when the frame allows;
    /// they may overlap one another.
    pub fn random(seed: u64, width: usize, height: usize) -> SceneSpec {
        let mut rng = SplitMix64::new(seed ^ 0x0005_ce4e_5eed);
        let (w, h) = (clamp_i32(width).max(1), clamp_i32(height).max(1));
        let background_disparity = clamp_u8(1 + rng.below((width / 40) as u64) as usize);
        let background_colour = Rgb8::new(
            rng.range(40, 215) as u8,
            rng.range(40, 215) as u8,
            rng.range(40, 215) as u8,
        );
        let n = match rng.below(10) {
            0..=5 => 1,
            6..=8 => 2,
            _ => 3,
        };
        let shapes = [
            Shape::Ellipse,
            Shape::Rectangle,
            Shape::Diamond,
            Shape::Triangle,
        ];
        let (x0, y0, y1) = (w / 8, h / 6, h - h / 6);
        let mut objects: heapless::Vec<ObjectSpec, MAX_OBJECTS> = heapless::Vec::new();
        // The selected area S of the segmentation stage and its pixels.
        let (sw, sh) = (w - x0 - 1, y1 - y0 - 1);
        let s_area = i64::from(sw.max(1)) * i64::from(sh.max(1));
        for i in 0..n {
            let shape = shapes
                .get(rng.below(4) as usize)
                .copied()
                .unwrap_or(Shape::Ellipse);
            let (rx, ry) = if i == 0 {
                main_object_size(&mut rng, shape, (sw, sh), s_area)
            } else {
                (rng.range(w / 14, w / 8), rng.range(h / 10, h / 6))
            };
            let cx = rng.range(x0 + rx + 3, w - rx - 3);
            let cy = rng.range(y0 + ry + 3, y1 - ry - 3);
            // A disparity at least 3 px from every other object's.
            let hi = (w / 10).max(6);
            let mut disparity = i32::from(background_disparity) + rng.range(5, hi);
            for _ in 0..16 {
                if objects
                    .iter()
                    .all(|o| (i32::from(o.disparity) - disparity).abs() >= 3)
                {
                    break;
                }
                disparity = i32::from(background_disparity) + rng.range(5, hi);
            }
            let colour = loop {
                let c = Rgb8::new(
                    rng.below(256) as u8,
                    rng.below(256) as u8,
                    rng.below(256) as u8,
                );
                let dist = |a: u8, b: u8| i32::from(a.abs_diff(b));
                let bg = background_colour;
                if dist(c.r, bg.r) + dist(c.g, bg.g) + dist(c.b, bg.b) >= 80 {
                    break c;
                }
            };
            // Capacity MAX_OBJECTS >= 3: the push cannot fail.
            let _ = objects.push(ObjectSpec {
                shape,
                cx,
                cy,
                rx,
                ry,
                disparity: clamp_u8(disparity.clamp(0, 255) as usize),
                colour,
            });
        }
        SceneSpec {
            seed,
            background_disparity,
            objects,
            background_colour,
            background_texture: rng.range(20, 60),
        }
    }

    /// The front-most object at left-image point `(x, y)`, if any.
    pub fn object_at(&self, x: i32, y: i32) -> Option<(usize, &ObjectSpec)> {
        self.objects
            .iter()
            .enumerate()
            .filter(|(_, o)| o.contains(x, y))
            .max_by_key(|(i, o)| (o.disparity, usize::MAX - i))
    }

    /// The colour of the surface seen at left-image point `(x, y)`.
    fn left_colour(&self, x: i32, y: i32) -> Rgb8 {
        match self.object_at(x, y) {
            Some((i, o)) => textured(o.colour, object_seed(self.seed, i), x, y, 24),
            None => textured(
                self.background_colour,
                self.seed,
                x,
                y,
                self.background_texture,
            ),
        }
    }

    /// The colour of pixel `(x, y)` of the left or right view, exactly what
    /// [`render_left`] / [`render_right`] write there (for cameras that
    /// deliver rows, e.g. the firmware's streamed stereo pair).
    pub fn colour(&self, right: bool, x: i32, y: i32) -> Rgb8 {
        if right {
            self.right_colour(x, y)
        } else {
            self.left_colour(x, y)
        }
    }

    /// The colour the right camera sees at `(x, y)`: the nearest surface `s`
    /// whose left-image point `(x + d_s, y)` it covers.
    fn right_colour(&self, x: i32, y: i32) -> Rgb8 {
        let front = self
            .objects
            .iter()
            .enumerate()
            .filter(|(_, o)| o.contains(x + i32::from(o.disparity), y))
            .max_by_key(|(i, o)| (o.disparity, usize::MAX - i));
        match front {
            Some((i, o)) => {
                let xl = x + i32::from(o.disparity);
                textured(o.colour, object_seed(self.seed, i), xl, y, 24)
            }
            None => {
                let xl = x + i32::from(self.background_disparity);
                textured(
                    self.background_colour,
                    self.seed,
                    xl,
                    y,
                    self.background_texture,
                )
            }
        }
    }
}

/// Half-sizes of the main object of [`SceneSpec::random`]: its area is 22 %
/// to 45 % of the selected area `s_area` and it fits the `(sw, sh)` box of S
/// with 4 px to spare. The paper's D_fg keeps `D < mean_S + 2σ_S`; over a
/// flat background that drops a single object covering less than 1/5 of S
/// (as wrong estimates), so the main object is drawn above that. Rejection
/// sampling; the last candidate after 64 tries.
fn main_object_size(
    rng: &mut SplitMix64,
    shape: Shape,
    (sw, sh): (i32, i32),
    s_area: i64,
) -> (i32, i32) {
    // Area per rx·ry, in thousandths.
    let k: i64 = match shape {
        Shape::Ellipse => 3142,
        Shape::Rectangle => 4000,
        Shape::Diamond | Shape::Triangle => 2000,
    };
    let (rx_max, ry_max) = (((sw - 8) / 2).max(1), ((sh - 8) / 2).max(1));
    let mut best = (rx_max, ry_max);
    for _ in 0..64 {
        let (rx, ry) = (rng.range(rx_max / 3, rx_max), rng.range(ry_max / 3, ry_max));
        let area = k * i64::from(rx) * i64::from(ry);
        best = (rx, ry);
        if area >= 220 * s_area && area <= 450 * s_area {
            break;
        }
    }
    best
}

fn object_seed(seed: u64, index: usize) -> u64 {
    seed ^ (index as u64 + 1).wrapping_mul(0x9e37_79b9)
}

fn clamp_i32(v: usize) -> i32 {
    i32::try_from(v).unwrap_or(i32::MAX)
}

fn clamp_u8(v: usize) -> u8 {
    u8::try_from(v).unwrap_or(u8::MAX)
}

/// SplitMix64 of a seed and a lattice point.
fn hash(seed: u64, x: i32, y: i32) -> u32 {
    let mut z = seed
        .wrapping_add((x as u32 as u64) << 32 | u64::from(y as u32))
        .wrapping_mul(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    (z ^ (z >> 31)) as u32
}

/// Value noise in [-128, 127]: random lattice values every `cell` px,
/// bilinearly interpolated.
fn value_noise(seed: u64, x: i32, y: i32, cell: i32) -> i32 {
    let (gx, gy) = (x.div_euclid(cell), y.div_euclid(cell));
    let (fx, fy) = (x.rem_euclid(cell), y.rem_euclid(cell));
    let v = |i: i32, j: i32| (hash(seed, gx + i, gy + j) & 0xff) as i32 - 128;
    let top = v(0, 0) * (cell - fx) + v(1, 0) * fx;
    let bottom = v(0, 1) * (cell - fx) + v(1, 1) * fx;
    (top * (cell - fy) + bottom * fy) / (cell * cell)
}

/// `base` plus a luminance texture: coarse value noise of amplitude `amp`
/// and fine per-pixel noise of amplitude `amp / 4`, plus a faint hue drift.
fn textured(base: Rgb8, seed: u64, x: i32, y: i32, amp: i32) -> Rgb8 {
    let coarse = value_noise(seed, x, y, 6) * amp / 128;
    let fine = ((hash(seed ^ 0xf1e, x, y) & 0xff) as i32 - 128) * amp / 512;
    let hue = value_noise(seed ^ 0x4e5, x, y, 16) * amp / 512;
    let ch = |c: u8, extra: i32| (i32::from(c) + coarse + fine + extra).clamp(0, 255) as u8;
    Rgb8::new(ch(base.r, hue), ch(base.g, 0), ch(base.b, -hue))
}

fn render<P: Copy>(out: &mut ImageViewMut<'_, P>, f: impl Fn(i32, i32) -> P) {
    for (y, row) in out.rows_mut().enumerate() {
        for (x, p) in row.iter_mut().enumerate() {
            *p = f(clamp_i32(x), clamp_i32(y));
        }
    }
}

/// Renders the left image.
///
/// # Errors
/// None today; the `Result` keeps the signature stable for checks to come.
pub fn render_left(spec: &SceneSpec, out: &mut ImageViewMut<'_, Rgb8>) -> Result<(), SynthError> {
    render(out, |x, y| spec.left_colour(x, y));
    Ok(())
}

/// Renders the right image.
///
/// # Errors
/// As [`render_left`].
pub fn render_right(spec: &SceneSpec, out: &mut ImageViewMut<'_, Rgb8>) -> Result<(), SynthError> {
    render(out, |x, y| spec.right_colour(x, y));
    Ok(())
}

/// Renders the left-referenced ground-truth disparity, px.
///
/// # Errors
/// As [`render_left`].
pub fn render_disparity(
    spec: &SceneSpec,
    out: &mut ImageViewMut<'_, u8>,
) -> Result<(), SynthError> {
    render(out, |x, y| {
        spec.object_at(x, y)
            .map_or(spec.background_disparity, |(_, o)| o.disparity)
    });
    Ok(())
}

/// Renders the ground-truth mask of object `index` as seen in the left
/// image: 255 where it is the front-most surface, else 0.
///
/// # Errors
/// [`SynthError::NoSuchObject`] for an index past the scene's objects.
pub fn render_mask(
    spec: &SceneSpec,
    index: usize,
    out: &mut ImageViewMut<'_, u8>,
) -> Result<(), SynthError> {
    if index >= spec.objects.len() {
        return Err(SynthError::NoSuchObject(index));
    }
    render(out, |x, y| match spec.object_at(x, y) {
        Some((i, _)) if i == index => 255,
        _ => 0,
    });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const W: usize = 64;
    const H: usize = 48;

    #[test]
    fn right_image_is_the_left_shifted_by_the_disparity() {
        let spec = SceneSpec::demo(W, H);
        let (mut l, mut r, mut d) = (
            [Rgb8::default(); W * H],
            [Rgb8::default(); W * H],
            [0u8; W * H],
        );
        render_left(&spec, &mut ImageViewMut::packed(&mut l, W, H).unwrap()).unwrap();
        render_right(&spec, &mut ImageViewMut::packed(&mut r, W, H).unwrap()).unwrap();
        render_disparity(&spec, &mut ImageViewMut::packed(&mut d, W, H).unwrap()).unwrap();
        let mut matched = 0;
        for y in 0..H {
            for x in 0..W {
                let disp = usize::from(d[y * W + x]);
                if x >= disp {
                    // Visible in both views unless occluded in the right one.
                    if l[y * W + x] == r[y * W + x - disp] {
                        matched += 1;
                    }
                }
            }
        }
        // Only the occluded band beside the object may differ.
        assert!(matched > W * H * 9 / 10, "{matched}");
        assert_ne!(l, r);
    }

    #[test]
    fn masks_cover_the_objects_and_nothing_else() {
        let spec = SceneSpec::demo(W, H);
        let mut m = [0u8; W * H];
        render_mask(&spec, 0, &mut ImageViewMut::packed(&mut m, W, H).unwrap()).unwrap();
        let area = m.iter().filter(|&&v| v == 255).count();
        let o = spec.objects[0];
        let expected = core::f64::consts::PI * o.rx as f64 * o.ry as f64;
        assert!(
            (area as f64 - expected).abs() < expected * 0.15,
            "{area} vs {expected}"
        );
        assert_eq!(
            render_mask(&spec, 1, &mut ImageViewMut::packed(&mut m, W, H).unwrap()),
            Err(SynthError::NoSuchObject(1))
        );
    }

    #[test]
    fn shapes_contain_their_centre_and_not_far_points() {
        for shape in [
            Shape::Ellipse,
            Shape::Rectangle,
            Shape::Diamond,
            Shape::Triangle,
        ] {
            let o = ObjectSpec {
                shape,
                cx: 10,
                cy: 10,
                rx: 4,
                ry: 6,
                disparity: 3,
                colour: Rgb8::default(),
            };
            assert!(o.contains(10, 10), "{shape:?}");
            assert!(!o.contains(15, 10) && !o.contains(10, 17), "{shape:?}");
        }
    }
}
