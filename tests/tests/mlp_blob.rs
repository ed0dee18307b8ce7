//! Issue 5 §5 and §11: the model blob parser never panics on arbitrary,
//! truncated or mutated bytes, and names each defect with a typed error.

use proptest::prelude::*;
use protogist::mlp::blob::{crc32, CRC_LEN, VERSION, VERSION_1};
use protogist::mlp::{
    forward, identify, mirror_check, mirror_outputs_len, top_k, verify, Identity, MirrorScratch,
    MlpError, Model, ModelError, Ranked, Scratch, Symmetry, TOP_K,
};
use protogist::shape::{Mirror, ShapeElem, SHAPE_LEN};
use protogist_host::classify::mlp::Mlp;
use protogist_host::classify::quant::{quantize_net, write_blob, BlobExtras};
use protogist_host::classify::symmetry::with_symmetry;
use protogist_tests::nets::blob_version_1;

/// A valid 9-5-3 blob.
fn small_blob() -> Vec<u8> {
    let net = Mlp::new(9, 5, 3, 4);
    let calib: Vec<Vec<i16>> = (0..3)
        .map(|i| (0..9).map(|j| (i * 100 + j * 37 - 150) as i16).collect())
        .collect();
    let q = quantize_net(&net, &calib).unwrap();
    let names: Vec<String> = ["alpha", "beta", "gamma"].map(String::from).to_vec();
    let templates: Vec<u16> = (0..9).map(|i| 1000 * i as u16).collect();
    write_blob(
        &q,
        &BlobExtras {
            templates: &templates,
            delta_q16: 40_000,
            names: &names,
            meta: "test",
            symmetry: None,
        },
    )
    .unwrap()
}

/// A valid 720-4-3 blob with symmetry `flags` (version 2), or version 1.
fn shape_blob(flags: Option<&[u8]>) -> Vec<u8> {
    let net = Mlp::new(SHAPE_LEN, 4, 3, 5);
    let calib: Vec<Vec<i16>> = (0..3)
        .map(|i| {
            (0..SHAPE_LEN)
                .map(|j| ((i * 977 + j * 37) % 4001) as i16 - 2000)
                .collect()
        })
        .collect();
    let q = quantize_net(&net, &calib).unwrap();
    let names: Vec<String> = ["a", "bb", "ccc"].map(String::from).to_vec();
    let templates: Vec<u16> = (0..9).map(|i| 7000 * (i as u16 % 4) + 100).collect();
    write_blob(
        &q,
        &BlobExtras {
            templates: &templates,
            delta_q16: 1000,
            names: &names,
            meta: "m",
            symmetry: flags,
        },
    )
    .unwrap()
}

/// With the CRC recomputed after an edit.
fn fix_crc(mut b: Vec<u8>) -> Vec<u8> {
    let n = b.len() - CRC_LEN;
    let crc = crc32(&b[..n]);
    b[n..].copy_from_slice(&crc.to_le_bytes());
    b
}

/// Whatever parses runs without panicking.
fn exercise(blob: &[u8]) {
    if let Ok(m) = Model::parse(blob) {
        let (d, h, k) = (m.inputs(), m.hidden(), m.classes());
        if d * h > 1 << 20 {
            return;
        }
        let (mut xi, mut hi, mut yo) = (
            vec![0u32; protogist::mlp::packed_len(d, h)],
            vec![0u8; h],
            vec![0u16; k],
        );
        let input = vec![ShapeElem::from_bits(1234); d];
        let mut s = Scratch {
            input: &mut xi,
            hidden: &mut hi,
            output: &mut yo,
        };
        let out = forward(&m, &input, &mut s).unwrap().to_vec();
        let mut r = [Ranked::default(); TOP_K];
        let n = top_k(&m, &out, &mut r).unwrap();
        assert_eq!(n, k.min(TOP_K));
        assert!(r[..n].windows(2).all(|w| w[0].score >= w[1].score));
        for c in 0..k {
            assert!(m.class_name(c).is_some());
            assert!(m.symmetry(c).bits() < 4);
        }
        if d == SHAPE_LEN {
            let mut v = vec![ShapeElem::ZERO; SHAPE_LEN];
            let mut o = vec![0u16; mirror_outputs_len(k)];
            let mut mean = vec![0u16; k];
            let mut s = Scratch {
                input: &mut xi,
                hidden: &mut hi,
                output: &mut yo,
            };
            let mut ms = MirrorScratch {
                vector: &mut v,
                outputs: &mut o,
                mean: &mut mean,
            };
            let mut r2 = [Ranked::default(); TOP_K];
            let n2 = mirror_check(&m, &input, &mut s, &mut ms, &mut r2).unwrap();
            assert_eq!(n2, n);
            if m.any_symmetry() == Symmetry::NONE {
                assert_eq!(r2, r);
            }
        }
    }
}

