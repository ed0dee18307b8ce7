//! Performance measures of the paper's section 5.1, as fractions in `[0, 1]`.
//!
//! * **CMC / ROR**: the recognition rate at rank `τ` is the share of probes
//!   whose true class is among the top `τ` of their ranked list; ROR is
//!   rank 1.
//! * **DET sweep**: a claim is accepted when its score is `>= Δ`. `Δ` takes
//!   every distinct score (ascending; at the smallest, every claim is
//!   accepted: FAR 1, FRR 0) and then `+∞` (none accepted: FAR 0, FRR 1),
//!   which are all the operating points the scores allow.
//!   `FAR(Δ) = #{impostor >= Δ} / #impostor`,
//!   `FRR(Δ) = #{genuine < Δ} / #genuine`.
//! * **EER**: FAR decreases and FRR increases along the sweep. Take the
//!   first pair of consecutive points where `FAR - FRR` goes from positive
//!   to zero or negative; the EER is where the straight segment between
//!   them, in (FAR, FRR) space, meets the line FAR = FRR (exactly the
//!   second point's FAR when it lies on the line).
//! * **HTER_min**: the smallest `(FAR + FRR) / 2` over the sweep points.
//!   The EER point is a convex combination of two sweep points, so
//!   HTER_min <= EER always.
//! * **Verification rate at a FAR**: the largest `1 - FRR` among sweep points
//!   whose FAR does not exceed the target (no interpolation). With fewer
//!   than `1 / target` impostor claims this is the rate at FAR = 0.
//! * **ROC / AUC**: (FAR, 1 - FRR) from FAR 0 to 1, area by trapezoids. Ties
//!   between a genuine and an impostor score make a diagonal step, so the
//!   AUC equals the Mann–Whitney probability `P(g > i) + P(g = i) / 2`.
//!
//! The probit for DET axes is in [`super::probit`].

use super::ClassifyError;

/// Recognition rate at ranks `1..=classes` from each probe's rank (from
/// 1) of its true class. `cmc[0]` is the ROR.
///
/// # Errors
/// [`ClassifyError::ZeroClasses`], [`ClassifyError::Empty`] for no ranks,
/// [`ClassifyError::LabelOutOfRange`] for a rank of 0 or above `classes`.
pub fn cmc(ranks: &[usize], classes: usize) -> Result<Vec<f64>, ClassifyError> {
    if classes == 0 {
        return Err(ClassifyError::ZeroClasses);
    }
    if ranks.is_empty() {
        return Err(ClassifyError::Empty { what: "ranks" });
    }
    let mut hits = vec![0usize; classes];
    for &r in ranks {
        if r == 0 || r > classes {
            return Err(ClassifyError::LabelOutOfRange { label: r, classes });
        }
        hits[r - 1] += 1;
    }
    let n = ranks.len() as f64;
    let mut acc = 0;
    Ok(hits
        .iter()
        .map(|&h| {
            acc += h;
            acc as f64 / n
        })
        .collect())
}

/// One operating point of the sweep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DetPoint {
    /// Acceptance threshold Δ (`+∞` for the last point).
    pub threshold: f64,
    /// False acceptance rate.
    pub far: f64,
    /// False rejection rate.
    pub frr: f64,
}

/// The FAR/FRR sweep over Δ, thresholds ascending.
#[derive(Clone, Debug, PartialEq)]
pub struct Det {
    points: Vec<DetPoint>,
}

fn sorted(scores: &[f64], what: &'static str) -> Result<Vec<f64>, ClassifyError> {
    if scores.is_empty() {
        return Err(ClassifyError::Empty { what });
    }
    if scores.iter().any(|s| !s.is_finite()) {
        return Err(ClassifyError::NonFinite { what });
    }
    let mut v = scores.to_vec();
    v.sort_by(f64::total_cmp);
    Ok(v)
}

