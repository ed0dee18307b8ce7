//! Integer inference of the proto-object classifier (paper sections 4.1 and
//! 4.4): the two-layer log-sigmoid network, quantised to int8, and the
//! classification rules on its outputs.
//!
//! ```text
//! shape vector (I4F12) ─► int8 input ─► W1·x + b1 (i32) ─► requantise ─► σ LUT ─► u8 hidden
//!                      ─► W2·h + b2 (i32) ─► requantise ─► σ LUT ─► u16 outputs
//!                      ─► integer cosine with u16 templates ─► top-k, Δ, unknown class
//! ```
//!
//! **Formats.** Weights are int8, symmetric (zero point 0, values in
//! `−127..=127`), one scale per output channel; biases are int32 at the
//! scale `s_in · s_w[c]`; each channel's accumulator is requantised to a
//! pre-activation `z` in Q12 by its own multiplier and shift
//! ([`requant::requantize`], TFLM's `MultiplyByQuantizedMultiplier`) and
//! goes through the log-sigmoid table ([`requant::logsig_q12`], at most
//! 1 LSB off). Hidden activations are u8 (`255 · σ`), outputs u16
//! (`65535 · σ`). No float anywhere.
//!
//! **Input.** The shape stage gives `I4F12` elements (`raw / 4096`,
//! z-normalised). The host calibrates an input scale `s_x` on the training
//! data (largest `|x|` over all training vectors, divided by 127) and stores
//! `1 / (4096 · s_x)` as a multiplier and shift; [`quantize_input`] applies
//! it to the raw `i16` and clamps to `−127..=127`, so
//! `q = clamp(round(x / s_x))` (rounding as in the requantisation).
//!
//! **Rules.** Templates `v_c` are u16 vectors (the class-mean outputs on the
//! training data). The score of class `c` is the cosine
//! `v·v_c / (‖v‖ ‖v_c‖)` in Q16 ([`cosine_q16`]): exact integer dot
//! products, one `u128` integer square root, one rounded division. The
//! ranked list orders by score, ties to the lower class. Identification
//! returns the best class if its score reaches the model's `Δ`
//! ([`Model::delta_q16`]), else [`Identity::Unknown`] (`U_{N+1}`);
//! verification accepts a claim when its score reaches `Δ`.
//!
//! **Memory.** Activations need [`scratch_bytes`] bytes in a caller-owned
//! [`Scratch`] (sizes from [`input_len`], [`hidden_len`], [`output_len`]);
//! the model is borrowed from wherever its bytes are (flash).

pub mod blob;
pub mod logsig_table;
pub mod requant;

pub use blob::{crc32, Model, ModelError};

use crate::fixed::isqrt_floor_u128;
use crate::shape::ShapeElem;
use blob::{le_i32, le_u16};
use requant::{logsig_q12, logsig_u8, requantize};

/// Ranked classes the demo prints.
pub const TOP_K: usize = 5;

/// Why inference failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum MlpError {
    /// The input vector does not have the model's input length.
    FeatureSize {
        /// The model's input length.
        expected: usize,
        /// The vector's length.
        got: usize,
    },
    /// A scratch buffer is shorter than the model needs.
    ScratchTooSmall {
        /// Which buffer.
        buffer: &'static str,
        /// Elements needed.
        needed: usize,
        /// Elements given.
        got: usize,
    },
    /// A class index (claim) out of range.
    ClassOutOfRange {
        /// The class.
        class: usize,
        /// Classes of the model.
        classes: usize,
    },
}

impl core::error::Error for MlpError {}

impl core::fmt::Display for MlpError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::FeatureSize { expected, got } => {
                write!(
                    f,
                    "feature vector has {got} elements, the model takes {expected}"
                )
            }
            Self::ScratchTooSmall {
                buffer,
                needed,
                got,
            } => write!(f, "{buffer} scratch has {got} elements, needs {needed}"),
            Self::ClassOutOfRange { class, classes } => {
                write!(f, "class {class} out of range for {classes} classes")
            }
        }
    }
}

/// Elements of [`Scratch::input`] for `inputs` inputs.
pub const fn input_len(inputs: usize) -> usize {
    inputs
}

/// Elements of [`Scratch::hidden`] for `hidden` units.
pub const fn hidden_len(hidden: usize) -> usize {
    hidden
}

/// Elements of [`Scratch::output`] for `classes` outputs.
pub const fn output_len(classes: usize) -> usize {
    classes
}

/// Activation RAM in bytes: the quantised input (`i16`), the hidden (`u8`)
/// and the output (`u16`) activations.
pub const fn scratch_bytes(inputs: usize, hidden: usize, classes: usize) -> usize {
    2 * input_len(inputs) + hidden_len(hidden) + 2 * output_len(classes)
}

/// Caller-owned activation memory.
#[derive(Debug)]
pub struct Scratch<'a> {
    /// Quantised input, int8 values widened to `i16`.
    pub input: &'a mut [i16],
    /// Hidden activations (`255 · σ`).
    pub hidden: &'a mut [u8],
    /// Outputs (`65535 · σ`).
    pub output: &'a mut [u16],
}

