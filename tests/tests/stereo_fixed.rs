//! The fixed-point stereo filters (`protogist::stereo`) against their f32
//! reference (`protogist_host::reference::stereo`): per stage within the
//! bounds of docs/ERROR_BOUNDS.md section 7, and bad parameters and tables.
//! The engine end to end is `stereo_c2f_core.rs`.

use proptest::prelude::*;
use protogist::image::{ImageView, Rgb8};
use protogist::stereo::filters::{self as qf, Gabor, Z};
use protogist::stereo::{self as qs, Dem, StereoError};
use protogist_host::reference::stereo::filters as ff;
use protogist_host::reference::stereo::population as fp;
use protogist_host::reference::stereo::table::DEFAULT_TABLE;
use protogist_host::reference::stereo::{self as dem};

/// The kernels' radii: the design's 7 and the pipeline's 2
/// (`C2fParams::HALF_NARROW`).
const RADII: [u8; 2] = [7, 2];

/// Carrier `k` of 3 at kernel radius `r` (as `k + 3·[r == 2]`: carrier
/// and radius in one index, so that the helpers keep one argument).
fn float_kernel(k: usize) -> ff::Gabor {
    let p = dem::DemParams {
        radius: RADII[k / 3],
        ..dem::DemParams::default()
    };
    ff::gabor(&p, ff::carrier_deg(k % 3, 3))
}

fn core_kernel(k: usize) -> Gabor {
    let p = qs::DemParams {
        radius: RADII[k / 3],
        ..qs::DemParams::default()
    };
    *Dem::new(&p).unwrap().kernel(k % 3).unwrap()
}

/// Σ over the 2-D taps of |K_q − K_f| per component (re, im): the kernel
/// part of the response bound (ERROR_BOUNDS.md §7.2).
fn kernel_l1_error(q: &Gabor, f: &ff::Gabor) -> [f64; 2] {
    let one = f64::from(1u32 << qf::KERNEL_FRAC);
    let n = q.taps;
    let dcq = [q.dc[0] as f64 / (one * one), q.dc[1] as f64 / (one * one)];
    let mut e = [0.0f64; 2];
    for y in 0..n {
        for x in 0..n {
            let (kx, ky) = (q.kx[x], q.ky[y]);
            let (ex, ey) = (f64::from(q.env[x]) / one, f64::from(q.env[y]) / one);
            let kq = [
                (f64::from(kx[0]) * f64::from(ky[0]) - f64::from(kx[1]) * f64::from(ky[1]))
                    / (one * one)
                    - dcq[0] * ex * ey,
                (f64::from(kx[0]) * f64::from(ky[1]) + f64::from(kx[1]) * f64::from(ky[0]))
                    / (one * one)
                    - dcq[1] * ex * ey,
            ];
            let (fx, fy) = (f.kx[x], f.ky[y]);
            let fe = f64::from(f.env[x]) * f64::from(f.env[y]);
            let kf = [
                f64::from(fx[0]) * f64::from(fy[0])
                    - f64::from(fx[1]) * f64::from(fy[1])
                    - f64::from(f.dc[0]) * fe,
                f64::from(fx[0]) * f64::from(fy[1]) + f64::from(fx[1]) * f64::from(fy[0])
                    - f64::from(f.dc[1]) * fe,
            ];
            e[0] += (kq[0] - kf[0]).abs();
            e[1] += (kq[1] - kf[1]).abs();
        }
    }
    e
}

/// f32 allowance of the reference's response (ERROR_BOUNDS.md §7.2).
const F32_Z: f64 = 100.0 * 384.0 / 16_777_216.0;

/// Per-component response bound, grey levels.
fn z_bound(k: usize) -> [f64; 2] {
    let e = kernel_l1_error(&core_kernel(k), &float_kernel(k));
    e.map(|e| 128.0 * e + 1.0 / 128.0 + 1.0 / 1_048_576.0 + F32_Z)
}

/// Core responses of a U8F8 plane, whole-plane (the engine streams the
/// same two passes row by row).
fn core_respond(g: &Gabor, grey: &[u16], w: usize, h: usize) -> Vec<Z> {
    let mut col = vec![[0i32; 3]; w];
    let mut out = vec![[0i16; 2]; w * h];
    let r = g.radius();
    for j in 0..h {
        let rows = (0..g.taps).map(|t| {
            let y = (j + t).saturating_sub(r).min(h - 1);
            &grey[y * w..(y + 1) * w]
        });
        qf::y_pass(g, rows, &mut col);
        qf::x_pass(g, &col, &mut out[j * w..(j + 1) * w]);
    }
    out
}

fn plane_of(grey: &[u16], w: usize, h: usize) -> ff::Plane {
    ff::Plane {
        width: w,
        height: h,
        data: grey.iter().map(|&v| f32::from(v) / 256.0).collect(),
    }
}

fn grey_plane() -> impl Strategy<Value = (Vec<u16>, usize, usize)> {
    (8usize..40, 8usize..40, any::<bool>()).prop_flat_map(|(w, h, dots)| {
        let v = if dots {
            prop_oneof![Just(0u16), Just(65280u16)].boxed()
        } else {
            (0u16..=65280).boxed()
        };
        proptest::collection::vec(v, w * h).prop_map(move |g| (g, w, h))
    })
}

