//! The RGB-D Object Dataset loader on what `gen-rgbd` writes, and its
//! typed errors.

use protogist_host::rgbd::features::{item_features, Condition};
use protogist_host::rgbd::gen::{gen_rgbd, GenRgbdOptions};
use protogist_host::rgbd::loader::{load_frame, scan};
use protogist_host::rgbd::RgbdError;
use std::path::{Path, PathBuf};

fn generate(dir: &Path, categories: usize, instances: usize, frames: u32) -> PathBuf {
    gen_rgbd(&GenRgbdOptions {
        out: dir.to_path_buf(),
        categories,
        instances,
        frames,
        seed: 3,
    })
    .unwrap();
    dir.join("rgbd-dataset")
}

#[test]
fn the_loader_reads_what_gen_rgbd_writes() {
    let tmp = tempfile::tempdir().unwrap();
    let root = generate(tmp.path(), 3, 3, 10);
    // Layout: category/instance/instance_video_frame_{crop,depthcrop,maskcrop}.png + _loc.txt.
    for f in ["crop.png", "depthcrop.png", "maskcrop.png", "loc.txt"] {
        assert!(
            root.join("can/can_2")
                .join(format!("can_2_3_7_{f}"))
                .is_file(),
            "{f}"
        );
    }
    let index = scan(tmp.path()).unwrap();
    assert_eq!(index.categories, ["ball", "can", "cereal_box"]);
    // 3 categories × 3 instances × 3 videos × 10 frames, frames 1 and 6 sampled.
    assert_eq!(index.frames_seen, 270);
    assert_eq!(index.counts(), (3 * 2 * 3 * 2, 3 * 3 * 2));
    assert!(index.items.iter().all(|i| i.frame % 5 == 1));
    assert!(index
        .items
        .iter()
        .all(|i| i.test == i.instance.ends_with("_1")));
    for item in index.items.iter().step_by(7) {
        let f = load_frame(item).unwrap();
        let n = (f.rgb.width() * f.rgb.height()) as usize;
        assert_eq!((f.depth.len(), f.mask.len()), (n, n));
        let object = f.mask.iter().filter(|&&m| m > 0).count();
        assert!(object > n / 5 && object < n, "{object} of {n}");
        // Depth: mm around a metre, holes (0) present but not everywhere.
        let holes = f.depth.iter().filter(|&&d| d == 0).count();
        assert!(holes > 0 && holes < n / 2, "{holes} holes of {n}");
        assert!(f.depth.iter().all(|&d| d == 0 || (300..3500).contains(&d)));
        let feats = item_features(item, true).unwrap();
        for c in Condition::PAPER.into_iter().chain([Condition::Colour3]) {
            assert_eq!(feats.input(c).len(), c.input_len(), "{c:?}");
        }
    }
}

#[test]
fn instances_differ_and_categories_differ_in_shape() {
    let tmp = tempfile::tempdir().unwrap();
    generate(tmp.path(), 2, 2, 5);
    let index = scan(tmp.path()).unwrap();
    let mask_area = |i: usize| {
        let f = load_frame(&index.items[i]).unwrap();
        (
            f.rgb.dimensions(),
            f.mask.iter().filter(|&&m| m > 0).count(),
        )
    };
    // Items: ball_1 (3 videos), ball_2, can_1, can_2; same view, other instance or category.
    let firsts: Vec<_> = [0, 3, 6, 9].iter().map(|&i| mask_area(i)).collect();
    for a in 0..4 {
        for b in a + 1..4 {
            assert_ne!(firsts[a], firsts[b], "{a} {b}");
        }
    }
}

