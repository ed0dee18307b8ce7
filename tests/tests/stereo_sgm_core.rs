//! The core's windowed, row-streamed SGM (`protogist::stereo::sgm`) against
//! the f32 reference (`aggregate` with 5 paths over the full cost volume,
//! `EXCLUDED` outside each pixel's window): bit-exact on random volumes,
//! the hand-worked 1x4 paths of `stereo_sgm.rs`, a window jump, and the
//! typed errors.

use proptest::prelude::*;
use protogist::stereo::sgm::{scratch_len, Sgm, SgmError};
use protogist_host::reference::stereo::sgm::{aggregate, EXCLUDED};

/// The core's sums over a `width x height` volume of windowed costs
/// (`[y][x][i]`) with windows `lo` (`[y][x]`).
fn core_sums(
    costs: &[u16],
    lo: &[u16],
    (width, height, n): (usize, usize, usize),
    (p1, p2): (u16, u16),
) -> Vec<u32> {
    core_sums_paths(costs, lo, (width, height, n), (p1, p2), 5)
}

/// [`core_sums`] over 5 paths, or 3 ([`Sgm::without_diagonals`]).
fn core_sums_paths(
    costs: &[u16],
    lo: &[u16],
    (width, height, n): (usize, usize, usize),
    (p1, p2): (u16, u16),
    paths: u32,
) -> Vec<u32> {
    let mut scratch = vec![0u16; scratch_len(width, n)];
    let mut sgm = Sgm::new(width, n, p1, p2, &mut scratch).unwrap();
    if paths == 3 {
        sgm = sgm.without_diagonals();
    }
    assert_eq!(sgm.paths(), paths);
    let mut out = vec![0u32; costs.len()];
    for ((c, l), o) in costs
        .chunks_exact(width * n)
        .zip(lo.chunks_exact(width))
        .zip(out.chunks_exact_mut(width * n))
        .take(height)
    {
        sgm.push_row(c, l, o).unwrap();
    }
    assert_eq!(sgm.rows(), height);
    out
}

/// The reference's sums over the full volume `0..=max`, `EXCLUDED` outside
/// each window.
fn reference_sums(
    costs: &[u16],
    lo: &[u16],
    (width, height, n): (usize, usize, usize),
    max: usize,
    (p1, p2): (u16, u16),
    paths: u8,
) -> Vec<f32> {
    let d = max + 1;
    let mut full = vec![EXCLUDED; width * height * d];
    for ((f, c), &l) in full.chunks_exact_mut(d).zip(costs.chunks_exact(n)).zip(lo) {
        let l = usize::from(l);
        for (v, &c) in f[l..l + n].iter_mut().zip(c) {
            *v = f32::from(c);
        }
    }
    aggregate(&full, width, height, d, paths, f32::from(p1), f32::from(p2))
}

/// A random volume: `(width, height, n, max, lo, costs, p1, p2)`.
#[allow(clippy::type_complexity)]
fn volume() -> impl Strategy<Value = (usize, usize, usize, usize, Vec<u16>, Vec<u16>, u16, u16)> {
    (1usize..=12, 1usize..=8, 1usize..=9, 4usize..=12, 0u16..=8)
        .prop_flat_map(|(w, h, n, max, p1)| {
            let max = max.max(n - 1);
            let top = (max + 1 - n) as u16;
            (
                Just((w, h, n, max)),
                proptest::collection::vec(0u16..=top, w * h),
                proptest::collection::vec(0u16..=255, w * h * n),
                Just(p1),
                p1..=64,
            )
        })
        .prop_map(|((w, h, n, max), lo, costs, p1, p2)| (w, h, n, max, lo, costs, p1, p2))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// 5 paths, and 3 without the diagonals (`directions(3)`), for
    /// windows of 1 to 9 (the fixed-size sweeps and the general one).
    #[test]
    fn windowed_sums_equal_the_reference(
        (w, h, n, max, lo, costs, p1, p2) in volume(),
        paths in prop_oneof![Just(3u8), Just(5u8)],
    ) {
        let dims = (w, h, n);
        let got = core_sums_paths(&costs, &lo, dims, (p1, p2), u32::from(paths));
        let want = reference_sums(&costs, &lo, dims, max, (p1, p2), paths);
        let d = max + 1;
        for (p, (g, &l)) in got.chunks_exact(n).zip(&lo).enumerate() {
            let l = usize::from(l);
            let r = &want[p * d + l..p * d + l + n];
            for (i, (&g, &r)) in g.iter().zip(r).enumerate() {
                // EXCLUDED never leaks into an in-window sum.
                prop_assert!(r < EXCLUDED, "pixel {p} candidate {}: {r}", l + i);
                prop_assert_eq!(g as f32, r, "pixel {} candidate {}", p, l + i);
            }
        }
    }
}

/// 1x4 pixels, 3 candidates, P1 = 1, P2 = 3 (`stereo_sgm.rs`).
const COST: [u16; 12] = [0, 2, 5, 4, 0, 4, 5, 5, 0, 0, 6, 6];
/// Worked by hand in `stereo_sgm.rs`.
const LEFT_TO_RIGHT: [u32; 12] = [0, 2, 5, 4, 1, 7, 6, 5, 1, 3, 7, 6];
/// Worked by hand in `stereo_sgm.rs`.
const RIGHT_TO_LEFT: [u32; 12] = [1, 2, 6, 6, 1, 4, 5, 6, 3, 0, 6, 6];