#[test]
fn the_quantised_kernels_are_zero_dc_and_close_to_the_float_ones() {
    for k in 0..6 {
        let (q, f) = (core_kernel(k), float_kernel(k));
        let e = kernel_l1_error(&q, &f);
        let b = z_bound(k);
        eprintln!(
            "radius {}, carrier {}: Σ|ΔK| = {:.2e}, {:.2e}; z bound {:.4}, {:.4} grey",
            RADII[k / 3],
            k % 3,
            e[0],
            e[1],
            b[0],
            b[1]
        );
        assert!(e[0] < 1e-2 && e[1] < 1e-2);
        assert_eq!(q.env[..q.taps].iter().sum::<i32>(), 1 << qf::KERNEL_FRAC);
        let flat = vec![23456u16; 30 * 30];
        assert!(core_respond(&q, &flat, 30, 30).iter().all(|z| *z == [0, 0]));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn grey_is_within_half_an_lsb(r: u8, g: u8, b: u8) {
        let q = f32::from(qf::grey(Rgb8::new(r, g, b))) / 256.0;
        let px = [Rgb8::new(r, g, b)];
        let f = ff::grey(&ImageView::packed(&px, 1, 1).unwrap()).data[0];
        // ½ LSB of U8F8 plus the f32 reference's rounding.
        prop_assert!((q - f).abs() <= 1.0 / 512.0 + 255.0 * 4.0 / 16_777_216.0, "{q} {f}");
    }

    #[test]
    fn responses_are_within_the_kernel_bound((grey, w, h) in grey_plane()) {
        let plane = plane_of(&grey, w, h);
        for k in 0..6 {
            let b = z_bound(k);
            let q = core_respond(&core_kernel(k), &grey, w, h);
            let f = ff::respond(&plane, &float_kernel(k));
            for (q, f) in q.iter().zip(&f.z) {
                for c in 0..2 {
                    let d = (f64::from(q[c]) / 64.0 - f64::from(f[c])).abs();
                    prop_assert!(d <= b[c], "carrier {k}: {d} > {}", b[c]);
                }
            }
        }
    }

    #[test]
    fn energies_are_within_the_propagated_bound((grey, w, h) in grey_plane(), shift in 0usize..8) {
        // Left = the plane, right = the plane shifted and perturbed.
        let right: Vec<u16> = grey.iter().enumerate().map(|(i, &v)| {
            let src = grey[(i / w) * w + (i % w + shift).min(w - 1)];
            src.wrapping_add(v >> 6).min(65280)
        }).collect();
        for k in 0..6 {
            let b = z_bound(k);
            let e = 2f64.sqrt() * b[0].max(b[1]);
            let (g, f) = (core_kernel(k), float_kernel(k));
            let (ql, qr) = (core_respond(&g, &grey, w, h), core_respond(&g, &right, w, h));
            let (fl, fr) = (ff::respond(&plane_of(&grey, w, h), &f), ff::respond(&plane_of(&right, w, h), &f));
            let fe = fp::energies_level(&fl, &fr, shift);
            for y in 0..h {
                for x in 0..w {
                    let i = y * w + x;
                    let zr = x.checked_sub(shift).map(|xr| qr[y * w + xr]);
                    let q = qf::energy(ql[i], zr);
                    let ml = f64::from(fl.z[i][0]).hypot(f64::from(fl.z[i][1]));
                    let mr = x.checked_sub(shift).map_or(0.0, |xr| {
                        let z = fr.z[y * w + xr];
                        f64::from(z[0]).hypot(f64::from(z[1]))
                    });
                    let f32_err = 8.0 * (ml + mr).powi(2) / 16_777_216.0;
                    let bound_a = 2.0 * (ml + mr) * e + 2.0 * e * e + f32_err;
                    let bound_x = (ml + mr) * e + e * e + f32_err;
                    for (c, bound) in [bound_a, bound_x, bound_x].into_iter().enumerate() {
                        let d = (q[c] as f64 / 4096.0 - f64::from(fe[i][c])).abs();
                        prop_assert!(d <= bound, "carrier {k} ({x},{y}) channel {c}: {d} > {bound}");
                    }
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------
// End to end.

#[test]
fn bad_params_are_typed_errors() {
    let d = qs::DemParams::default();
    for p in [
        qs::DemParams { carriers: 0, ..d },
        qs::DemParams { carriers: 7, ..d },
        qs::DemParams { levels: 0, ..d },
        qs::DemParams { levels: 5, ..d },
        qs::DemParams { radius: 16, ..d },
        qs::DemParams { shift_step: 0, ..d },
        qs::DemParams {
            pool_radius: 8,
            ..d
        },
        qs::DemParams {
            wavelength: f32::NAN,
            ..d
        },
        qs::DemParams {
            min_energy: -1.0,
            ..d
        },
        qs::DemParams {
            lr_tolerance: f32::NAN,
            ..d
        },
    ] {
        assert!(
            matches!(Dem::new(&p), Err(StereoError::BadParams(_))),
            "{p:?}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn arbitrary_table_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        let _ = qs::DemTable::parse(&bytes);
    }

    #[test]
    fn flipped_tables_are_rejected(flip in 0usize..100_000, bit in 0u8..8) {
        let mut b = DEFAULT_TABLE.to_vec();
        let i = flip % b.len();
        b[i] ^= 1 << bit;
        prop_assert!(qs::DemTable::parse(&b).is_err());
    }
}
