//! Post-training quantisation of the float network into the core's int8
//! model blob (`PGML` v1, or v2 with per-class symmetry bytes,
//! [`super::symmetry`]; docs/MODEL_FORMAT.md), and host-side helpers around the core's integer
//! inference.
//!
//! **Scales.**
//! * input: `s_x = max |x| / 127` over every element of every training
//!   shape vector (`x` the `I4F12` value `raw / 4096`); the blob stores
//!   `1 / (4096 · s_x) = 127 / max |raw|` as a multiplier and shift;
//! * weights: per output channel `s_w[c] = max_j |W[c, j]| / 127`,
//!   `q = round(W / s_w)` in `−127..=127` (a zero row gets `s_w = 1`);
//! * biases: `round(b[c] / (s_in · s_w[c]))` as `i32` (`s_in` is `s_x` for
//!   the hidden layer and `1/255` for the output layer);
//! * requantisation of channel `c` to a Q12 pre-activation:
//!   `m = s_in · s_w[c] · 4096` as a Q31 multiplier and shift
//!   ([`quantize_multiplier`]).
//!
//! **Templates and Δ.** The integer network runs on the training split;
//! each class template is the rounded mean of its u16 outputs, and `Δ` is
//! the equal-error threshold of the training scores (first point of the
//! sweep where FAR <= FRR).

use super::metrics::Det;
use super::mlp::Mlp;
use super::ClassifyError;
use protogist::mlp::blob::{
    blob_len, crc32, InputKind, Model, ModelError, HEADER_LEN, HIDDEN_U8, MAGIC, MAX_CLASSES,
    MAX_NAME_LEN, OUTPUT_U16, VERSION, VERSION_1, WEIGHTS_I8_PER_CHANNEL,
};
use protogist::mlp::{forward, hidden_len, output_len, packed_len, scores, Scratch};
use protogist::shape::ShapeElem;
use rayon::prelude::*;

/// Q12: the pre-activation format the requantisation targets.
pub const Z_SCALE: f64 = 4096.0;

/// A real factor `m >= 0` as `(M, shift)` with `m ≈ M · 2^(shift − 31)`,
/// `M` in `[2^30, 2^31)`, as TFLM's `QuantizeMultiplier`; `(0, 0)` for
/// `m = 0` or below `2^−32`. Relative error at most `2^−31`.
pub fn quantize_multiplier(m: f64) -> (i32, i32) {
    if !m.is_finite() || m <= 0.0 {
        return (0, 0);
    }
    // m = q · 2^e with q in [0.5, 1).
    let mut e = m.log2().floor() as i32 + 1;
    let mut q = m / 2f64.powi(e);
    if q >= 1.0 {
        q /= 2.0;
        e += 1;
    } else if q < 0.5 {
        q *= 2.0;
        e -= 1;
    }
    let mut qf = (q * 2f64.powi(31)).round() as i64;
    if qf == 1i64 << 31 {
        qf /= 2;
        e += 1;
    }
    if e < -31 {
        return (0, 0);
    }
    (qf as i32, e.min(30))
}

/// The real factor of a `(multiplier, shift)` pair.
pub fn multiplier_value((m, s): (i32, i32)) -> f64 {
    f64::from(m) * 2f64.powi(s - 31)
}

/// One quantised layer.
#[derive(Clone, Debug, PartialEq)]
pub struct QuantLayer {
    /// int8 weights, `outputs × inputs`, row-major.
    pub w: Vec<i8>,
    /// int32 biases.
    pub b: Vec<i32>,
    /// Per-channel weight scales.
    pub w_scale: Vec<f64>,
    /// Per-channel requantisation to Q12.
    pub rq: Vec<(i32, i32)>,
}

/// The quantised network (without templates).
#[derive(Clone, Debug, PartialEq)]
pub struct QuantNet {
    /// Input scale `s_x`.
    pub x_scale: f64,
    /// `I4F12` raw to int8.
    pub input_rq: (i32, i32),
    /// Hidden layer (input scale `s_x`).
    pub l1: QuantLayer,
    /// Output layer (input scale `1/255`).
    pub l2: QuantLayer,
    /// Inputs, hidden units, classes.
    pub dims: (usize, usize, usize),
}

