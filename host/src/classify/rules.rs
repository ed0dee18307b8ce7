//! Classification rules of the paper's section 4.1, and the
//! normalisation of section 4.3.
//!
//! **Similarity.** `ξ(v, v_c) = vᵀv_c / (‖v‖ ‖v_c‖)`, the plain cosine
//! similarity in `[-1, 1]`. The paper prints it with a leading minus, as in
//! Štruc and Pavešić's toolbox where it is a *distance*; with the minus,
//! "accept when `ξ >= Δ`" and "argmax of `ξ`" would pick the worst match,
//! so the rules here use the similarity. A zero vector has similarity 0
//! with everything.
//!
//! **Templates.** `v_c` is the mean output over the training vectors of
//! class `c`.
//!
//! **Ties.** Ranked lists sort by similarity, best first, and break ties by
//! the lower class index (a stable sort). The rank of the true class is its
//! position in that list, from 1.

use super::ClassifyError;

/// The cosine similarity of `a` and `b` (0 when either is all zero), in
/// `f64` accumulation. Lengths must match (checked by the callers here).
pub fn cosine(a: &[f32], b: &[f32]) -> f64 {
    let (mut ab, mut aa, mut bb) = (0f64, 0f64, 0f64);
    for (&x, &y) in a.iter().zip(b) {
        let (x, y) = (f64::from(x), f64::from(y));
        ab += x * y;
        aa += x * x;
        bb += y * y;
    }
    if aa == 0.0 || bb == 0.0 {
        return 0.0;
    }
    (ab / (aa.sqrt() * bb.sqrt())).clamp(-1.0, 1.0)
}

/// Z-normalises `v` in place: subtract the mean, divide by the population
/// standard deviation (section 4.3, step c).
///
/// # Errors
/// [`ClassifyError::Empty`], [`ClassifyError::NonFinite`] or
/// [`ClassifyError::ZeroVariance`].
pub fn z_normalise(v: &mut [f32]) -> Result<(), ClassifyError> {
    if v.is_empty() {
        return Err(ClassifyError::Empty { what: "values" });
    }
    if v.iter().any(|x| !x.is_finite()) {
        return Err(ClassifyError::NonFinite { what: "the vector" });
    }
    let n = v.len() as f64;
    let mean = v.iter().map(|&x| f64::from(x)).sum::<f64>() / n;
    let var = v
        .iter()
        .map(|&x| (f64::from(x) - mean).powi(2))
        .sum::<f64>()
        / n;
    if var <= 0.0 {
        return Err(ClassifyError::ZeroVariance);
    }
    let sd = var.sqrt();
    for x in v.iter_mut() {
        *x = ((f64::from(*x) - mean) / sd) as f32;
    }
    Ok(())
}

/// The outcome of identification.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Identity {
    /// Class `U_c`, `c` from 0.
    Known(usize),
    /// `U_{N+1}`: no template reaches the threshold.
    Unknown,
}

/// Class templates `v_1 .. v_N`, all of one dimension.
#[derive(Clone, Debug, PartialEq)]
pub struct Templates {
    templates: Vec<Vec<f32>>,
}

/// Checks that every vector has `dim` elements and finite values.
fn check_vectors(vs: &[Vec<f32>], dim: usize) -> Result<(), ClassifyError> {
    for (index, v) in vs.iter().enumerate() {
        if v.len() != dim {
            return Err(ClassifyError::DimensionMismatch {
                index,
                expected: dim,
                got: v.len(),
            });
        }
        if v.iter().any(|x| !x.is_finite()) {
            return Err(ClassifyError::NonFinite { what: "a vector" });
        }
    }
    Ok(())
}

impl Templates {
    /// Templates as the per-class mean of `outputs` (training data), with
    /// `labels[i]` in `0..classes` the class of `outputs[i]`.
    ///
    /// # Errors
    /// [`ClassifyError`] for no classes, no outputs, mismatched counts or
    /// lengths, non-finite values, a label out of range, or a class without
    /// any training vector.
    pub fn from_outputs(
        outputs: &[Vec<f32>],
        labels: &[usize],
        classes: usize,
    ) -> Result<Self, ClassifyError> {
        if classes == 0 {
            return Err(ClassifyError::ZeroClasses);
        }
        let dim = outputs
            .first()
            .ok_or(ClassifyError::Empty { what: "outputs" })?
            .len();
        if dim == 0 {
            return Err(ClassifyError::Empty {
                what: "output elements",
            });
        }
        if labels.len() != outputs.len() {
            return Err(ClassifyError::LabelCount {
                outputs: outputs.len(),
                labels: labels.len(),
            });
        }
        check_vectors(outputs, dim)?;
        let mut sums = vec![vec![0f64; dim]; classes];
        let mut counts = vec![0usize; classes];
        for (v, &label) in outputs.iter().zip(labels) {
            let sum = sums
                .get_mut(label)
                .ok_or(ClassifyError::LabelOutOfRange { label, classes })?;
            for (s, &x) in sum.iter_mut().zip(v) {
                *s += f64::from(x);
            }
            counts[label] += 1;
        }
        if let Some(class) = counts.iter().position(|&c| c == 0) {
            return Err(ClassifyError::EmptyClass { class });
        }
        let templates = sums
            .iter()
            .zip(&counts)
            .map(|(s, &n)| s.iter().map(|&x| (x / n as f64) as f32).collect())
            .collect();
        Ok(Self { templates })
    }

