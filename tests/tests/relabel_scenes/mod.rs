//! The relabelling tests' scenes: seeded stereo scenes of blocky
//! disparity with objects close in colour to their background, the
//! stereo's map fattened around them, and a hand-made one.

use proptest::prelude::*;
use protogist::conspicuity::{Conspicuity, EdgeCell};
use protogist::disparity::{Disparity, DisparityCell};
use protogist::image::Rgb8;

/// Most frame sizes of the scenes.
pub const MAX_W: usize = 64;
pub const MAX_H: usize = 44;
/// Background disparity tiles, px.
pub const TILE_W: usize = 8;
pub const TILE_H: usize = 6;
pub const TILES: usize = MAX_W.div_ceil(TILE_W) * MAX_H.div_ceil(TILE_H);

/// An object: its true box `(x, y, w, h)` in colour, nearer than the
/// background by `rise` disparity bits; the stereo's map has it grown by
/// `fat` px on the left, top, right and bottom (its blur); its colour is
/// the background's plus `colour`; an `outlined` one has its box's ring
/// in C.
#[derive(Clone, Debug)]
pub struct Object {
    pub rect: (usize, usize, usize, usize),
    pub rise: u16,
    pub fat: [usize; 4],
    pub colour: [i16; 3],
    pub outlined: bool,
}

/// A stereo scene of `w` x `h`: a background at `base` disparity bits,
/// plus per tile `tiles`; objects; OFF cells of the map, and rows of it
/// OFF but every fifth cell (rows without a dominant disparity); C's random
/// edges (`edge[i] < density`); the background colour; noise of the
/// left image and of the right (`noise_l`, `noise_r`, times `amp` / 16;
/// none in a flat scene).
#[derive(Clone, Debug)]
pub struct Scene {
    pub w: usize,
    pub h: usize,
    pub base: u16,
    pub tiles: Vec<i16>,
    pub objects: Vec<Object>,
    pub off: Vec<bool>,
    pub off_rows: Vec<bool>,
    pub edge: Vec<u8>,
    pub density: u8,
    pub bg: [u8; 3],
    pub amp: i16,
    pub noise_l: Vec<i16>,
    pub noise_r: Vec<i16>,
}

pub fn object(w: usize, h: usize) -> impl Strategy<Value = Object> {
    (
        (0..w - 12, 0..h - 10, 12usize..26, 10usize..22),
        (4 * 256u16)..(20 * 256),
        prop::array::uniform4(0usize..4),
        prop_oneof![1 => Just([0; 3]), 4 => prop::array::uniform3(-24i16..25)],
        prop::bool::weighted(0.15),
    )
        .prop_map(
            move |((x, y, bw, bh), rise, fat, colour, outlined)| Object {
                rect: (x, y, bw.min(w - x), bh.min(h - y)),
                rise,
                fat,
                colour,
                outlined,
            },
        )
}

pub fn scene() -> impl Strategy<Value = Scene> {
    (32usize..=MAX_W, 24usize..=MAX_H).prop_flat_map(|(w, h)| {
        (
            (Just(w), Just(h), 0u16..(6 * 256)),
            (
                prop::collection::vec(-96i16..97, TILES),
                prop_oneof![3 => Just(1i16), 1 => 2i16..9],
            ),
            prop::collection::vec(object(w, h), 1..3),
            (
                prop::collection::vec(prop::bool::weighted(0.04), w * h),
                prop::collection::vec(prop::bool::weighted(0.1), h),
            ),
            (
                prop::collection::vec(any::<u8>(), w * h),
                prop_oneof![Just(0u8), 0u8..10],
            ),
            (
                prop::array::uniform3(40u8..216),
                prop_oneof![1 => Just(0i16), 4 => 4i16..17],
            ),
            prop::collection::vec(-20i16..21, w * h),
            prop::collection::vec(-3i16..4, w * h),
        )
            .prop_map(
                |(
                    (w, h, base),
                    (tiles, spread),
                    objects,
                    (off, off_rows),
                    (edge, density),
                    (bg, amp),
                    nl,
                    nr,
                )| Scene {
                    w,
                    h,
                    base,
                    tiles: tiles.iter().map(|t| t * spread).collect(),
                    objects,
                    off,
                    off_rows,
                    edge,
                    density,
                    bg,
                    amp,
                    noise_l: nl,
                    noise_r: nr,
                },
            )
    })
}

pub fn inside((x0, y0, bw, bh): (usize, usize, usize, usize), x: usize, y: usize) -> bool {
    (x0..x0 + bw).contains(&x) && (y0..y0 + bh).contains(&y)
}

pub fn add(c: u8, d: i16) -> u8 {
    (i16::from(c) + d).clamp(0, 255) as u8
}

impl Scene {
    /// The background's disparity bits at `(x, y)`.
    pub fn background(&self, x: usize, y: usize) -> u16 {
        let t = (y / TILE_H) * MAX_W.div_ceil(TILE_W) + x / TILE_W;
        (i32::from(self.base) + i32::from(self.tiles[t])).max(0) as u16
    }