fn quantize_layer(w: &ndarray::Array2<f64>, b: &ndarray::Array1<f64>, s_in: f64) -> QuantLayer {
    let mut layer = QuantLayer {
        w: Vec::with_capacity(w.len()),
        b: vec![],
        w_scale: vec![],
        rq: vec![],
    };
    for (row, &bias) in w.rows().into_iter().zip(b) {
        let max = row.fold(0f64, |a, &v| a.max(v.abs()));
        let s = if max > 0.0 { max / 127.0 } else { 1.0 };
        layer.w.extend(
            row.iter()
                .map(|&v| (v / s).round().clamp(-127.0, 127.0) as i8),
        );
        layer.b.push(
            (bias / (s_in * s))
                .round()
                .clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32,
        );
        layer.w_scale.push(s);
        layer.rq.push(quantize_multiplier(s_in * s * Z_SCALE));
    }
    layer
}

/// Quantises `net` with the input scale calibrated on `calib` (raw `I4F12`
/// shape vectors).
///
/// # Errors
/// [`ClassifyError`] for no calibration vectors, all-zero ones, non-finite
/// parameters, or dimensions beyond the blob's limits.
pub fn quantize_net(net: &Mlp, calib: &[Vec<i16>]) -> Result<QuantNet, ClassifyError> {
    let (d, h, k) = (net.inputs(), net.hidden(), net.outputs());
    if calib.is_empty() {
        return Err(ClassifyError::Empty {
            what: "calibration vectors",
        });
    }
    if let Some(index) = calib.iter().position(|v| v.len() != d) {
        return Err(ClassifyError::DimensionMismatch {
            index,
            expected: d,
            got: calib[index].len(),
        });
    }
    if [d, h, k]
        .iter()
        .any(|&n| n == 0 || n > usize::from(u16::MAX))
        || k > MAX_CLASSES
    {
        return Err(ClassifyError::Empty {
            what: "network dimensions within the model format's limits",
        });
    }
    let finite = |a: &[f64]| a.iter().all(|v| v.is_finite());
    let all = [
        net.w1.as_slice(),
        net.b1.as_slice(),
        net.w2.as_slice(),
        net.b2.as_slice(),
    ];
    if !all.iter().all(|s| s.is_some_and(finite)) {
        return Err(ClassifyError::NonFinite {
            what: "the network",
        });
    }
    let max_raw = calib
        .iter()
        .flat_map(|v| v.iter().map(|&r| i32::from(r).unsigned_abs()))
        .max()
        .unwrap_or(0);
    if max_raw == 0 {
        return Err(ClassifyError::ZeroVariance);
    }
    let x_scale = f64::from(max_raw) / Z_SCALE / 127.0;
    Ok(QuantNet {
        x_scale,
        input_rq: quantize_multiplier(127.0 / f64::from(max_raw)),
        l1: quantize_layer(&net.w1, &net.b1, x_scale),
        l2: quantize_layer(&net.w2, &net.b2, 1.0 / 255.0),
        dims: (d, h, k),
    })
}

/// What goes into a blob beside the network.
#[derive(Clone, Debug, PartialEq)]
pub struct BlobExtras<'a> {
    /// `classes × classes` u16 templates.
    pub templates: &'a [u16],
    /// Δ in Q16.
    pub delta_q16: u32,
    /// Class names.
    pub names: &'a [String],
    /// Free-form metadata.
    pub meta: &'a str,
    /// One symmetry byte per class ([`Symmetry::bits`](protogist::mlp::Symmetry::bits)): a version-2
    /// blob; `None` writes version 1.
    pub symmetry: Option<&'a [u8]>,
}

/// Serialises a network and its extras into a `PGML` blob: version 2 with
/// [`BlobExtras::symmetry`], else version 1.
///
/// # Errors
/// [`ClassifyError`] for a name that is empty or longer than 64 bytes, or
/// counts that do not match the dimensions.
pub fn write_blob(q: &QuantNet, x: &BlobExtras<'_>) -> Result<Vec<u8>, ClassifyError> {
    write_blob_as(q, x, InputKind::Shape)
}

