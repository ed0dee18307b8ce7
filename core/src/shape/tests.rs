//! Unit tests of the shape vector.

use super::*;

/// A mask from ASCII art: `#` is object, anything else background.
fn mask(art: &[&str]) -> ([u8; 256], usize, usize) {
    let (w, h) = (art[0].len(), art.len());
    let mut px = [0u8; 256];
    for (y, line) in art.iter().enumerate() {
        for (x, c) in line.bytes().enumerate() {
            px[y * w + x] = u8::from(c == b'#');
        }
    }
    (px, w, h)
}

fn run(art: &[&str]) -> (Result<ShapeReport, ShapeError>, RadialProfile, ShapeVector) {
    let (px, w, h) = mask(art);
    let view = ImageView::packed(&px[..w * h], w, h).unwrap();
    let mut p = RadialProfile::new();
    let mut v = [ShapeElem::ZERO; SHAPE_LEN];
    let r = shape_vector(&view, &mut p, &mut v);
    (r, p, v)
}

fn contour(art: &[&str]) -> heapless::Vec<(usize, usize), 64> {
    let (px, w, h) = mask(art);
    let mut out = heapless::Vec::new();
    for_each_contour_pixel(&ImageView::packed(&px[..w * h], w, h).unwrap(), |x, y| {
        out.push((x, y)).unwrap()
    });
    out
}

#[allow(clippy::float_arithmetic)]
fn float_bin(dx: f64, dy: f64) -> usize {
    let deg = libm::atan2(-dy, dx).to_degrees();
    (libm::floor(deg) as i64 + 180).rem_euclid(360) as usize
}

#[test]
#[allow(clippy::float_arithmetic)]
fn tan_table_matches_libm() {
    for (k, &t) in TAN_Q32.iter().enumerate() {
        let exact = libm::tan((k as f64).to_radians()) * 4_294_967_296.0;
        assert!(
            (t as f64 - exact).abs() <= 0.5 + 1e-6 * exact / 4e9,
            "k={k}"
        );
    }
}

#[test]
fn angle_bins_on_axes_and_diagonals() {
    assert_eq!(angle_bin(0, 0), None);
    assert_eq!(angle_bin(5, 0), Some(180)); // 0°, right
    assert_eq!(angle_bin(0, -5), Some(270)); // 90°, up on screen
    assert_eq!(angle_bin(-5, 0), Some(0)); // 180° = -180°
    assert_eq!(angle_bin(0, 5), Some(90)); // -90°, down
    assert_eq!(angle_bin(3, -3), Some(225)); // 45°
    assert_eq!(angle_bin(-3, -3), Some(315)); // 135°
    assert_eq!(angle_bin(-3, 3), Some(45)); // -135°
    assert_eq!(angle_bin(3, 3), Some(135)); // -45°
                                            // Just below the axes.
    assert_eq!(angle_bin(1000, 1), Some(179)); // -0.06°
    assert_eq!(angle_bin(-1000, 1), Some(0)); // -179.94°
    assert_eq!(angle_bin(-1000, -1), Some(359)); // 179.94°
}

#[test]
#[allow(clippy::float_arithmetic)]
fn angle_bins_match_f64_atan2_away_from_edges() {
    let mut checked = 0;
    for dy in (-300i32..=300).step_by(7) {
        for dx in (-300i32..=300).step_by(3) {
            let Some(b) = angle_bin(dx, dy) else { continue };
            let deg = libm::atan2(-f64::from(dy), f64::from(dx)).to_degrees();
            if (deg - libm::round(deg)).abs() < 1e-9 {
                continue; // exactly on an edge: checked above
            }
            assert_eq!(b, float_bin(f64::from(dx), f64::from(dy)), "{dx} {dy}");
            checked += 1;
        }
    }
    assert!(checked > 8000);
    for k in -180..180 {
        // Points just either side of each edge, radius 2^20.
        let t = f64::from(k).to_radians();
        for eps in [-1e-5, 1e-5] {
            let (dx, dy) = (
                libm::round(1048576.0 * libm::cos(t + eps)),
                -libm::round(1048576.0 * libm::sin(t + eps)),
            );
            let b = angle_bin(dx as i32, dy as i32).unwrap();
            assert_eq!(b, float_bin(dx, dy), "k={k} eps={eps}");
        }
    }
}

