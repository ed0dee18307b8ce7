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
//! unmatched detection called unknown does not spoil it). Three diagnostics
//! go with them: the share of detections called unknown under Δ, and the
//! recall and top-1 of the objects drawn without contrast to their
//! surroundings (whose masks come from disparity alone, docs/RECALL.md).

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
    /// Detections called unknown under Δ.
    pub unknown: usize,
    /// Objects drawn without contrast to their surroundings.
    pub low_contrast: usize,
    /// Of those, the matched ones.
    pub low_contrast_matched: usize,
    /// Of those, the ones whose detection's best class is theirs.
    pub low_contrast_top1: usize,
    /// Every detection, in the detector's order.
    pub found: Vec<Found>,
}

/// One detection as scored: where it is, what it overlaps and what it is
/// called.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Found {
    /// Its box.
    pub bbox: BoxPx,
    /// Its largest box IoU with any object of the truth (0 with none).
    pub best_iou: f64,
    /// The object it is matched to.
    pub object: Option<usize>,
    /// Its best class's cosine score (`None` without a shape).
    pub score: Option<f32>,
    /// Its best class, known or not (`None` without a shape).
    pub class: Option<String>,
    /// The class of the object it is matched to.
    pub truth: Option<String>,
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
        let right = d.top5.first().is_some_and(|(c, _)| *c == o.class);
        s.top1 += usize::from(right);
        s.low_contrast_top1 += usize::from(right && !o.contrast);
        s.top5 += usize::from(d.top5.iter().any(|(c, _)| *c == o.class));
        claimed_right += usize::from(d.category() == Some(o.class.as_str()));
    }
    s.found = dets
        .iter()
        .enumerate()
        .map(|(k, d)| {
            let object = matches.iter().find(|m| m.detection == k).map(|m| m.object);
            Found {
                bbox: d.bbox,
                best_iou: gt.iter().map(|b| d.bbox.iou(b)).fold(0.0, f64::max),
                object,
                score: d.top5.first().map(|t| t.1),
                class: d.top5.first().map(|t| t.0.clone()),
                truth: object.and_then(|o| truth.get(o)).map(|o| o.class.clone()),
            }
        })
        .collect();
    let claims = dets.iter().filter(|d| d.category().is_some()).count();
    s.gist = claimed_right == truth.len() && claims == truth.len();
    s.unknown = dets.len() - claims;
    s.low_contrast = truth.iter().filter(|o| !o.contrast).count();
    s.low_contrast_matched = matches.iter().filter(|m| !truth[m.object].contrast).count();
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
    /// Detections called unknown under Δ / detections.
    pub unknown: Option<f64>,
    /// Recall of the objects drawn without contrast.
    pub low_contrast_recall: Option<f64>,
    /// Top-1 accuracy of the matched objects drawn without contrast.
    pub low_contrast_top1: Option<f64>,
}

