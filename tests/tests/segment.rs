//! The whole segmentation stage: mask accuracy on seeded synthetic scenes
//! (GT disparity and the disparity energy model as input), bad input, and
//! several objects.

use protogist::conspicuity::{Conspicuity, EdgeCell};
use protogist::disparity::{from_pixels, DisparityCell};
use protogist::image::ImageView;
use protogist::segment::{self as sg, Connectivity, Labeller, Ratio};
use protogist::segment::{segment, SegmentParams};
use protogist_host::eval::DisparitySource;
use protogist_tests::{mask, SegmentStorage};

const W: usize = 160;
const H: usize = 120;
const SCENES: u64 = 24;

#[test]
fn mean_mask_iou_on_seeded_scenes() {
    // The same code as `protogist segment-eval`, which `cargo xtask bench`
    // runs for docs/BENCHMARKS.md.
    let results = protogist_host::eval::segment_eval(SCENES, W, H, DisparitySource::Gt).unwrap();
    for r in &results {
        println!(
            "scene {:2}: IoU {:.3} (object {:?} of {})",
            r.seed, r.iou, r.object, r.objects
        );
    }
    let mean = results.iter().map(|r| r.iou).sum::<f64>() / results.len() as f64;
    println!("mean IoU over {SCENES} scenes: {mean:.3}");
    assert!(mean >= 0.85, "mean IoU {mean:.3} < 0.85");
}

#[test]
fn mean_mask_iou_with_the_disparity_energy_model() {
    // The pipeline's path: the f32 model on the rendered pair, completed over
    // the conspicuity regions (`protogist::complete`). Issue 4 asks >= 0.85.
    let results = protogist_host::eval::segment_eval(SCENES, W, H, DisparitySource::Dem).unwrap();
    let mean = results.iter().map(|r| r.iou).sum::<f64>() / results.len() as f64;
    println!("mean IoU over {SCENES} scenes with the model: {mean:.3}");
    assert!(mean >= 0.85, "mean IoU {mean:.3} < 0.85");
    let worst = results.iter().map(|r| r.iou).fold(1.0, f64::min);
    assert!(worst > 0.5, "a scene fell to IoU {worst:.3}");
}

// ---------------------------------------------------------------------------
// Bad input (issue section 8): typed errors or empty results, never a panic.

/// Runs the stage on whole-px disparities and a conspicuity map.
fn run(
    d: &[DisparityCell],
    c: &[EdgeCell],
    w: usize,
    h: usize,
    params: &SegmentParams,
) -> (Result<sg::SegmentReport, sg::SegmentError>, Vec<bool>) {
    let mut store = SegmentStorage::new(w, h);
    let mut masks = vec![false; usize::from(params.max_objects) * w * h];
    let r = segment(
        params,
        &ImageView::packed(d, w, h).unwrap(),
        &ImageView::packed(c, w, h).unwrap(),
        &mut store.buffers().unwrap(),
        &mut masks,
    );
    (r, masks)
}

/// A 48x36 scene: background 2 px; boxes `(x0, y0, x1, y1, d)` with a strong
/// outline and a weak inside in C.
fn boxes(
    w: usize,
    h: usize,
    list: &[(usize, usize, usize, usize, u8)],
) -> (Vec<DisparityCell>, Vec<EdgeCell>) {
    let mut d = vec![from_pixels(2); w * h];
    let mut c = vec![EdgeCell::OFF; w * h];
    for &(x0, y0, x1, y1, disp) in list {
        for y in y0..y1 {
            for x in x0..x1 {
                d[y * w + x] = from_pixels(disp);
                let ring = x == x0 || y == y0 || x + 1 == x1 || y + 1 == y1;
                c[y * w + x] =
                    EdgeCell::on(Conspicuity::from_num(if ring { 40 } else { 5 })).unwrap();
            }
        }
    }
    (d, c)
}

const BW: usize = 48;
const BH: usize = 36;

#[test]
fn no_foreground_all_off_and_flat_maps_give_no_object() {
    let p = SegmentParams::default();
    let c = vec![EdgeCell::on(Conspicuity::from_num(9)).unwrap(); BW * BH];
    // All OFF disparity.
    let (r, m) = run(&vec![DisparityCell::OFF; BW * BH], &c, BW, BH, &p);
    let r = r.unwrap();
    assert!(r.stats.is_none() && r.objects.is_empty() && m.iter().all(|&b| !b));
    // Zero variance: D_fg is empty (mean + 0.1σ < D fails everywhere).
    let (r, _) = run(&vec![from_pixels(7); BW * BH], &c, BW, BH, &p);
    let r = r.unwrap();
    assert_eq!(r.stats.unwrap().sigma, 0);
    assert_eq!(r.foreground, 0);
    assert!(r.objects.is_empty());
    // Foreground but no edge at all.
    let (d, _) = boxes(BW, BH, &[(12, 10, 36, 26, 9)]);
    let (r, _) = run(&d, &vec![EdgeCell::OFF; BW * BH], BW, BH, &p);
    let r = r.unwrap();
    assert!(r.foreground > 0 && r.objects.is_empty());
    // Valid disparity only outside S.
    let mut d = vec![DisparityCell::OFF; BW * BH];
    d[0] = from_pixels(30);
    let (r, _) = run(&d, &c, BW, BH, &p);
    assert!(r.unwrap().stats.is_none());
}

