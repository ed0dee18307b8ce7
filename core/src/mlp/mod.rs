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
//! [`Scratch`] (sizes from [`packed_len`], [`hidden_len`], [`output_len`]);
//! the model is borrowed from wherever its bytes are (flash).
//!
//! **Kernel.** The dot products go through [`MacKernel`] (CMSIS-NN
//! style): [`forward`] uses the portable [`SafeKernel`] (four rows share
//! each input load; per four inputs and row, one weight word masked into
//! even and odd bytes and four 16x16 multiply-accumulates that read their
//! operands' register halves, `SMLAxy` on the Cortex-M4); a target may pass
//! its own to [`forward_with`], as the firmware does with an `SMLAD`
//! kernel in assembly (safe Rust cannot reach `SMLAD` from byte weights,
//! and core forbids `unsafe`). Any kernel that honours the contract gives
//! the same bits. docs/MODEL_FORMAT.md, section Kernel, has the costs.

pub mod blob;
mod input_kind;
mod kernel;
pub mod logsig_table;
pub mod mirror;
pub mod requant;
mod rules;
mod symmetry;

pub use blob::{crc32, InputKind, Model, ModelError, Symmetry};
pub use kernel::{safe_dot_rows, MacKernel, SafeKernel};
pub use mirror::{
    mirror_check, mirror_check_below_with, mirror_check_with, mirror_mean, mirror_mean_len,
    mirror_outputs_len, mirror_scratch_bytes, mirror_top_k, MirrorScratch, MIRROR_VIEWS,
};
pub use rules::{cosine_q16, identify, scores, top_k, verify};

use crate::shape::ShapeElem;
use blob::le_i32;
use kernel::{hi16, lo16};
use requant::{logsig_q12, logsig_u8, requantize, requantize_i16};

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
    /// The input is of another kind than the model's.
    InputKind {
        /// What the model takes.
        model: InputKind,
        /// What was given.
        given: InputKind,
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
            Self::InputKind { model, given } => write!(
                f,
                "the model takes {} input ({} values), given {} ({} values)",
                model.name(),
                model.input_len(),
                given.name(),
                given.input_len()
            ),
        }
    }
}

/// Words of [`Scratch::input`] for a layer input of `n` values: each
/// group of four values `x[4g..4g + 4]` takes two words, `x0 | x2 << 16`
/// and `x1 | x3 << 16` (the `SMLAD` pairing of even and odd weight bytes;
/// missing values are 0).
pub const fn input_len(n: usize) -> usize {
    2 * n.div_ceil(4)
}

/// Words of [`Scratch::input`] for a network: the quantised input, then the
/// hidden activations reuse the same words.
pub const fn packed_len(inputs: usize, hidden: usize) -> usize {
    if input_len(inputs) > input_len(hidden) {
        input_len(inputs)
    } else {
        input_len(hidden)
    }
}

/// Elements of [`Scratch::hidden`] for `hidden` units.
pub const fn hidden_len(hidden: usize) -> usize {
    hidden
}

/// Elements of [`Scratch::output`] for `classes` outputs.
pub const fn output_len(classes: usize) -> usize {
    classes
}

/// Activation RAM in bytes: the packed layer input (`u32` words), the
/// hidden (`u8`) and the output (`u16`) activations.
pub const fn scratch_bytes(inputs: usize, hidden: usize, classes: usize) -> usize {
    4 * packed_len(inputs, hidden) + hidden_len(hidden) + 2 * output_len(classes)
}

/// Caller-owned activation memory.
#[derive(Debug)]
pub struct Scratch<'a> {
    /// The current layer's input, `i16` values packed in pairs
    /// ([`packed_len`] words).
    pub input: &'a mut [u32],
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

/// Packs `f` of every value into `out` as [`input_len`] describes
/// (missing values are 0).
#[inline(always)]
fn pack<S: Copy>(values: &[S], f: impl Fn(S) -> i16, out: &mut [u32]) {
    let half = |v: i16| u32::from(v as u16);
    let put = |w: &mut [u32], x: [i16; 4]| {
        if let [w02, w13] = w {
            *w02 = half(x[0]) | (half(x[2]) << 16);
            *w13 = half(x[1]) | (half(x[3]) << 16);
        }
    };
    let mut groups = values.chunks_exact(4);
    let mut words = out.chunks_exact_mut(2);
    for (g, w) in (&mut groups).zip(&mut words) {
        if let [a, b, c, d] = *g {
            put(w, [f(a), f(b), f(c), f(d)]);
        }
    }
    let rest = groups.remainder();
    if let Some(w) = words.next() {
        let x = core::array::from_fn(|i| rest.get(i).map_or(0, |&v| f(v)));
        put(w, x);
    }
}

/// `clamp(requantize(raw), −127, 127)` of every element, packed in pairs
/// into `out` ([`input_len`] words).
///
/// # Errors
/// [`MlpError::FeatureSize`] when `input` is not the model's length,
/// [`MlpError::ScratchTooSmall`] when `out` is short.
pub fn quantize_input(
    model: &Model<'_>,
    input: &[ShapeElem],
    out: &mut [u32],
) -> Result<(), MlpError> {
    if input.len() != model.inputs() {
        return Err(MlpError::FeatureSize {
            expected: model.inputs(),
            got: input.len(),
        });
    }
    let words = input_len(input.len());
    check_scratch("input", words, out.len())?;
    let (m, s) = model.input_requant();
    let q = requantize_i16(m, s);
    pack(
        input,
        |x| q(x.to_bits()).clamp(-127, 127) as i16,
        out.get_mut(..words).unwrap_or(&mut []),
    );
    Ok(())
}

