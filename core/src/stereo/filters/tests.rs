use super::*;
use crate::rng::SplitMix64;

const W: usize = 40;

/// `Bank::row` against `y_pass` + `x_pass` per carrier on random rows
/// (with the extremes 0 and 65535 often), every width up to `W`.
fn check(kernels: &[Gabor], rng: &mut SplitMix64) -> bool {
    let bank = Bank::new(kernels);
    let taps = bank.taps();
    for w in [1, 2, 3, taps - 1, taps, taps + 1, 2 * taps + 3, W] {
        let w = w.clamp(1, W);
        let mut grey = [[0u16; W]; MAX_TAPS];
        for v in grey.iter_mut().flatten() {
            *v = match rng.below(4) {
                0 => 0,
                1 => 65535,
                _ => rng.below(65536) as u16,
            };
        }
        let rows: [&[u16]; MAX_TAPS] = core::array::from_fn(|t| &grey[t][..w]);
        let mut col = [[0i32; 3]; W];
        let mut fast = [[0i16; 2]; MAX_CARRIERS * W];
        bank.row(&rows[..taps], &mut col[..w], &mut fast[..kernels.len() * w]);
        for (c, g) in kernels.iter().enumerate() {
            let skip = taps / 2 - g.radius();
            let mut slow = [[0i16; 2]; W];
            y_pass(g, rows[skip..].iter().copied(), &mut col[..w]);
            x_pass(g, &col[..w], &mut slow[..w]);
            assert_eq!(
                &fast[c * w..(c + 1) * w],
                &slow[..w],
                "carrier {c} width {w}"
            );
        }
    }
    bank.is_fast()
}

#[test]
fn the_bank_gives_the_reference_bits() {
    let mut rng = SplitMix64::new(3);
    let (mut fast, mut all) = (0, 0);
    for n in 1..=MAX_CARRIERS {
        for radius in [1u8, 2, 3, 7, 11, 15] {
            for lambda in [2.5f32, 4.0, 7.0, 13.0] {
                for sigma in [0.3f32, 0.56, 1.2] {
                    let kernels: [Gabor; MAX_CARRIERS] = core::array::from_fn(|k| {
                        Gabor::new(lambda, sigma, radius, carrier_deg(k.min(n - 1), n))
                    });
                    fast += usize::from(check(&kernels[..n], &mut rng));
                    all += 1;
                }
            }
        }
    }
    // Every setting was checked above; the defaults take the fast path
    // (the others fall back where the largest-remainder envelope is not
    // symmetric or Σ|ky| > 2^14).
    let d: [Gabor; 3] = core::array::from_fn(|k| Gabor::new(4.0, 0.56, 7, carrier_deg(k, 3)));
    assert!(Bank::new(&d).is_fast());
    assert!(
        fast > 0 && fast < all,
        "fast path for {fast} of {all} settings"
    );
}

/// A random kernel of `taps` the fast path accepts, at the edges of
/// its checks: `|kx|` up to 2^14 (often exactly ±2^14), `Σ|ky| ≤ 2^14`
/// per component, `dc` anywhere in `i32` (often its ends), the
/// envelope `env`; `conj` mirrors `ky_im` (the `b` of a unit), `flat`
/// makes `ky` the envelope (a rider).
fn extreme(
    env: &[i32; MAX_TAPS],
    taps: usize,
    rng: &mut SplitMix64,
    conj: Option<&Gabor>,
    flat: bool,
) -> Gabor {
    let r = taps / 2;
    let one = 1i32 << KERNEL_FRAC;
    let mut g = Gabor {
        taps,
        kx: [[0; 2]; MAX_TAPS],
        ky: [[0; 2]; MAX_TAPS],
        env: *env,
        dc: [0; 2],
    };
    let big = |rng: &mut SplitMix64| match rng.below(3) {
        0 => one,
        1 => -one,
        _ => rng.below(2 * one as u64 + 1) as i32 - one,
    };
    // Halves of ky with Σ|·| ≤ 2^14 over all taps.
    let mut budget = [one; 2];
    for i in 0..=r {
        let kx = [big(rng), if i == r { 0 } else { big(rng) }];
        let n = if i == r { 1 } else { 2 };
        let mut ky = [0; 2];
        for (c, k) in ky.iter_mut().enumerate() {
            let most = budget[c] / n;
            if !(c == 1 && i == r) && most > 0 {
                *k = rng.below(2 * most as u64 + 1) as i32 - most;
                budget[c] -= n * k.abs();
            }
        }
        for (t, sign) in [(i, 1), (taps - 1 - i, -1)] {
            g.kx[t] = [kx[0], sign * kx[1]];
            g.ky[t] = [ky[0], sign * ky[1]];
        }
    }
    if let Some(a) = conj {
        g.kx = a.kx;
        g.ky = a.ky.map(|k| [k[0], -k[1]]);
    }
    if flat {
        g.ky = env.map(|e| [e, 0]);
    }
    for d in &mut g.dc {
        *d = match rng.below(4) {
            0 => i64::from(i32::MIN),
            1 => i64::from(i32::MAX),
            _ => rng.next_u64() as i32 as i64,
        };
    }
    g
}