#[test]
fn version_2_round_trips_and_version_1_still_parses() {
    let v1 = shape_blob(None);
    let m1 = Model::parse(&v1).unwrap();
    assert_eq!(u16::from_le_bytes([v1[4], v1[5]]), VERSION_1);
    assert!(!m1.has_symmetry_section());
    assert_eq!(m1.any_symmetry(), Symmetry::NONE);
    for c in 0..4 {
        assert_eq!(m1.symmetry(c), Symmetry::NONE);
    }
    let flags = [1u8, 2, 3];
    let v2 = shape_blob(Some(&flags));
    assert_eq!(u16::from_le_bytes([v2[4], v2[5]]), VERSION);
    assert_eq!(v2.len(), v1.len() + 3);
    let m2 = Model::parse(&v2).unwrap();
    assert!(m2.has_symmetry_section());
    for (c, &f) in flags.iter().enumerate() {
        assert_eq!(m2.symmetry(c).bits(), f);
    }
    assert_eq!(m2.symmetry(3), Symmetry::NONE);
    assert!(m2.symmetry(0).has(Mirror::Vertical) && !m2.symmetry(0).has(Mirror::Horizontal));
    assert!(m2.symmetry(1).has(Mirror::Horizontal) && !m2.symmetry(1).has(Mirror::Vertical));
    assert_eq!(m2.any_symmetry().bits(), 3);
    // Everything else as in version 1.
    assert_eq!(
        (
            m2.inputs(),
            m2.hidden(),
            m2.classes(),
            m2.delta_q16(),
            m2.meta()
        ),
        (
            m1.inputs(),
            m1.hidden(),
            m1.classes(),
            m1.delta_q16(),
            m1.meta()
        )
    );
    assert_eq!(m2.class_name(2), Some("ccc"));
    assert_eq!(m2.parameter_bytes(), m1.parameter_bytes());
    // Adding flags to the v1 blob writes the same bytes; replacing them too.
    assert_eq!(with_symmetry(&v1, &flags).unwrap(), v2);
    assert_eq!(
        with_symmetry(&shape_blob(Some(&[0, 0, 0])), &flags).unwrap(),
        v2
    );
    assert!(with_symmetry(&v1, &flags[..2]).is_err());
    // Same outputs either way.
    let x = vec![ShapeElem::from_bits(-777); SHAPE_LEN];
    let run = |m: &Model<'_>| {
        let (mut xi, mut hi, mut yo) = (
            vec![0u32; protogist::mlp::packed_len(SHAPE_LEN, 4)],
            vec![0u8; 4],
            vec![0u16; 3],
        );
        let mut s = Scratch {
            input: &mut xi,
            hidden: &mut hi,
            output: &mut yo,
        };
        forward(m, &x, &mut s).unwrap().to_vec()
    };
    assert_eq!(run(&m1), run(&m2));
}

#[test]
fn bad_symmetry_bytes_are_errors() {
    let v2 = shape_blob(Some(&[1, 2, 3]));
    // The section sits before the names (1+1, 1+2, 1+3 bytes), the meta
    // ("m") and the CRC.
    let at = v2.len() - CRC_LEN - 1 - 9 - 3;
    assert_eq!(v2[at..at + 3], [1, 2, 3]);
    for (i, bad) in [(0usize, 4u8), (2, 0x80), (1, 7)] {
        let mut b = v2.clone();
        b[at + i] = bad;
        assert_eq!(
            Model::parse(&fix_crc(b)),
            Err(ModelError::BadSymmetry { index: i })
        );
    }
    // A v1 blob labelled version 2 misses its section.
    let mut relabelled = shape_blob(None);
    relabelled[4] = 2;
    assert!(matches!(
        Model::parse(&fix_crc(relabelled)),
        Err(ModelError::Truncated { .. })
    ));
    // Flags on a model that does not take 720-element shape vectors.
    let small = small_blob();
    assert!(with_symmetry(&small, &[0, 0, 0]).is_ok());
    assert!(with_symmetry(&small, &[0, 1, 0]).is_err());
    let mut b = with_symmetry(&small, &[0, 0, 0]).unwrap();
    let at = b.len() - CRC_LEN - 4 - 17 - 3;
    b[at + 1] = 2;
    assert_eq!(
        Model::parse(&fix_crc(b)),
        Err(ModelError::BadSymmetry { index: 1 })
    );
}