impl Det {
    /// Sweeps Δ over every distinct score (see the module doc), in
    /// `O((g + i) log(g + i))`.
    ///
    /// # Errors
    /// [`ClassifyError::Empty`] or [`ClassifyError::NonFinite`] for either
    /// score set.
    pub fn sweep(genuine: &[f64], impostor: &[f64]) -> Result<Self, ClassifyError> {
        let g = sorted(genuine, "genuine scores")?;
        let i = sorted(impostor, "impostor scores")?;
        let (ng, ni) = (g.len() as f64, i.len() as f64);
        let mut points = Vec::with_capacity(g.len() + i.len() + 1);
        // gi: genuine scores below Δ; ii: impostor scores below Δ.
        let (mut gi, mut ii) = (0usize, 0usize);
        loop {
            let next = match (g.get(gi), i.get(ii)) {
                (Some(&a), Some(&b)) => a.min(b),
                (Some(&a), None) => a,
                (None, Some(&b)) => b,
                (None, None) => break,
            };
            points.push(DetPoint {
                threshold: next,
                far: (i.len() - ii) as f64 / ni,
                frr: gi as f64 / ng,
            });
            while g.get(gi).is_some_and(|&s| s <= next) {
                gi += 1;
            }
            while i.get(ii).is_some_and(|&s| s <= next) {
                ii += 1;
            }
        }
        points.push(DetPoint {
            threshold: f64::INFINITY,
            far: 0.0,
            frr: 1.0,
        });
        Ok(Self { points })
    }

    /// The operating points, thresholds ascending (FAR falling, FRR rising).
    pub fn points(&self) -> &[DetPoint] {
        &self.points
    }

    /// Equal error rate, interpolated where FAR and FRR cross.
    pub fn eer(&self) -> f64 {
        for w in self.points.windows(2) {
            let (a, b) = (w[0], w[1]);
            let (da, db) = (a.far - a.frr, b.far - b.frr);
            if da > 0.0 && db <= 0.0 {
                if db == 0.0 {
                    return b.far;
                }
                let t = da / (da - db);
                return a.far + t * (b.far - a.far);
            }
        }
        // The sweep starts at FAR - FRR = 1 and ends at -1: unreachable,
        // but FRR at the start is the safe answer.
        self.points.first().map_or(0.0, |p| p.frr)
    }

    /// HTER_min = min over Δ of (FAR + FRR) / 2, and the point reaching it
    /// (the first one, lowest Δ, on ties).
    pub fn hter_min(&self) -> (f64, DetPoint) {
        let hter = |p: &DetPoint| (p.far + p.frr) / 2.0;
        let mut best = self.points[0];
        for p in &self.points[1..] {
            if hter(p) < hter(&best) {
                best = *p;
            }
        }
        (hter(&best), best)
    }

    /// Verification rate `1 - FRR` at FAR <= `target` (e.g. 0.01, 0.001).
    ///
    /// # Errors
    /// [`ClassifyError::BadRate`] when `target` is not in `[0, 1]`.
    pub fn verification_rate_at(&self, target: f64) -> Result<f64, ClassifyError> {
        if !(0.0..=1.0).contains(&target) {
            return Err(ClassifyError::BadRate(target));
        }
        Ok(self
            .points
            .iter()
            .filter(|p| p.far <= target)
            .map(|p| 1.0 - p.frr)
            .fold(0.0, f64::max))
    }

    /// ROC points (FAR, verification rate), FAR ascending from (0, 0) to
    /// (1, 1).
    pub fn roc(&self) -> Vec<(f64, f64)> {
        self.points
            .iter()
            .rev()
            .map(|p| (p.far, 1.0 - p.frr))
            .collect()
    }