impl Totals {
    /// Sums `scores`.
    pub fn of<'a>(scores: impl IntoIterator<Item = &'a SceneScore>) -> Self {
        let mut t = Self::default();
        let (mut iou, mut top1, mut top5, mut gist, mut ms) = (0.0, 0, 0, 0, 0.0);
        let (mut unknown, mut low, mut low_matched, mut low_top1) = (0, 0, 0, 0);
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
            unknown += s.unknown;
            low += s.low_contrast;
            low_matched += s.low_contrast_matched;
            low_top1 += s.low_contrast_top1;
        }
        t.recall = ratio(t.matched as f64, t.objects);
        t.precision = ratio(t.matched as f64, t.detections);
        t.mask_iou = ratio(iou, t.matched);
        t.top1 = ratio(top1 as f64, t.matched);
        t.top5 = ratio(top5 as f64, t.matched);
        t.gist = ratio(gist as f64, t.scenes);
        t.ms_per_scene = ratio(ms, t.scenes);
        t.unknown = ratio(unknown as f64, t.detections);
        t.low_contrast_recall = ratio(low_matched as f64, low);
        t.low_contrast_top1 = ratio(low_top1 as f64, low_matched);
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes::{ObjectTruth, SceneTruth};

    fn b(x: u32, y: u32, width: u32, height: u32) -> BoxPx {
        BoxPx {
            x,
            y,
            width,
            height,
        }
    }

    #[test]
    fn matching_takes_iou_of_one_half_and_not_below() {
        let gt = [b(0, 0, 10, 10)];
        // Exactly 0.5 (a half-size box inside) matches.
        assert_eq!(match_boxes(&[b(0, 0, 10, 5)], &gt).len(), 1);
        // 45 / 100 does not.
        assert!(match_boxes(&[b(0, 0, 9, 5)], &gt).is_empty());
        assert!(match_boxes(&[], &gt).is_empty());
        assert!(match_boxes(&gt, &[]).is_empty());
    }

    #[test]
    fn matching_is_greedy_by_iou_one_to_one() {
        // Detection 0 overlaps both objects; detection 1 fits object 1 best.
        let gt = [b(0, 0, 10, 10), b(2, 0, 10, 10)];
        let dets = [b(1, 0, 10, 10), b(2, 0, 10, 10)];
        let m = match_boxes(&dets, &gt);
        assert_eq!(m.len(), 2);
        assert_eq!((m[0].detection, m[0].object, m[0].iou), (1, 1, 1.0));
        assert_eq!((m[1].detection, m[1].object), (0, 0));
        // Two detections of one object: only the better one matches.
        let m = match_boxes(&[b(1, 0, 10, 10), b(0, 0, 10, 10)], &gt[..1]);
        assert_eq!(m.len(), 1);
        assert_eq!(m[0].detection, 1);
        // Ties go to the lower index.
        let m = match_boxes(&[b(0, 0, 10, 10), b(0, 0, 10, 10)], &gt[..1]);
        assert_eq!(m[0].detection, 0);
    }

    #[test]
    fn mask_iou_counts_pixels() {
        assert_eq!(
            mask_iou(&[true, true, false, false], &[255, 0, 255, 0]),
            1.0 / 3.0
        );
        assert_eq!(mask_iou(&[false; 3], &[0; 3]), 0.0);
    }

    /// A 10x10 scene with objects `(class, box)` filling their boxes.
    fn scene(objects: &[(&str, BoxPx)]) -> Scene {
        let (w, h) = (10, 10);
        let fill = |bx: &BoxPx| -> Vec<u8> {
            (0..w * h)
                .map(|i| {
                    let (x, y) = ((i % w) as u32, (i / w) as u32);
                    let inside = (bx.x..bx.x + bx.width).contains(&x)
                        && (bx.y..bx.y + bx.height).contains(&y);
                    u8::from(inside) * 255
                })
                .collect()
        };
        Scene {
            dir: "scene_0007".into(),
            width: w,
            height: h,
            left: vec![],
            right: vec![],
            disparity: vec![],
            truth: SceneTruth {
                format: String::new(),
                width: 10,
                height: 10,
                objects: objects
                    .iter()
                    .map(|(c, bx)| ObjectTruth {
                        class: (*c).into(),
                        mask: String::new(),
                        bbox: *bx,
                        disparity: 1.0,
                        area: 0,
                        contrast: true,
                    })
                    .collect(),
            },
            masks: objects.iter().map(|(_, bx)| fill(bx)).collect(),
        }
    }

    fn det(s: &Scene, k: usize, top: &[&str], known: bool) -> Detection {
        Detection {
            bbox: s.truth.objects[k].bbox,
            mask: s.masks[k].iter().map(|&v| v != 0).collect(),
            top5: top.iter().map(|c| ((*c).to_string(), 0.9)).collect(),
            known,
        }
    }

    #[test]
    fn scene_scores_and_the_gist() {
        let s = scene(&[("a", b(0, 0, 4, 4)), ("b", b(5, 5, 5, 5))]);
        let right = [det(&s, 0, &["a", "c"], true), det(&s, 1, &["b"], true)];
        let sc = score_scene(&s, &right, 2.0);
        assert_eq!((sc.objects, sc.detections, sc.matched), (2, 2, 2));
        assert_eq!((sc.top1, sc.top5, sc.mask_iou_sum), (2, 2, 2.0));
        assert!(sc.gist);
        assert_eq!(sc.scene, "scene_0007");

        // Second best class: top-5 but not top-1, and the gist is wrong.
        let second = [det(&s, 0, &["c", "a"], true), det(&s, 1, &["b"], true)];
        let sc = score_scene(&s, &second, 0.0);
        assert_eq!((sc.top1, sc.top5, sc.gist), (1, 2, false));

        // Right class but unknown under Δ: top-1 counts, the gist does not.
        let unknown = [det(&s, 0, &["a"], false), det(&s, 1, &["b"], true)];
        let sc = score_scene(&s, &unknown, 0.0);
        assert_eq!((sc.top1, sc.gist, sc.unknown), (2, false, 1));

        // An extra detection: harmless when unknown, wrong when it claims.
        let mut extra = right.to_vec();
        extra.push(Detection {
            bbox: b(0, 6, 3, 3),
            mask: vec![false; 100],
            top5: vec![("d".into(), 0.5)],
            known: false,
        });
        let sc = score_scene(&s, &extra, 0.0);
        assert_eq!((sc.detections, sc.matched, sc.gist), (3, 2, true));
        // Every detection is listed with its best box IoU and its match.
        let found: Vec<_> = sc.found.iter().map(|f| (f.object, f.best_iou)).collect();
        assert_eq!(found[..2], [(Some(0), 1.0), (Some(1), 1.0)]);
        assert_eq!(found[2].0, None);
        assert!(found[2].1 < MIN_IOU, "{found:?}");
        assert_eq!(sc.found[0].bbox, b(0, 0, 4, 4));
        assert_eq!(sc.found[0].score, Some(0.9));
        // Each names its best class and, when matched, its object's class.
        let names: Vec<_> = sc
            .found
            .iter()
            .map(|f| (f.class.as_deref(), f.truth.as_deref()))
            .collect();
        assert_eq!(
            names,
            [
                (Some("a"), Some("a")),
                (Some("b"), Some("b")),
                (Some("d"), None)
            ]
        );
        let sc = score_scene(&s, &second, 0.0);
        assert_eq!(
            (sc.found[0].class.as_deref(), sc.found[0].truth.as_deref()),
            (Some("c"), Some("a"))
        );
        extra[2].known = true;
        assert!(!score_scene(&s, &extra, 0.0).gist);

        // Nothing found.
        let sc = score_scene(&s, &[], 0.0);
        assert_eq!((sc.matched, sc.gist), (0, false));

        // Low-contrast objects are counted apart.
        let mut low = scene(&[("a", b(0, 0, 4, 4)), ("b", b(5, 5, 5, 5))]);
        low.truth.objects[1].contrast = false;
        let sc = score_scene(&low, &right[..1], 0.0);
        assert_eq!((sc.low_contrast, sc.low_contrast_matched), (1, 0));
        let sc = score_scene(&low, &right, 0.0);
        assert_eq!((sc.low_contrast, sc.low_contrast_matched), (1, 1));
        assert_eq!((sc.top1, sc.low_contrast_top1), (2, 1));
        // Named wrong: matched, not right.
        let wrong = [det(&low, 0, &["a"], true), det(&low, 1, &["a", "b"], true)];
        let sc = score_scene(&low, &wrong, 0.0);
        assert_eq!((sc.low_contrast_matched, sc.low_contrast_top1), (1, 0));
    }

    #[test]
    fn totals_are_ratios_of_sums() {
        let one = SceneScore {
            objects: 2,
            detections: 4,
            matched: 2,
            mask_iou_sum: 1.5,
            top1: 1,
            top5: 2,
            gist: false,
            ms: 10.0,
            unknown: 1,
            low_contrast: 1,
            low_contrast_matched: 1,
            low_contrast_top1: 1,
            ..SceneScore::default()
        };
        let two = SceneScore {
            objects: 2,
            detections: 0,
            matched: 0,
            gist: false,
            ms: 30.0,
            low_contrast: 1,
            ..SceneScore::default()
        };
        let three = SceneScore {
            objects: 1,
            detections: 1,
            matched: 1,
            mask_iou_sum: 0.9,
            top1: 1,
            top5: 1,
            gist: true,
            ms: 20.0,
            ..SceneScore::default()
        };
        let t = Totals::of([&one, &two, &three]);
        assert_eq!((t.scenes, t.objects, t.detections, t.matched), (3, 5, 5, 3));
        assert_eq!(t.recall, Some(0.6));
        assert_eq!(t.precision, Some(0.6));
        assert!((t.mask_iou.unwrap() - 0.8).abs() < 1e-12);
        assert_eq!(t.top1, Some(2.0 / 3.0));
        assert_eq!(t.top5, Some(1.0));
        assert_eq!(t.gist, Some(1.0 / 3.0));
        assert_eq!(t.ms_per_scene, Some(20.0));
        assert_eq!(t.unknown, Some(0.2));
        assert_eq!(t.low_contrast_recall, Some(0.5));
        assert_eq!(t.low_contrast_top1, Some(1.0));
        // No detections at all: precision and per-match rates undefined.
        let t = Totals::of([&two]);
        assert_eq!((t.recall, t.precision, t.top1), (Some(0.0), None, None));
        assert_eq!(Totals::of([]).recall, None);
    }
}
