//! The per-class symmetry of a model (blob version 2,
//! docs/MODEL_FORMAT.md, "Symmetry"), for the mirror check.
//!
//! Class `c` is taken as symmetric under a mirror when the quantised
//! model names the mirrored shape vectors of `c`'s clean silhouettes (the
//! held-out ones, `symmetry_cmd::symmetry_samples`) as `c` at least
//! [`SYMMETRY_MIN_RATIO`] times as often as it names the unmirrored ones
//! (that rate above zero; plain identification, Δ included;
//! [`mirror_agreement`], [`Agreement::symmetry`]); the flags go into a
//! version-2 blob ([`with_symmetry`]).

use super::quant::shape_elems;
use super::ClassifyError;
use protogist::mlp::blob::{crc32, Model, Symmetry, CRC_LEN, HEADER_LEN, VERSION};
use protogist::mlp::InputKind;
use protogist::mlp::{forward, hidden_len, identify, output_len, packed_len, Identity, Scratch};
use protogist::shape::{Mirror, ShapeElem, ShapeVector, SHAPE_LEN};
use rayon::prelude::*;

/// The least ratio of the rate at which a class's mirrored
/// vectors are named as the class to the rate for its unmirrored ones for
/// the class to count as symmetric under the mirror (relative, so that a
/// class the model names only moderately well, such as the circle, is not
/// held to a bar its own silhouettes do not reach).
pub const SYMMETRY_MIN_RATIO: f64 = 0.9;

/// One class's identification rates on its silhouettes' vectors
/// ([`mirror_agreement`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Agreement {
    /// The share of the vectors the model names as the class.
    pub plain: f64,
    /// The share of their mirror images it names as the class, per mirror
    /// ([`Mirror::ALL`] order).
    pub mirrored: [f64; 2],
}

impl Agreement {
    /// The symmetry under the relative rule: mirror `m` when
    /// `plain > 0` and `mirrored[m] ≥ min_ratio · plain`.
    #[must_use]
    pub fn symmetry(&self, min_ratio: f64) -> Symmetry {
        Mirror::ALL
            .into_iter()
            .zip(self.mirrored)
            .filter(|&(_, r)| self.plain > 0.0 && r >= min_ratio * self.plain)
            .fold(Symmetry::NONE, |s, (m, _)| s.with(m))
    }
}

/// Per class, the share of the class's vectors (`inputs`, labelled
/// `labels`) that `model` names as the class, unmirrored and under each
/// mirror (plain identification: best cosine, reaching Δ).
///
/// # Errors
/// [`ClassifyError::DimensionMismatch`] when the model does not take
/// 720-element shape vectors or a vector is not 720 long,
/// [`ClassifyError::LabelOutOfRange`], [`ClassifyError::EmptyClass`].
pub fn mirror_agreement(
    model: &Model<'_>,
    inputs: &[Vec<i16>],
    labels: &[usize],
) -> Result<Vec<Agreement>, ClassifyError> {
    let (d, h, k) = (model.inputs(), model.hidden(), model.classes());
    if d != SHAPE_LEN || model.input_kind() != InputKind::Shape {
        return Err(ClassifyError::DimensionMismatch {
            index: 0,
            expected: SHAPE_LEN,
            got: d,
        });
    }
    let hits: Vec<[bool; 3]> = inputs
        .par_iter()
        .zip(labels)
        .enumerate()
        .map_init(
            || {
                (
                    vec![0u32; packed_len(d, h)],
                    vec![0u8; hidden_len(h)],
                    vec![0u16; output_len(k)],
                )
            },
            |(i, hd, o), (index, (raw, &c))| {
                let x: ShapeVector = shape_elems(raw).try_into().map_err(|v: Vec<ShapeElem>| {
                    ClassifyError::DimensionMismatch {
                        index,
                        expected: SHAPE_LEN,
                        got: v.len(),
                    }
                })?;
                let mut hit = [false; 3];
                let modes = [None, Some(Mirror::ALL[0]), Some(Mirror::ALL[1])];
                for (m, hit) in modes.into_iter().zip(&mut hit) {
                    let mut v = x;
                    if let Some(m) = m {
                        m.apply(&x, &mut v);
                    }
                    let mut s = Scratch {
                        input: i,
                        hidden: hd,
                        output: o,
                    };
                    let out = forward(model, &v, &mut s)?;
                    *hit = identify(model, out)?.0 == Identity::Known(c as u16);
                }
                Ok(hit)
            },
        )
        .collect::<Result<_, ClassifyError>>()?;
    let mut counts = vec![(0usize, [0usize; 3]); k];
    for (hit, &c) in hits.iter().zip(labels) {
        let e = counts.get_mut(c).ok_or(ClassifyError::LabelOutOfRange {
            label: c,
            classes: k,
        })?;
        e.0 += 1;
        for (n, &h) in e.1.iter_mut().zip(hit) {
            *n += usize::from(h);
        }
    }
    counts
        .iter()
        .enumerate()
        .map(|(class, &(n, hits))| {
            if n == 0 {
                return Err(ClassifyError::EmptyClass { class });
            }
            let r = hits.map(|h| h as f64 / n as f64);
            Ok(Agreement {
                plain: r[0],
                mirrored: [r[1], r[2]],
            })
        })
        .collect()
}

/// `blob` (version 1 or 2) as a version-2 blob with the symmetry bytes
/// `symmetry` (one per class); every other byte as it was, the CRC
/// recomputed.
///
/// # Errors
/// [`ClassifyError::Model`] when `blob` or the result does not parse (a
/// flag on a model that does not take shape vectors),
/// [`ClassifyError::DimensionMismatch`] for a count other than the
/// classes.
pub fn with_symmetry(blob: &[u8], symmetry: &[u8]) -> Result<Vec<u8>, ClassifyError> {
    let m = Model::parse(blob)?;
    let (d, h, k) = (m.inputs(), m.hidden(), m.classes());
    if symmetry.len() != k {
        return Err(ClassifyError::DimensionMismatch {
            index: 0,
            expected: k,
            got: symmetry.len(),
        });
    }
    let at = HEADER_LEN + 12 * h + 12 * k + h * d + k * h + 2 * k * k;
    let old = if m.has_symmetry_section() { k } else { 0 };
    let body = &blob[..blob.len() - CRC_LEN];
    let mut b = Vec::with_capacity(body.len() + k + CRC_LEN);
    b.extend_from_slice(&body[..at]);
    b.extend_from_slice(symmetry);
    b.extend_from_slice(&body[at + old..]);
    b[4..6].copy_from_slice(&VERSION.to_le_bytes());
    let crc = crc32(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    Model::parse(&b)?;
    Ok(b)
}
