//! `clear_square_bits` (the depth pass's clearance: a map less another
//! grown by `n` square dilations, the dilation row-wise then column-wise)
//! and `square_bits` (the holes' and the refinement's insides and rings:
//! `n` square erosions or dilations in one pass) against `n` steps of the
//! `bool` erosion or dilation by the 3x3 square, bit for bit, on random
//! maps of random sizes (widths on both sides of the word boundaries, a
//! word's width among them); a full first map gives the whole dilation.

use proptest::prelude::*;
use protogist::image::ImageViewMut;
use protogist::segment::{self as sg, Disk};

fn pack(m: &[bool], w: usize, h: usize) -> Vec<u32> {
    let stride = sg::words_per_row(w);
    let mut out = vec![0u32; stride * h];
    for (i, &v) in m.iter().enumerate() {
        if v {
            let (x, y) = (i % w, i / w);
            out[y * stride + x / 32] |= 1 << (x % 32);
        }
    }
    out
}

/// `fg` less `n` steps of the `bool` square dilation of `taken`, packed.
fn by_steps(fg: &[bool], taken: &[bool], w: usize, h: usize, n: u8) -> Vec<u32> {
    let mut map = taken.to_vec();
    let mut scratch = vec![false; w * h];
    sg::dilate_n(
        Disk::Square,
        &mut ImageViewMut::packed(&mut map, w, h).unwrap(),
        &mut ImageViewMut::packed(&mut scratch, w, h).unwrap(),
        n,
    )
    .unwrap();
    let left: Vec<bool> = fg.iter().zip(&map).map(|(&f, &t)| f && !t).collect();
    pack(&left, w, h)
}

fn bools(len: usize, pct: u32) -> impl Strategy<Value = Vec<bool>> {
    proptest::collection::vec(proptest::bool::weighted(f64::from(pct) / 100.0), len)
}

/// `(fg, taken, w, h)`: `fg` full in about half of the cases.
fn maps() -> impl Strategy<Value = (Vec<bool>, Vec<bool>, usize, usize)> {
    (
        prop_oneof![1usize..=8, 28usize..=36, 60usize..=70, 94usize..=98],
        1usize..=40,
        prop_oneof![Just(100u32), 0u32..=100],
        // Sparse maps too: a lone bit far from the others.
        prop_oneof![0u32..=2, 0u32..=20],
    )
        .prop_flat_map(|(w, h, fg, taken)| {
            (bools(w * h, fg), bools(w * h, taken), Just(w), Just(h))
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    #[test]
    fn the_clearance_is_n_square_dilations(
        (fg, taken, w, h) in maps(),
        n in prop_oneof![0u8..=17, 18u8..=80],
    ) {
        let fg_words = pack(&fg, w, h);
        let mut words = vec![u32::MAX; fg_words.len()];
        let mut spread = pack(&taken, w, h);
        sg::clear_square_bits(&mut words, &fg_words, &mut spread, w, h, n).unwrap();
        prop_assert_eq!(&words, &by_steps(&fg, &taken, w, h, n));
        // The view's invariant: bits past the width stay 0.
        let bits: Vec<bool> = sg::BitView::new(&words, w, h).unwrap().bools().collect();
        prop_assert_eq!(pack(&bits, w, h), words);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    #[test]
    fn a_square_is_n_square_steps(
        (full, map, w, h) in maps(),
        n in prop_oneof![0u8..=17, 18u8..=80],
        erode in any::<bool>(),
    ) {
        // Erosions need dense maps to leave anything: the full-ish one.
        let src = if erode { full } else { map };
        let mut words = pack(&src, w, h);
        let mut out = vec![u32::MAX; words.len()];
        sg::square_bits(&mut out, &mut words, w, h, n, erode).unwrap();
        let mut want = src.clone();
        let mut scratch = vec![false; w * h];
        let mut m = ImageViewMut::packed(&mut want, w, h).unwrap();
        let mut sc = ImageViewMut::packed(&mut scratch, w, h).unwrap();
        if erode {
            sg::erode_n(Disk::Square, &mut m, &mut sc, n).unwrap();
        } else {
            sg::dilate_n(Disk::Square, &mut m, &mut sc, n).unwrap();
        }
        prop_assert_eq!(&out, &pack(&want, w, h));
    }
}

#[test]
fn short_buffers_are_an_error() {
    let (mut a, b, mut c) = (vec![0u32; 4], vec![0u32; 4], vec![0u32; 3]);
    assert!(sg::clear_square_bits(&mut a, &b, &mut c, 40, 2, 1).is_err());
    assert!(sg::clear_square_bits(&mut a, &b, &mut c, 40, 1, 1).is_ok());
    let (mut o, mut m) = (vec![0u32; 4], vec![0u32; 3]);
    assert!(sg::square_bits(&mut o, &mut m, 40, 2, 1, true).is_err());
    assert!(sg::square_bits(&mut o, &mut m, 40, 1, 1, false).is_ok());
}