    /// Templates given directly (one per class).
    ///
    /// # Errors
    /// As [`Templates::from_outputs`] for the vectors.
    pub fn new(templates: Vec<Vec<f32>>) -> Result<Self, ClassifyError> {
        let dim = templates.first().ok_or(ClassifyError::ZeroClasses)?.len();
        if dim == 0 {
            return Err(ClassifyError::Empty {
                what: "template elements",
            });
        }
        check_vectors(&templates, dim)?;
        Ok(Self { templates })
    }

    /// Number of classes N.
    pub fn classes(&self) -> usize {
        self.templates.len()
    }

    /// Dimension of the vectors.
    pub fn dim(&self) -> usize {
        self.templates.first().map_or(0, Vec::len)
    }

    /// Template `v_c`.
    pub fn template(&self, c: usize) -> Option<&[f32]> {
        self.templates.get(c).map(Vec::as_slice)
    }

    fn check(&self, v: &[f32]) -> Result<(), ClassifyError> {
        if v.len() != self.dim() {
            return Err(ClassifyError::DimensionMismatch {
                index: 0,
                expected: self.dim(),
                got: v.len(),
            });
        }
        if v.iter().any(|x| !x.is_finite()) {
            return Err(ClassifyError::NonFinite { what: "the probe" });
        }
        Ok(())
    }

    /// `ξ(v, v_c)` for every class `c`.
    ///
    /// # Errors
    /// [`ClassifyError::DimensionMismatch`] or [`ClassifyError::NonFinite`].
    pub fn scores(&self, v: &[f32]) -> Result<Vec<f64>, ClassifyError> {
        self.check(v)?;
        Ok(self.templates.iter().map(|t| cosine(v, t)).collect())
    }

    /// Verification: accept (`true`) the claim "`v` is class `claim`" when
    /// `ξ(v, v_claim) >= delta`.
    ///
    /// # Errors
    /// [`ClassifyError::LabelOutOfRange`] for a bad claim, or as
    /// [`Templates::scores`].
    pub fn verify(&self, v: &[f32], claim: usize, delta: f64) -> Result<bool, ClassifyError> {
        self.check(v)?;
        let t = self.template(claim).ok_or(ClassifyError::LabelOutOfRange {
            label: claim,
            classes: self.classes(),
        })?;
        Ok(cosine(v, t) >= delta)
    }

    /// Identification: the class of the best similarity if it reaches
    /// `delta`, else [`Identity::Unknown`]. Ties go to the lower class.
    ///
    /// # Errors
    /// As [`Templates::scores`].
    pub fn identify(&self, v: &[f32], delta: f64) -> Result<Identity, ClassifyError> {
        let scores = self.scores(v)?;
        let best = ranked(&scores)[0];
        Ok(if scores[best] >= delta {
            Identity::Known(best)
        } else {
            Identity::Unknown
        })
    }
}

/// Class indices sorted by score, best first; ties by lower index.
pub fn ranked(scores: &[f64]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..scores.len()).collect();
    idx.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]));
    idx
}

/// Everything the metrics need from a labelled test set.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Evaluation {
    /// Rank (from 1) of the true class in each probe's ranked list.
    pub ranks: Vec<usize>,
    /// Genuine scores: `ξ(v, v_true)`, one per probe.
    pub genuine: Vec<f64>,
    /// Impostor scores: `ξ(v, v_c)` for every other class, N - 1 per probe
    /// (each probe claims every class once).
    pub impostor: Vec<f64>,
    /// Number of classes.
    pub classes: usize,
}