#[test]
fn hand_worked_paths_with_a_full_window() {
    // A row: left→right + right→left, and the three paths from above have
    // no predecessor (L = C).
    let row = core_sums(&COST, &[0; 4], (4, 1, 3), (1, 3));
    let want: Vec<u32> = (0..12)
        .map(|k| LEFT_TO_RIGHT[k] + RIGHT_TO_LEFT[k] + 3 * u32::from(COST[k]))
        .collect();
    assert_eq!(row, want);
    // A column: top→bottom is the left→right of the row; the horizontal
    // paths and the diagonals have no predecessor.
    let column = core_sums(&COST, &[0; 4], (1, 4, 3), (1, 3));
    let want: Vec<u32> = (0..12)
        .map(|k| LEFT_TO_RIGHT[k] + 4 * u32::from(COST[k]))
        .collect();
    assert_eq!(column, want);
    // Without penalties every path is the cost itself.
    let flat = core_sums(&COST, &[0; 4], (4, 1, 3), (0, 0));
    let want: Vec<u32> = COST.iter().map(|&c| 5 * u32::from(c)).collect();
    assert_eq!(flat, want);
}

#[test]
fn disjoint_windows_take_the_p2_branch() {
    // Two pixels, n = 2: windows 0..2 and 5..7 share no candidate and no
    // neighbour, so each horizontal step costs exactly P2 over the costs.
    let costs: [u16; 4] = [3, 1, 4, 9];
    let (p1, p2) = (2, 7);
    let got = core_sums(&costs, &[0, 5], (2, 1, 2), (p1, p2));
    // Pixel 0: right→left enters from pixel 1 (min 4 + P2 − 4); pixel 1:
    // left→right enters from pixel 0. The 4 other paths are L = C.
    let want: Vec<u32> = costs
        .iter()
        .map(|&c| 5 * u32::from(c) + u32::from(p2))
        .collect();
    assert_eq!(got, want);
    // Adjacent windows 0..2 and 2..4: candidate 2 of pixel 1 reaches
    // candidate 1 of pixel 0 with P1 (L 1 − min 1 + P1 = 2 < P2), candidate
    // 3 only with P2.
    let got = core_sums(&costs, &[0, 2], (2, 1, 2), (p1, p2));
    assert_eq!(got[2..], [5 * 4 + u32::from(p1), 5 * 9 + u32::from(p2)]);
    // The same jump in a column, through top→bottom only.
    let got = core_sums(&costs, &[0, 5], (1, 2, 2), (p1, p2));
    assert_eq!(got[2..], [5 * 4 + u32::from(p2), 5 * 9 + u32::from(p2)]);
}

#[test]
fn bad_input_is_a_typed_error() {
    let mut scratch = vec![0u16; scratch_len(4, 3)];
    assert_eq!(
        Sgm::new(4, 0, 1, 3, &mut scratch).err(),
        Some(SgmError::NoCandidates)
    );
    assert_eq!(
        Sgm::new(4, 3, 4, 3, &mut scratch).err(),
        Some(SgmError::Penalties { p1: 4, p2: 3 })
    );
    let needed = scratch_len(4, 3);
    assert_eq!(
        Sgm::new(4, 3, 1, 3, &mut scratch[1..]).err(),
        Some(SgmError::Buffer {
            what: "scratch",
            needed,
            got: needed - 1
        })
    );
    let mut sgm = Sgm::new(4, 3, 1, 3, &mut scratch).unwrap();
    let mut out = [7u32; 12];
    let bad = |what, needed, got| Err(SgmError::Buffer { what, needed, got });
    assert_eq!(
        sgm.push_row(&COST[1..], &[0; 4], &mut out),
        bad("costs", 12, 11)
    );
    assert_eq!(sgm.push_row(&COST, &[0; 5], &mut out), bad("lo", 4, 5));
    assert_eq!(
        sgm.push_row(&COST, &[0; 4], &mut out[1..]),
        bad("out", 12, 11)
    );
    let mut big = COST;
    big[5] = u16::MAX - 2;
    assert_eq!(
        sgm.push_row(&big, &[0; 4], &mut out),
        Err(SgmError::CostTooLarge {
            index: 5,
            cost: u16::MAX - 2,
            max: u16::MAX - 3
        })
    );
    // Nothing changed: no row counted, the output untouched, and the
    // largest allowed cost goes through.
    assert_eq!(sgm.rows(), 0);
    assert_eq!(out, [7; 12]);
    big[5] = sgm.max_cost();
    assert_eq!(sgm.push_row(&big, &[0; 4], &mut out), Ok(()));
}

#[test]
fn reset_starts_a_new_frame() {
    // Two rows, then reset: the next row is a first row again (the paths
    // from above restart with L = C).
    let mut scratch = vec![0u16; scratch_len(4, 3)];
    let mut sgm = Sgm::new(4, 3, 1, 3, &mut scratch).unwrap();
    let (mut first, mut again) = ([0u32; 12], [0u32; 12]);
    sgm.push_row(&COST, &[0; 4], &mut first).unwrap();
    sgm.push_row(&COST, &[0; 4], &mut again).unwrap();
    assert_ne!(first, again);
    sgm.reset();
    sgm.push_row(&COST, &[0; 4], &mut again).unwrap();
    assert_eq!((first, sgm.rows()), (again, 1));
}

/// The scratch the module docs state: `3·w·n + w + 2·n`
/// `u16`s (printed with `--nocapture`).
#[test]
fn scratch_at_160_px() {
    use protogist::stereo::sgm::scratch_bytes;
    let (w, n) = (160, 5);
    println!("scratch at {w} px, n = {n}: {} B", scratch_bytes(w, n));
    assert_eq!(scratch_bytes(w, n), 2 * (3 * w * n + w + 2 * n));
    let mut scratch = vec![0u16; scratch_len(w, n)];
    assert!(Sgm::new(w, n, 0, 0, &mut scratch).is_ok());
}
