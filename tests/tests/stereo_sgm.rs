//! Semi-global aggregation of the DEM f32 read-out (the reference of core's
//! engine): the recurrence against hand-worked paths, the cost
//! normalisation, and bad parameters.

use protogist_host::reference::stereo::readout::Scores;
use protogist_host::reference::stereo::sgm::{aggregate, aggregate_path, costs, directions};
use protogist_host::reference::stereo::{DemParams, StereoError};

/// 1x4 pixels, 3 candidates, P1 = 1, P2 = 3.
const COST: [f32; 12] = [
    0.0, 2.0, 5.0, // x0
    4.0, 0.0, 4.0, // x1
    5.0, 5.0, 0.0, // x2
    0.0, 6.0, 6.0, // x3
];

/// Left to right, by hand. L(x0) = C(x0) = [0, 2, 5], min 0.
/// x1, C = [4, 0, 4]:
///   d0: min(L0 0, L1+P1 3, min+P2 3) = 0  -> 4 + 0 − 0 = 4
///   d1: min(L1 2, L0+P1 1, L2+P1 6, 3) = 1 -> 0 + 1 − 0 = 1
///   d2: min(L2 5, L1+P1 3, 3) = 3         -> 4 + 3 − 0 = 7   L = [4, 1, 7], min 1
/// x2, C = [5, 5, 0]:
///   d0: min(4, 1+1, 1+3) = 2       -> 5 + 2 − 1 = 6
///   d1: min(1, 4+1, 7+1, 4) = 1    -> 5 + 1 − 1 = 5
///   d2: min(7, 1+1, 4) = 2         -> 0 + 2 − 1 = 1   L = [6, 5, 1], min 1
/// x3, C = [0, 6, 6]:
///   d0: min(6, 5+1, 1+3) = 4 (P2)  -> 0 + 4 − 1 = 3
///   d1: min(5, 6+1, 1+1, 4) = 2    -> 6 + 2 − 1 = 7
///   d2: min(1, 5+1, 4) = 1         -> 6 + 1 − 1 = 6   L = [3, 7, 6]
const LEFT_TO_RIGHT: [f32; 12] = [0.0, 2.0, 5.0, 4.0, 1.0, 7.0, 6.0, 5.0, 1.0, 3.0, 7.0, 6.0];

/// Right to left, by hand. L(x3) = [0, 6, 6], min 0.
/// x2, C = [5, 5, 0]: d0 min(0, 7, 3) = 0 -> 5; d1 min(6, 1, 7, 3) = 1 -> 6;
///   d2 min(6, 7, 3) = 3 -> 3.                       L = [5, 6, 3], min 3
/// x1, C = [4, 0, 4]: d0 min(5, 7, 6) = 5 -> 6; d1 min(6, 6, 4, 6) = 4 -> 1;
///   d2 min(3, 7, 6) = 3 -> 4.                       L = [6, 1, 4], min 1
/// x0, C = [0, 2, 5]: d0 min(6, 2, 4) = 2 -> 1; d1 min(1, 7, 5, 4) = 1 -> 2;
///   d2 min(4, 2, 4) = 2 -> 6.                       L = [1, 2, 6]
const RIGHT_TO_LEFT: [f32; 12] = [1.0, 2.0, 6.0, 6.0, 1.0, 4.0, 5.0, 6.0, 3.0, 0.0, 6.0, 6.0];