pub(crate) fn check_scratch(
    buffer: &'static str,
    needed: usize,
    got: usize,
) -> Result<(), MlpError> {
    if got < needed {
        return Err(MlpError::ScratchTooSmall {
            buffer,
            needed,
            got,
        });
    }
    Ok(())
}

/// Input value `j` of packed words.
#[inline]
fn x_at(x: &[u32], j: usize) -> i32 {
    let w = x.get(j / 4 * 2 + j % 2).copied().unwrap_or(0) as i32;
    if j % 4 < 2 {
        lo16(w)
    } else {
        hi16(w)
    }
}

/// Rows per [`MacKernel::dot_rows`] call of [`layer`] (a multiple of 3 and
/// 4, so that kernels blocking 3 or 4 rows have no remainder but the
/// layer's last).
const ROWS_PER_CALL: usize = 48;

/// One fully connected layer: `out[c] = act(requantize(W[c]·x + b[c]))`
/// over `n` packed inputs. Weights are stored excess-128 (`u = w + 128`),
/// so `W·x = Σ u·x − 128·Σx`. With `|w| <= 127`, `|x| <= 255` and at most
/// 65535 inputs, `|W·x| < 2^31`.
fn layer<K: MacKernel, T>(
    w: &[u8],
    b: &[u8],
    rq: &[u8],
    x: &[u32],
    n: usize,
    out: &mut [T],
    act: impl Fn(i32) -> T,
) {
    if n == 0 {
        return;
    }
    // Missing values are packed as 0, so summing whole words is exact.
    let xsum = x
        .get(..input_len(n))
        .unwrap_or(&[])
        .iter()
        .fold(0i32, |a, &w| {
            a.wrapping_add(lo16(w as i32)).wrapping_add(hi16(w as i32))
        });
    let offset = xsum.wrapping_mul(128);
    // Bias (4 bytes) and requantisation pair (8 bytes) of each channel, in
    // step with the outputs (the blob parser checked the lengths).
    let mut params = b.chunks_exact(4).zip(rq.chunks_exact(8));
    let finish = |acc: i32, (b, rq): (&[u8], &[u8])| -> T {
        let acc = acc.wrapping_sub(offset).saturating_add(le_i32(b, 0));
        act(requantize(acc, le_i32(rq, 0), le_i32(rq, 4)))
    };
    // The kernel takes whole groups of four inputs; the rest (n % 4) is
    // added per row here.
    let full = n - n % 4;
    let xs = x.get(..full / 2).unwrap_or(&[]);
    let mut acc = [0i32; ROWS_PER_CALL];
    // n >= 1, so the block is never 0; `max` lets the compiler see it too
    // and drop `chunks`' panic path.
    let block = ROWS_PER_CALL.saturating_mul(n).max(1);
    for (rows, outs) in w.chunks(block).zip(out.chunks_mut(ROWS_PER_CALL)) {
        let acc = acc.get_mut(..outs.len()).unwrap_or(&mut []);
        K::dot_rows(rows, n, full, xs, acc);
        for (((o, &a), row), p) in outs
            .iter_mut()
            .zip(acc.iter())
            .zip(rows.chunks(n))
            .zip(&mut params)
        {
            let tail = row.get(full..).unwrap_or(&[]);
            let a = tail.iter().enumerate().fold(a, |a, (j, &u)| {
                a.wrapping_add(i32::from(u).wrapping_mul(x_at(x, full + j)))
            });
            *o = finish(a, p);
        }
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
    forward_with::<SafeKernel>(model, input, scratch)
}

/// [`forward`] with the dot-product kernel `K` (see [`MacKernel`]).
///
/// # Errors
/// As [`forward`].
pub fn forward_with<'s, K: MacKernel>(
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
    check_scratch("input", packed_len(d, h), scratch.input.len())?;
    check_scratch("hidden", hidden_len(h), scratch.hidden.len())?;
    check_scratch("output", output_len(k), scratch.output.len())?;
    quantize_input(model, input, scratch.input)?;
    let hidden = scratch.hidden.get_mut(..h).unwrap_or(&mut []);
    layer::<K, _>(
        model.w1,
        model.b1,
        model.rq1,
        scratch.input,
        d,
        hidden,
        logsig_u8,
    );
    // The output layer reads the hidden activations packed like an input.
    pack(
        hidden,
        i16::from,
        scratch.input.get_mut(..input_len(h)).unwrap_or(&mut []),
    );
    let out = scratch.output.get_mut(..k).unwrap_or(&mut []);
    layer::<K, _>(
        model.w2,
        model.b2,
        model.rq2,
        scratch.input,
        h,
        out,
        logsig_q12,
    );
    Ok(scratch.output.get(..k).unwrap_or(&[]))
}
