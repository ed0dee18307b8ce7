//! The classification rules on the network outputs: cosine scores with the
//! class templates, the ranked list, identification and verification.

use super::blob::le_u16;
use super::{Identity, MlpError, Model, Ranked};
use crate::fixed::isqrt_floor_u128;

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
    Ok(rank_by(
        k,
        |c| model.template(c).map_or(0, |t| cosine_q16(outputs, t)),
        ranked,
    ))
}

/// The best `ranked.len()` of `classes` classes by `score(c)`, best first,
/// ties to the lower class; returns how many entries were filled.
pub(crate) fn rank_by(
    classes: usize,
    mut score: impl FnMut(usize) -> u32,
    ranked: &mut [Ranked],
) -> usize {
    let mut filled = 0usize;
    for c in 0..classes {
        let score = score(c);
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
            // Shift the tail one place right, dropping its last entry, with
            // `entry` first.
            let mut carry = entry;
            for slot in tail.iter_mut() {
                core::mem::swap(slot, &mut carry);
            }
        }
        filled = (filled + 1).min(ranked.len());
    }
    filled
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