/// [`write_blob`] for an input of `kind` (the header's input code).
///
/// # Errors
/// As [`write_blob`]; [`ClassifyError::DimensionMismatch`] when an image
/// kind's length is not the network's input length.
pub fn write_blob_as(
    q: &QuantNet,
    x: &BlobExtras<'_>,
    kind: InputKind,
) -> Result<Vec<u8>, ClassifyError> {
    let (d, h, k) = q.dims;
    if kind != InputKind::Shape && kind.input_len() != d {
        return Err(ClassifyError::DimensionMismatch {
            index: 0,
            expected: kind.input_len(),
            got: d,
        });
    }
    if x.names.len() != k {
        return Err(ClassifyError::LabelCount {
            outputs: k,
            labels: x.names.len(),
        });
    }
    if x.templates.len() != k * k {
        return Err(ClassifyError::DimensionMismatch {
            index: 0,
            expected: k * k,
            got: x.templates.len(),
        });
    }
    if let Some(index) = x
        .names
        .iter()
        .position(|n| n.is_empty() || n.len() > MAX_NAME_LEN)
    {
        return Err(ClassifyError::DimensionMismatch {
            index,
            expected: MAX_NAME_LEN,
            got: x.names[index].len(),
        });
    }
    if let Some(sym) = x.symmetry {
        if sym.len() != k {
            return Err(ClassifyError::DimensionMismatch {
                index: 0,
                expected: k,
                got: sym.len(),
            });
        }
    }
    let version = if x.symmetry.is_some() {
        VERSION
    } else {
        VERSION_1
    };
    let names_len: usize = x.names.iter().map(|n| 1 + n.len()).sum();
    let total =
        blob_len(version, d, h, k, names_len, x.meta.len()).ok_or(ClassifyError::Empty {
            what: "a model small enough for the format",
        })?;
    let mut b = Vec::with_capacity(total);
    b.extend_from_slice(&MAGIC);
    b.extend_from_slice(&version.to_le_bytes());
    b.extend_from_slice(&[kind.code(), WEIGHTS_I8_PER_CHANNEL, HIDDEN_U8, OUTPUT_U16]);
    for n in [d, h, k] {
        b.extend_from_slice(&(n as u16).to_le_bytes());
    }
    b.extend_from_slice(&q.input_rq.0.to_le_bytes());
    b.extend_from_slice(&q.input_rq.1.to_le_bytes());
    b.extend_from_slice(&x.delta_q16.to_le_bytes());
    b.extend_from_slice(&0u32.to_le_bytes());
    b.extend_from_slice(&(names_len as u32).to_le_bytes());
    b.extend_from_slice(&(x.meta.len() as u32).to_le_bytes());
    debug_assert_eq!(b.len(), HEADER_LEN);
    for l in [&q.l1, &q.l2] {
        for &(m, s) in &l.rq {
            b.extend_from_slice(&m.to_le_bytes());
            b.extend_from_slice(&s.to_le_bytes());
        }
    }
    for l in [&q.l1, &q.l2] {
        for &v in &l.b {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    for l in [&q.l1, &q.l2] {
        // Excess-128: the byte is w + 128 (1..=255).
        b.extend(l.w.iter().map(|&v| (i16::from(v) + 128) as u8));
    }
    for &t in x.templates {
        b.extend_from_slice(&t.to_le_bytes());
    }
    if let Some(sym) = x.symmetry {
        b.extend_from_slice(sym);
    }
    for n in x.names {
        b.push(n.len() as u8);
        b.extend_from_slice(n.as_bytes());
    }
    b.extend_from_slice(x.meta.as_bytes());
    let crc = crc32(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    debug_assert_eq!(b.len(), total);
    Ok(b)
}

/// Raw `I4F12` bits as shape elements.
pub fn shape_elems(raw: &[i16]) -> Vec<ShapeElem> {
    raw.iter().map(|&r| ShapeElem::from_bits(r)).collect()
}

/// The integer network's outputs for every vector (in parallel).
///
/// # Errors
/// [`ClassifyError::Mlp`] for a vector of the wrong length.
pub fn int_outputs(model: &Model<'_>, inputs: &[Vec<i16>]) -> Result<Vec<Vec<u16>>, ClassifyError> {
    let (d, h, k) = (model.inputs(), model.hidden(), model.classes());
    inputs
        .par_iter()
        .map_init(
            || {
                (
                    vec![0u32; packed_len(d, h)],
                    vec![0u8; hidden_len(h)],
                    vec![0u16; output_len(k)],
                )
            },
            |(i, hd, o), raw| {
                let mut s = Scratch {
                    input: i,
                    hidden: hd,
                    output: o,
                };
                Ok(forward(model, &shape_elems(raw), &mut s)?.to_vec())
            },
        )
        .collect()
}

/// Q16 scores of every output vector against the model's templates.
///
/// # Errors
/// [`ClassifyError::Mlp`] for a vector of the wrong length.
pub fn int_scores(model: &Model<'_>, outputs: &[Vec<u16>]) -> Result<Vec<Vec<u32>>, ClassifyError> {
    outputs
        .iter()
        .map(|o| {
            let mut s = vec![0u32; model.classes()];
            scores(model, o, &mut s)?;
            Ok(s)
        })
        .collect()
}

/// Class-mean templates (rounded) of u16 outputs, row per class.
///
/// # Errors
/// [`ClassifyError::EmptyClass`] or [`ClassifyError::LabelOutOfRange`].
pub fn int_templates(
    outputs: &[Vec<u16>],
    labels: &[usize],
    classes: usize,
) -> Result<Vec<u16>, ClassifyError> {
    let dim = outputs.first().map_or(0, Vec::len);
    let mut sums = vec![0u64; classes * dim];
    let mut counts = vec![0u64; classes];
    for (o, &c) in outputs.iter().zip(labels) {
        if c >= classes {
            return Err(ClassifyError::LabelOutOfRange { label: c, classes });
        }
        counts[c] += 1;
        for (s, &v) in sums[c * dim..(c + 1) * dim].iter_mut().zip(o) {
            *s += u64::from(v);
        }
    }
    if let Some(class) = counts.iter().position(|&n| n == 0) {
        return Err(ClassifyError::EmptyClass { class });
    }
    Ok(sums
        .chunks(dim.max(1))
        .zip(&counts)
        .flat_map(|(s, &n)| s.iter().map(move |&v| ((v + n / 2) / n) as u16))
        .collect())
}

/// Genuine and impostor scores (as cosines in `[0, 1]`) and ranks from
/// Q16 scores.
pub fn score_sets(scores: &[Vec<u32>], labels: &[usize]) -> super::rules::Evaluation {
    let n = scores.first().map_or(0, Vec::len);
    let mut ev = super::rules::Evaluation {
        classes: n,
        ..Default::default()
    };
    for (s, &label) in scores.iter().zip(labels) {
        let f: Vec<f64> = s.iter().map(|&v| f64::from(v) / 65536.0).collect();
        let rank = super::rules::ranked(&f).iter().position(|&c| c == label);
        ev.ranks.push(rank.map_or(n, |r| r + 1));
        for (c, &v) in f.iter().enumerate() {
            if c == label {
                ev.genuine.push(v);
            } else {
                ev.impostor.push(v);
            }
        }
    }
    ev
}

/// Quantises `net`, computes the templates and Δ on the training data
/// (`calib`, `labels`), and returns the finished blob.
///
/// # Errors
/// As [`quantize_net`] and [`write_blob`]; [`ClassifyError`] for a class
/// without training vector.
pub fn quantize(
    net: &Mlp,
    calib: &[Vec<i16>],
    labels: &[usize],
    names: &[String],
    meta: &str,
) -> Result<Vec<u8>, ClassifyError> {
    quantize_as(net, calib, labels, names, meta, InputKind::Shape)
}

/// [`quantize`] for an input of `kind` (raw `I4F12` values of that kind).
///
/// # Errors
/// As [`quantize`] and [`write_blob_as`].
pub fn quantize_as(
    net: &Mlp,
    calib: &[Vec<i16>],
    labels: &[usize],
    names: &[String],
    meta: &str,
    kind: InputKind,
) -> Result<Vec<u8>, ClassifyError> {
    let q = quantize_net(net, calib)?;
    let write = |x: &BlobExtras<'_>| write_blob_as(&q, x, kind);
    let k = q.dims.2;
    let zeros = vec![0u16; k * k];
    let draft = write(&BlobExtras {
        templates: &zeros,
        delta_q16: 0,
        names,
        meta,
        symmetry: None,
    })?;
    let model = Model::parse(&draft).map_err(|_| ClassifyError::Empty {
        what: "a well-formed draft model",
    })?;
    let outputs = int_outputs(&model, calib)?;
    let templates = int_templates(&outputs, labels, k)?;
    let with_templates = write(&BlobExtras {
        templates: &templates,
        delta_q16: 0,
        names,
        meta,
        symmetry: None,
    })?;
    let model = Model::parse(&with_templates).map_err(|_| ClassifyError::Empty {
        what: "a well-formed draft model",
    })?;
    let ev = score_sets(&int_scores(&model, &outputs)?, labels);
    let delta_q16 = if k > 1 {
        let det = Det::sweep(&ev.genuine, &ev.impostor)?;
        let t = det
            .points()
            .iter()
            .find(|p| p.far <= p.frr)
            .map_or(f64::INFINITY, |p| p.threshold);
        (t * 65536.0).round().min(f64::from(u32::MAX)) as u32
    } else {
        0
    };
    write(&BlobExtras {
        templates: &templates,
        delta_q16,
        names,
        meta,
        symmetry: None,
    })
}

/// A Rust source file holding `blob` as `pub static MODEL: [u8; N]`.
pub fn emit_rust(blob: &[u8], what: &str) -> String {
    let mut s = format!(
        "//! Generated by `protogist quantize --emit-rust`: {what}.\n\
         //! A `PGML` v{} model blob (docs/MODEL_FORMAT.md); parse it with\n\
         //! `protogist::mlp::Model::parse(&MODEL)`.\n\n\
         /// The model blob, {} bytes.\n#[rustfmt::skip]\npub static MODEL: [u8; {}] = [\n",
        u16::from_le_bytes([
            blob.get(4).copied().unwrap_or(0),
            blob.get(5).copied().unwrap_or(0)
        ]),
        blob.len(),
        blob.len()
    );
    for chunk in blob.chunks(16) {
        s.push_str("   ");
        for b in chunk {
            s.push_str(&format!(" 0x{b:02x},"));
        }
        s.push('\n');
    }
    s.push_str("];\n");
    s
}

/// The log-sigmoid table recomputed in `f64`: `round(65535 · 256 · σ(i/64))`.
pub fn logsig_table() -> Vec<u32> {
    (0..protogist::mlp::logsig_table::LOGSIG_Q8.len())
        .map(|i| (65535.0 * 256.0 * super::mlp::logsig(i as f64 / 64.0)).round() as u32)
        .collect()
}

/// `ρ = ½ + ½·2^−right` of a requantisation pair (docs/ERROR_BOUNDS.md §9).
fn rho((_, shift): (i32, i32)) -> f64 {
    0.5 + 0.5 * 2f64.powi(-(-shift).max(0))
}

/// The derived bound `B_k` (docs/ERROR_BOUNDS.md §9) on
/// `|ŷ_k − y_k|` (in units of σ, 1 = 65535 LSB) for the raw input `raw`,
/// with the float network `net` and its quantisation `q`; also returns the
/// float outputs `y`.
pub fn output_error_bound(net: &Mlp, q: &QuantNet, raw: &[i16]) -> (Vec<f64>, Vec<f64>) {
    use super::mlp::logsig;
    let x: Vec<f64> = raw.iter().map(|&r| f64::from(r) / Z_SCALE).collect();
    let rq_mul = 4096.0 * 2f64.powi(-31);
    let eps_x = q.x_scale * (rho(q.input_rq) + 127.0 * 2f64.powi(-31));
    let sum_abs_x: f64 = x.iter().map(|v| v.abs()).sum();
    let (d, h_n, _) = q.dims;
    let mut h = vec![0f64; h_n];
    let mut eps_h = vec![0f64; h_n];
    for (i, (hv, eh)) in h.iter_mut().zip(&mut eps_h).enumerate() {
        let s = q.l1.w_scale[i];
        let row = &q.l1.w[i * d..(i + 1) * d];
        let sum_w: f64 = row.iter().map(|&w| s * f64::from(w).abs()).sum();
        let z = net.w1.row(i).dot(&ndarray::ArrayView1::from(&x)) + net.b1[i];
        let e_a = eps_x * sum_w + s / 2.0 * sum_abs_x + q.x_scale * s / 2.0;
        let e_z = e_a + (rho(q.l1.rq[i]) + (z.abs() + e_a) * rq_mul) / Z_SCALE;
        *hv = logsig(z);
        *eh = e_z / 4.0 + 0.504 / 255.0;
    }
    let mut y = vec![];
    let mut bound = vec![];
    for k in 0..q.dims.2 {
        let s = q.l2.w_scale[k];
        let row = &q.l2.w[k * h_n..(k + 1) * h_n];
        let z = net.w2.row(k).dot(&ndarray::ArrayView1::from(&h)) + net.b2[k];
        let e_a: f64 = row
            .iter()
            .zip(&eps_h)
            .map(|(&w, &e)| s * f64::from(w).abs() * e)
            .sum::<f64>()
            + s / 2.0 * h.iter().sum::<f64>()
            + s / (2.0 * 255.0);
        let e_z = e_a + (rho(q.l2.rq[k]) + (z.abs() + e_a) * rq_mul) / Z_SCALE;
        y.push(logsig(z));
        bound.push(e_z / 4.0 + 1.0 / 65535.0);
    }
    (y, bound)
}

/// A core model error as text.
pub fn model_error(e: ModelError) -> String {
    e.to_string()
}

#[cfg(test)]
mod tests;
