//! The mirror check: identification that also asks the network about the
//! object's mirror images, class by class.
//!
//! A class drawn in one pose may look the same under a mirror about the
//! vertical axis, the horizontal axis, both or neither (the model blob's
//! per-class [`Symmetry`], version 2). For an object `x` the network runs
//! on `x` and on each mirror ([`Mirror`], an exact permutation of the
//! shape vector) that some class has; class `c`'s score is the cosine of
//! its template with the mean of the outputs over `x` and the mirrors `c`
//! has (u16, rounded half up), and the classes are ranked by these scores
//! as [`super::top_k`] ranks. A class without symmetry is scored on `x`'s
//! outputs alone, so a model without symmetry gives exactly
//! [`super::top_k`]'s ranking, with one forward pass.
//!
//! Cost: one forward pass per mirror in [`Model::any_symmetry`] beside
//! `x`'s (two more for a model with both), and `K²` more operations for
//! the per-class means; memory: [`mirror_scratch_bytes`].
//! [`mirror_check_below_with`] spends them only on the objects whose own
//! best cosine is under a bar, where the check changes rankings.

use super::blob::{Model, Symmetry};
use super::rules::{cosine_q16, rank_by};
use super::{check_scratch, forward_with, MacKernel, MlpError, Ranked, SafeKernel, Scratch};
use crate::shape::{Mirror, ShapeElem, ShapeVector, SHAPE_LEN};

/// Views of an object the check may run the network on: the object, its
/// mirror about the vertical axis, about the horizontal axis.
pub const MIRROR_VIEWS: usize = 3;

/// Elements of [`MirrorScratch::outputs`] for `classes` outputs.
pub const fn mirror_outputs_len(classes: usize) -> usize {
    MIRROR_VIEWS * classes
}

/// Elements of [`MirrorScratch::mean`] for `classes` outputs.
pub const fn mirror_mean_len(classes: usize) -> usize {
    classes
}

/// Bytes of a [`MirrorScratch`] for `classes` outputs (beside the
/// network's own [`super::scratch_bytes`]): the mirrored vector, the
/// outputs of the three views and one class's mean.
pub const fn mirror_scratch_bytes(classes: usize) -> usize {
    2 * SHAPE_LEN + 2 * (mirror_outputs_len(classes) + mirror_mean_len(classes))
}

/// Caller-owned memory of the mirror check.
#[derive(Debug)]
pub struct MirrorScratch<'a> {
    /// The mirrored shape vector ([`SHAPE_LEN`] elements).
    pub vector: &'a mut [ShapeElem],
    /// The outputs of the views, [`MIRROR_VIEWS`] rows of one per class:
    /// the object's, its vertical mirror's, its horizontal mirror's
    /// ([`mirror_outputs_len`]).
    pub outputs: &'a mut [u16],
    /// One class's mean outputs ([`mirror_mean_len`]).
    pub mean: &'a mut [u16],
}

/// The row of [`MirrorScratch::outputs`] of a mirror's view.
const fn view(m: Mirror) -> usize {
    match m {
        Mirror::Vertical => 1,
        Mirror::Horizontal => 2,
    }
}

/// [`mirror_check_with`] with the portable kernel.
///
/// # Errors
/// As [`mirror_check_with`].
pub fn mirror_check(
    model: &Model<'_>,
    input: &[ShapeElem],
    scratch: &mut Scratch<'_>,
    mirror: &mut MirrorScratch<'_>,
    ranked: &mut [Ranked],
) -> Result<usize, MlpError> {
    mirror_check_with::<SafeKernel>(model, input, scratch, mirror, ranked)
}

/// Runs the network on the shape vector `input` and on each mirror some
/// class of `model` has, and ranks the classes by the cosine of their
/// template with their mean output (see the module doc) into `ranked`,
/// best first, ties to the lower class; returns how many entries were
/// filled (`min(ranked.len(), classes)`).
///
/// # Errors
/// [`MlpError::FeatureSize`] when `input` is not the model's length,
/// [`MlpError::ScratchTooSmall`] for a short buffer (the mirrored vector
/// is checked only when the model has a symmetry).
pub fn mirror_check_with<K: MacKernel>(
    model: &Model<'_>,
    input: &[ShapeElem],
    scratch: &mut Scratch<'_>,
    mirror: &mut MirrorScratch<'_>,
    ranked: &mut [Ranked],
) -> Result<usize, MlpError> {
    mirror_check_below_with::<K>(model, input, scratch, mirror, ranked, u32::MAX)
}