#[test]
fn empty_and_degenerate_masks_are_typed_errors() {
    assert_eq!(run(&["...", "..."]).0, Err(ShapeError::EmptyMask));
    // One pixel: it is the centroid, no direction, an all-zero profile.
    assert_eq!(run(&["...", ".#."]).0, Err(ShapeError::ZeroVariance));
    // Two pixels: radius 1/2 at 0° and 180° only; interpolated, flat.
    assert_eq!(run(&["##"]).0, Err(ShapeError::ZeroVariance));
    // 2x2: four corners at √2/2, flat.
    assert_eq!(run(&["##", "##"]).0, Err(ShapeError::ZeroVariance));
}

#[test]
fn square_5x5_has_contour_ring_and_symmetric_profile() {
    let art = [
        ".......", ".#####.", ".#####.", ".#####.", ".#####.", ".#####.", ".......",
    ];
    assert_eq!(contour(&art).len(), 16);
    let (r, p, v) = run(&art);
    let r = r.unwrap();
    assert_eq!(
        (r.centroid.x_q8, r.centroid.y_q8, r.centroid.area),
        (768, 768, 25)
    );
    assert_eq!(r.profile.contour_pixels, 16);
    // Right, up, left, down: 2 px; the corners (±45°, ±135°): 2√2.
    for b in [180, 270, 0, 90] {
        assert_eq!(p.max()[b], 512, "bin {b}");
    }
    for b in [135, 225, 315, 45] {
        assert_eq!(p.max()[b], 724, "bin {b}"); // 2√2 · 256 = 724.08
    }
    // Quarter-turn symmetry of the vector (a 90° turn is 90 bins).
    for b in 0..BINS {
        assert_eq!(v[b], v[(b + 90) % BINS], "bin {b}");
    }
    // Filled: min equals max nearly everywhere (one pixel per direction).
    assert_eq!(p.max(), p.min());
}

#[test]
fn plus_sign_arms_are_long_and_the_gaps_short() {
    let thin = [
        "...#...", "...#...", "...#...", "#######", "...#...", "...#...", "...#...",
    ];
    let (r, p, v) = run(&thin);
    r.unwrap();
    // Every pixel but the centre is contour, all on the axes: only bins
    // 0, 90, 180 and 270 are filled. Tips at 3 px, the radius-1 pixels
    // (background above and below) give min 1 px.
    assert_eq!(r.unwrap().profile.empty_bins, 356);
    for b in [0, 90, 180, 270] {
        assert_eq!((p.max()[b], p.min()[b]), (768, 256));
    }
    // Interpolation joins the tips: a thin plus is a flat profile, z = ±1.
    assert!(v[..BINS].iter().all(|&z| z == ShapeElem::ONE));
    assert!(v[BINS..].iter().all(|&z| z == -ShapeElem::ONE));
    let thick = [
        "...###...",
        "...###...",
        "...###...",
        "#########",
        "#########",
        "#########",
        "...###...",
        "...###...",
        "...###...",
    ];
    let (r, p, v) = run(&thick);
    r.unwrap();
    // Right: the arm's tip at 4 px. The inner corner (5, 3) at 45° has
    // only object 4-neighbours, so it is no contour pixel: bin 225 is
    // interpolated between (6, 3) and (5, 2), both √5 px away.
    assert_eq!(p.max()[180], 1024);
    assert_eq!(p.max()[225], 572);
    assert!(v[180] > ShapeElem::ONE && v[225] < v[180]);
    // Quarter-turn symmetric.
    assert!((0..BINS).all(|b| v[b] == v[(b + 90) % BINS]));
}

