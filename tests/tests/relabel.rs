//! The band relabelling (`protogist::segment::relabel`): its settings'
//! checks, its errors, a fattened low-contrast object cut back to its
//! colour, and every mask against the integer reference, bit for bit.

use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::TestRunner;
use protogist::conspicuity::{Conspicuity, EdgeCell};
use protogist::disparity::{Disparity, DisparityCell};
use protogist::image::{ImageError, ImageView, Rgb8};
use protogist::segment::{
    bit_map_len, relabel_len, relabel_object, segment_with_depth_pass, BitView, BoundingBox,
    DepthPass, Detection, Holes, Masks, Ratio, Refine, Relabel, SegmentError, SegmentParams,
};
use protogist_host::reference::relabel as rfl;
use protogist_host::reference::segment as rf;
use protogist_tests::SegmentStorage;

// ---------------------------------------------------------------------------
// The settings and the errors.

#[test]
fn each_setting_out_of_range_is_named() {
    assert_eq!(Relabel::DEFAULT.validate(), Ok(()));
    let d = Relabel::DEFAULT;
    let bad = [
        (Relabel { core: 9, ..d }, "relabel.core"),
        (Relabel { reach: 0, ..d }, "relabel.reach"),
        (Relabel { reach: 9, ..d }, "relabel.reach"),
        (Relabel { ring: 0, ..d }, "relabel.ring"),
        (Relabel { ring: 9, ..d }, "relabel.ring"),
        (Relabel { passes: 0, ..d }, "relabel.passes"),
        (Relabel { passes: 17, ..d }, "relabel.passes"),
        (Relabel { matching: 17, ..d }, "relabel.matching"),
        (Relabel { smooth: 65, ..d }, "relabel.smooth"),
        (
            Relabel {
                edge_percent: 101,
                ..d
            },
            "relabel.edge_percent",
        ),
    ];
    for (p, name) in bad {
        assert_eq!(p.validate(), Err(SegmentError::BadParams(name)), "{p:?}");
    }
    // The ends of every range pass.
    for p in [
        Relabel {
            core: 0,
            reach: 1,
            ring: 1,
            passes: 1,
            matching: 0,
            smooth: 0,
            edge_percent: 0,
        },
        Relabel {
            core: 8,
            reach: 8,
            ring: 8,
            passes: 16,
            matching: 16,
            smooth: 64,
            edge_percent: 100,
        },
    ] {
        assert_eq!(p.validate(), Ok(()), "{p:?}");
    }
}

// ---------------------------------------------------------------------------
// Scenes.

/// Most frame sizes of the scenes.
const MAX_W: usize = 64;
const MAX_H: usize = 44;
/// Background disparity tiles, px.
const TILE_W: usize = 8;
const TILE_H: usize = 6;
const TILES: usize = MAX_W.div_ceil(TILE_W) * MAX_H.div_ceil(TILE_H);

/// An object: its true box `(x, y, w, h)` in colour, nearer than the
/// background by `rise` disparity bits; the stereo's map has it grown by
/// `fat` px on the left, top, right and bottom (its blur); its colour is
/// the background's plus `colour`; an `outlined` one has its box's ring
/// in C.
#[derive(Clone, Debug)]
struct Object {
    rect: (usize, usize, usize, usize),
    rise: u16,
    fat: [usize; 4],
    colour: [i16; 3],
    outlined: bool,
}

/// A stereo scene of `w` x `h`: a background at `base` disparity bits,
/// plus per tile `tiles`; objects; OFF cells of the map, and rows of it
/// OFF but every fifth cell (rows without a dominant disparity); C's random
/// edges (`edge[i] < density`); the background colour; noise of the
/// left image and of the right (`noise_l`, `noise_r`, times `amp` / 16;
/// none in a flat scene).
#[derive(Clone, Debug)]
struct Scene {
    w: usize,
    h: usize,
    base: u16,
    tiles: Vec<i16>,
    objects: Vec<Object>,
    off: Vec<bool>,
    off_rows: Vec<bool>,
    edge: Vec<u8>,
    density: u8,
    bg: [u8; 3],
    amp: i16,
    noise_l: Vec<i16>,
    noise_r: Vec<i16>,
}

