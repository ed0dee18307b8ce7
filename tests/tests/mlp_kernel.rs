//! Issue 5 §4 and §10: the classifier's pluggable dot-product kernel
//! (`protogist::mlp::MacKernel`). Any kernel that honours the documented
//! contract must give the same bits as the portable one; the firmware's
//! `SMLAD` kernel relies on it (its equality on the board is the
//! `checksum mlp` lines that xtask compares). Here: the portable kernel
//! against the contract written out naively, and `forward_with` with a
//! naive kernel against `forward`, on layers that cross the 48-row call
//! blocks and have input counts that are not a multiple of 4.

use proptest::prelude::*;
use protogist::mlp::{
    forward, forward_with, input_len, packed_len, safe_dot_rows, MacKernel, Model, Scratch,
};
use protogist_host::classify::mlp::{unit, SplitMix};
use protogist_host::classify::quant::{quantize_net, shape_elems};
use protogist_tests::nets::{blob, random_net};

/// Input `i` of words packed as `x0 | x2 << 16`, `x1 | x3 << 16` per group
/// of four (the contract's packing, written out independently).
fn unpacked(x: &[u32], i: usize) -> i32 {
    let w = x[i / 4 * 2 + i % 2];
    let half = if i % 4 < 2 {
        w as u16
    } else {
        (w >> 16) as u16
    };
    i32::from(half as i16)
}

/// Packs values the contract's way.
fn pack(values: &[i16]) -> Vec<u32> {
    let mut out = vec![0u32; input_len(values.len())];
    for (i, &v) in values.iter().enumerate() {
        let shift = if i % 4 < 2 { 0 } else { 16 };
        out[i / 4 * 2 + i % 2] |= u32::from(v as u16) << shift;
    }
    out
}

/// The contract, one multiply-accumulate at a time.
struct NaiveKernel;

impl MacKernel for NaiveKernel {
    fn dot_rows(w: &[u8], stride: usize, len: usize, x: &[u32], acc: &mut [i32]) {
        for (r, a) in acc.iter_mut().enumerate() {
            *a = (0..len).fold(0i32, |s, i| {
                s.wrapping_add(i32::from(w[r * stride + i]).wrapping_mul(unpacked(x, i)))
            });
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// The portable kernel computes exactly the contract's sums.
    #[test]
    fn portable_kernel_honours_the_contract(
        rows in 0usize..11,
        groups in 0usize..20,
        pad in 0usize..9,
        seed in any::<u64>(),
    ) {
        let len = 4 * groups;
        let stride = len + pad;
        let mut rng = SplitMix::new(seed);
        let mut byte = || (unit(&mut rng) * 256.0) as u8;
        let w: Vec<u8> = (0..rows * stride).map(|_| byte()).collect();
        let xs: Vec<i16> = (0..len).map(|_| i16::from(byte()) - 128).collect();
        let x = pack(&xs);
        let (mut got, mut want) = (vec![7i32; rows], vec![0i32; rows]);
        safe_dot_rows(&w, stride, len, &x, &mut got);
        NaiveKernel::dot_rows(&w, stride, len, &x, &mut want);
        prop_assert_eq!(got, want);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// `forward_with` a naive kernel gives `forward`'s outputs bit for bit,
    /// with hidden layers beyond one 48-row block and any input count.
    #[test]
    fn forward_with_any_faithful_kernel_is_bit_identical(
        d in 1usize..70,
        h in 1usize..130,
        k in 1usize..60,
        seed in any::<u64>(),
    ) {
        let mut rng = SplitMix::new(seed);
        let net = random_net(&mut rng, (d, h, k), 1.0, 2.0, 0.5);
        let inputs: Vec<Vec<i16>> = (0..3)
            .map(|_| (0..d).map(|_| (8000.0 * (2.0 * unit(&mut rng) - 1.0)) as i16).collect())
            .collect();
        prop_assume!(inputs.iter().flatten().any(|&r| r != 0));
        let q = quantize_net(&net, &inputs).unwrap();
        let blob = blob(&q, k);
        let model = Model::parse(&blob).unwrap();
        let (mut xi, mut hi, mut yo) = (vec![0u32; packed_len(d, h)], vec![0u8; h], vec![0u16; k]);
        for raw in &inputs {
            let v = shape_elems(raw);
            let mut s = Scratch { input: &mut xi, hidden: &mut hi, output: &mut yo };
            let portable = forward(&model, &v, &mut s).unwrap().to_vec();
            let mut s = Scratch { input: &mut xi, hidden: &mut hi, output: &mut yo };
            let naive = forward_with::<NaiveKernel>(&model, &v, &mut s).unwrap().to_vec();
            prop_assert_eq!(portable, naive);
        }
    }
}
