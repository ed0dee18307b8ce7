//! Matching detections to ground truth, and the benchmark's measures.
//!
//! **Matching** is greedy by box IoU: every (detection, object) pair with
//! IoU ≥ [`MIN_IOU`] is a candidate; candidates are taken in decreasing
//! IoU (ties: lower detection, then lower object index first), each
//! detection and each object at most once. With at most 4 objects and K
//! detections per scene this equals the optimal assignment except in rare
//! ties of overlapping boxes.
//!
//! **Measures.** Recall is matched objects over objects; precision matched
//! detections over detections. Mask IoU, top-1 and top-5 are over matched
//! objects: top-1 counts the detection's best class (whatever Δ says),
//! top-5 whether the class is among its five best. A scene's **gist** is
//! right when every object is matched by a detection that claims its class
//! (best class, known under Δ) and no other detection claims a class (an
//! unmatched detection called unknown does not spoil it).

use super::detect::Detection;
use crate::scenes::load::Scene;
use crate::scenes::BoxPx;
use serde::Serialize;

/// Least box IoU of a match.
pub const MIN_IOU: f64 = 0.5;

/// One match: detection, object, box IoU.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Match {
    /// Detection index.
    pub detection: usize,
    /// Ground-truth object index.
    pub object: usize,
    /// Their box IoU.
    pub iou: f64,
}

/// Greedy matching by box IoU (see the module doc).
pub fn match_boxes(detections: &[BoxPx], objects: &[BoxPx]) -> Vec<Match> {
    let mut cands: Vec<Match> = detections
        .iter()
        .enumerate()
        .flat_map(|(d, db)| {
            objects.iter().enumerate().map(move |(o, ob)| Match {
                detection: d,
                object: o,
                iou: db.iou(ob),
            })
        })
        .filter(|m| m.iou >= MIN_IOU)
        .collect();
    cands.sort_by(|a, b| {
        b.iou
            .total_cmp(&a.iou)
            .then(a.detection.cmp(&b.detection))
            .then(a.object.cmp(&b.object))
    });
    let (mut det_used, mut obj_used) = (vec![false; detections.len()], vec![false; objects.len()]);
    let mut out = Vec::new();
    for m in cands {
        if !det_used[m.detection] && !obj_used[m.object] {
            det_used[m.detection] = true;
            obj_used[m.object] = true;
            out.push(m);
        }
    }
    out
}

/// Mask IoU of two row-major masks (0 when both are empty).
pub fn mask_iou(a: &[bool], b: &[u8]) -> f64 {
    let (i, u) = a.iter().zip(b).fold((0u64, 0u64), |(i, u), (&a, &b)| {
        let b = b != 0;
        (i + u64::from(a && b), u + u64::from(a || b))
    });
    if u == 0 {
        0.0
    } else {
        i as f64 / u as f64
    }
}

/// One scene's counts.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SceneScore {
    /// Scene folder name.
    pub scene: String,
    /// Objects in the truth.
    pub objects: usize,
    /// Detections.
    pub detections: usize,
    /// Matched pairs.
    pub matched: usize,
    /// Sum of the mask IoUs of the matched pairs.
    pub mask_iou_sum: f64,
    /// Matched pairs whose best class is the object's.
    pub top1: usize,
    /// Matched pairs with the object's class among the five best.
    pub top5: usize,
    /// The gist is right.
    pub gist: bool,
    /// Time in the detector, ms.
    pub ms: f64,
}

/// Scores one scene's detections against its truth.
pub fn score_scene(scene: &Scene, dets: &[Detection], ms: f64) -> SceneScore {
    let truth = &scene.truth.objects;
    let boxes: Vec<BoxPx> = dets.iter().map(|d| d.bbox).collect();
    let gt: Vec<BoxPx> = truth.iter().map(|o| o.bbox).collect();
    let matches = match_boxes(&boxes, &gt);
    let mut s = SceneScore {
        scene: scene
            .dir
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
        objects: truth.len(),
        detections: dets.len(),
        matched: matches.len(),
        ms,
        ..SceneScore::default()
    };
    let mut claimed_right = 0;
    for m in &matches {
        let (d, o) = (&dets[m.detection], &truth[m.object]);
        s.mask_iou_sum += mask_iou(&d.mask, &scene.masks[m.object]);
        s.top1 += usize::from(d.top5.first().is_some_and(|(c, _)| *c == o.class));
        s.top5 += usize::from(d.top5.iter().any(|(c, _)| *c == o.class));
        claimed_right += usize::from(d.category() == Some(o.class.as_str()));
    }
    let claims = dets.iter().filter(|d| d.category().is_some()).count();
    s.gist = claimed_right == truth.len() && claims == truth.len();
    s
}

/// A ratio, `None` for an empty denominator.
fn ratio(num: f64, den: usize) -> Option<f64> {
    (den > 0).then(|| num / den as f64)
}

/// The measures over a group of scenes.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Totals {
    /// Scenes.
    pub scenes: usize,
    /// Objects.
    pub objects: usize,
    /// Detections.
    pub detections: usize,
    /// Matched pairs.
    pub matched: usize,
    /// Matched objects / objects.
    pub recall: Option<f64>,
    /// Matched detections / detections.
    pub precision: Option<f64>,
    /// Mean mask IoU of matched pairs.
    pub mask_iou: Option<f64>,
    /// Top-1 accuracy of matched objects.
    pub top1: Option<f64>,
    /// Top-5 accuracy of matched objects.
    pub top5: Option<f64>,
    /// Share of scenes whose gist is right.
    pub gist: Option<f64>,
    /// Mean detector time per scene, ms.
    pub ms_per_scene: Option<f64>,
}

impl Totals {
    /// Sums `scores`.
    pub fn of<'a>(scores: impl IntoIterator<Item = &'a SceneScore>) -> Self {
        let mut t = Self::default();
        let (mut iou, mut top1, mut top5, mut gist, mut ms) = (0.0, 0, 0, 0, 0.0);
        for s in scores {
            t.scenes += 1;
            t.objects += s.objects;
            t.detections += s.detections;
            t.matched += s.matched;
            iou += s.mask_iou_sum;
            top1 += s.top1;
            top5 += s.top5;
            gist += usize::from(s.gist);
            ms += s.ms;
        }
        t.recall = ratio(t.matched as f64, t.objects);
        t.precision = ratio(t.matched as f64, t.detections);
        t.mask_iou = ratio(iou, t.matched);
        t.top1 = ratio(top1 as f64, t.matched);
        t.top5 = ratio(top5 as f64, t.matched);
        t.gist = ratio(gist as f64, t.scenes);
        t.ms_per_scene = ratio(ms, t.scenes);
        t
    }
}