#[test]
fn ring_min_radius_differs_from_max() {
    let art = [
        ".........",
        "..#####..",
        ".##...##.",
        ".#.....#.",
        ".#.....#.",
        ".#.....#.",
        ".##...##.",
        "..#####..",
        ".........",
    ];
    let (r, p, v) = run(&art);
    r.unwrap();
    // Right: outer edge pixel (7, 4) at 3 px, and it is also the inner edge.
    assert_eq!(p.max()[180], 768);
    // The hole keeps every contour pixel at least 2√2 px out.
    assert!(p.min().iter().all(|&m| m >= 724));
    let thick_ring = [
        "...........",
        ".#########.",
        ".#########.",
        ".##.....##.",
        ".##.....##.",
        ".##.....##.",
        ".##.....##.",
        ".##.....##.",
        ".#########.",
        ".#########.",
        "...........",
    ];
    let (r2, p2, v2) = run(&thick_ring);
    r2.unwrap();
    // Right: outer 4 px, inner edge of the hole 3 px.
    assert_eq!((p2.max()[180], p2.min()[180]), (1024, 768));
    // On the axes both edges fall in the bin: min < max. Near the
    // corners only the outer corner pixel does (the hole's corner pixels
    // have object 4-neighbours), so there min = max.
    for b in [0, 90, 180, 270] {
        assert!(p2.min()[b] < p2.max()[b]);
        assert!(v2[BINS + b] < v2[b]);
    }
    assert!(p2.min()[225] == p2.max()[225]);
    let half = |h: &[ShapeElem]| h.iter().map(|z| i32::from(z.to_bits())).sum::<i32>();
    assert!(half(&v2[BINS..]) < 0 && half(&v2[..BINS]) > 0);
    assert_ne!(v, v2);
}

#[test]
fn objects_touching_the_border_are_closed_by_it() {
    // A full 4x3 mask: every pixel touches the border, all are contour.
    let art = ["####", "####", "####"];
    assert_eq!(contour(&art).len(), 10);
    let (r, _, _) = run(&art);
    r.unwrap();
    let art = ["#####", "#####", "#####"];
    let c = contour(&art);
    assert_eq!(c.len(), 12);
    assert!(!c.contains(&(2, 1)));
}

#[test]
fn empty_bins_are_interpolated_circularly() {
    let mut v = [0u32; BINS];
    let mut filled = [false; BINS];
    for (b, val) in [(10, 100u32), (20, 200), (350, 40)] {
        v[b] = val;
        filled[b] = true;
    }
    interpolate(&mut v, &filled);
    assert_eq!(v[15], 150);
    assert_eq!(v[11], 110);
    // Wrapping gap 350 -> 10 (20 bins): 40 + 60 t / 20.
    assert_eq!(v[355], 55);
    assert_eq!(v[0], 70);
    assert_eq!(v[5], 85);
    // 20 -> 350 (330 bins): 200 - 160 t / 330, rounded.
    assert_eq!(v[185], 120);
    assert_eq!(v[21], 200); // 200 - 0.48 rounds to 200
                            // One filled bin: constant.
    let mut w = [0u32; BINS];
    let mut f = [false; BINS];
    w[7] = 9;
    f[7] = true;
    interpolate(&mut w, &f);
    assert!(w.iter().all(|&x| x == 9));
}

#[test]
fn small_divisions_match_the_wide_ones() {
    let mut rng = crate::rng::SplitMix64::new(7);
    for i in 0..200_000u32 {
        // Divisors up to 2^49, numerators up to 2^61, both signs.
        let d = 2 * ((rng.next_u64() >> (15 + i % 48)) + 1);
        let n = (rng.next_u64() >> (3 + (i / 7) % 60)) as i64;
        let n = if i % 2 == 0 { n } else { -n };
        let inv = u64::try_from((1u128 << 64) / u128::from(d)).unwrap();
        let want = i128::from(n).div_euclid(i128::from(d));
        match div_floor_small(n, d, inv) {
            Some(q) => assert_eq!(i128::from(q), want, "{n} / {d}"),
            None => assert!(want.abs() >= 1 << 16, "{n} / {d}"),
        }
        // Quotients near 2^16 and exact multiples.
        let q = (rng.next_u64() % (1 << 17)) as i64 - (1 << 16);
        let m = q
            .checked_mul(d as i64)
            .filter(|m| m.unsigned_abs() < 1 << 61);
        for n in m.into_iter().flat_map(|m| [m, m - 1, m + 1]) {
            let want = i128::from(n).div_euclid(i128::from(d));
            match div_floor_small(n, d, inv) {
                Some(got) => assert_eq!(i128::from(got), want, "{n} / {d}"),
                None => assert!(want.abs() >= 1 << 16, "{n} / {d}"),
            }
        }
        let (x, g) = (
            (rng.next_u64() >> 40) as i64 - (1 << 23),
            1 + (i % 360) as i64,
        );
        assert_eq!(div_round_small(x, g), div_round_i64(x, g));
    }
}

#[test]
fn scratch_is_small() {
    assert_eq!(scratch_bytes(), 2880);
    assert_eq!(core::mem::size_of::<ShapeVector>(), 1440);
}