/// Scores every probe `outputs[i]` of true class `labels[i]` against all
/// templates.
///
/// # Errors
/// [`ClassifyError`] for no probes, mismatched counts or lengths,
/// non-finite values or a label out of range.
pub fn evaluate(
    templates: &Templates,
    outputs: &[Vec<f32>],
    labels: &[usize],
) -> Result<Evaluation, ClassifyError> {
    if outputs.is_empty() {
        return Err(ClassifyError::Empty { what: "probes" });
    }
    if labels.len() != outputs.len() {
        return Err(ClassifyError::LabelCount {
            outputs: outputs.len(),
            labels: labels.len(),
        });
    }
    check_vectors(outputs, templates.dim())?;
    let n = templates.classes();
    let mut ev = Evaluation {
        classes: n,
        ..Evaluation::default()
    };
    for (v, &label) in outputs.iter().zip(labels) {
        if label >= n {
            return Err(ClassifyError::LabelOutOfRange { label, classes: n });
        }
        let scores = templates.scores(v)?;
        let rank = ranked(&scores).iter().position(|&c| c == label);
        ev.ranks.push(rank.map_or(n, |r| r + 1));
        for (c, &s) in scores.iter().enumerate() {
            if c == label {
                ev.genuine.push(s);
            } else {
                ev.impostor.push(s);
            }
        }
    }
    Ok(ev)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_classes() -> Templates {
        // Class 0 training: (1,0) and (1,2) -> mean (1,1).
        // Class 1 training: (0,-1) and (-2,-1) -> mean (-1,-1).
        Templates::from_outputs(
            &[
                vec![1.0, 0.0],
                vec![0.0, -1.0],
                vec![1.0, 2.0],
                vec![-2.0, -1.0],
            ],
            &[0, 1, 0, 1],
            2,
        )
        .unwrap()
    }

    #[test]
    fn templates_are_class_means() {
        let t = two_classes();
        assert_eq!(t.template(0), Some(&[1.0, 1.0][..]));
        assert_eq!(t.template(1), Some(&[-1.0, -1.0][..]));
    }

    #[test]
    fn verification_and_identification_by_hand() {
        let t = two_classes();
        // v = (1, 0): cos with (1,1) = 1/√2 ≈ 0.7071, with (-1,-1) = -0.7071.
        let v = [1.0, 0.0];
        let s = t.scores(&v).unwrap();
        assert!((s[0] - 0.5f64.sqrt()).abs() < 1e-12 && (s[1] + 0.5f64.sqrt()).abs() < 1e-12);
        assert!(t.verify(&v, 0, 0.7).unwrap());
        assert!(!t.verify(&v, 0, 0.71).unwrap());
        assert!(!t.verify(&v, 1, 0.0).unwrap());
        assert_eq!(t.identify(&v, 0.0).unwrap(), Identity::Known(0));
        // Best cosine 0.7071 < 0.8: the unknown class U_{N+1}.
        assert_eq!(t.identify(&v, 0.8).unwrap(), Identity::Unknown);
    }

    #[test]
    fn ranks_and_score_sets() {
        let t = Templates::new(vec![vec![1.0, 0.0], vec![0.0, 1.0], vec![-1.0, 0.0]]).unwrap();
        // Probe (1, 1), true class 1: scores (0.707, 0.707, -0.707); the tie
        // goes to class 0, so class 1 is rank 2. Probe (-1, 0.1), true 2:
        // rank 1.
        let ev = evaluate(&t, &[vec![1.0, 1.0], vec![-1.0, 0.1]], &[1, 2]).unwrap();
        assert_eq!(ev.ranks, vec![2, 1]);
        assert_eq!(ev.genuine.len(), 2);
        assert_eq!(ev.impostor.len(), 4);
    }

    #[test]
    fn bad_inputs_are_typed_errors() {
        use ClassifyError as E;
        let one = vec![vec![1.0f32]];
        assert_eq!(Templates::from_outputs(&one, &[0], 0), Err(E::ZeroClasses));
        assert_eq!(
            Templates::from_outputs(&[], &[], 1),
            Err(E::Empty { what: "outputs" })
        );
        assert!(matches!(
            Templates::from_outputs(&one, &[1], 1),
            Err(E::LabelOutOfRange { .. })
        ));
        assert_eq!(
            Templates::from_outputs(&one, &[0], 2),
            Err(E::EmptyClass { class: 1 })
        );
        assert!(matches!(
            Templates::from_outputs(&[vec![1.0], vec![1.0, 2.0]], &[0, 0], 1),
            Err(E::DimensionMismatch { index: 1, .. })
        ));
        let t = two_classes();
        assert!(t.verify(&[1.0, 0.0], 5, 0.0).is_err());
        assert!(t.scores(&[f32::NAN, 0.0]).is_err());
        assert!(t.scores(&[1.0]).is_err());
        let mut flat = [2.0f32; 4];
        assert_eq!(z_normalise(&mut flat), Err(E::ZeroVariance));
    }

    #[test]
    fn z_normalise_by_hand() {
        // (1, 3): mean 2, population σ 1 -> (-1, 1).
        let mut v = [1.0f32, 3.0];
        z_normalise(&mut v).unwrap();
        assert_eq!(v, [-1.0, 1.0]);
    }
}
