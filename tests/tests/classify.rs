//! Issue 5, host side: the development silhouettes feed the core shape
//! stage, and the classification rules and metrics run end to end on their
//! shape vectors.

use image::GrayImage;
use protogist::image::ImageView;
use protogist::shape::{shape_vector, RadialProfile, ShapeElem, SHAPE_LEN};
use protogist_host::classify::metrics::{cmc, Det};
use protogist_host::classify::plots::{cmc_points, write_plot, Curve, PlotKind, SHAPE_BLUE};
use protogist_host::classify::rules::{evaluate, Templates};
use protogist_host::classify::shapes::{class_dir, gen_shapes, render, GenShapesOptions};

/// The core (fixed-point) shape vector of a grey mask (non-zero = object),
/// as f32.
fn shape_of(img: &GrayImage) -> Vec<f32> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let px: Vec<u8> = img.pixels().map(|p| u8::from(p.0[0] > 0)).collect();
    let view = ImageView::packed(&px, w, h).unwrap();
    let mut profile = RadialProfile::new();
    let mut v = [ShapeElem::ZERO; SHAPE_LEN];
    shape_vector(&view, &mut profile, &mut v).unwrap();
    v.iter().map(|e| e.to_num::<f32>()).collect()
}

#[test]
fn gen_shapes_writes_an_image_folder_tree_of_binary_masks() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("shapes");
    gen_shapes(&GenShapesOptions {
        out: out.clone(),
        classes: 5,
        per_class: 3,
        seed: 9,
        size: 48,
    })
    .unwrap();
    let mut classes: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    classes.sort();
    let expected: Vec<String> = (0..5).map(|c| class_dir(c).unwrap()).collect();
    assert_eq!(classes, expected);
    for c in &classes {
        let files: Vec<_> = std::fs::read_dir(out.join(c))
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        assert_eq!(files.len(), 3, "{c}: {files:?}");
        for f in files {
            assert_eq!(f.extension().unwrap(), "png", "no temporary left: {f:?}");
            let img = image::open(&f).unwrap();
            assert!(matches!(img.color(), image::ColorType::L8), "{f:?} is grey");
            let img = img.to_luma8();
            assert!(img.pixels().all(|p| p.0[0] == 0 || p.0[0] == 255));
            let v = shape_of(&img);
            assert!(v.iter().all(|x| x.is_finite()));
        }
    }
}

/// A baseline, not the paper's classifier: the "network" is the identity,
/// so the outputs are the 720-element shape vectors themselves and the
/// templates their class means. 12 classes (look-alike pairs included),
/// 8 training and 8 test images each.
#[test]
fn identity_network_baseline_on_generated_shapes() {
    const N: usize = 12;
    let (mut train, mut train_y, mut test, mut test_y) = (vec![], vec![], vec![], vec![]);
    for c in 0..N {
        for i in 0..16u64 {
            let v = shape_of(&render(c, i, 2024, 64).unwrap());
            if i < 8 {
                train.push(v);
                train_y.push(c);
            } else {
                test.push(v);
                test_y.push(c);
            }
        }
    }
    let templates = Templates::from_outputs(&train, &train_y, N).unwrap();
    let ev = evaluate(&templates, &test, &test_y).unwrap();
    let rates = cmc(&ev.ranks, N).unwrap();
    let det = Det::sweep(&ev.genuine, &ev.impostor).unwrap();
    let (hter, _) = det.hter_min();
    println!(
        "identity baseline, {N} classes: ROR {:.1} %, rank-5 {:.1} %, EER {:.1} %, \
         HTER_min {:.1} %, AUC {:.1} %, VR@FAR1% {:.1} %, VR@FAR0.1% {:.1} %",
        100.0 * rates[0],
        100.0 * rates[4],
        100.0 * det.eer(),
        100.0 * hter,
        100.0 * det.auc(),
        100.0 * det.verification_rate_at(0.01).unwrap(),
        100.0 * det.verification_rate_at(0.001).unwrap(),
    );
    // What must hold: well above chance (1/N), a monotone CMC reaching 1,
    // HTER_min <= EER, better than random verification.
    assert!(rates[0] > 3.0 / N as f64, "ROR {}", rates[0]);
    assert!(rates.windows(2).all(|w| w[0] <= w[1]) && rates[N - 1] == 1.0);
    assert!(hter <= det.eer() + 1e-12);
    assert!(det.eer() < 0.5 && det.auc() > 0.5);

    // PROTOGIST_PLOT_DIR keeps the plots for a look; else a temp dir.
    let tmp = tempfile::tempdir().unwrap();
    let dir = std::env::var_os("PROTOGIST_PLOT_DIR").map_or(tmp.path().to_path_buf(), Into::into);
    let curve = |points| Curve {
        label: "shape".into(),
        points,
        colour: SHAPE_BLUE,
        dashed: true,
    };
    let det_pts = det.points().iter().map(|p| (p.far, p.frr)).collect();
    for (name, kind, c) in [
        (
            "cmc",
            PlotKind::Cmc { classes: N },
            curve(cmc_points(&rates)),
        ),
        ("det", PlotKind::Det, curve(det_pts)),
        ("roc", PlotKind::Roc, curve(det.roc())),
    ] {
        let [png, svg] = write_plot(&dir, name, kind, &[c], (320, 240)).unwrap();
        assert!(png.is_file() && svg.is_file());
    }
}
