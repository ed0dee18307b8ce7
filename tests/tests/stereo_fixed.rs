//! The fixed-point stereo stage (`protogist::stereo`) against its f32
//! reference (`protogist_host::reference::stereo`): per stage within the
//! bounds of docs/ERROR_BOUNDS.md section 7, end to end on random-dot
//! stereograms and on Aloe, and bad input.

use proptest::prelude::*;
use protogist::disparity::DisparityCell;
use protogist::image::{ImageView, ImageViewMut, Rgb8};
use protogist::stereo::filters::{self as qf, Gabor, Z};
use protogist::stereo::{self as qs, Dem, StereoBuffers, StereoError, StereoReport, TableError};
use protogist_host::reference::stereo::filters as ff;
use protogist_host::reference::stereo::population as fp;
use protogist_host::reference::stereo::table::{DemTable as HostTable, DEFAULT_TABLE};
use protogist_host::reference::stereo::{self as dem};
use protogist_tests::{aloe_160_rgb, rds_rgb, stereo_agreement};

/// Owned scratch of the stage.
struct Storage {
    grey: Vec<u16>,
    z: Vec<Z>,
    col: Vec<[i32; 3]>,
    energy: Vec<i32>,
    scores: Vec<i64>,
    picks: Vec<i32>,
}

impl Storage {
    fn new(w: usize, h: usize, p: &qs::DemParams) -> Self {
        Self {
            grey: vec![0; qs::grey_len(w, h, p)],
            z: vec![[0; 2]; qs::z_len(w, p)],
            col: vec![[0; 3]; qs::col_len(w)],
            energy: vec![0; qs::energy_len(p)],
            scores: vec![0; qs::score_len(p)],
            picks: vec![0; qs::pick_len(w)],
        }
    }

    fn bufs(&mut self) -> StereoBuffers<'_> {
        StereoBuffers {
            grey: &mut self.grey,
            z: &mut self.z,
            col: &mut self.col,
            energy: &mut self.energy,
            scores: &mut self.scores,
            picks: &mut self.picks,
        }
    }
}

fn host_params(p: &qs::DemParams) -> dem::DemParams {
    dem::DemParams {
        max_disp: p.max_disp,
        carriers: p.carriers,
        levels: p.levels,
        wavelength: p.wavelength,
        sigma_per_wavelength: p.sigma_per_wavelength,
        radius: p.radius,
        shift_step: p.shift_step,
        pool_radius: p.pool_radius,
        min_energy: p.min_energy,
        min_margin: p.min_margin,
        lr_tolerance: p.lr_tolerance,
        ..dem::DemParams::default()
    }
}

/// Runs core on an RGB pair.
fn run_core(
    p: &qs::DemParams,
    table: &[u8],
    l: &[Rgb8],
    r: &[Rgb8],
    w: usize,
    h: usize,
) -> Result<(Vec<DisparityCell>, StereoReport), StereoError> {
    let dem = Dem::new(p)?;
    let t = qs::DemTable::parse(table)?;
    let mut st = Storage::new(w, h, p);
    let mut out = vec![DisparityCell::OFF; w * h];
    let rep = qs::stereo(
        &dem,
        &t,
        &ImageView::packed(l, w, h).unwrap(),
        &ImageView::packed(r, w, h).unwrap(),
        &mut st.bufs(),
        &mut ImageViewMut::packed(&mut out, w, h).unwrap(),
    )?;
    Ok((out, rep))
}

/// Runs the reference on the same pair with the same table.
fn run_float(
    p: &qs::DemParams,
    table: &[u8],
    l: &[Rgb8],
    r: &[Rgb8],
    w: usize,
    h: usize,
) -> dem::DisparityMapsF {
    let dec = HostTable::parse(table).unwrap().to_decoder();
    dem::stereo(
        &host_params(p),
        &dec,
        &ImageView::packed(l, w, h).unwrap(),
        &ImageView::packed(r, w, h).unwrap(),
    )
    .unwrap()
}

// ---------------------------------------------------------------------------
// Per stage.

/// The f32 kernel of carrier `k` for the default parameters.
fn float_kernel(k: usize) -> ff::Gabor {
    ff::gabor(&dem::DemParams::default(), ff::carrier_deg(k, 3))
}

