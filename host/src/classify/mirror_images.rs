//! Training on mirror images (`protogist train --mirror-images`): each
//! training vector of a class that has a mirror symmetry is also trained
//! on mirrored, so that the network sees the mirror images the class has
//! (docs/CLASSIFY.md, "Training on mirror images").
//!
//! The symmetry has to be known before there is a network, so it is
//! measured without one: class `c` has mirror `m` when the nearest other
//! clean silhouette of the dataset (leave one out, by the cosine of the
//! shape vectors) is of class `c` for the mirrored silhouettes of `c` at
//! least [`SYMMETRY_MIN_RATIO`] times as often as for the unmirrored ones
//! ([`nearest_agreement`]; the rule of the model's own
//! [`Agreement::symmetry`]). Leave one out over the whole dataset rather
//! than the held-out split, so that each class's rates rest on all its
//! silhouettes: with the 100 held-out silhouettes a class of the shipped
//! dataset, the circle's (55: 62 / 49 %) and the pentagon's (63: 55 / 1 %)
//! rates fell under the bar by sampling alone.

use super::dataset::Sample;
use super::mirror::mirror_vector;
use super::symmetry::Agreement;
#[cfg(doc)]
use super::symmetry::SYMMETRY_MIN_RATIO;
use super::ClassifyError;
use ndarray::{Array2, Axis};
use protogist::mlp::Symmetry;
use protogist::shape::{Mirror, SHAPE_LEN};

/// The rows of `vectors`, each scaled to unit length (a zero row stays
/// zero).
fn unit_rows(vectors: &[&[f32]]) -> Result<Array2<f32>, ClassifyError> {
    let mut a = Array2::zeros((vectors.len(), SHAPE_LEN));
    for (index, (mut row, v)) in a.rows_mut().into_iter().zip(vectors).enumerate() {
        if v.len() != SHAPE_LEN {
            return Err(ClassifyError::DimensionMismatch {
                index,
                expected: SHAPE_LEN,
                got: v.len(),
            });
        }
        let norm = v
            .iter()
            .map(|&x| f64::from(x) * f64::from(x))
            .sum::<f64>()
            .sqrt();
        if norm > 0.0 {
            for (r, &x) in row.iter_mut().zip(v.iter()) {
                *r = (f64::from(x) / norm) as f32;
            }
        }
    }
    Ok(a)
}

/// Query rows per block of [`nearest_agreement`]'s cosines.
const BLOCK: usize = 2048;

/// Per class, the share of the class's `samples` whose nearest other
/// sample (leave one out: the largest cosine of the shape vectors `x`, the
/// first on a tie) is of the class, unmirrored and with the sample under
/// each mirror ([`Mirror::ALL`] order).
///
/// # Errors
/// [`ClassifyError::DimensionMismatch`] for a vector not 720 long,
/// [`ClassifyError::LabelOutOfRange`] for a label not below `classes`,
/// [`ClassifyError::EmptyClass`] for a class without a sample.
pub fn nearest_agreement(
    samples: &[&Sample],
    classes: usize,
) -> Result<Vec<Agreement>, ClassifyError> {
    let mut counts = vec![0usize; classes];
    for s in samples {
        *counts
            .get_mut(s.label)
            .ok_or(ClassifyError::LabelOutOfRange {
                label: s.label,
                classes,
            })? += 1;
    }
    if let Some(class) = counts.iter().position(|&n| n == 0) {
        return Err(ClassifyError::EmptyClass { class });
    }
    let plain: Vec<&[f32]> = samples.iter().map(|s| s.x.as_slice()).collect();
    let refs = unit_rows(&plain)?;
    let mut hits = vec![[0usize; 3]; classes];
    let mirrors = Mirror::ALL.map(Some);
    for (v, mirror) in [None].into_iter().chain(mirrors).enumerate() {
        for (b, block) in samples.chunks(BLOCK).enumerate() {
            let rows = block
                .iter()
                .map(|s| match mirror {
                    Some(m) => mirror_vector(m, &s.x),
                    None => Ok(s.x.clone()),
                })
                .collect::<Result<Vec<_>, _>>()?;
            let q = unit_rows(&rows.iter().map(Vec::as_slice).collect::<Vec<_>>())?;
            let cos = q.dot(&refs.t());
            for (i, (row, s)) in cos.axis_iter(Axis(0)).zip(block).enumerate() {
                let own = b * BLOCK + i;
                let best = row.iter().enumerate().filter(|&(j, _)| j != own).fold(
                    (own, f32::NEG_INFINITY),
                    |b, (j, &c)| if c > b.1 { (j, c) } else { b },
                );
                hits[s.label][v] += usize::from(best.0 != own && samples[best.0].label == s.label);
            }
        }
    }
    Ok(hits
        .iter()
        .zip(&counts)
        .map(|(h, &n)| {
            let r = h.map(|k| k as f64 / n as f64);
            Agreement {
                plain: r[0],
                mirrored: [r[1], r[2]],
            }
        })
        .collect())
}

/// `samples` followed by the mirror images of each sample under every
/// mirror its class has in `symmetry` (one entry per class; samples in
/// order, [`Mirror::ALL`] order within a sample), each with the sample's
/// label and its key marked with the mirror.
///
/// # Errors
/// [`ClassifyError::DimensionMismatch`] for a vector not 720 long,
/// [`ClassifyError::LabelOutOfRange`] for a label without a symmetry.
pub fn with_mirror_images(
    samples: &[Sample],
    symmetry: &[Symmetry],
) -> Result<Vec<Sample>, ClassifyError> {
    let mut out = samples.to_vec();
    for s in samples {
        let sym = symmetry
            .get(s.label)
            .ok_or(ClassifyError::LabelOutOfRange {
                label: s.label,
                classes: symmetry.len(),
            })?;
        for m in Mirror::ALL.into_iter().filter(|&m| sym.has(m)) {
            out.push(Sample {
                key: format!("{}#{}", s.key, mirror_name(m)),
                label: s.label,
                x: mirror_vector(m, &s.x)?,
                shape: mirror_vector(m, &s.shape)?,
            });
        }
    }
    Ok(out)
}