/// One entry of a ranked list.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Ranked {
    /// Class index.
    pub class: u16,
    /// Cosine in Q16 (65536 = 1).
    pub score: u32,
}

/// The outcome of identification.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Identity {
    /// Class `U_c`, `c` from 0.
    Known(u16),
    /// `U_{N+1}`: no template reaches `Δ`.
    Unknown,
}

/// `clamp(requantize(raw), −127, 127)` of every element into `out`.
///
/// # Errors
/// [`MlpError::FeatureSize`] when the lengths differ.
pub fn quantize_input(
    model: &Model<'_>,
    input: &[ShapeElem],
    out: &mut [i16],
) -> Result<(), MlpError> {
    if input.len() != model.inputs() || out.len() != input.len() {
        return Err(MlpError::FeatureSize {
            expected: model.inputs(),
            got: input.len(),
        });
    }
    let (m, s) = model.input_requant();
    for (q, x) in out.iter_mut().zip(input) {
        *q = requantize(i32::from(x.to_bits()), m, s).clamp(-127, 127) as i16;
    }
    Ok(())
}

fn check_scratch(buffer: &'static str, needed: usize, got: usize) -> Result<(), MlpError> {
    if got < needed {
        return Err(MlpError::ScratchTooSmall {
            buffer,
            needed,
            got,
        });
    }
    Ok(())
}

/// `Σ w[j] · x[j]` for int8 weight bytes and `i16` activations. With the
/// model's limits (`|w|, |x| <= 127` or `x <= 255`, at most 65535 terms)
/// the sum stays below `2^31`; it wraps rather than panics otherwise.
#[inline]
fn dot(w: &[u8], x: &[i16]) -> i32 {
    w.iter().zip(x).fold(0i32, |a, (&w, &x)| {
        a.wrapping_add(i32::from(w as i8) * i32::from(x))
    })
}

/// Four rows at once, sharing each input load.
#[inline]
fn dot4(w: &[u8], n: usize, x: &[i16]) -> [i32; 4] {
    let (r0, rest) = w.split_at(n.min(w.len()));
    let (r1, rest) = rest.split_at(n.min(rest.len()));
    let (r2, r3) = rest.split_at(n.min(rest.len()));
    let mut s = [0i32; 4];
    for ((((&a, &b), &c), &d), &x) in r0.iter().zip(r1).zip(r2).zip(r3).zip(x) {
        let x = i32::from(x);
        s[0] = s[0].wrapping_add(i32::from(a as i8) * x);
        s[1] = s[1].wrapping_add(i32::from(b as i8) * x);
        s[2] = s[2].wrapping_add(i32::from(c as i8) * x);
        s[3] = s[3].wrapping_add(i32::from(d as i8) * x);
    }
    s
}

/// One fully connected layer: `out[c] = act(requantize(W[c]·x + b[c]))`.
fn layer<T>(w: &[u8], b: &[u8], rq: &[u8], x: &[i16], out: &mut [T], act: impl Fn(i32) -> T) {
    let n = x.len();
    if n == 0 {
        return;
    }
    let finish = |acc: i32, c: usize| -> T {
        let acc = acc.saturating_add(le_i32(b, 4 * c));
        let z = requantize(acc, le_i32(rq, 8 * c), le_i32(rq, 8 * c + 4));
        act(z)
    };
    let mut blocks = w.chunks_exact(4 * n);
    let mut outs = out.chunks_exact_mut(4);
    let mut c = 0;
    for (block, o) in (&mut blocks).zip(&mut outs) {
        let s = dot4(block, n, x);
        for (o, s) in o.iter_mut().zip(s) {
            *o = finish(s, c);
            c += 1;
        }
    }
    for (row, o) in blocks
        .remainder()
        .chunks_exact(n)
        .zip(outs.into_remainder())
    {
        *o = finish(dot(row, x), c);
        c += 1;
    }
}

/// Runs the network on a shape vector; the outputs (`65535 · σ`, one per
/// class) are in `scratch.output[..model.classes()]` and returned.
///
/// # Errors
/// [`MlpError::FeatureSize`] for an input of another length than the
/// model's, [`MlpError::ScratchTooSmall`].
pub fn forward<'s>(
    model: &Model<'_>,
    input: &[ShapeElem],
    scratch: &'s mut Scratch<'_>,
) -> Result<&'s [u16], MlpError> {
    let (d, h, k) = (model.inputs(), model.hidden(), model.classes());
    if input.len() != d {
        return Err(MlpError::FeatureSize {
            expected: d,
            got: input.len(),
        });
    }
    check_scratch("input", input_len(d), scratch.input.len())?;
    check_scratch("hidden", hidden_len(h), scratch.hidden.len())?;
    check_scratch("output", output_len(k), scratch.output.len())?;
    let x = scratch.input.get_mut(..d).unwrap_or(&mut []);
    quantize_input(model, input, x)?;
    let x = &*x;
    let hidden = scratch.hidden.get_mut(..h).unwrap_or(&mut []);
    layer(model.w1, model.b1, model.rq1, x, hidden, logsig_u8);
    // The output layer reads the hidden activations as i16 (0..=255): reuse
    // the input buffer when it is long enough, else go row by row.
    let out = scratch.output.get_mut(..k).unwrap_or(&mut []);
    if let Some(hx) = scratch.input.get_mut(..h) {
        for (t, &v) in hx.iter_mut().zip(scratch.hidden.iter()) {
            *t = i16::from(v);
        }
        layer(model.w2, model.b2, model.rq2, hx, out, logsig_q12);
    } else {
        for (c, (o, row)) in out.iter_mut().zip(model.w2.chunks_exact(h)).enumerate() {
            let acc = row
                .iter()
                .zip(scratch.hidden.iter())
                .fold(0i32, |a, (&w, &v)| {
                    a.wrapping_add(i32::from(w as i8) * i32::from(v))
                })
                .saturating_add(le_i32(model.b2, 4 * c));
            *o = logsig_q12(requantize(
                acc,
                le_i32(model.rq2, 8 * c),
                le_i32(model.rq2, 8 * c + 4),
            ));
        }
    }
    Ok(scratch.output.get(..k).unwrap_or(&[]))
}