#[test]
fn recurrence_matches_the_hand_worked_paths() {
    assert_eq!(
        aggregate_path(&COST, 4, 1, 3, (1, 0), 1.0, 3.0),
        LEFT_TO_RIGHT
    );
    assert_eq!(
        aggregate_path(&COST, 4, 1, 3, (-1, 0), 1.0, 3.0),
        RIGHT_TO_LEFT
    );
    // The same costs as a 1x4 column: top to bottom is left to right.
    assert_eq!(
        aggregate_path(&COST, 1, 4, 3, (0, 1), 1.0, 3.0),
        LEFT_TO_RIGHT
    );
    assert_eq!(
        aggregate_path(&COST, 1, 4, 3, (0, -1), 1.0, 3.0),
        RIGHT_TO_LEFT
    );
    // On a single row the vertical and diagonal paths have no predecessor:
    // L = C. Three paths: left-right + right-left + C.
    let sum = aggregate(&COST, 4, 1, 3, 3, 1.0, 3.0);
    for ((s, (a, b)), c) in sum
        .iter()
        .zip(LEFT_TO_RIGHT.iter().zip(&RIGHT_TO_LEFT))
        .zip(&COST)
    {
        assert_eq!(*s, a + b + c);
    }
    // Five paths on a row: 2 horizontal + 3 with no predecessor.
    let sum5 = aggregate(&COST, 4, 1, 3, 5, 1.0, 3.0);
    assert_eq!(
        &sum5[9..],
        &[3.0 + 0.0 + 0.0, 7.0 + 6.0 + 18.0, 6.0 + 6.0 + 18.0]
    );
    // Without penalties each path is the cost itself.
    assert_eq!(aggregate_path(&COST, 4, 1, 3, (1, 0), 0.0, 0.0), COST);
    assert_eq!(directions(5).map(<[_]>::len), Some(5));
    assert_eq!(directions(6), None);
}

#[test]
fn costs_are_zero_at_the_best_candidate_with_mean_gap_one() {
    // Two pixels, 3 candidates, no bias: scores raw / total.
    let scores = Scores {
        width: 2,
        height: 1,
        disparities: 3,
        raw: vec![2.0, 6.0, 4.0, 1.0, 3.0, 9.0],
        total: vec![2.0, 1.0],
    };
    let bias = [0.0; 3];
    // Pixel 0: s = [1, 3, 2], gaps [2, 0, 1], mean 1. Pixel 1, only d <= 1
    // valid: s = [1, 3], gaps [2, 0], mean 1; d = 2 costs the worst valid, 2.
    let c = costs(&scores, &bias, |_| true, |p| if p == 0 { 2 } else { 1 });
    assert_eq!(c, [2.0, 0.0, 1.0, 2.0, 0.0, 2.0]);
    // Scaling a pixel's responses does not change its costs.
    let double = Scores {
        raw: scores.raw.iter().map(|v| 2.0 * v).collect(),
        total: scores.total.iter().map(|v| 2.0 * v).collect(),
        ..scores.clone()
    };
    assert_eq!(
        costs(&double, &bias, |_| true, |_| 2),
        costs(&scores, &bias, |_| true, |_| 2)
    );
    // No evidence: flat zero costs.
    assert_eq!(costs(&scores, &bias, |p| p == 1, |_| 2)[..3], [0.0; 3]);
}

#[test]
fn bad_sgm_parameters_are_typed_errors() {
    use protogist_host::reference::stereo::Aggregation::Sgm;
    for aggregation in [
        Sgm {
            p1: 2.0,
            p2: 1.0,
            paths: 5,
        },
        Sgm {
            p1: -1.0,
            p2: 1.0,
            paths: 5,
        },
        Sgm {
            p1: 1.0,
            p2: f32::INFINITY,
            paths: 5,
        },
        Sgm {
            p1: 1.0,
            p2: 2.0,
            paths: 6,
        },
    ] {
        let p = DemParams {
            aggregation,
            ..DemParams::default()
        };
        assert!(
            matches!(p.check(), Err(StereoError::BadParams(_))),
            "{aggregation:?}"
        );
    }
    // The right map derived from the left path sums needs the sums.
    let derived = DemParams {
        lr_from_left: true,
        ..DemParams::default()
    };
    assert!(matches!(derived.check(), Err(StereoError::BadParams(_))));
    let with_sgm = DemParams {
        aggregation: Sgm {
            p1: 0.25,
            p2: 4.0,
            paths: 5,
        },
        ..derived
    };
    assert!(with_sgm.check().is_ok());
}