#[test]
fn valid_blob_parses_and_runs() {
    let b = small_blob();
    let m = Model::parse(&b).unwrap();
    assert_eq!((m.inputs(), m.hidden(), m.classes()), (9, 5, 3));
    assert_eq!(m.class_name(1), Some("beta"));
    assert_eq!(m.class_name(3), None);
    assert_eq!((m.delta_q16(), m.meta()), (40_000, "test"));
    exercise(&b);
    // Feature size and scratch mismatches are typed errors.
    let (mut xi, mut hi, mut yo) = (
        vec![0u32; protogist::mlp::packed_len(9, 5)],
        vec![0u8; 5],
        vec![0u16; 3],
    );
    let mut s = Scratch {
        input: &mut xi,
        hidden: &mut hi,
        output: &mut yo,
    };
    assert_eq!(
        forward(&m, &[ShapeElem::ZERO; 720], &mut s),
        Err(MlpError::FeatureSize {
            expected: 9,
            got: 720
        })
    );
    let mut short = [0u8; 4];
    let mut s = Scratch {
        input: &mut xi,
        hidden: &mut short,
        output: &mut yo,
    };
    assert!(matches!(
        forward(&m, &[ShapeElem::ZERO; 9], &mut s),
        Err(MlpError::ScratchTooSmall {
            buffer: "hidden",
            ..
        })
    ));
}

/// Rules by hand on the small blob's templates (0, 1000, 2000),
/// (3000, 4000, 5000), (6000, 7000, 8000) and Δ = 40000 / 65536 = 0.610.
#[test]
fn ranking_identification_and_verification_by_hand() {
    let b = small_blob();
    let m = Model::parse(&b).unwrap();
    // v = template 0: cosines 1, 14e6 / (2236.07 · 7071.07) = 0.8854 and
    // 23e6 / (2236.07 · 12206.56) = 0.8427.
    let v = [0u16, 1000, 2000];
    let mut r = [Ranked::default(); TOP_K];
    assert_eq!(top_k(&m, &v, &mut r).unwrap(), 3);
    let classes: Vec<u16> = r[..3].iter().map(|e| e.class).collect();
    assert_eq!(classes, [0, 1, 2]);
    assert_eq!(r[0].score, 65536);
    assert!((f64::from(r[1].score) / 65536.0 - 0.8854).abs() < 1e-4);
    assert!((f64::from(r[2].score) / 65536.0 - 0.8427).abs() < 1e-4);
    assert_eq!(identify(&m, &v).unwrap().0, Identity::Known(0));
    assert!(verify(&m, &v, 2).unwrap());
    // v = (5000, 0, 0): cosines 0, 0.4243, 0.4915: all below Δ, U_{N+1}.
    let u = [5000u16, 0, 0];
    let (id, best) = identify(&m, &u).unwrap();
    assert_eq!((id, best.class), (Identity::Unknown, 2));
    assert!(!verify(&m, &u, 1).unwrap());
    assert_eq!(
        verify(&m, &u, 3),
        Err(MlpError::ClassOutOfRange {
            class: 3,
            classes: 3
        })
    );
    // Fewer slots than classes: the best ones, in order.
    let mut two = [Ranked::default(); 2];
    assert_eq!(top_k(&m, &v, &mut two).unwrap(), 2);
    assert_eq!((two[0].class, two[1].class), (0, 1));
    assert!(top_k(&m, &v[..2], &mut two).is_err());
}