/// The cosine of `v` and a template given as little-endian u16 bytes, in
/// Q16 (65536 = 1), rounded; 0 when either is all zero.
pub fn cosine_q16(v: &[u16], template_le: &[u8]) -> u32 {
    let (mut vt, mut vv, mut tt) = (0u64, 0u64, 0u64);
    for (&a, t) in v.iter().zip(template_le.chunks_exact(2)) {
        let (a, t) = (u64::from(a), u64::from(le_u16(t, 0)));
        vt += a * t;
        vv += a * a;
        tt += t * t;
    }
    // Each sum is below 2^32 · MAX_CLASSES = 2^42: the product fits u128.
    let norm = isqrt_floor_u128(u128::from(vv) * u128::from(tt));
    if norm == 0 {
        return 0;
    }
    let q = ((u128::from(vt) << 16) + norm / 2) / norm;
    q.min(1 << 16) as u32
}

/// The Q16 cosine of `outputs` with every class template, in `scores`.
///
/// # Errors
/// [`MlpError::FeatureSize`] when `outputs` or `scores` is not one per class.
pub fn scores(model: &Model<'_>, outputs: &[u16], scores: &mut [u32]) -> Result<(), MlpError> {
    let k = model.classes();
    for len in [outputs.len(), scores.len()] {
        if len != k {
            return Err(MlpError::FeatureSize {
                expected: k,
                got: len,
            });
        }
    }
    for (c, s) in scores.iter_mut().enumerate() {
        *s = model.template(c).map_or(0, |t| cosine_q16(outputs, t));
    }
    Ok(())
}

/// The best `ranked.len()` classes by score, best first, ties to the lower
/// class; returns how many entries were filled (`min(len, classes)`).
///
/// # Errors
/// [`MlpError::FeatureSize`] when `outputs` is not one per class.
pub fn top_k(model: &Model<'_>, outputs: &[u16], ranked: &mut [Ranked]) -> Result<usize, MlpError> {
    let k = model.classes();
    if outputs.len() != k {
        return Err(MlpError::FeatureSize {
            expected: k,
            got: outputs.len(),
        });
    }
    let mut filled = 0usize;
    for c in 0..k {
        let score = model.template(c).map_or(0, |t| cosine_q16(outputs, t));
        let entry = Ranked {
            class: c as u16,
            score,
        };
        // Insert after every entry with a score >= this one (stable).
        let pos = ranked
            .iter()
            .take(filled)
            .position(|r| r.score < score)
            .unwrap_or(filled);
        if pos >= ranked.len() {
            continue;
        }
        let end = filled.min(ranked.len().saturating_sub(1));
        if let Some(tail) = ranked.get_mut(pos..=end) {
            tail.rotate_right(1);
            if let Some(first) = tail.first_mut() {
                *first = entry;
            }
        }
        filled = (filled + 1).min(ranked.len());
    }
    Ok(filled)
}

/// Identification: the best class if its score reaches `Δ`, else
/// [`Identity::Unknown`].
///
/// # Errors
/// As [`top_k`].
pub fn identify(model: &Model<'_>, outputs: &[u16]) -> Result<(Identity, Ranked), MlpError> {
    let mut best = [Ranked::default()];
    top_k(model, outputs, &mut best)?;
    let [b] = best;
    let id = if b.score >= model.delta_q16() {
        Identity::Known(b.class)
    } else {
        Identity::Unknown
    };
    Ok((id, b))
}

/// Verification: accept the claim "class `claim`" when its score reaches
/// `Δ`.
///
/// # Errors
/// [`MlpError::ClassOutOfRange`], or as [`top_k`].
pub fn verify(model: &Model<'_>, outputs: &[u16], claim: usize) -> Result<bool, MlpError> {
    let k = model.classes();
    if outputs.len() != k {
        return Err(MlpError::FeatureSize {
            expected: k,
            got: outputs.len(),
        });
    }
    let t = model.template(claim).ok_or(MlpError::ClassOutOfRange {
        class: claim,
        classes: k,
    })?;
    Ok(cosine_q16(outputs, t) >= model.delta_q16())
}