/// [`mirror_check_with`] for the objects the network is unsure of: the
/// mirrors run only when the object's own best cosine (the plain
/// identification's, [`super::top_k`]) is below `below_q16` (Q16); else
/// `ranked` is the plain ranking, after one forward pass. `u32::MAX`
/// checks every object, as [`mirror_check_with`].
///
/// # Errors
/// As [`mirror_check_with`].
pub fn mirror_check_below_with<K: MacKernel>(
    model: &Model<'_>,
    input: &[ShapeElem],
    scratch: &mut Scratch<'_>,
    mirror: &mut MirrorScratch<'_>,
    ranked: &mut [Ranked],
    below_q16: u32,
) -> Result<usize, MlpError> {
    let k = model.classes();
    check_scratch("outputs", mirror_outputs_len(k), mirror.outputs.len())?;
    check_scratch("mean", mirror_mean_len(k), mirror.mean.len())?;
    let out = forward_with::<K>(model, input, scratch)?;
    copy_view(out, mirror.outputs, 0, k);
    if below_q16 < u32::MAX {
        let filled = super::top_k(model, out, ranked)?;
        if ranked.first().is_none_or(|b| b.score >= below_q16) {
            return Ok(filled);
        }
    }
    let any = model.any_symmetry();
    if any != Symmetry::NONE {
        // The model parser allows a symmetry only on SHAPE_LEN inputs,
        // and `forward_with` checked the input's length.
        let x: &ShapeVector = input.try_into().map_err(|_| MlpError::FeatureSize {
            expected: SHAPE_LEN,
            got: input.len(),
        })?;
        let got = mirror.vector.len();
        let v: &mut ShapeVector = mirror
            .vector
            .get_mut(..SHAPE_LEN)
            .and_then(|s| s.try_into().ok())
            .ok_or(MlpError::ScratchTooSmall {
                buffer: "mirrored vector",
                needed: SHAPE_LEN,
                got,
            })?;
        for m in Mirror::ALL {
            if any.has(m) {
                m.apply(x, v);
                let out = forward_with::<K>(model, v, scratch)?;
                copy_view(out, mirror.outputs, view(m), k);
            }
        }
    }
    mirror_top_k(model, mirror.outputs, mirror.mean, ranked)
}

fn copy_view(out: &[u16], outputs: &mut [u16], row: usize, k: usize) {
    if let Some(dst) = outputs.get_mut(row * k..(row + 1) * k) {
        for (d, &o) in dst.iter_mut().zip(out) {
            *d = o;
        }
    }
}

/// The ranking step of [`mirror_check_with`] on given outputs: `outputs`
/// holds [`MIRROR_VIEWS`] rows of one output per class (the object's, its
/// vertical mirror's, its horizontal mirror's; a mirror's row is read only
/// for the classes that have that mirror); class `c` is scored by the
/// cosine of its template with the rounded mean of the rows of `x` and of
/// `c`'s mirrors, computed in `mean`.
///
/// # Errors
/// [`MlpError::ScratchTooSmall`] when `outputs` or `mean` is short.
pub fn mirror_top_k(
    model: &Model<'_>,
    outputs: &[u16],
    mean: &mut [u16],
    ranked: &mut [Ranked],
) -> Result<usize, MlpError> {
    let k = model.classes();
    check_scratch("outputs", mirror_outputs_len(k), outputs.len())?;
    check_scratch("mean", mirror_mean_len(k), mean.len())?;
    let mean = mean.get_mut(..k).unwrap_or(&mut []);
    Ok(rank_by(
        k,
        |c| {
            mirror_mean(model.symmetry(c), outputs, mean);
            model.template(c).map_or(0, |t| cosine_q16(mean, t))
        },
        ranked,
    ))
}

/// The mean of the object's outputs and those of the mirrors in
/// `symmetry`, each rounded half up: `mean[j] = (Σ_v outputs[v·K + j] + n/2) / n`
/// over the `n` views, `K = mean.len()` (missing values read 0).
pub fn mirror_mean(symmetry: Symmetry, outputs: &[u16], mean: &mut [u16]) {
    let k = mean.len();
    let row = |r: usize| outputs.get(r * k..(r + 1) * k).unwrap_or(&[]);
    let n = 1 + symmetry.count();
    for (j, m) in mean.iter_mut().enumerate() {
        let mut sum = u32::from(row(0).get(j).copied().unwrap_or(0));
        for mir in Mirror::ALL {
            if symmetry.has(mir) {
                sum += u32::from(row(view(mir)).get(j).copied().unwrap_or(0));
            }
        }
        // At most 3 · 65535 + 1: fits u32, and the mean fits u16 (n >= 1;
        // `checked_div` leaves no division-by-zero panic path to link).
        *m = (sum + n / 2).checked_div(n).unwrap_or(0) as u16;
    }
}
