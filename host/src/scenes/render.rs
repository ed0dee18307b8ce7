//! Rendering one scene: layers in left-image coordinates, each with a
//! disparity that depends on the row only, so both views sample the same
//! textures exactly and the nearest layer covering a pixel wins.
//!
//! Layers, far to near: a textured back wall (constant disparity), a
//! textured ground plane below a horizon whose disparity grows linearly
//! towards the bottom row (tilting away), clutter blobs just in front of
//! the background, and the objects (fronto-parallel, each at its own
//! disparity, always nearer than the background under it).
//!
//! The right view is the left view warped by disparity with occlusion
//! order: right pixel `xr` shows, of the layers covering left position
//! `xr + d_layer`, the one of largest disparity. Evaluating each layer at
//! its own warped position (rather than pushing left pixels across) leaves
//! no holes where the right eye sees what the left eye does not.

use super::given::{fit_silhouette, GivenObject, GIVEN_FILL};
use super::{BoxPx, ObjectTruth, SceneKey, SceneParams};
use crate::classify::mlp::{unit, SplitMix};
use crate::classify::shapes::{class_dir, render as render_silhouette};
use crate::error::{HostError, Result};
use image::{GrayImage, Luma, Rgb, RgbImage};

/// One rendered scene, in memory.
#[derive(Clone, Debug)]
pub struct RenderedScene {
    /// Left view.
    pub left: RgbImage,
    /// Right view.
    pub right: RgbImage,
    /// Left-referenced disparity, px, row-major.
    pub disparity: Vec<f32>,
    /// Visible mask of each object in the left view (255 = object).
    pub masks: Vec<GrayImage>,
    /// Each object's truth (its `mask` field is the mask's file name).
    pub objects: Vec<ObjectTruth>,
    /// Each object's position in the objects drawn (or given, for
    /// [`render_given`](super::given::render_given)).
    pub sources: Vec<usize>,
}

