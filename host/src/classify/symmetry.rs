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

use super::mirror::mirror_vector;
use super::quant::int_outputs;
use super::ClassifyError;
use protogist::mlp::blob::{crc32, Model, Symmetry, CRC_LEN, HEADER_LEN, VERSION};
use protogist::mlp::InputKind;
use protogist::mlp::{identify, Identity};
use protogist::shape::{Mirror, SHAPE_LEN};

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
    /// The symmetry under the rule: mirror `m` when `plain > 0` and
    /// `mirrored[m] ≥` [`SYMMETRY_MIN_RATIO`] `· plain`.
    #[must_use]
    pub fn symmetry(&self) -> Symmetry {
        Mirror::ALL
            .into_iter()
            .zip(self.mirrored)
            .filter(|&(_, r)| self.plain > 0.0 && r >= SYMMETRY_MIN_RATIO * self.plain)
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
    let (d, k) = (model.inputs(), model.classes());
    if d != SHAPE_LEN || model.input_kind() != InputKind::Shape {
        return Err(ClassifyError::DimensionMismatch {
            index: 0,
            expected: SHAPE_LEN,
            got: d,
        });
    }
    // The vectors' mirror images ([`Mirror::ALL`] order), then the integer
    // network's outputs on the vectors and on each mirror's images.
    let mirrored = Mirror::ALL.map(|m| {
        inputs
            .iter()
            .enumerate()
            .map(|(index, raw)| {
                mirror_vector(m, raw).map_err(|_| ClassifyError::DimensionMismatch {
                    index,
                    expected: SHAPE_LEN,
                    got: raw.len(),
                })
            })
            .collect::<Result<Vec<_>, _>>()
    });
    let [v, h] = mirrored;
    let outputs = [
        int_outputs(model, inputs)?,
        int_outputs(model, &v?)?,
        int_outputs(model, &h?)?,
    ];
    let mut counts = vec![(0usize, [0usize; 3]); k];
    for (n, &c) in labels.iter().enumerate().take(inputs.len()) {
        let e = counts.get_mut(c).ok_or(ClassifyError::LabelOutOfRange {
            label: c,
            classes: k,
        })?;
        e.0 += 1;
        for (hits, out) in e.1.iter_mut().zip(&outputs) {
            *hits += usize::from(identify(model, &out[n])?.0 == Identity::Known(c as u16));
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