fn object(w: usize, h: usize) -> impl Strategy<Value = Object> {
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

fn scene() -> impl Strategy<Value = Scene> {
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

fn inside((x0, y0, bw, bh): (usize, usize, usize, usize), x: usize, y: usize) -> bool {
    (x0..x0 + bw).contains(&x) && (y0..y0 + bh).contains(&y)
}

fn add(c: u8, d: i16) -> u8 {
    (i16::from(c) + d).clamp(0, 255) as u8
}

impl Scene {
    /// The background's disparity bits at `(x, y)`.
    fn background(&self, x: usize, y: usize) -> u16 {
        let t = (y / TILE_H) * MAX_W.div_ceil(TILE_W) + x / TILE_W;
        (i32::from(self.base) + i32::from(self.tiles[t])).max(0) as u16
    }

    /// The object seen at `(x, y)` (the last one there), if any.
    fn object_at(&self, x: usize, y: usize) -> Option<&Object> {
        self.objects.iter().rev().find(|o| inside(o.rect, x, y))
    }

    /// The stereo's map: the background's tiles, each object's box grown
    /// by its blur at its disparity, OFF cells.
    fn disparity(&self) -> Vec<DisparityCell> {
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
    fn edges(&self) -> Vec<EdgeCell> {
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
    fn left(&self) -> Vec<Rgb8> {
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
    fn right(&self, left: &[Rgb8]) -> Vec<Rgb8> {
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

/// The whole frame as S, no upper cut, up to 3 objects, the depth pass
/// of `depth_pass.rs`.
const PASS: SegmentParams = SegmentParams {
    top_bottom_strip: Ratio::new(0, 1),
    left_strip: Ratio::new(0, 1),
    fg_high: Ratio::new(100, 1),
    max_objects: 3,
    depth_pass: Some(DepthPass {
        searches: 2,
        clearance: 2,
        min_area: Ratio::new(1, 48),
        ..DepthPass::DEFAULT
    }),
    ..SegmentParams::PAPER
};

/// Per object: core's input mask and report, whether core relabelled
/// it, its mask and report after, and the reference's answer for the
/// input mask.
struct Outcome {
    before: Vec<bool>,
    relabelled: bool,
    after: Vec<bool>,
    det: Detection,
    was: Detection,
    want: Option<Vec<bool>>,
}

fn bools(words: &[u32], w: usize, h: usize) -> Vec<bool> {
    BitView::new(words, w, h).unwrap().bools().collect()
}

fn bbox(m: &[bool], w: usize) -> Option<BoundingBox> {
    let on: Vec<(usize, usize)> = (0..m.len())
        .filter(|&i| m[i])
        .map(|i| (i % w, i / w))
        .collect();
    let x0 = on.iter().map(|p| p.0).min()?;
    let x1 = on.iter().map(|p| p.0).max()?;
    let y0 = on.iter().map(|p| p.1).min()?;
    let y1 = on.iter().map(|p| p.1).max()?;
    Some(BoundingBox {
        x: x0,
        y: y0,
        width: x1 + 1 - x0,
        height: y1 + 1 - y0,
    })
}

/// Core's segmentation of `scene` with `p`, then the relabelling of each
/// object with `relabel`, each against the reference.
fn relabel_scene(scene: &Scene, p: &SegmentParams, relabel: &Relabel) -> Vec<Outcome> {
    let (w, h) = (scene.w, scene.h);
    let (d, c) = (scene.disparity(), scene.edges());
    let left = scene.left();
    let right = scene.right(&left);
    let mut store = SegmentStorage::new(w, h);
    let mut bufs = store.buffers().unwrap();
    let chunk = bit_map_len(w, h);
    let mut masks = vec![0u32; usize::from(p.max_objects) * chunk];
    let (lv, rv, cv) = (
        ImageView::packed(&left, w, h).unwrap(),
        ImageView::packed(&right, w, h).unwrap(),
        ImageView::packed(&c, w, h).unwrap(),
    );
    let mut report = segment_with_depth_pass(
        p,
        &ImageView::packed(&d, w, h).unwrap(),
        &cv,
        &lv,
        &mut bufs,
        Masks::Bits(&mut masks),
        &mut (),
    )
    .unwrap();
    let df: Vec<rf::DispF> = d.iter().map(|v| v.get().map(f32::from)).collect();
    let ground = rf::row_disparities(&df, w, h);
    let mut scratch = vec![0u32; relabel_len(w)];
    let mut out = Vec::new();
    for det in report.objects.iter_mut() {
        let slot = det.index * chunk..(det.index + 1) * chunk;
        let before = bools(&masks[slot.clone()], w, h);
        let want = rfl::relabel_mask(
            relabel, &before, &left, &right, &c, &ground, det.range, w, h,
        );
        let was = *det;
        let relabelled = relabel_object(
            relabel,
            &lv,
            &rv,
            &cv,
            det,
            &mut masks,
            &mut bufs,
            &mut scratch,
        )
        .unwrap();
        out.push(Outcome {
            after: bools(&masks[slot], w, h),
            before,
            relabelled,
            det: *det,
            was,
            want,
        });
    }
    out
}

/// Checks core's relabelling of every object (of a frame `w` wide)
/// against the reference; returns the objects relabelled and those of
/// them whose mask changed.
fn check(outcomes: &[Outcome], w: usize) -> Result<(usize, usize), String> {
    let (mut relabelled, mut changed) = (0, 0);
    for (k, o) in outcomes.iter().enumerate() {
        let fail = |what: &str| Err(format!("object {k}: {what}"));
        match &o.want {
            None => {
                if o.relabelled || o.after != o.before || o.det != o.was {
                    return fail("core relabelled what the reference leaves");
                }
            }
            Some(m) => {
                if !o.relabelled {
                    return fail("core left what the reference relabels");
                }
                if &o.after != m {
                    let diff: Vec<(usize, usize, bool)> = (0..m.len())
                        .filter(|&i| m[i] != o.after[i])
                        .map(|i| (i % w, i / w, o.after[i]))
                        .collect();
                    return fail(&format!("masks differ at (x, y, core's) {diff:?}"));
                }
                let area = m.iter().filter(|&&b| b).count() as u32;
                let want = Detection {
                    area,
                    bbox: bbox(m, w),
                    ..o.was
                };
                if o.det != want {
                    return fail(&format!("report {:?}, want {want:?}", o.det));
                }
                relabelled += 1;
                changed += usize::from(m != &o.before);
            }
        }
    }
    Ok((relabelled, changed))
}

/// Relabel settings: the default, settings near it, or any within the
/// checked ranges.
fn relabel_settings() -> impl Strategy<Value = Relabel> {
    let near = (
        (0u8..=3, 1u8..=4, 1u8..=6, 1u8..=8),
        (0u8..=16, 0u8..=64, 30u8..=100),
    );
    let any = (
        (0u8..=8, 1u8..=8, 1u8..=8, 1u8..=16),
        (0u8..=16, 0u8..=64, 0u8..=100),
    );
    let make = |((core, reach, ring, passes), (matching, smooth, edge_percent))| Relabel {
        core,
        reach,
        ring,
        passes,
        matching,
        smooth,
        edge_percent,
    };
    prop_oneof![
        Just(Relabel::DEFAULT),
        near.prop_map(make),
        any.prop_map(make),
    ]
}

/// Segmentation settings: the pass's refinement and holes on or off.
fn segment_settings() -> impl Strategy<Value = SegmentParams> {
    (any::<bool>(), any::<bool>()).prop_map(|(refine, holes)| SegmentParams {
        depth_pass: PASS.depth_pass.map(|dp| DepthPass {
            refine: refine.then_some(Refine::DEFAULT),
            holes: holes.then_some(Holes::DEFAULT),
            ..dp
        }),
        ..PASS
    })
}

/// `n` values in `-a..=a`, from a fixed LCG.
fn fixed_noise(n: usize, a: i16, seed: u64) -> Vec<i16> {
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
fn fattened() -> Scene {
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

/// Intersection over union of a mask and a box.
fn iou_box(m: &[bool], w: usize, rect: (usize, usize, usize, usize)) -> f64 {
    let (mut i, mut u) = (0, 0);
    for (k, &on) in m.iter().enumerate() {
        let b = inside(rect, k % w, k / w);
        i += usize::from(on && b);
        u += usize::from(on || b);
    }
    i as f64 / u.max(1) as f64
}

#[test]
fn a_fattened_low_contrast_object_is_cut_back_to_its_colour() {
    let scene = fattened();
    let truth = scene.objects[0].rect;
    // Without the colour refinement the pass's mask is the map's box.
    let p = SegmentParams {
        depth_pass: PASS.depth_pass.map(|dp| DepthPass {
            refine: None,
            holes: None,
            ..dp
        }),
        ..PASS
    };
    let out = relabel_scene(&scene, &p, &Relabel::DEFAULT);
    assert_eq!(out.len(), 1);
    let o = &out[0];
    assert_eq!(iou_box(&o.before, scene.w, (12, 8, 22, 18)), 1.0);
    assert!(o.relabelled);
    // The matching keeps the background the right eye does not see, left
    // of the object; elsewhere the band is the object's colour.
    let (before, after) = (
        iou_box(&o.before, scene.w, truth),
        iou_box(&o.after, scene.w, truth),
    );
    assert!(before < 0.65 && after > 0.85, "IoU {before} then {after}");
    assert_eq!(check(&out, scene.w), Ok((1, 1)));
    // An outline on C's edges is left as it is.
    let outlined = Scene {
        objects: vec![Object {
            outlined: true,
            fat: [0; 4],
            ..scene.objects[0].clone()
        }],
        ..scene.clone()
    };
    let out = relabel_scene(&outlined, &p, &Relabel::DEFAULT);
    assert!(!out.is_empty());
    assert!(out.iter().all(|o| !o.relabelled && o.after == o.before));
    assert!(check(&out, scene.w).is_ok());
}

#[test]
fn short_scratch_and_frames_of_another_size_are_typed_errors() {
    let scene = fattened();
    let (w, h) = (scene.w, scene.h);
    let (d, c) = (scene.disparity(), scene.edges());
    let left = scene.left();
    let right = scene.right(&left);
    let mut store = SegmentStorage::new(w, h);
    let mut bufs = store.buffers().unwrap();
    let chunk = bit_map_len(w, h);
    let mut masks = vec![0u32; usize::from(PASS.max_objects) * chunk];
    let (lv, rv, cv) = (
        ImageView::packed(&left, w, h).unwrap(),
        ImageView::packed(&right, w, h).unwrap(),
        ImageView::packed(&c, w, h).unwrap(),
    );
    let mut report = segment_with_depth_pass(
        &PASS,
        &ImageView::packed(&d, w, h).unwrap(),
        &cv,
        &lv,
        &mut bufs,
        Masks::Bits(&mut masks),
        &mut (),
    )
    .unwrap();
    let det = &mut report.objects[0];
    let (was, before) = (*det, masks.clone());
    let needed = relabel_len(w);
    let mut short = vec![0u32; needed - 1];
    let r = relabel_object(
        &Relabel::DEFAULT,
        &lv,
        &rv,
        &cv,
        det,
        &mut masks,
        &mut bufs,
        &mut short,
    );
    assert_eq!(
        r,
        Err(SegmentError::Image(ImageError::BufferTooSmall {
            needed,
            got: needed - 1
        }))
    );
    let narrow = ImageView::packed(&right[..w * h - h], w - 1, h).unwrap();
    let mut scratch = vec![0u32; needed];
    let r = relabel_object(
        &Relabel::DEFAULT,
        &lv,
        &narrow,
        &cv,
        det,
        &mut masks,
        &mut bufs,
        &mut scratch,
    );
    assert_eq!(
        r,
        Err(SegmentError::SizeMismatch {
            expected: (w, h),
            got: (w - 1, h)
        })
    );
    assert_eq!((*det, &masks), (was, &before));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Every object's relabelling is the reference's, mask for mask, and
    /// its area and box those of its mask; a mask core leaves is one the
    /// reference leaves (error bound: none).
    #[test]
    fn the_relabelling_is_the_references(
        scene in scene(),
        p in segment_settings(),
        relabel in relabel_settings(),
    ) {
        if let Err(e) = check(&relabel_scene(&scene, &p, &relabel), scene.w) {
            return Err(TestCaseError::fail(e));
        }
    }
}

#[test]
fn the_scenes_exercise_the_relabelling() {
    // The property's cases, from a fixed seed: in a quarter of the
    // scenes or more a mask is relabelled and changed, a fifth of the
    // objects or more are relabelled, and most of these change (when
    // written: 26 of 64 scenes; 30 of 96 objects, 29 changed).
    let mut runner = TestRunner::deterministic();
    let strategy = (scene(), segment_settings(), relabel_settings());
    let cases = 64;
    let (mut objects, mut relabelled, mut changed, mut scenes) = (0, 0, 0, 0);
    for _ in 0..cases {
        let (scene, p, relabel) = strategy.new_tree(&mut runner).unwrap().current();
        let outcomes = relabel_scene(&scene, &p, &relabel);
        let (r, c) = check(&outcomes, scene.w).unwrap();
        objects += outcomes.len();
        relabelled += r;
        changed += c;
        scenes += usize::from(c > 0);
    }
    eprintln!(
        "{cases} scenes: {objects} objects, {relabelled} relabelled, {changed} changed, \
         in {scenes} scenes"
    );
    assert!(objects >= cases, "{objects} objects");
    assert!(4 * scenes >= cases, "{scenes} scenes of {cases}");
    assert!(5 * relabelled >= objects, "{relabelled} of {objects}");
    assert!(2 * changed >= relabelled, "{changed} of {relabelled}");
}