/// Splitmix64's finaliser: a well-mixed 64-bit hash of `x`.
pub(crate) fn mix64(mut x: u64) -> u64 {
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// Smooth value noise with three octaves, in about `[-0.5, 0.5]`.
#[derive(Clone, Copy, Debug)]
struct Texture {
    seed: u64,
    /// Cell size of the coarsest octave, px.
    cell: f64,
}

impl Texture {
    fn lattice(&self, octave: u64, ix: i64, iy: i64) -> f64 {
        let h = mix64(self.seed ^ mix64((octave << 58) ^ ((ix as u64) << 29) ^ (iy as u64)));
        (h >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }

    fn octave(&self, octave: u64, x: f64, y: f64) -> f64 {
        let cell = self.cell / f64::from(1u32 << octave);
        let (u, v) = (x / cell, y / cell);
        let (fx, fy) = (u.floor(), v.floor());
        let (ix, iy) = (fx as i64, fy as i64);
        let s = |t: f64| t * t * (3.0 - 2.0 * t);
        let (tx, ty) = (s(u - fx), s(v - fy));
        let l = |dx, dy| self.lattice(octave, ix + dx, iy + dy);
        let top = l(0, 0) + (l(1, 0) - l(0, 0)) * tx;
        let bottom = l(0, 1) + (l(1, 1) - l(0, 1)) * tx;
        top + (bottom - top) * ty
    }

    fn at(&self, x: f64, y: f64) -> f64 {
        0.5 * self.octave(0, x, y) + 0.3 * self.octave(1, x, y) + 0.2 * self.octave(2, x, y)
    }
}

/// Where a layer is, in left-image coordinates.
#[derive(Clone, Debug)]
enum Extent {
    /// The whole frame.
    All,
    /// Rows at or below the horizon.
    Below(f64),
    /// An ellipse.
    Blob { cx: f64, cy: f64, rx: f64, ry: f64 },
    /// A silhouette whose canvas starts at `(x0, y0)`.
    Silhouette { mask: GrayImage, x0: f64, y0: f64 },
}

/// A layer's disparity: `near` at the bottom row, `far` at `from_row`.
#[derive(Clone, Copy, Debug)]
struct Depth {
    far: f64,
    near: f64,
    from_row: f64,
    to_row: f64,
}

impl Depth {
    fn constant(d: f64) -> Self {
        Self {
            far: d,
            near: d,
            from_row: 0.0,
            to_row: 1.0,
        }
    }

    fn at(&self, y: f64) -> f64 {
        let t = ((y - self.from_row) / (self.to_row - self.from_row)).clamp(0.0, 1.0);
        self.far + (self.near - self.far) * t
    }
}

#[derive(Clone, Debug)]
struct Layer {
    extent: Extent,
    depth: Depth,
    colour: [f64; 3],
    texture: Texture,
    /// Texture amplitude, grey levels.
    amplitude: f64,
    /// Object number, for the masks.
    object: Option<usize>,
}

impl Layer {
    fn covers(&self, x: f64, y: f64) -> bool {
        match &self.extent {
            Extent::All => true,
            Extent::Below(h) => y >= *h,
            Extent::Blob { cx, cy, rx, ry } => {
                ((x - cx) / rx).powi(2) + ((y - cy) / ry).powi(2) <= 1.0
            }
            Extent::Silhouette { mask, x0, y0 } => {
                let (u, v) = ((x - x0).floor(), (y - y0).floor());
                u >= 0.0
                    && v >= 0.0
                    && (u as u32) < mask.width()
                    && (v as u32) < mask.height()
                    && mask.get_pixel(u as u32, v as u32).0[0] != 0
            }
        }
    }

    fn colour_at(&self, x: f64, y: f64) -> [f64; 3] {
        let t = self.amplitude * 2.0 * self.texture.at(x, y);
        self.colour.map(|c| c + t)
    }
}

/// Uniform in `[lo, hi)`.
fn range(rng: &mut SplitMix, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * unit(rng)
}

fn luminance(c: [f64; 3]) -> f64 {
    0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]
}

fn random_colour(rng: &mut SplitMix) -> [f64; 3] {
    [0; 3].map(|_| range(rng, 30.0, 225.0))
}

/// A colour that contrasts with `bg` (luminance 45 apart or colour 110
/// apart), or, when `contrast` is false, one close to it.
fn object_colour(rng: &mut SplitMix, bg: [f64; 3], contrast: bool) -> [f64; 3] {
    if !contrast {
        return bg.map(|c| (c + range(rng, -18.0, 18.0)).clamp(20.0, 235.0));
    }
    loop {
        let c = random_colour(rng);
        let dist = c
            .iter()
            .zip(&bg)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        if (luminance(c) - luminance(bg)).abs() >= 45.0 || dist >= 110.0 {
            return c;
        }
    }
}

/// The chosen layers of one scene.
struct Layout {
    layers: Vec<Layer>,
}

impl Layout {
    /// The nearest layer covering left position `(x, y)` when layer `k` is
    /// seen at `x + shift(k)`: the winner's index and disparity.
    fn nearest(&self, x: f64, y: f64, shifted: bool) -> Option<(usize, f64)> {
        nearest(&self.layers, x, y, shifted)
    }
}

/// [`Layout::nearest`] over `layers`.
fn nearest(layers: &[Layer], x: f64, y: f64, shifted: bool) -> Option<(usize, f64)> {
    let mut best: Option<(usize, f64)> = None;
    for (k, l) in layers.iter().enumerate() {
        let d = l.depth.at(y);
        let xl = if shifted { x + d } else { x };
        if l.covers(xl, y) && best.is_none_or(|(_, b)| d >= b) {
            best = Some((k, d));
        }
    }
    best
}

/// Largest disparity of the scenes at `width` px: 28 at 160 px, inside the
/// 31 px the evaluation's stereo searches.
pub fn max_disparity(width: u32) -> f64 {
    28.0 * f64::from(width) / 160.0
}

/// Renders scene `key` with `params`.
///
/// # Errors
/// [`HostError::InvalidArgument`] for a class count out of range (checked
/// by the caller first), or a silhouette size out of range.
pub fn render_scene(params: &SceneParams, key: SceneKey) -> Result<RenderedScene> {
    render_stream(params, key.stream(), None)
}

/// Renders a scene of the stream `stream`: objects drawn from the classes,
/// or `given` ([`super::given::render_given`]).
pub(super) fn render_stream(
    params: &SceneParams,
    stream: u64,
    given: Option<&[GivenObject<'_>]>,
) -> Result<RenderedScene> {
    let (w, h) = (params.width, params.height);
    let (wf, hf) = (f64::from(w), f64::from(h));
    let s = wf / 160.0;
    let mut rng = SplitMix::new(stream);
    let tex = |rng: &mut SplitMix, cell: f64| Texture {
        seed: rng.next_u64(),
        cell: cell * s,
    };

    // Background: wall and tilting ground plane.
    let wall_d = range(&mut rng, 2.0, 5.0) * s;
    let ground_d = range(&mut rng, 9.0, 14.0) * s;
    let horizon = range(&mut rng, 0.35, 0.6) * hf;
    let wall = Layer {
        extent: Extent::All,
        depth: Depth::constant(wall_d),
        colour: random_colour(&mut rng),
        texture: tex(&mut rng, 8.0),
        amplitude: range(&mut rng, 25.0, 45.0),
        object: None,
    };
    let ground = Layer {
        extent: Extent::Below(horizon),
        depth: Depth {
            far: wall_d,
            near: ground_d,
            from_row: horizon,
            to_row: hf,
        },
        colour: random_colour(&mut rng),
        texture: tex(&mut rng, 6.0),
        amplitude: range(&mut rng, 25.0, 45.0),
        object: None,
    };
    let background = |y: f64| {
        if y >= horizon {
            ground.depth.at(y)
        } else {
            wall_d
        }
    };
    let bg_colour = |y: f64| {
        if y >= horizon {
            ground.colour
        } else {
            wall.colour
        }
    };
    let mut layers = vec![wall.clone(), ground.clone()];

    // Clutter: small blobs just in front of the background.
    let clutter = 3 + rng.next_u64() % 6;
    for _ in 0..clutter {
        let (cx, cy) = (range(&mut rng, 0.0, wf), range(&mut rng, 0.0, hf));
        layers.push(Layer {
            extent: Extent::Blob {
                cx,
                cy,
                rx: range(&mut rng, 1.5, 4.5) * s,
                ry: range(&mut rng, 1.5, 4.5) * s,
            },
            depth: Depth::constant(background(cy) + range(&mut rng, 0.5, 2.0) * s),
            colour: random_colour(&mut rng),
            texture: tex(&mut rng, 3.0),
            amplitude: range(&mut rng, 15.0, 35.0),
            object: None,
        });
    }

    // Objects: distinct classes, each placed so that it is fully inside
    // both views and keeps most of its area visible.
    let (lo, hi) = params.objects;
    let count = match given {
        Some(g) => g.len(),
        None => usize::from(lo + (rng.next_u64() % u64::from(hi - lo + 1)) as u8),
    };
    let mut pool: Vec<usize> = (0..params.classes).collect();
    let d_max = max_disparity(w);
    let mut objects = Vec::new();
    let mut sources = Vec::new();
    for source in 0..count {
        let (class_name, mask) = match given.and_then(|g| g.get(source)) {
            Some(g) => {
                let size = range(&mut rng, 36.0, 72.0) * s;
                let Some(mask) = fit_silhouette(g.mask, (GIVEN_FILL * size).round()) else {
                    continue;
                };
                (g.class.to_owned(), mask)
            }
            None => {
                if pool.is_empty() {
                    break;
                }
                let class = pool.swap_remove((rng.next_u64() % pool.len() as u64) as usize);
                let size = ((range(&mut rng, 36.0, 72.0) * s).round() as u32).clamp(16, w.min(h));
                let mask = render_silhouette(class, rng.next_u64(), rng.next_u64(), size)?;
                (class_dir(class).unwrap_or_default(), mask)
            }
        };
        let Some(mb) = BoxPx::of_mask(&mask) else {
            continue;
        };
        let contrast = unit(&mut rng) < 0.8;
        for _attempt in 0..30 {
            // Box x within [d, w), y within [0, h), with d known only after
            // the row range; draw the row first.
            let y0 = range(&mut rng, 0.0, (hf - f64::from(mb.height)).max(0.0)).floor()
                - f64::from(mb.y);
            let rows = (y0 + f64::from(mb.y), y0 + f64::from(mb.y + mb.height));
            let bg_max = background(rows.1 - 1.0).max(background(rows.0));
            let d_lo = (bg_max + 4.0 * s).min(d_max);
            let d = (range(&mut rng, d_lo, d_max) * 4.0).round() / 4.0;
            let x_room = wf - f64::from(mb.width) - d.ceil();
            if x_room < 0.0 {
                continue;
            }
            let x0 = (d.ceil() + range(&mut rng, 0.0, x_room)).floor() - f64::from(mb.x);
            let cell = range(&mut rng, 3.0, 7.0);
            let layer = Layer {
                extent: Extent::Silhouette {
                    mask: mask.clone(),
                    x0,
                    y0,
                },
                depth: Depth::constant(d),
                colour: object_colour(&mut rng, bg_colour((rows.0 + rows.1) / 2.0), contrast),
                texture: tex(&mut rng, cell),
                amplitude: range(&mut rng, 20.0, 40.0),
                object: Some(objects.len()),
            };
            layers.push(layer);
            let full = mask.pixels().filter(|p| p.0[0] != 0).count();
            let seen = visible_area(&layers, w, h, objects.len());
            // Earlier objects must stay mostly visible too.
            let earlier_ok = objects
                .iter()
                .enumerate()
                .all(|(k, o): (usize, &ObjectTruth)| {
                    visible_area(&layers, w, h, k) * 10 >= o.area * 7
                });
            if seen * 10 >= full * 7 && seen >= 40 && earlier_ok {
                sources.push(source);
                objects.push(ObjectTruth {
                    class: class_name.clone(),
                    mask: format!("mask_{}.png", objects.len()),
                    bbox: mb,
                    disparity: d,
                    area: full,
                    contrast,
                });
                break;
            }
            layers.pop();
        }
    }
    let layout = Layout { layers };

    // Views, disparity and masks.
    let mut cam = SplitMix::new(mix64(stream ^ 0xCA3E));
    let gain: [f64; 3] = {
        let g = range(&mut cam, 0.92, 1.08);
        [0; 3].map(|_| g * range(&mut cam, 0.98, 1.02))
    };
    let offset = range(&mut cam, -6.0, 6.0);
    let noise = |rng: &mut SplitMix| (0..4).map(|_| unit(rng)).sum::<f64>() - 2.0;
    let mut disparity = vec![0f32; (w * h) as usize];
    let mut left = RgbImage::new(w, h);
    let mut right = RgbImage::new(w, h);
    for y in 0..h {
        let yc = f64::from(y) + 0.5;
        for x in 0..w {
            let xc = f64::from(x) + 0.5;
            let (k, d) = layout.nearest(xc, yc, false).unwrap_or((0, wall_d));
            disparity[(y * w + x) as usize] = d as f32;
            let c = layout.layers[k].colour_at(xc, yc);
            left.put_pixel(x, y, pixel(c.map(|v| v + 3.5 * noise(&mut cam))));
            let (k, d) = layout.nearest(xc, yc, true).unwrap_or((0, wall_d));
            let c = layout.layers[k].colour_at(xc + d, yc);
            let mut i = 0;
            let c = c.map(|v| {
                i += 1;
                gain[i - 1] * v + offset + 3.5 * noise(&mut cam)
            });
            right.put_pixel(x, y, pixel(c));
        }
    }
    let masks: Vec<GrayImage> = (0..objects.len())
        .map(|k| visible_mask(&layout, w, h, k))
        .collect();
    for (o, m) in objects.iter_mut().zip(&masks) {
        // The truth is what the left eye sees.
        o.bbox = BoxPx::of_mask(m).ok_or_else(|| HostError::InvalidArgument {
            name: "objects",
            reason: "an object vanished behind others".into(),
        })?;
        o.area = m.pixels().filter(|p| p.0[0] != 0).count();
    }
    Ok(RenderedScene {
        left,
        right,
        disparity,
        masks,
        objects,
        sources,
    })
}

fn pixel(c: [f64; 3]) -> Rgb<u8> {
    Rgb(c.map(|v| v.round().clamp(0.0, 255.0) as u8))
}

/// The pixels of [`visible_mask`], counted over object `k`'s silhouette
/// window only (it is nowhere else).
fn visible_area(layers: &[Layer], w: u32, h: u32, k: usize) -> usize {
    let Some(Extent::Silhouette { mask, x0, y0 }) = layers
        .iter()
        .find(|l| l.object == Some(k))
        .map(|l| &l.extent)
    else {
        return 0;
    };
    // Pixel x (centre x + 0.5) can be covered only when
    // x0 <= x + 0.5 < x0 + width.
    let span = |o: f64, len: u32, max: u32| {
        let lo = (o - 0.5).ceil().max(0.0) as u32;
        let hi = ((o + f64::from(len) - 0.5).ceil().max(0.0) as u32).min(max);
        lo..hi.max(lo)
    };
    let mut n = 0;
    for y in span(*y0, mask.height(), h) {
        for x in span(*x0, mask.width(), w) {
            let hit = nearest(layers, f64::from(x) + 0.5, f64::from(y) + 0.5, false)
                .is_some_and(|(i, _)| layers[i].object == Some(k));
            n += usize::from(hit);
        }
    }
    n
}

/// Where object `k` is the nearest layer in the left view.
fn visible_mask(layout: &Layout, w: u32, h: u32, k: usize) -> GrayImage {
    GrayImage::from_fn(w, h, |x, y| {
        let hit = layout
            .nearest(f64::from(x) + 0.5, f64::from(y) + 0.5, false)
            .is_some_and(|(i, _)| layout.layers[i].object == Some(k));
        Luma([if hit { 255 } else { 0 }])
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes::fixtures::{bar, params};

    #[test]
    fn visible_area_counts_the_visible_mask() {
        for index in 0..4 {
            let key = SceneKey {
                seed: 9,
                split: super::super::Split::Train,
                index,
            };
            let s = render_scene(&params(), key).unwrap();
            for (o, m) in s.objects.iter().zip(&s.masks) {
                assert_eq!(m.pixels().filter(|p| p.0[0] != 0).count(), o.area);
            }
        }
        // Against the full-frame mask, on a layout with an occluder.
        let a = bar();
        let layer = |x0: f64, d: f64, k: usize| Layer {
            extent: Extent::Silhouette {
                mask: a.clone(),
                x0,
                y0: 3.0,
            },
            depth: Depth::constant(d),
            colour: [0.0; 3],
            texture: Texture { seed: 1, cell: 4.0 },
            amplitude: 0.0,
            object: Some(k),
        };
        let layers = vec![layer(0.0, 2.0, 0), layer(25.0, 3.0, 1)];
        for k in 0..2 {
            let full = visible_mask(
                &Layout {
                    layers: layers.clone(),
                },
                80,
                60,
                k,
            );
            let n = full.pixels().filter(|p| p.0[0] != 0).count();
            assert_eq!(visible_area(&layers, 80, 60, k), n);
            assert!(n > 0);
        }
        assert_eq!(visible_area(&layers, 80, 60, 7), 0);
    }
}
