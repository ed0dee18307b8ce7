//! The f32/f64 reference of core's mirror check (`protogist::mlp::mirror`):
//! the float network on a shape vector and on its mirror images, each
//! class scored by the cosine of its template with the mean output over
//! the vector and the mirrors the class has. Same names and argument order
//! as core (the core's model split into network, templates and
//! symmetry); no rounding of the mean, so the integer path's is the only
//! difference beside the network's (docs/ERROR_BOUNDS.md §9).

use super::mlp::Mlp;
use super::rules::{cosine, ranked, Templates};
use super::ClassifyError;
use ndarray::Array2;
use protogist::mlp::{Symmetry, MIRROR_VIEWS};
use protogist::shape::{Mirror, SHAPE_LEN};

/// The row of a mirror's view ([`MIRROR_VIEWS`] rows: the vector, its
/// vertical mirror, its horizontal mirror), as core orders them.
fn view(m: Mirror) -> usize {
    match m {
        Mirror::Vertical => 1,
        Mirror::Horizontal => 2,
    }
}

/// `x` mirrored by `m` (a permutation, [`Mirror::source`]).
///
/// # Errors
/// [`ClassifyError::DimensionMismatch`] when `x` is not 720 long.
pub fn mirror_vector<T: Copy>(m: Mirror, x: &[T]) -> Result<Vec<T>, ClassifyError> {
    if x.len() != SHAPE_LEN {
        return Err(ClassifyError::DimensionMismatch {
            index: 0,
            expected: SHAPE_LEN,
            got: x.len(),
        });
    }
    Ok((0..SHAPE_LEN).map(|i| x[m.source(i)]).collect())
}

/// The float outputs of the views the check runs (a mirror's row only when
/// `any` has it, else zeros), [`MIRROR_VIEWS`] rows.
///
/// # Errors
/// As [`mirror_vector`].
pub fn mirror_outputs(
    net: &Mlp,
    input: &[f64],
    any: Symmetry,
) -> Result<Vec<Vec<f64>>, ClassifyError> {
    let mut rows = vec![vec![0.0; net.outputs()]; MIRROR_VIEWS];
    let run = |x: &[f64]| -> Vec<f64> {
        let a = Array2::from_shape_vec((1, x.len()), x.to_vec()).expect("one row");
        net.predict(a.view()).row(0).to_vec()
    };
    rows[0] = run(input);
    for m in Mirror::ALL {
        if any.has(m) {
            rows[view(m)] = run(&mirror_vector(m, input)?);
        }
    }
    Ok(rows)
}

/// The mean of the vector's outputs and those of the mirrors in
/// `symmetry` (unrounded).
pub fn mirror_mean(symmetry: Symmetry, outputs: &[Vec<f64>]) -> Vec<f64> {
    let mut rows = vec![&outputs[0]];
    for m in Mirror::ALL {
        if symmetry.has(m) {
            rows.push(&outputs[view(m)]);
        }
    }
    let n = rows.len() as f64;
    (0..outputs[0].len())
        .map(|j| rows.iter().map(|r| r[j]).sum::<f64>() / n)
        .collect()
}

/// Every class's score: the cosine of its template with its
/// [`mirror_mean`] (rank them with [`ranked`]).
///
/// # Errors
/// [`ClassifyError::LabelCount`] when `symmetry` is not one per class, or
/// as [`Templates::scores`].
pub fn mirror_top_k(
    templates: &Templates,
    symmetry: &[Symmetry],
    outputs: &[Vec<f64>],
) -> Result<Vec<f64>, ClassifyError> {
    if symmetry.len() != templates.classes() {
        return Err(ClassifyError::LabelCount {
            outputs: templates.classes(),
            labels: symmetry.len(),
        });
    }
    symmetry
        .iter()
        .enumerate()
        .map(|(c, &s)| {
            let mean: Vec<f32> = mirror_mean(s, outputs).iter().map(|&v| v as f32).collect();
            let t = templates
                .template(c)
                .ok_or(ClassifyError::LabelOutOfRange {
                    label: c,
                    classes: templates.classes(),
                })?;
            if mean.len() != t.len() {
                return Err(ClassifyError::DimensionMismatch {
                    index: c,
                    expected: t.len(),
                    got: mean.len(),
                });
            }
            Ok(cosine(&mean, t))
        })
        .collect()
}

/// The mirror check on the float network: scores per class (see the
/// module doc); the best class is `ranked(&scores)[0]`.
///
/// # Errors
/// As [`mirror_outputs`] and [`mirror_top_k`].
pub fn mirror_check(
    net: &Mlp,
    templates: &Templates,
    symmetry: &[Symmetry],
    input: &[f64],
) -> Result<Vec<f64>, ClassifyError> {
    let any = symmetry.iter().fold(Symmetry::NONE, |a, s| {
        Symmetry::from_bits(a.bits() | s.bits()).unwrap_or(a)
    });
    let outputs = mirror_outputs(net, input, any)?;
    mirror_top_k(templates, symmetry, &outputs)
}

/// The best class of [`mirror_check`]'s scores.
pub fn best(scores: &[f64]) -> Option<usize> {
    ranked(scores).first().copied()
}
