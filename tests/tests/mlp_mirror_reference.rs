//! The mirror check against the float reference (`classify::mirror`)
//! and its error bound (docs/ERROR_BOUNDS.md §9); the check's own
//! semantics: `mlp_mirror.rs`.

mod mirror_common;

use mirror_common::*;
use proptest::prelude::*;
use protogist::mlp::{mirror_mean, Model, Symmetry};
use protogist::shape::{Mirror, ShapeVector, SHAPE_LEN};
use protogist_host::classify::mirror as fref;
use protogist_host::classify::mlp::{unit, SplitMix};
use protogist_host::classify::quant::{
    output_error_bound, quantize_net, shape_elems, write_blob, BlobExtras,
};
use protogist_host::classify::rules::Templates;
use protogist_tests::nets::random_net;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Per class, the rounded mean of the int8 outputs over the views stays
    /// within the mean of the views' bounds `B_k` plus half an output LSB
    /// of the float network's mean (docs/ERROR_BOUNDS.md §9).
    #[test]
    fn averaged_outputs_within_the_bound(
        h in 1usize..12,
        k in 1usize..5,
        seed in any::<u64>(),
        a1 in 0.002f64..0.2,
        a2 in 0.05f64..8.0,
        flags in proptest::collection::vec(0u8..4, 4),
    ) {
        let mut rng = SplitMix::new(seed);
        let net = random_net(&mut rng, (SHAPE_LEN, h, k), a1, a2, 1.0);
        let raw: Vec<i16> = (0..SHAPE_LEN)
            .map(|_| (8000.0 * (2.0 * unit(&mut rng) - 1.0)).round() as i16)
            .collect();
        let q = quantize_net(&net, std::slice::from_ref(&raw)).unwrap();
        let names: Vec<String> = (0..k).map(|c| format!("c{c}")).collect();
        let sym: Vec<u8> = flags[..k].to_vec();
        let blob = write_blob(&q, &BlobExtras {
            templates: &vec![1; k * k],
            delta_q16: 0,
            names: &names,
            meta: "",
            symmetry: Some(&sym),
        }).unwrap();
        let m = Model::parse(&blob).unwrap();
        let x: ShapeVector = shape_elems(&raw).try_into().unwrap();
        let views = [x, mirrored(Mirror::Vertical, &x), mirrored(Mirror::Horizontal, &x)];
        let mut b = Bufs::new(&m);
        let mut ints = Vec::new();
        let mut bounds = Vec::new();
        for v in &views {
            ints.extend(b.plain(&m, v).0);
            let vr: Vec<i16> = v.iter().map(|e| e.to_bits()).collect();
            bounds.push(output_error_bound(&net, &q, &vr).1);
        }
        let xf: Vec<f64> = raw.iter().map(|&r| f64::from(r) / 4096.0).collect();
        let floats = fref::mirror_outputs(&net, &xf, Symmetry::from_bits(3).unwrap()).unwrap();
        for (c, &f) in sym.iter().enumerate() {
            let s = Symmetry::from_bits(f).unwrap();
            let mut mean = vec![0u16; k];
            mirror_mean(s, &ints, &mut mean);
            let fmean = fref::mirror_mean(s, &floats);
            let rows: Vec<usize> = std::iter::once(0)
                .chain(Mirror::ALL.into_iter().enumerate().filter(|(_, m)| s.has(*m)).map(|(i, _)| i + 1))
                .collect();
            for j in 0..k {
                let bound = rows.iter().map(|&r| bounds[r][j]).sum::<f64>() / rows.len() as f64
                    + 0.5 / 65535.0;
                let err = (f64::from(mean[j]) / 65535.0 - fmean[j]).abs();
                prop_assert!(err <= bound, "class {c} output {j}: {err:e} > {bound:e}");
            }
        }
    }
}

/// The float reference ranks as core does on a model whose int8 outputs
/// are close to the float ones: the shipped network's sidecar is not in the
/// repository, so a random one with its own float templates.
#[test]
fn float_reference_check_follows_the_flags() {
    let mut rng = SplitMix::new(7);
    let net = random_net(&mut rng, (SHAPE_LEN, 6, 3), 0.05, 4.0, 1.0);
    let x: Vec<f64> = vector(blob).iter().map(|e| e.to_num::<f64>()).collect();
    let t = Templates::new(vec![
        vec![1.0, 0.2, 0.1],
        vec![0.1, 1.0, 0.3],
        vec![0.2, 0.1, 1.0],
    ])
    .unwrap();
    let none = [Symmetry::NONE; 3];
    let plain = fref::mirror_check(&net, &t, &none, &x).unwrap();
    let direct: Vec<f32> = fref::mirror_outputs(&net, &x, Symmetry::NONE).unwrap()[0]
        .iter()
        .map(|&v| v as f32)
        .collect();
    assert_eq!(plain, t.scores(&direct).unwrap());
    let vh = [Symmetry::from_bits(3).unwrap(); 3];
    let outs = fref::mirror_outputs(&net, &x, vh[0]).unwrap();
    let all = fref::mirror_check(&net, &t, &vh, &x).unwrap();
    for (c, &score) in all.iter().enumerate() {
        let mean: Vec<f32> = (0..3)
            .map(|j| ((outs[0][j] + outs[1][j] + outs[2][j]) / 3.0) as f32)
            .collect();
        assert!((score - t.scores(&mean).unwrap()[c]).abs() < 1e-12);
    }
    assert!(fref::mirror_check(&net, &t, &none[..2], &x).is_err());
}
