//! Helpers of the mirror check's tests (`mlp_mirror.rs`,
//! `mlp_mirror_reference.rs`): the shipped model without and with
//! symmetry, masks drawn as shape vectors, and the classifier's buffers.
#![allow(dead_code)]

use protogist::image::ImageView;
use protogist::mlp::{
    forward, mirror_check, mirror_check_below_with, mirror_outputs_len, top_k, MirrorScratch,
    Model, Ranked, SafeKernel, Scratch, TOP_K,
};
use protogist::shape::{shape_vector, Mirror, RadialProfile, ShapeElem, ShapeVector, SHAPE_LEN};
use protogist_host::classify::symmetry::with_symmetry;
use protogist_tests::nets::blob_version_1;

/// The shipped model as version 1 (no symmetry section).
pub static MODEL_V1: std::sync::LazyLock<Vec<u8>> =
    std::sync::LazyLock::new(|| blob_version_1(SHIPPED));
pub const SHIPPED: &[u8] = include_bytes!("../../../host/data/shapes_model.bin");
/// The shipped model's network and templates, without symmetry.
pub fn shipped_v1() -> &'static [u8] {
    &MODEL_V1
}

/// An asymmetric blob (a tilted, off-centre L with a notch and a disc),
/// 41x41, as the tta26 probe drew it.
pub fn blob(x: i32, y: i32) -> bool {
    let (u, v) = (x - 20, 20 - y);
    let l = (-12..=10).contains(&u) && (-12..=-4).contains(&v)
        || (-12..=-5).contains(&u) && (-12..=14).contains(&v);
    l && !(u == 3 && v == -8) || (u - 8).pow(2) + (v - 6).pow(2) <= 9
}

pub fn vector(f: impl Fn(i32, i32) -> bool) -> ShapeVector {
    let px: Vec<u8> = (0..41 * 41).map(|i| u8::from(f(i % 41, i / 41))).collect();
    let mask = ImageView::packed(&px, 41, 41).unwrap();
    let mut p = RadialProfile::new();
    let mut v = [ShapeElem::ZERO; SHAPE_LEN];
    shape_vector(&mask, &mut p, &mut v).unwrap();
    v
}

pub fn mirrored(m: Mirror, x: &ShapeVector) -> ShapeVector {
    let mut v = [ShapeElem::ZERO; SHAPE_LEN];
    m.apply(x, &mut v);
    v
}

pub fn mean_abs(a: &ShapeVector, b: &ShapeVector) -> f32 {
    a.iter()
        .zip(b)
        .map(|(a, b)| (*a - *b).abs().to_num::<f32>())
        .sum::<f32>()
        / SHAPE_LEN as f32
}

/// The shipped model with symmetry `flags` (one byte per class).
pub fn with_flags(flags: &[u8]) -> Vec<u8> {
    with_symmetry(shipped_v1(), flags).unwrap()
}

/// Shape vectors of a few real masks and their mirrors.
pub fn probes() -> Vec<ShapeVector> {
    let mut out = vec![vector(blob)];
    for (a, b) in [(9, 4), (5, 12), (14, 7)] {
        out.push(vector(|x, y| {
            let (u, v) = (x - 20, y - 20);
            (u * u * b + v * v * a <= 12 * a * b) || (u > 0 && v.abs() < 2 && u < 18)
        }));
    }
    let m: Vec<ShapeVector> = out
        .iter()
        .flat_map(|x| Mirror::ALL.map(|m| mirrored(m, x)))
        .collect();
    out.extend(m);
    out
}

pub struct Bufs {
    pub xi: Vec<u32>,
    pub hi: Vec<u8>,
    pub yo: Vec<u16>,
    pub v: Vec<ShapeElem>,
    pub o: Vec<u16>,
    pub mean: Vec<u16>,
}

impl Bufs {
    pub fn new(m: &Model<'_>) -> Self {
        let (d, h, k) = (m.inputs(), m.hidden(), m.classes());
        Self {
            xi: vec![0; protogist::mlp::packed_len(d, h)],
            hi: vec![0; h],
            yo: vec![0; k],
            v: vec![ShapeElem::ZERO; SHAPE_LEN],
            o: vec![0; mirror_outputs_len(k)],
            mean: vec![0; k],
        }
    }

    pub fn plain(&mut self, m: &Model<'_>, x: &[ShapeElem]) -> (Vec<u16>, Vec<Ranked>) {
        let mut s = Scratch {
            input: &mut self.xi,
            hidden: &mut self.hi,
            output: &mut self.yo,
        };
        let out = forward(m, x, &mut s).unwrap().to_vec();
        let mut r = [Ranked::default(); TOP_K];
        let n = top_k(m, &out, &mut r).unwrap();
        (out, r[..n].to_vec())
    }

    /// `f` on the scratch, the mirror scratch and a ranking; the ranks it
    /// filled.
    pub fn ranked(
        &mut self,
        f: impl FnOnce(&mut Scratch<'_>, &mut MirrorScratch<'_>, &mut [Ranked]) -> usize,
    ) -> Vec<Ranked> {
        let mut s = Scratch {
            input: &mut self.xi,
            hidden: &mut self.hi,
            output: &mut self.yo,
        };
        let mut ms = MirrorScratch {
            vector: &mut self.v,
            outputs: &mut self.o,
            mean: &mut self.mean,
        };
        let mut r = [Ranked::default(); TOP_K];
        let n = f(&mut s, &mut ms, &mut r);
        r[..n].to_vec()
    }

    pub fn check(&mut self, m: &Model<'_>, x: &[ShapeElem]) -> Vec<Ranked> {
        self.ranked(|s, ms, r| mirror_check(m, x, s, ms, r).unwrap())
    }

    /// The check for an object whose own best cosine is under `below`.
    pub fn gated(&mut self, m: &Model<'_>, x: &[ShapeElem], below: u32) -> Vec<Ranked> {
        self.ranked(|s, ms, r| {
            mirror_check_below_with::<SafeKernel>(m, x, s, ms, r, below).unwrap()
        })
    }
}