#[test]
fn the_bank_is_exact_at_the_edges_of_its_checks() {
    let mut rng = SplitMix64::new(11);
    for round in 0..200 {
        let taps = 2 * (1 + round % MAX_RADIUS) + 1;
        // A symmetric envelope, taps ≥ 0, Σ = 2^14 exactly.
        let mut env = [0i32; MAX_TAPS];
        let mut left = 1i32 << KERNEL_FRAC;
        for i in 0..taps / 2 {
            let v = rng.below((left / 2) as u64 / 2 + 1) as i32;
            env[i] = v;
            env[taps - 1 - i] = v;
            left -= 2 * v;
        }
        env[taps / 2] = left;
        let a = extreme(&env, taps, &mut rng, None, false);
        let k = [
            a,
            extreme(&env, taps, &mut rng, None, true),
            extreme(&env, taps, &mut rng, Some(&a), false),
        ];
        assert!(check(&k, &mut rng), "fast path, round {round}");
    }
}

#[test]
fn the_default_bank_shares_the_y_passes() {
    let d: [Gabor; 3] = core::array::from_fn(|k| Gabor::new(4.0, 0.56, 7, carrier_deg(k, 3)));
    let bank = Bank::new(&d);
    let units = &bank.units[..bank.n_units];
    assert_eq!(
        units,
        [Unit {
            a: Some(0),
            b: Some(2),
            e: Some(1)
        }]
    );
}

#[test]
fn mixed_radii_fall_back_to_the_reference() {
    let mut rng = SplitMix64::new(5);
    let k = [
        Gabor::new(4.0, 0.56, 7, -45.0),
        Gabor::new(4.0, 0.56, 4, 0.0),
    ];
    assert!(!check(&k, &mut rng));
}

#[test]
fn the_envelope_is_even_sums_to_one_and_stays_within_one_lsb() {
    for r in 1..=MAX_RADIUS as u8 {
        for lambda in [2.0f32, 4.0, 8.0] {
            let g = Gabor::new(lambda, 0.56, r, 0.0);
            let taps = g.taps;
            assert_eq!(
                g.env.iter().sum::<i32>(),
                1 << KERNEL_FRAC,
                "r {r} λ {lambda}"
            );
            let sigma = 0.56 * f64::from(lambda);
            let f = |i: usize| {
                let t = i as f64 - f64::from(r);
                libm::exp(-(t * t) / (2.0 * sigma * sigma))
            };
            let total: f64 = (0..taps).map(f).sum();
            for i in 0..taps {
                assert_eq!(g.env[i], g.env[taps - 1 - i], "r {r} λ {lambda} tap {i}");
                let exact = f(i) / total * f64::from(1u32 << KERNEL_FRAC);
                assert!(
                    (f64::from(g.env[i]) - exact).abs() < 1.0,
                    "r {r} λ {lambda} tap {i}"
                );
            }
        }
    }
}

#[test]
fn the_narrow_bank_takes_the_fast_path() {
    let k: [Gabor; 3] = core::array::from_fn(|c| Gabor::new(4.0, 0.56, 2, carrier_deg(c, 3)));
    let bank = Bank::new(&k);
    assert!(bank.is_fast());
    let mut rng = SplitMix64::new(11);
    assert!(check(&k, &mut rng));
}