    /// The object seen at `(x, y)` (the last one there), if any.
    pub fn object_at(&self, x: usize, y: usize) -> Option<&Object> {
        self.objects.iter().rev().find(|o| inside(o.rect, x, y))
    }

    /// The stereo's map: the background's tiles, each object's box grown
    /// by its blur at its disparity, OFF cells.
    pub fn disparity(&self) -> Vec<DisparityCell> {
        let (w, h) = (self.w, self.h);
        let mut d: Vec<u16> = (0..w * h).map(|i| self.background(i % w, i / w)).collect();
        for o in &self.objects {
            let (x0, y0, bw, bh) = o.rect;
            let [l, t, r, b] = o.fat;
            for y in y0.saturating_sub(t)..(y0 + bh + b).min(h) {
                for x in x0.saturating_sub(l)..(x0 + bw + r).min(w) {
                    d[y * w + x] = self.base + o.rise;
                }
            }
        }
        d.iter()
            .zip(&self.off)
            .enumerate()
            .map(|(i, (&v, &off))| {
                if off || (self.off_rows[i / w] && i % w % 5 != 0) {
                    DisparityCell::OFF
                } else {
                    DisparityCell::on(Disparity::from_bits(v)).unwrap()
                }
            })
            .collect()
    }

    /// C: random edges, and the true boxes' rings of the outlined objects.
    pub fn edges(&self) -> Vec<EdgeCell> {
        let (w, h) = (self.w, self.h);
        let on = |v: u8| EdgeCell::on(Conspicuity::from_num(v)).unwrap();
        let mut c: Vec<EdgeCell> = self
            .edge
            .iter()
            .map(|&e| {
                if e < self.density {
                    on(5 + e % 30)
                } else {
                    EdgeCell::OFF
                }
            })
            .collect();
        for o in self.objects.iter().filter(|o| o.outlined) {
            let (x0, y0, bw, bh) = o.rect;
            for y in y0..y0 + bh {
                for x in x0..x0 + bw {
                    if x == x0 || y == y0 || x + 1 == x0 + bw || y + 1 == y0 + bh {
                        c[y * w + x] = on(40);
                    }
                }
            }
        }
        debug_assert_eq!(c.len(), w * h);
        c
    }

    /// The left image: the background's colour, the objects' close to
    /// it, and noise.
    pub fn left(&self) -> Vec<Rgb8> {
        let w = self.w;
        (0..w * self.h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let d = self.object_at(x, y).map_or([0; 3], |o| o.colour);
                let n = self.noise_l[i] * self.amp / 16;
                Rgb8 {
                    r: add(self.bg[0], d[0] + n),
                    g: add(self.bg[1], d[1] + n),
                    b: add(self.bg[2], d[2] + n),
                }
            })
            .collect()
    }

    /// The right image: each left pixel moved left by its true disparity
    /// (whole px; the nearer wins), the background's colour where none
    /// lands, and noise.
    pub fn right(&self, left: &[Rgb8]) -> Vec<Rgb8> {
        let (w, h) = (self.w, self.h);
        let truth = |i: usize| {
            let (x, y) = (i % w, i / w);
            let bits = match self.object_at(x, y) {
                Some(o) => self.base + o.rise,
                None => self.background(x, y),
            };
            usize::from((bits + 128) >> 8)
        };
        let mut order: Vec<usize> = (0..w * h).collect();
        order.sort_by_key(|&i| truth(i));
        let plain = Rgb8 {
            r: self.bg[0],
            g: self.bg[1],
            b: self.bg[2],
        };
        let mut right = vec![plain; w * h];
        for i in order {
            let (x, y, d) = (i % w, i / w, truth(i));
            if x >= d {
                right[y * w + x - d] = left[i];
            }
        }
        right
            .iter()
            .zip(&self.noise_r)
            .map(|(p, &n)| {
                let n = n * self.amp / 16;
                Rgb8 {
                    r: add(p.r, n),
                    g: add(p.g, n),
                    b: add(p.b, n),
                }
            })
            .collect()
    }
}

/// `n` values in `-a..=a`, from a fixed LCG.
pub fn fixed_noise(n: usize, a: i16, seed: u64) -> Vec<i16> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((s >> 33) % (2 * a as u64 + 1)) as i16 - a
        })
        .collect()
}

/// A 48x36 scene: a 18x14 object at (14, 10), 10 px against a background
/// at 2 px, its colour close to the background's, with textures of
/// noise; the stereo's map has it 2 px too wide on every side.
pub fn fattened() -> Scene {
    let (w, h) = (48, 36);
    Scene {
        w,
        h,
        base: 2 * 256,
        tiles: vec![0; TILES],
        objects: vec![Object {
            rect: (14, 10, 18, 14),
            rise: 8 * 256,
            fat: [2; 4],
            colour: [14, -10, 8],
            outlined: false,
        }],
        off: vec![false; w * h],
        off_rows: vec![false; h],
        edge: vec![0; w * h],
        density: 0,
        bg: [100, 110, 90],
        amp: 16,
        noise_l: fixed_noise(w * h, 12, 7),
        noise_r: fixed_noise(w * h, 3, 11),
    }
}
