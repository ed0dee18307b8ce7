//! Fuzz targets of every parser of untrusted files (issue 22 §6): the PFM
//! and PNG ground-truth readers, the image loader's size checks, the model
//! blob and its float sidecar, the decoder table and the dataset loader's
//! per-image path.
//!
//! Each target mutates a valid seed file (bytes overwritten, the file cut,
//! bytes appended; for the blob and the PNG header, with their checksums
//! fixed up so the mutation reaches the checks behind them) and checks
//! that the parser returns a typed result, never panics, and that what it
//! accepts keeps its invariants. `cargo test` runs a short budget
//! ([`DEFAULT_CASES`] per target); `cargo xtask fuzz` runs them long
//! (`PROTOGIST_FUZZ_CASES`, docs/FUZZ.md).

use proptest::prelude::*;
use protogist_host::classify::dataset::{mask_of, shape_inputs};
use protogist_host::classify::model::{parse_sidecar, ModelFile, MODEL_FORMAT};
use protogist_host::classify::shipped::SHIPPED_MODEL;
use protogist_host::ground_truth::{gt_from_bytes, parse_pfm};
use protogist_host::io::{decode_image, MAX_INPUT_PIXELS};
use protogist_host::reference::stereo::table::{DemTable, DEFAULT_TABLE};
use std::path::Path;

/// Cases per target under `cargo test`.
const DEFAULT_CASES: u32 = 256;