#[test]
fn each_defect_has_its_error() {
    let b = small_blob();
    let n = b.len();
    assert!(matches!(
        Model::parse(&b[..n - 1]),
        Err(ModelError::Truncated { .. })
    ));
    let mut long = b.clone();
    long.push(0);
    assert!(matches!(
        Model::parse(&long),
        Err(ModelError::TrailingBytes { .. })
    ));
    let mut c = b.clone();
    c[60] ^= 1;
    assert!(matches!(Model::parse(&c), Err(ModelError::BadCrc { .. })));
    let mut v = b.clone();
    v[4] = 9;
    assert_eq!(Model::parse(&v), Err(ModelError::UnsupportedVersion(9)));
    let mut m = b.clone();
    m[0] = b'X';
    assert_eq!(Model::parse(&m), Err(ModelError::BadMagic));
    let mut f = b.clone();
    f[9] = 7;
    assert!(matches!(
        Model::parse(&f),
        Err(ModelError::UnsupportedFormat {
            field: "output",
            code: 7
        })
    ));
    // Zero classes; more hidden units than the bytes hold.
    let mut z = b.clone();
    z[14] = 0;
    assert_eq!(Model::parse(&fix_crc(z)), Err(ModelError::BadDims));
    let mut h = b.clone();
    h[12] = 6;
    assert!(matches!(
        Model::parse(&fix_crc(h)),
        Err(ModelError::Truncated { .. })
    ));
    // A negative multiplier (first hidden pair at offset 40).
    let mut r = b.clone();
    r[43] = 0x80;
    assert_eq!(Model::parse(&fix_crc(r)), Err(ModelError::BadRequant));
    // Names sit before the 4-byte meta "test" and the CRC: "gamma" is the
    // last one; invalid UTF-8 in it, then a zero length for the first.
    let names_end = n - CRC_LEN - 4;
    let mut u = b.clone();
    u[names_end - 1] = 0xff;
    assert_eq!(
        Model::parse(&fix_crc(u)),
        Err(ModelError::BadClassName { index: 2 })
    );
    let first = names_end - (1 + 5 + 1 + 4 + 1 + 5);
    let mut e = b.clone();
    e[first] = 0;
    assert_eq!(
        Model::parse(&fix_crc(e)),
        Err(ModelError::BadClassName { index: 0 })
    );
    let mut meta = b.clone();
    meta[n - CRC_LEN - 1] = 0xc0;
    assert_eq!(Model::parse(&fix_crc(meta)), Err(ModelError::BadMeta));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        exercise(&bytes);
        // With the magic and version in front, the parser gets further.
        let mut b = b"PGML\x01\x00\x01\x01\x01\x02".to_vec();
        b.extend_from_slice(&bytes);
        exercise(&b);
        exercise(&fix_crc(b.clone()));
    }

    #[test]
    fn truncated_blobs_are_errors(cut in 0usize..10_000) {
        let b = small_blob();
        let cut = cut % b.len();
        prop_assert!(Model::parse(&b[..cut]).is_err());
    }

    /// Any single-byte change is caught; with the CRC recomputed the parse
    /// may succeed, and then inference runs without panicking.
    #[test]
    fn mutated_blobs_never_panic(at in 0usize..10_000, xor in 1u8..=255) {
        let mut b = small_blob();
        let at = at % b.len();
        b[at] ^= xor;
        prop_assert!(Model::parse(&b).is_err());
        exercise(&fix_crc(b));
    }

    /// The same for a version-2 blob of shape vectors, whose flags let the
    /// mirror check run.
    #[test]
    fn mutated_v2_blobs_never_panic(at in 0usize..20_000, xor in 1u8..=255, flags in proptest::collection::vec(0u8..4, 3)) {
        let mut b = shape_blob(Some(&flags));
        exercise(&b);
        let at = at % b.len();
        b[at] ^= xor;
        prop_assert!(Model::parse(&b).is_err());
        exercise(&fix_crc(b));
    }
}

/// `blob_version_1`, which the mirror tests use for a model without
/// symmetry, keeps every other byte of the shipped model.
#[test]
fn the_shipped_model_as_version_1_keeps_everything_but_symmetry() {
    const SHIPPED: &[u8] = include_bytes!("../../host/data/shapes_model.bin");
    let v1_blob = blob_version_1(SHIPPED);
    let (v1, v2) = (
        Model::parse(&v1_blob).unwrap(),
        Model::parse(SHIPPED).unwrap(),
    );
    assert!(!v1.has_symmetry_section() && v2.any_symmetry().bits() == 3);
    assert_eq!(v1_blob.len() + v2.classes(), SHIPPED.len());
    assert_eq!(
        with_symmetry(
            &v1_blob,
            &(0..v2.classes())
                .map(|c| v2.symmetry(c).bits())
                .collect::<Vec<_>>()
        )
        .unwrap(),
        SHIPPED
    );
}