#[test]
fn loader_errors_are_typed() {
    let tmp = tempfile::tempdir().unwrap();
    let root = generate(tmp.path(), 2, 2, 5);
    let inst = root.join("ball/ball_2");
    let stem = |s: &str| inst.join(format!("ball_2_2_1_{s}"));

    // Missing depth, then missing mask.
    let depth = std::fs::read(stem("depthcrop.png")).unwrap();
    std::fs::remove_file(stem("depthcrop.png")).unwrap();
    assert!(matches!(
        scan(&root),
        Err(RgbdError::MissingCompanion { kind: "depth", .. })
    ));
    std::fs::write(stem("depthcrop.png"), &depth).unwrap();
    let mask = std::fs::read(stem("maskcrop.png")).unwrap();
    std::fs::remove_file(stem("maskcrop.png")).unwrap();
    let e = scan(&root).unwrap_err();
    assert!(
        matches!(e, RgbdError::MissingCompanion { kind: "mask", .. }),
        "{e}"
    );
    std::fs::write(stem("maskcrop.png"), &mask).unwrap();

    let index = scan(&root).unwrap();
    let item = index
        .items
        .iter()
        .find(|i| i.instance == "ball_2" && i.video == 2 && i.frame == 1)
        .unwrap()
        .clone();
    load_frame(&item).unwrap();
    // Depth of another size than the crop.
    image::ImageBuffer::<image::Luma<u16>, _>::from_pixel(7, 5, image::Luma([900u16]))
        .save(stem("depthcrop.png"))
        .unwrap();
    let e = load_frame(&item).unwrap_err();
    assert!(
        matches!(
            e,
            RgbdError::SizeMismatch {
                kind: "depth",
                got: (7, 5),
                ..
            }
        ),
        "{e}"
    );
    // An 8-bit depth, then bytes that are no PNG.
    image::GrayImage::new(7, 5)
        .save(stem("depthcrop.png"))
        .unwrap();
    let e = load_frame(&item).unwrap_err();
    assert!(matches!(e, RgbdError::BadDepth { .. }), "{e}");
    std::fs::write(stem("depthcrop.png"), b"not a png").unwrap();
    let e = load_frame(&item).unwrap_err();
    assert!(matches!(e, RgbdError::BadDepth { .. }), "{e}");
    std::fs::write(stem("depthcrop.png"), &depth).unwrap();
    // A mask of another size.
    image::GrayImage::new(3, 3)
        .save(stem("maskcrop.png"))
        .unwrap();
    let e = load_frame(&item).unwrap_err();
    assert!(
        matches!(e, RgbdError::SizeMismatch { kind: "mask", .. }),
        "{e}"
    );
    std::fs::write(stem("maskcrop.png"), &mask).unwrap();

    // An empty category.
    std::fs::create_dir(root.join("cup")).unwrap();
    let e = scan(&root).unwrap_err();
    assert!(
        matches!(&e, RgbdError::EmptyCategory { category } if category == "cup"),
        "{e}"
    );
    std::fs::remove_dir(root.join("cup")).unwrap();
    scan(&root).unwrap();
}

#[test]
fn other_layouts_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    // No folder at all, and a folder without categories.
    assert!(matches!(
        scan(&tmp.path().join("missing")),
        Err(RgbdError::NotDataset { .. })
    ));
    assert!(matches!(
        scan(tmp.path()),
        Err(RgbdError::NotDataset { .. })
    ));
    // An image-folder dataset (class/image.png) is not this layout.
    let shapes = tmp.path().join("shapes");
    std::fs::create_dir_all(shapes.join("circle")).unwrap();
    image::GrayImage::new(4, 4)
        .save(shapes.join("circle/0001.png"))
        .unwrap();
    let e = scan(&shapes).unwrap_err();
    assert!(matches!(e, RgbdError::NotDataset { .. }), "{e}");
    // Instance folders not named <category>_<n>, and crops not named <instance>_<v>_<f>_crop.png.
    let bad = tmp.path().join("bad");
    std::fs::create_dir_all(bad.join("apple/pear_1")).unwrap();
    let e = scan(&bad).unwrap_err();
    assert!(e.to_string().contains("apple_<number>"), "{e}");
    std::fs::remove_dir(bad.join("apple/pear_1")).unwrap();
    std::fs::create_dir_all(bad.join("apple/apple_1")).unwrap();
    std::fs::write(bad.join("apple/apple_1/apple_1_x_crop.png"), b"").unwrap();
    let e = scan(&bad).unwrap_err();
    assert!(matches!(e, RgbdError::NotDataset { .. }), "{e}");
}