/// Cases per target: `PROTOGIST_FUZZ_CASES`, else [`DEFAULT_CASES`].
fn config() -> ProptestConfig {
    let cases = std::env::var("PROTOGIST_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(DEFAULT_CASES);
    ProptestConfig {
        cases,
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// A mutation of `seed`: up to 8 bytes overwritten, maybe cut, up to 4
/// bytes appended.
fn mutate(seed: Vec<u8>) -> impl Strategy<Value = Vec<u8>> {
    let n = seed.len();
    (
        prop::collection::vec((0..n.max(1), any::<u8>()), 0..8),
        prop::option::weighted(0.2, 0..=n),
        prop::collection::vec(any::<u8>(), 0..4),
        prop::bool::weighted(0.2),
    )
        .prop_map(move |(edits, cut, tail, append)| {
            let mut b = seed.clone();
            for (i, v) in edits {
                if let Some(x) = b.get_mut(i) {
                    *x = v;
                }
            }
            if let Some(c) = cut {
                b.truncate(c);
            }
            if append {
                b.extend(tail);
            }
            b
        })
}

fn pfm_seed() -> Vec<u8> {
    let mut b = b"Pf\n6 4\n-1.0\n".to_vec();
    for k in 0..24u8 {
        let v = if k % 7 == 3 {
            f32::INFINITY
        } else {
            f32::from(k) / 5.0
        };
        b.extend_from_slice(&v.to_le_bytes());
    }
    b
}

fn png_of(img: image::DynamicImage) -> Vec<u8> {
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

fn grey16_seed() -> Vec<u8> {
    png_of(image::DynamicImage::ImageLuma16(
        image::ImageBuffer::from_fn(8, 6, |x, y| image::Luma([((x + y) % 5 * 64) as u16])),
    ))
}

fn rgb_seed() -> Vec<u8> {
    png_of(image::DynamicImage::ImageRgb8(image::RgbImage::from_fn(
        12,
        8,
        |x, y| image::Rgb([(x * 20) as u8, (y * 30) as u8, 7]),
    )))
}

fn jpeg_seed() -> Vec<u8> {
    let img = image::RgbImage::from_fn(16, 16, |x, y| {
        image::Rgb([(x * 16) as u8, (y * 9) as u8, 99])
    });
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Jpeg).unwrap();
    out.into_inner()
}

fn silhouette_seed() -> Vec<u8> {
    png_of(image::DynamicImage::ImageLuma8(image::GrayImage::from_fn(
        24,
        24,
        |x, y| {
            let (dx, dy) = (x as i32 - 12, y as i32 - 11);
            image::Luma([if dx * dx + 2 * dy * dy < 70 { 255 } else { 0 }])
        },
    )))
}

/// A PNG whose header says `w x h` (IHDR CRC fixed up), its data unchanged.
fn with_size(mut png: Vec<u8>, w: u32, h: u32) -> Vec<u8> {
    png[16..20].copy_from_slice(&w.to_be_bytes());
    png[20..24].copy_from_slice(&h.to_be_bytes());
    let crc = protogist::mlp::blob::crc32(&png[12..29]);
    png[29..33].copy_from_slice(&crc.to_be_bytes());
    png
}

fn sidecar_seed() -> Vec<u8> {
    let (d, h, k) = (720, 2, 2);
    let file = ModelFile {
        format: MODEL_FORMAT.into(),
        classes: vec!["a".into(), "b".into()],
        inputs: d,
        hidden: h,
        gamma: 0.2,
        seed: 1,
        test_fraction: 0.5,
        epochs: 1,
        final_perf: 0.1,
        final_mse: 0.1,
        train: vec!["a/1.png".into()],
        test: vec!["b/1.png".into()],
        w1: (0..h * d).map(|i| (i % 13) as f64 / 100.0).collect(),
        b1: vec![0.5; h],
        w2: vec![0.25; k * h],
        b2: vec![-0.5; k],
        blob_crc32: Some(7),
        templates: Some(vec![vec![0.9, 0.1], vec![0.1, 0.9]]),
        pipeline: None,
        mirror_images: false,
    };
    serde_json::to_vec(&file).unwrap()
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn pfm_reader(bytes in mutate(pfm_seed()), scale in 0.5f32..4.0) {
        let p = Path::new("gt.pfm");
        if let Ok(g) = gt_from_bytes(&bytes, p, scale) {
            prop_assert_eq!(g.data.len(), g.width * g.height);
            let max = g.width as f32;
            prop_assert!(g.data.iter().flatten().all(|v| (0.0..max).contains(v)));
            prop_assert!(g.data.iter().any(Option::is_some));
        }
        if let Ok(g) = parse_pfm(&bytes) {
            prop_assert_eq!(g.data.len(), g.width * g.height);
        }
    }

    #[test]
    fn png_gt_reader(bytes in mutate(grey16_seed()), scale in 0.5f32..300.0) {
        if let Ok(g) = gt_from_bytes(&bytes, Path::new("gt.png"), scale) {
            prop_assert_eq!(g.data.len(), g.width * g.height);
            let max = g.width as f32;
            prop_assert!(g.data.iter().flatten().all(|v| (0.0..max).contains(v)));
        }
    }

    #[test]
    fn image_loader_size_checks(
        png in mutate(rgb_seed()),
        jpeg in mutate(jpeg_seed()),
        w in prop_oneof![1u32..64, 1u32..=u32::MAX],
        h in prop_oneof![1u32..64, 1u32..=u32::MAX],
    ) {
        let p = Path::new("in");
        for bytes in [png, jpeg, with_size(rgb_seed(), w, h)] {
            if let Ok(img) = decode_image(&bytes, p) {
                prop_assert!(u64::from(img.width()) * u64::from(img.height()) <= MAX_INPUT_PIXELS);
            }
        }
    }

    #[test]
    fn model_blob(bytes in mutate(SHIPPED_MODEL.to_vec()), fix_crc in any::<bool>()) {
        let mut bytes = bytes;
        if fix_crc && bytes.len() > 4 {
            let n = bytes.len() - 4;
            let crc = protogist::mlp::blob::crc32(&bytes[..n]);
            bytes[n..].copy_from_slice(&crc.to_le_bytes());
        }
        if let Ok(m) = protogist::mlp::Model::parse(&bytes) {
            prop_assert!(m.classes() >= 1 && m.hidden() >= 1);
            for c in 0..m.classes() {
                prop_assert!(m.class_name(c).is_some());
            }
        }
    }

    #[test]
    fn model_sidecar(bytes in mutate(sidecar_seed())) {
        let p = Path::new("m.bin.json");
        if let Ok(file) = parse_sidecar(&bytes, p) {
            if let Ok(net) = file.network(p) {
                prop_assert_eq!(net.hidden(), file.hidden);
            }
        }
    }

    #[test]
    fn decoder_table(bytes in mutate(DEFAULT_TABLE.to_vec())) {
        if let Ok(t) = DemTable::parse(&bytes) {
            prop_assert_eq!(DemTable::parse(&t.to_bytes()), Ok(t));
        }
    }

    #[test]
    fn dataset_image(bytes in mutate(silhouette_seed())) {
        if let Ok(img) = decode_image(&bytes, Path::new("class/a.png")) {
            let (mask, w, h) = mask_of(&img);
            prop_assert_eq!(mask.len(), w * h);
            if let Ok(Some((x, shape))) = shape_inputs(&mask, w, h) {
                prop_assert_eq!(x.len(), shape.len());
                prop_assert!(x.iter().all(|v| v.is_finite()));
            }
        }
    }
}