    /// Area under the ROC curve, by trapezoids.
    pub fn auc(&self) -> f64 {
        self.roc()
            .windows(2)
            .map(|w| (w[1].0 - w[0].0) * (w[1].1 + w[0].1) / 2.0)
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// genuine 0.9 0.8 0.6 0.4; impostor 0.7 0.5 0.3 0.2 0.1.
    fn hand() -> Det {
        Det::sweep(&[0.9, 0.8, 0.6, 0.4], &[0.7, 0.5, 0.3, 0.2, 0.1]).unwrap()
    }

    #[test]
    fn cmc_by_hand() {
        // Ranks 1, 2, 1, 3 of 3 classes: rank 1 holds 2 of 4 (0.5), rank <= 2
        // holds 3 (0.75), rank <= 3 all (1.0).
        assert_eq!(cmc(&[1, 2, 1, 3], 3).unwrap(), vec![0.5, 0.75, 1.0]);
        assert!(cmc(&[0], 3).is_err() && cmc(&[4], 3).is_err() && cmc(&[], 3).is_err());
    }

    #[test]
    fn sweep_by_hand() {
        // Δ:    0.1 0.2 0.3 0.4 0.5  0.6  0.7 0.8 0.9  +∞
        // FAR:  1   .8  .6  .4  .4   .2   .2  0   0    0    (impostors >= Δ, of 5)
        // FRR:  0   0   0   0   .25  .25  .5  .5  .75  1    (genuines < Δ, of 4)
        let far = [1.0, 0.8, 0.6, 0.4, 0.4, 0.2, 0.2, 0.0, 0.0, 0.0];
        let frr = [0.0, 0.0, 0.0, 0.0, 0.25, 0.25, 0.5, 0.5, 0.75, 1.0];
        let det = hand();
        let pts = det.points();
        assert_eq!(pts.len(), 10);
        for (k, p) in pts.iter().enumerate() {
            assert!((p.far - far[k]).abs() < 1e-12, "FAR at {k}");
            assert!((p.frr - frr[k]).abs() < 1e-12, "FRR at {k}");
        }
    }

    #[test]
    fn eer_hter_and_verification_rate_by_hand() {
        let det = hand();
        // FAR - FRR: .15 at Δ=0.5 (.4, .25), -.05 at Δ=0.6 (.2, .25); t =
        // .15 / .2 = .75; EER = .4 + .75 (.2 - .4) = .25 (= FRR there).
        assert!((det.eer() - 0.25).abs() < 1e-12);
        // (FAR + FRR)/2: .5 .4 .3 .2 .325 .225 .35 .25 .375 .5 -> .2 at Δ=0.4.
        let (h, p) = det.hter_min();
        assert!((h - 0.2).abs() < 1e-12 && p.threshold == 0.4);
        assert!(h <= det.eer());
        // FAR <= 1 % only where FAR = 0: best FRR there .5 (Δ=0.8) -> VR .5.
        assert!((det.verification_rate_at(0.01).unwrap() - 0.5).abs() < 1e-12);
        assert!((det.verification_rate_at(0.001).unwrap() - 0.5).abs() < 1e-12);
        // FAR <= 0.2: Δ=0.6 has FRR .25 -> .75.
        assert!((det.verification_rate_at(0.2).unwrap() - 0.75).abs() < 1e-12);
        assert!(det.verification_rate_at(1.5).is_err());
    }

    #[test]
    fn eer_exactly_on_a_point() {
        // genuine .8 .3, impostor .5 .1. Δ: .1 (FAR 1, FRR 0), .3 (.5, 0),
        // .5 (.5, .5), .8 (0, .5), +∞ (0, 1): FAR = FRR = .5 at Δ = .5.
        let det = Det::sweep(&[0.8, 0.3], &[0.5, 0.1]).unwrap();
        assert_eq!(det.eer(), 0.5);
    }

    #[test]
    fn auc_by_hand_and_extremes() {
        // ROC (FAR, TAR) from the sweep reversed: (0,0) (0,.25) (0,.5) (.2,.5)
        // (.2,.75) (.4,.75) (.4,1) (.6,1) (.8,1) (1,1); trapezoids .2·.5 +
        // .2·.75 + .2·1 + .2·1 + .2·1 = .85. Mann–Whitney: pairs g > i are
        // 5 + 5 + 4 + 3 = 17 of 20 = .85.
        assert!((hand().auc() - 0.85).abs() < 1e-12);
        let perfect = Det::sweep(&[0.9, 0.8, 0.7], &[0.1, 0.2]).unwrap();
        assert_eq!(perfect.auc(), 1.0);
        assert_eq!(perfect.eer(), 0.0);
        let same = [0.1, 0.2, 0.3, 0.4];
        assert!((Det::sweep(&same, &same).unwrap().auc() - 0.5).abs() < 1e-12);
        // Two independent draws from one distribution: about 0.5.
        let mut x = 12345u64;
        let mut draw = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        let g: Vec<f64> = (0..2000).map(|_| draw()).collect();
        let i: Vec<f64> = (0..2000).map(|_| draw()).collect();
        let auc = Det::sweep(&g, &i).unwrap().auc();
        assert!((auc - 0.5).abs() < 0.03, "{auc}");
    }

    #[test]
    fn auc_matches_mann_whitney_with_ties() {
        let g = [0.5, 0.5, 0.7, 0.2, 0.9];
        let i = [0.5, 0.1, 0.7, 0.3];
        let mut wins = 0.0;
        for &a in &g {
            for &b in &i {
                wins += if a > b {
                    1.0
                } else if a == b {
                    0.5
                } else {
                    0.0
                };
            }
        }
        let expect = wins / (g.len() * i.len()) as f64;
        assert!((Det::sweep(&g, &i).unwrap().auc() - expect).abs() < 1e-12);
    }

    #[test]
    fn bad_scores_are_typed_errors() {
        assert!(Det::sweep(&[], &[0.1]).is_err());
        assert!(Det::sweep(&[0.1], &[]).is_err());
        assert!(Det::sweep(&[f64::NAN], &[0.1]).is_err());
    }
}