/// What [`add_mirror_images`] did: each class's rates under
/// [`nearest_agreement`], and how many vectors it added.
#[derive(Clone, Debug, PartialEq)]
pub struct MirrorImages {
    /// Per class, the nearest-neighbour rates the symmetry comes from.
    pub rates: Vec<Agreement>,
    /// Mirror images added.
    pub added: usize,
}

/// `train_set` [`with_mirror_images`], the symmetry of each of the
/// `classes` classes measured by [`nearest_agreement`] on `dataset` (every
/// clean silhouette): what `train --mirror-images` trains on and what
/// `quantize` calibrates on for such a model.
///
/// # Errors
/// As [`nearest_agreement`] and [`with_mirror_images`].
pub fn add_mirror_images(
    dataset: &[Sample],
    train_set: &[Sample],
    classes: usize,
) -> Result<(Vec<Sample>, MirrorImages), ClassifyError> {
    let rates = nearest_agreement(&dataset.iter().collect::<Vec<_>>(), classes)?;
    let flags: Vec<Symmetry> = rates.iter().map(Agreement::symmetry).collect();
    let with = with_mirror_images(train_set, &flags)?;
    let added = with.len() - train_set.len();
    Ok((with, MirrorImages { rates, added }))
}

/// `V` or `H`, as the summaries write them.
const fn mirror_name(m: Mirror) -> &'static str {
    match m {
        Mirror::Vertical => "V",
        Mirror::Horizontal => "H",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sample of class `label` whose vector is `f` of the element index.
    fn sample(label: usize, f: impl Fn(usize) -> f32) -> Sample {
        let x: Vec<f32> = (0..SHAPE_LEN).map(f).collect();
        Sample {
            key: format!("{label}/x"),
            label,
            shape: x.iter().map(|&v| (v * 100.0) as i16).collect(),
            x,
        }
    }

    #[test]
    fn mirror_images_follow_the_symmetry_of_each_class() {
        let s = [sample(0, |i| i as f32), sample(1, |i| (i % 7) as f32)];
        let sym = [
            Symmetry::NONE
                .with(Mirror::Vertical)
                .with(Mirror::Horizontal),
            Symmetry::NONE,
        ];
        let out = with_mirror_images(&s, &sym).unwrap();
        assert_eq!(out.len(), 4);
        assert_eq!(&out[..2], &s);
        for (o, m) in out[2..].iter().zip(Mirror::ALL) {
            assert_eq!(o.label, 0);
            assert_eq!(o.x, mirror_vector(m, &s[0].x).unwrap());
            assert_eq!(o.shape, mirror_vector(m, &s[0].shape).unwrap());
            assert_ne!(o.x, s[0].x);
        }
        assert!(matches!(
            with_mirror_images(&s, &sym[..1]),
            Err(ClassifyError::LabelOutOfRange {
                label: 1,
                classes: 1
            })
        ));
    }

    #[test]
    fn nearest_agreement_tells_a_symmetric_class_from_an_asymmetric_one() {
        use std::f32::consts::TAU;
        // Class 0: a profile symmetric under both mirrors (cos 2θ); class 1:
        // one that is not (a bump at one angle), and class 1's mirror
        // images lie nearer class 0's references than its own.
        let bins = SHAPE_LEN / 2;
        let angle = |i: usize| (i % bins) as f32 / bins as f32 * TAU;
        let sym = |k: f32| move |i: usize| 2.0 + (2.0 * angle(i)).cos() + k;
        let bump =
            |k: f32| move |i: usize| 0.1 + (-(angle(i) - 0.6).powi(2) * 4.0).exp() * (2.0 + k);
        let all = [
            sample(0, sym(0.0)),
            sample(0, sym(0.1)),
            sample(1, bump(0.0)),
            sample(1, bump(0.1)),
        ];
        let r: Vec<&Sample> = all.iter().collect();
        let a = nearest_agreement(&r, 2).unwrap();
        assert_eq!(a[0].plain, 1.0);
        assert_eq!(a[0].mirrored, [1.0, 1.0]);
        assert_eq!(a[1].plain, 1.0);
        assert_eq!(a[1].mirrored, [0.0, 0.0]);
        let flags: Vec<Symmetry> = a.iter().map(Agreement::symmetry).collect();
        assert_eq!(
            flags[0],
            Symmetry::NONE
                .with(Mirror::Vertical)
                .with(Mirror::Horizontal)
        );
        assert_eq!(flags[1], Symmetry::NONE);
        // Leave one out: a class of one sample is never its own neighbour.
        let one = nearest_agreement(&r[1..], 2).unwrap();
        assert_eq!(one[0].plain, 0.0);
        assert_eq!(one[0].symmetry(), Symmetry::NONE);
        // Bad input: a class without a sample, a label out of range.
        assert!(matches!(
            nearest_agreement(&r[..2], 2),
            Err(ClassifyError::EmptyClass { class: 1 })
        ));
        assert!(matches!(
            nearest_agreement(&r, 1),
            Err(ClassifyError::LabelOutOfRange {
                label: 1,
                classes: 1
            })
        ));
    }
}