#[test]
fn a_box_is_found_and_a_one_pixel_object_gives_a_tiny_mask_or_none() {
    let p = SegmentParams::default();
    let (d, c) = boxes(BW, BH, &[(12, 10, 36, 26, 9)]);
    let (r, m) = run(&d, &c, BW, BH, &p);
    let o = r.unwrap().objects[0];
    assert_eq!((o.delta, o.area), (9, 24 * 16));
    assert_eq!(m.iter().filter(|&&b| b).count(), 24 * 16);
    // One pixel at 30 px over a 2 px background: above mean + 2σ, so D_fg
    // drops it as a wrong estimate; nothing is found.
    let mut d = vec![from_pixels(2); BW * BH];
    d[18 * BW + 24] = from_pixels(30);
    let mut c = vec![EdgeCell::OFF; BW * BH];
    c[18 * BW + 24] = EdgeCell::on(Conspicuity::from_num(50)).unwrap();
    let (r, m) = run(&d, &c, BW, BH, &p);
    let r = r.unwrap();
    assert!(r.objects.iter().all(|o| o.area <= 1));
    assert!(m.iter().filter(|&&b| b).count() <= 1);
}

#[test]
fn objects_touching_the_border_and_open_contours_give_partial_masks() {
    let p = SegmentParams::default();
    // A box running off the right border: its outline is open there.
    let (d, mut c) = boxes(BW, BH, &[(20, 10, BW, 26, 9)]);
    for y in 10..26 {
        c[y * BW + BW - 1] = EdgeCell::on(Conspicuity::from_num(5)).unwrap();
    }
    let (r, m) = run(&d, &c, BW, BH, &p);
    let r = r.unwrap();
    assert_eq!(r.objects.len(), 1);
    let area = m.iter().filter(|&&b| b).count();
    assert!(area < 28 * 16, "a partial mask at most: {area}");
    // A box whose outline has a 12-px gap, too wide for the closing.
    let (d, mut c) = boxes(BW, BH, &[(10, 9, 38, 27, 9)]);
    for x in 18..30 {
        c[9 * BW + x] = EdgeCell::on(Conspicuity::from_num(5)).unwrap();
    }
    let (r, m) = run(&d, &c, BW, BH, &p);
    let r = r.unwrap();
    let area = m.iter().filter(|&&b| b).count();
    assert!(area < 28 * 18 / 2, "the open outline is not filled: {area}");
    assert_eq!(r.objects[0].area as usize, area);
}

#[test]
fn running_out_of_labels_is_a_typed_error() {
    let (w, h) = (9, 9);
    let (m, _, _) = mask![
        "#.#.#.#.#",
        ".........",
        "#.#.#.#.#",
        ".........",
        "#.#.#.#.#",
        ".........",
        "#.#.#.#.#",
        ".........",
        "#.#.#.#.#",
    ];
    let (mut labels, mut parent, mut area) = (vec![0u16; w * h], vec![0u16; 10], vec![0u32; 10]);
    let mut lab = Labeller::new(w, h, &mut labels, &mut parent, &mut area).unwrap();
    assert_eq!(
        lab.label(
            &ImageView::packed(&m, w, h).unwrap(),
            true,
            Connectivity::Eight
        ),
        Err(sg::SegmentError::LabelCapacity { capacity: 10 })
    );
    // 25 components need 26 entries.
    let (mut parent, mut area) = (vec![0u16; 26], vec![0u32; 26]);
    let mut lab = Labeller::new(w, h, &mut labels, &mut parent, &mut area).unwrap();
    assert_eq!(
        lab.label(
            &ImageView::packed(&m, w, h).unwrap(),
            true,
            Connectivity::Eight
        ),
        Ok(25)
    );
    // The whole stage reports it too.
    let (d, c) = boxes(BW, BH, &[(12, 10, 36, 26, 9)]);
    let mut store = SegmentStorage::new(BW, BH);
    store.area.truncate(3);
    let mut masks = vec![false; BW * BH];
    let r = segment(
        &SegmentParams::default(),
        &ImageView::packed(&d, BW, BH).unwrap(),
        &ImageView::packed(&c, BW, BH).unwrap(),
        &mut store.buffers().unwrap(),
        &mut masks,
    );
    assert!(
        matches!(r, Err(sg::SegmentError::LabelCapacity { .. })),
        "{r:?}"
    );
}