fn core_kernel(k: usize) -> Gabor {
    *Dem::new(&qs::DemParams::default())
        .unwrap()
        .kernel(k)
        .unwrap()
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
    for k in 0..3 {
        let (q, f) = (core_kernel(k), float_kernel(k));
        let e = kernel_l1_error(&q, &f);
        let b = z_bound(k);
        eprintln!(
            "carrier {k}: Σ|ΔK| = {:.2e}, {:.2e}; z bound {:.4}, {:.4} grey",
            e[0], e[1], b[0], b[1]
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
    fn pyramid_is_within_half_an_lsb((grey, w, h) in grey_plane()) {
        let (lw, lh) = (qf::level_size(w, 1), qf::level_size(h, 1));
        let mut out = vec![0u16; lw * lh];
        for j in 0..lh {
            let rows: [&[u16]; 5] = core::array::from_fn(|t| {
                let y = (2 * j + t).saturating_sub(2).min(h - 1);
                &grey[y * w..(y + 1) * w]
            });
            qf::pyramid_row(rows, &mut out[j * lw..(j + 1) * lw]);
        }
        let f = ff::pyramid_down(&plane_of(&grey, w, h));
        for (q, f) in out.iter().zip(&f.data) {
            let q = f32::from(*q) / 256.0;
            prop_assert!((q - f).abs() <= 1.0 / 512.0 + 10.0 * 256.0 / 16_777_216.0, "{q} {f}");
        }
    }

    #[test]
    fn responses_are_within_the_kernel_bound((grey, w, h) in grey_plane()) {
        let plane = plane_of(&grey, w, h);
        for k in 0..3 {
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
        for k in 0..3 {
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
fn random_dots_end_to_end_agree() {
    let p = qs::DemParams::default();
    let (w, h) = (64, 40);
    let (mut close_n, mut both_n, mut agree_n, mut px) = (0.0, 0usize, 0.0, 0usize);
    for d in [0usize, 3, 6, 9, 12, 15] {
        let (l, r) = rds_rgb(w, h, d, 0x5eed_0000 + d as u64);
        let (q, _) = run_core(&p, DEFAULT_TABLE, &l, &r, w, h).unwrap();
        let f = run_float(&p, DEFAULT_TABLE, &l, &r, w, h);
        let (close, agree, both) = stereo_agreement(&q, &f);
        eprintln!("RDS d={d}: within 0.25 px {close:.2} % of {both}, OFF agree {agree:.2} %");
        close_n += close * both as f64 / 100.0;
        both_n += both;
        agree_n += agree * (w * h) as f64 / 100.0;
        px += w * h;
    }
    let (close, agree) = (100.0 * close_n / both_n as f64, 100.0 * agree_n / px as f64);
    eprintln!("RDS total: within 0.25 px {close:.2} %, OFF agree {agree:.2} %");
    assert!(both_n > px / 2);
    assert!(close >= 99.0, "{close}");
    assert!(agree >= 99.0, "{agree}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    #[test]
    fn random_dot_pairs_agree(seed: u64, d in 0usize..=15, pool in 0u8..=2) {
        let p = qs::DemParams { pool_radius: pool, ..qs::DemParams::default() };
        let (w, h) = (56, 36);
        let (l, r) = rds_rgb(w, h, d, seed);
        let (q, _) = run_core(&p, DEFAULT_TABLE, &l, &r, w, h).unwrap();
        let f = run_float(&p, DEFAULT_TABLE, &l, &r, w, h);
        let (close, agree, both) = stereo_agreement(&q, &f);
        prop_assert!(both > 0);
        prop_assert!(close >= 99.0, "d={d} pool={pool}: {close} % within 0.25 px");
        prop_assert!(agree >= 99.0, "d={d} pool={pool}: OFF agree {agree} %");
    }
}

#[test]
fn aloe_160_d32_end_to_end_agrees() {
    let Some((l, r, w, h)) = aloe_160_rgb() else {
        return;
    };
    let p = qs::DemParams {
        max_disp: 31,
        ..qs::DemParams::default()
    };
    let table = HostTable::from_decoder(&dem::train(&host_params(&p))).to_bytes();
    let (q, rep) = run_core(&p, &table, &l, &r, w, h).unwrap();
    let f = run_float(&p, &table, &l, &r, w, h);
    let (close, agree, both) = stereo_agreement(&q, &f);
    eprintln!(
        "Aloe {w}x{h} D=32: within 0.25 px {close:.2} % of {both} ON in both, OFF agree {agree:.2} %; core {rep:?}; float ON {}",
        f.disparity_f32.iter().filter(|v| v.is_some()).count()
    );
    assert!(both > w * h / 4);
    assert!(close >= 99.0, "{close}");
    assert!(agree >= 99.0, "{agree}");
}

// ---------------------------------------------------------------------------
// Bad input (issue 3 §6, the items that concern core).

#[test]
fn flat_images_give_an_all_off_map() {
    let (w, h) = (64, 48);
    let px = vec![Rgb8::new(90, 120, 30); w * h];
    let (m, rep) = run_core(&qs::DemParams::default(), DEFAULT_TABLE, &px, &px, w, h).unwrap();
    assert!(m.iter().all(|c| c.is_off()));
    assert_eq!(rep.off_texture, w * h);
}

#[test]
fn bad_sizes_are_typed_errors() {
    let p = qs::DemParams::default();
    let px = vec![Rgb8::new(1, 2, 3); 64 * 48];
    let dem = Dem::new(&p).unwrap();
    let t = qs::DemTable::parse(DEFAULT_TABLE).unwrap();
    let run = |lw: usize, lh: usize, rw: usize, rh: usize| {
        let mut st = Storage::new(lw, lh, &p);
        let mut out = vec![DisparityCell::OFF; lw * lh];
        qs::stereo(
            &dem,
            &t,
            &ImageView::packed(&px[..lw * lh], lw, lh).unwrap(),
            &ImageView::packed(&px[..rw * rh], rw, rh).unwrap(),
            &mut st.bufs(),
            &mut ImageViewMut::packed(&mut out, lw, lh).unwrap(),
        )
    };
    assert!(matches!(
        run(64, 48, 60, 48),
        Err(StereoError::SizeMismatch { .. })
    ));
    assert!(matches!(
        run(20, 48, 20, 48),
        Err(StereoError::TooSmall { min: 30, .. })
    ));
    assert!(matches!(
        run(64, 29, 64, 29),
        Err(StereoError::TooSmall { .. })
    ));
    // max_disp at or above the width.
    let wide = qs::DemParams { max_disp: 40, ..p };
    let table = HostTable::from_decoder(&dem::train(&dem::DemParams {
        train_images: 1,
        train_width: 8,
        train_height: 4,
        ..host_params(&wide)
    }))
    .to_bytes();
    let l = vec![Rgb8::new(1, 2, 3); 40 * 40];
    assert!(matches!(
        run_core(&wide, &table, &l, &l, 40, 40),
        Err(StereoError::MaxDispTooLarge {
            max_disp: 40,
            width: 40
        })
    ));
    // Short scratch and a wrongly sized output.
    let mut st = Storage::new(64, 48, &p);
    st.scores.pop();
    let mut out = vec![DisparityCell::OFF; 64 * 48];
    let v = ImageView::packed(&px, 64, 48).unwrap();
    assert!(matches!(
        qs::stereo(
            &dem,
            &t,
            &v,
            &v,
            &mut st.bufs(),
            &mut ImageViewMut::packed(&mut out, 64, 48).unwrap()
        ),
        Err(StereoError::Buffer { what: "scores", .. })
    ));
    let mut st = Storage::new(64, 48, &p);
    assert!(matches!(
        qs::stereo(
            &dem,
            &t,
            &v,
            &v,
            &mut st.bufs(),
            &mut ImageViewMut::packed(&mut out[..64 * 47], 64, 47).unwrap()
        ),
        Err(StereoError::Image(_))
    ));
}

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

#[test]
fn corrupt_or_mismatched_tables_are_typed_errors() {
    let (w, h) = (64, 48);
    let px = vec![Rgb8::new(1, 2, 3); w * h];
    let p = qs::DemParams::default();
    let mut b = DEFAULT_TABLE.to_vec();
    b[30] ^= 1;
    assert!(matches!(
        run_core(&p, &b, &px, &px, w, h),
        Err(StereoError::Table(TableError::Checksum { .. }))
    ));
    assert!(matches!(
        run_core(&p, &DEFAULT_TABLE[..100], &px, &px, w, h),
        Err(StereoError::Table(TableError::Truncated { .. }))
    ));
    assert!(matches!(
        run_core(&p, b"nope", &px, &px, w, h),
        Err(StereoError::Table(TableError::Truncated { .. }))
    ));
    let other = qs::DemParams { max_disp: 14, ..p };
    assert!(matches!(
        run_core(&other, DEFAULT_TABLE, &px, &px, w, h),
        Err(StereoError::DecoderMismatch { .. })
    ));
    let other = qs::DemParams {
        wavelength: 4.5,
        ..p
    };
    assert!(matches!(
        run_core(&other, DEFAULT_TABLE, &px, &px, w, h),
        Err(StereoError::DecoderMismatch { .. })
    ));
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

#[test]
fn scratch_for_160x120_d32_is_within_96_kb() {
    let bytes = qs::scratch_bytes(160, 120, 31);
    eprintln!("scratch stereo 160x120 D=32: {bytes} bytes");
    assert!(bytes <= 96 * 1024, "{bytes}");
}

// ---------------------------------------------------------------------------
// Streaming and the random-dot anchor.

/// One eye of a synthetic scene, rendered row by row on demand.
struct SceneRows<'s> {
    spec: &'s protogist::synth::SceneSpec,
    right: bool,
    w: usize,
    h: usize,
}

impl qs::GreyRows for SceneRows<'_> {
    fn size(&self) -> (usize, usize) {
        (self.w, self.h)
    }
    fn grey_row(&self, y: usize, out: &mut [u16]) {
        for (x, o) in out.iter_mut().enumerate() {
            *o = qf::grey(self.spec.colour(self.right, x as i32, y as i32));
        }
    }
}

#[test]
fn streamed_rows_and_sink_equal_the_in_memory_run() {
    use protogist::synth::{render_left, render_right, SceneSpec};
    let (w, h) = (96, 64);
    let spec = SceneSpec::demo(w, h);
    let (mut l, mut r) = (vec![Rgb8::default(); w * h], vec![Rgb8::default(); w * h]);
    render_left(&spec, &mut ImageViewMut::packed(&mut l, w, h).unwrap()).unwrap();
    render_right(&spec, &mut ImageViewMut::packed(&mut r, w, h).unwrap()).unwrap();
    let p = qs::DemParams::default();
    let (whole, rep) = run_core(&p, DEFAULT_TABLE, &l, &r, w, h).unwrap();
    let dem = Dem::new(&p).unwrap();
    let t = qs::DemTable::parse(DEFAULT_TABLE).unwrap();
    let mut st = Storage::new(w, h, &p);
    let mut streamed = vec![DisparityCell::OFF; w * h];
    let mut order = Vec::new();
    let eye = |right| SceneRows {
        spec: &spec,
        right,
        w,
        h,
    };
    let rep2 = qs::stereo_streamed(
        &dem,
        &t,
        &eye(false),
        &eye(true),
        &mut st.bufs(),
        &mut |x, y, c| {
            order.push(y * w + x);
            streamed[y * w + x] = c;
        },
        &mut (),
    )
    .unwrap();
    assert_eq!(whole, streamed);
    assert_eq!(rep, rep2);
    assert!(
        order.iter().copied().eq(0..w * h),
        "cells arrive row-major once each"
    );
    assert!(rep.on > w * h / 2, "{rep:?}");
}

#[test]
fn random_dots_bad1_below_5_percent_unpooled() {
    // Issue 3 §2's unit anchor, on the fixed-point stage: argmax off by
    // more than 1 px, interior pixels, ON pixels only (the left-right
    // check is off here, as in the reference's raw-argmax anchor).
    let p = qs::DemParams {
        pool_radius: 0,
        lr_tolerance: -1.0,
        min_energy: 0.0,
        ..qs::DemParams::default()
    };
    let (w, h) = (72, 48);
    let (mut bad, mut n) = (0usize, 0usize);
    for d in 0..=15usize {
        let (l, r) = rds_rgb(w, h, d, 0xabcd_0000 + d as u64);
        let (m, _) = run_core(&p, DEFAULT_TABLE, &l, &r, w, h).unwrap();
        for y in 12..h - 12 {
            for x in 15 + 12..w - 12 {
                n += 1;
                let v = m[y * w + x]
                    .get()
                    .map_or(f32::INFINITY, |v| v.to_num::<f32>());
                bad += usize::from((v - d as f32).abs() > 1.0);
            }
        }
    }
    let pct = 100.0 * bad as f64 / n as f64;
    eprintln!("core RDS bad-1 unpooled: {pct:.2} %");
    assert!(pct < 5.0, "{pct}");
}

#[test]
fn extreme_parameters_and_contrast_do_not_overflow() {
    // The largest pooling box, most carriers and levels, step 1, on
    // full-contrast gratings and dots: every integer range of
    // ERROR_BOUNDS.md §7 at its widest (the test profile checks overflow).
    let p = qs::DemParams {
        max_disp: 7,
        carriers: 6,
        levels: 4,
        wavelength: 2.0,
        sigma_per_wavelength: 0.3,
        radius: 3,
        shift_step: 1,
        pool_radius: 7,
        min_energy: 0.0,
        ..qs::DemParams::default()
    };
    let table = HostTable::from_decoder(&dem::train(&dem::DemParams {
        train_images: 1,
        train_width: 8,
        train_height: 4,
        ..host_params(&p)
    }))
    .to_bytes();
    let (w, h) = (64, 60);
    let grating: Vec<Rgb8> = (0..w * h)
        .map(|i| {
            if (i % w + i / w) % 2 == 0 {
                Rgb8::new(255, 255, 255)
            } else {
                Rgb8::new(0, 0, 0)
            }
        })
        .collect();
    let (dots_l, dots_r) = rds_rgb(w, h, 5, 77);
    for (l, r) in [
        (&grating, &grating),
        (&dots_l, &dots_r),
        (&grating, &dots_r),
    ] {
        let (m, rep) = run_core(&p, &table, l, r, w, h).unwrap();
        assert_eq!(
            rep.on + rep.off_texture + rep.off_ambiguous + rep.off_inconsistent,
            w * h
        );
        assert_eq!(m.iter().filter(|c| c.is_on()).count(), rep.on);
    }
}