#[test]
fn bad_sizes_and_parameters_are_typed_errors() {
    let (d, c) = boxes(BW, BH, &[(12, 10, 36, 26, 9)]);
    let mut store = SegmentStorage::new(BW, BH);
    let mut masks = vec![false; BW * BH - 1];
    let p = SegmentParams::default();
    let dv = ImageView::packed(&d, BW, BH).unwrap();
    let cv = ImageView::packed(&c, BW, BH).unwrap();
    assert_eq!(
        segment(&p, &dv, &cv, &mut store.buffers().unwrap(), &mut masks),
        Err(sg::SegmentError::MasksTooSmall {
            needed: BW * BH,
            got: BW * BH - 1
        })
    );
    let mut masks = vec![false; BW * BH];
    let small = ImageView::packed(&c, BW, BH - 1).unwrap();
    assert!(matches!(
        segment(&p, &dv, &small, &mut store.buffers().unwrap(), &mut masks),
        Err(sg::SegmentError::SizeMismatch { .. })
    ));
    for bad in [
        SegmentParams {
            max_objects: 0,
            ..p
        },
        SegmentParams {
            max_objects: 9,
            ..p
        },
        SegmentParams { exponent: 9, ..p },
        SegmentParams {
            closing_steps: sg::MAX_CLOSING_STEPS + 1,
            ..p
        },
        SegmentParams {
            range: Ratio::new(1, 0),
            ..p
        },
        SegmentParams {
            top_bottom_strip: Ratio::new(1, 2),
            ..p
        },
    ] {
        let r = segment(&bad, &dv, &cv, &mut store.buffers().unwrap(), &mut masks);
        assert!(matches!(r, Err(sg::SegmentError::BadParams(_))), "{bad:?}");
        assert!(!r.unwrap_err().to_string().is_empty());
    }
    let (mut maps, mut ar) = (vec![0u32; 3], vec![0u32; 3]);
    assert!(sg::SegmentBuffers::new(BW, BH, &mut maps, &mut ar).is_err());
}

#[test]
fn several_objects_are_found_one_after_another() {
    // Two boxes at 11 and 14 px, side by side, and a background at 2 px
    // (both inside mean + 0.1σ .. mean + 2σ, and 3 px apart: r is 1.9 px).
    // Kept 5 px from the right border: the closing's erosion counts the
    // outside as ON, so a mask within 4 px of the border may grow to it.
    let (d, c) = boxes(BW, BH, &[(8, 8, 22, 28, 11), (26, 9, 42, 27, 14)]);
    let p = SegmentParams {
        max_objects: 4,
        ..Default::default()
    };
    let (r, m) = run(&d, &c, BW, BH, &p);
    let r = r.unwrap();
    let found: Vec<(u16, u32)> = r.objects.iter().map(|o| (o.delta, o.area)).collect();
    assert!(found.len() >= 2, "{found:?}");
    // The nearer box first (A^C·d favours it), then the other; each mask is
    // exactly its box.
    assert_eq!(found[0], (14, 16 * 18), "{found:?}");
    assert_eq!(found[1], (11, 14 * 20), "{found:?}");
    let first = &m[..BW * BH];
    assert!(first[18 * BW + 36] && !first[18 * BW + 15]);
    let second = &m[BW * BH..2 * BW * BH];
    assert!(second[18 * BW + 15] && !second[18 * BW + 36]);
    // Later searches find nothing new: empty slots stay clear.
    for (o, mask) in r.objects.iter().zip(m.chunks(BW * BH)).skip(2) {
        assert_eq!(o.area as usize, mask.iter().filter(|&&b| b).count());
    }
}

/// The other reading of ψ̄, on the same scenes: docs/SEGMENT.md chose the
/// region mean because this one loses to it; the test holds that claim.
#[test]
fn psi_mean_over_on_cells_for_comparison() {
    let params = SegmentParams {
        psi_mean: sg::PsiMean::OnCells,
        ..Default::default()
    };
    let sum: f64 = (0..SCENES)
        .map(|s| {
            protogist_host::eval::segment_scene_iou(s, W, H, &params, DisparitySource::Gt, None)
                .unwrap()
                .iou
        })
        .sum();
    let on_cells = sum / SCENES as f64;
    let region = protogist_host::eval::segment_eval(SCENES, W, H, DisparitySource::Gt)
        .unwrap()
        .iter()
        .map(|r| r.iou)
        .sum::<f64>()
        / SCENES as f64;
    println!("mean IoU: PsiMean::OnCells {on_cells:.3}, PsiMean::Region {region:.3}");
    assert!(
        on_cells < region,
        "the default reading is not the better one"
    );
}
