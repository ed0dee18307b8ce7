//! The product on the desktop: the demo scene's objects against the
//! committed golden list (`golden/demo_objects.txt`, which `cargo xtask
//! firmware` also holds the QEMU run to), the RGB565 cameras, and bad
//! input.
//!
//! After an intended change of the pipeline's output, regenerate the list
//! with `UPDATE_GOLDEN=1 cargo test -p firmware-sim --test product` and
//! review its diff.

use std::convert::Infallible;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use embedded_hal::digital::{ErrorType, OutputPin};

use firmware_sim::pg::conspicuity::{snn_row, ColourKernel, Luv, LUV_TABLES};
use firmware_sim::pg::image::{mean_2x2_row, ImageViewMut, Rgb8};
use firmware_sim::pg::mlp::MacKernel;
use firmware_sim::pg::pipeline::{Pipeline, PipelineError, Region, RgbRows};
use firmware_sim::pg::stereo::phase::{grey8, PhaseKernel};
use firmware_sim::pg::stereo::sgm::sgm_step;
use firmware_sim::pg::synth::{render_left, render_mask, render_right, SceneSpec};
use firmware_sim::product::{
    is_compared, Product, ProductError, FRAME_LEN, HEIGHT, KEPT_WORDS, MODEL, PARAMS, SHARED_WORDS,
    TABLES, WIDTH, WORKSPACE_WORDS,
};
use firmware_sim::stereo_camera::{
    expand_rgb565, grey8_of_rgb565, luv_of_rgb565, mean_rgb565, pack_rgb565, pair_len, PairLayout,
    Rgb565Camera, Rgb565View, SideBySide, SideBySideError, SimSideBySideSensor, SimStereoCamera,
    SimStereoError, StereoCamera,
};
use firmware_sim::{CameraError, CameraErrorKind, NoTicks};

/// Counts the LED's switch-ons and remembers its state.
#[derive(Default)]
struct MockLed {
    on: bool,
    switched_on: u32,
}

impl ErrorType for MockLed {
    type Error = Infallible;
}

impl OutputPin for MockLed {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.on = false;
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.on = true;
        self.switched_on += 1;
        Ok(())
    }
}

fn pipeline() -> Pipeline<'static> {
    Pipeline::new(&PARAMS, &TABLES, MODEL).unwrap()
}

/// The workspace's two parts, kept maps and shared region.
/// The simulated camera's demo pair in a frame buffer, and where each eye is.
fn demo_frame() -> (Vec<u16>, PairLayout) {
    let mut frame = vec![0u16; pair_len(WIDTH, HEIGHT)];
    let layout = SimStereoCamera::new()
        .capture_pair(&mut frame, WIDTH, HEIGHT)
        .unwrap();
    (frame, layout)
}

fn workspace() -> (Vec<u64>, Vec<u64>) {
    assert_eq!(KEPT_WORDS + SHARED_WORDS, WORKSPACE_WORDS);
    (vec![0u64; KEPT_WORDS], vec![0u64; SHARED_WORDS])
}

/// One frame of `camera`: the report and the LED.
fn report<C: StereoCamera>(camera: C) -> (String, MockLed)
where
    C::Error: std::fmt::Debug,
{
    let mut product = Product::new(camera, MockLed::default(), pipeline());
    let (mut frame, (mut kept, mut shared)) = (vec![0u16; FRAME_LEN], workspace());
    let mut out = String::new();
    let s = product
        .frame(
            (WIDTH, HEIGHT),
            &mut frame,
            (&mut kept, &mut shared),
            &mut NoTicks,
            &mut out,
        )
        .unwrap();
    assert_eq!(
        out.lines().filter(|l| l.starts_with("object ")).count(),
        s.objects
    );
    assert!(out.contains(&format!("objects-checksum 160x120 0x{:08x}", s.checksum)));
    (out, product.release().1)
}

fn compared(text: &str) -> Vec<&str> {
    text.lines().filter(|l| is_compared(l)).collect()
}

#[test]
fn the_demo_objects_are_the_golden_list() {
    let (out, led) = report(SimStereoCamera::new());
    assert_eq!(led.switched_on, 1);
    assert!(!led.on, "the LED is off between frames");
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("golden/demo_objects.txt");
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        let header = "# The product's objects on the demo scene (160x120, K = 4, RGB565 pair):\n\
                      # `cargo run -p firmware-sim --release` and the QEMU run must print these lines.\n\
                      # Regenerate: UPDATE_GOLDEN=1 cargo test -p firmware-sim --test product\n";
        let body: String = compared(&out).iter().map(|l| format!("{l}\n")).collect();
        std::fs::write(&path, format!("{header}{body}")).unwrap();
    }
    let golden = std::fs::read_to_string(&path).unwrap();
    assert_eq!(compared(&out), compared(&golden), "report:\n{out}");
    assert!(
        compared(&golden).iter().any(|l| l.starts_with("object 0 ")),
        "the golden list has the demo's object"
    );
}

/// The portable kernels, counting the SGM steps of 5 candidates (the
/// finer levels' windows) and the smoothing rows they run.
struct CountingKernel;

static SGM_STEPS: AtomicUsize = AtomicUsize::new(0);
static SMOOTHED_ROWS: AtomicUsize = AtomicUsize::new(0);

impl PhaseKernel for CountingKernel {
    fn sgm_step5(
        c: &[u16; 5],
        p: &[u16; 5],
        pad: u32,
        pen: (u32, u32),
        acc: &mut [u32; 5],
    ) -> [u16; 5] {
        SGM_STEPS.fetch_add(1, Ordering::Relaxed);
        sgm_step(c, p, pad, pen, acc)
    }
}

impl MacKernel for CountingKernel {}

impl ColourKernel for CountingKernel {
    fn snn_row(prev: &[Luv], cur: &[Luv], next: &[Luv], out: &mut [Luv]) {
        SMOOTHED_ROWS.fetch_add(1, Ordering::Relaxed);
        snn_row(prev, cur, next, out);
    }
}

#[test]
fn the_pipeline_runs_the_kernel_it_is_given() {
    // As the board runs its assembly kernels: the SGM steps of the
    // half-size level's windows (at least one per pixel of it) and every
    // row of the smoothing go through the kernel, and the objects are the
    // golden list's (the portable pipeline's).
    let p = Pipeline::<CountingKernel>::with_kernel(&PARAMS, &TABLES, MODEL).unwrap();
    let mut product = Product::new(SimStereoCamera::new(), MockLed::default(), p);
    let (mut frame, (mut kept, mut shared)) = (vec![0u16; FRAME_LEN], workspace());
    let mut out = String::new();
    product
        .frame(
            (WIDTH, HEIGHT),
            &mut frame,
            (&mut kept, &mut shared),
            &mut NoTicks,
            &mut out,
        )
        .unwrap();
    let steps = SGM_STEPS.load(Ordering::Relaxed);
    assert!(steps >= (WIDTH / 2) * (HEIGHT / 2), "{steps}");
    assert_eq!(SMOOTHED_ROWS.load(Ordering::Relaxed), HEIGHT);
    let (portable, _) = report(SimStereoCamera::new());
    assert_eq!(compared(&out), compared(&portable));
}

#[test]
fn the_first_object_is_the_demo_scene_object() {
    // The RGB565 pair loses the colours' low bits; the object must survive.
    let p = pipeline();
    let (frame, layout) = demo_frame();
    let (l, r) = layout.views(&frame).unwrap();
    let mut ws = vec![0u64; WORKSPACE_WORDS];
    let result = p.run(&l, &r, &mut ws).unwrap();
    let o = result.objects().first().copied().expect("an object");
    let spec = SceneSpec::demo(WIDTH, HEIGHT);
    let mut gt = vec![0u8; WIDTH * HEIGHT];
    render_mask(
        &spec,
        0,
        &mut ImageViewMut::packed(&mut gt, WIDTH, HEIGHT).unwrap(),
    )
    .unwrap();
    let mask = result.mask(&o).unwrap();
    let (mut inter, mut union) = (0u32, 0u32);
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let (a, b) = (mask.get(x, y), gt[y * WIDTH + x] != 0);
            inter += u32::from(a && b);
            union += u32::from(a || b);
        }
    }
    let iou = f64::from(inter) / f64::from(union.max(1));
    assert!(iou > 0.8, "mask IoU {iou:.3}");
    // δ within a pixel of the object's disparity.
    let d = i64::from(spec.objects[0].disparity);
    assert!((i64::from(o.delta) - d).abs() <= 1, "δ {} for {d}", o.delta);
}

#[test]
fn the_cameras_deliver_the_demo_pair_in_rgb565() {
    let spec = SceneSpec::demo(WIDTH, HEIGHT);
    let mut l8 = vec![Rgb8::default(); WIDTH * HEIGHT];
    let mut r8 = l8.clone();
    render_left(
        &spec,
        &mut ImageViewMut::packed(&mut l8, WIDTH, HEIGHT).unwrap(),
    )
    .unwrap();
    render_right(
        &spec,
        &mut ImageViewMut::packed(&mut r8, WIDTH, HEIGHT).unwrap(),
    )
    .unwrap();
    let mut stacked = vec![0u16; FRAME_LEN];
    let a = SimStereoCamera::new()
        .capture_pair(&mut stacked, WIDTH, HEIGHT)
        .unwrap();
    assert_eq!(a, PairLayout::stacked(WIDTH, HEIGHT));
    let mut sbs = vec![0u16; FRAME_LEN];
    let mut camera = SideBySide::new(SimSideBySideSensor);
    let b = camera.capture_pair(&mut sbs, WIDTH, HEIGHT).unwrap();
    assert_eq!(b, PairLayout::side_by_side(WIDTH, HEIGHT));
    // The side-by-side frame's rows: left half, then right half.
    assert_eq!(sbs[WIDTH], pack_rgb565(r8[0]));
    let (al, ar) = a.views(&stacked).unwrap();
    let (bl, br) = b.views(&sbs).unwrap();
    let mut row = vec![Rgb8::default(); WIDTH];
    for (eye, rgb8) in [(&al, &l8), (&ar, &r8), (&bl, &l8), (&br, &r8)] {
        assert_eq!(eye.size(), (WIDTH, HEIGHT));
        for y in 0..HEIGHT {
            eye.rgb_row(y, &mut row);
            let want: Vec<Rgb8> = rgb8[y * WIDTH..(y + 1) * WIDTH]
                .iter()
                .map(|&p| expand_rgb565(pack_rgb565(p)))
                .collect();
            assert_eq!(row, want, "row {y}");
        }
    }
    // So the product reports the same objects through either camera.
    let (direct, _) = report(SimStereoCamera::new());
    let (adapted, _) = report(SideBySide::new(SimSideBySideSensor));
    assert_eq!(compared(&direct), compared(&adapted));
}

/// An RGB565 eye through `RgbRows`'s default rows (`luv_row`,
/// `grey8_row`, `half_row`: from `rgb_row`), not the frame's tables.
struct Converted<'a>(Rgb565View<'a>);

impl RgbRows for Converted<'_> {
    fn size(&self) -> (usize, usize) {
        self.0.size()
    }

    fn rgb_row(&self, y: usize, out: &mut [Rgb8]) {
        self.0.rgb_row(y, out);
    }
}

/// The frame's table of CIELUV gives core's conversion for all 65,536
/// RGB565 values, and a row by table is the default (convert) row.
#[test]
fn rgb565_luv_table_is_the_conversion() {
    for v in 0..=u16::MAX {
        let want = LUV_TABLES.convert(expand_rgb565(v));
        assert_eq!(luv_of_rgb565(v), want, "RGB565 {v:#06x}");
    }
    let (frame, layout) = demo_frame();
    let (left, _) = layout.views(&frame).unwrap();
    let mut rgb = vec![Rgb8::default(); WIDTH];
    let (mut by_table, mut converted) = (vec![Luv::default(); WIDTH], vec![Luv::default(); WIDTH]);
    let mut distinct = std::collections::HashSet::new();
    for y in 0..HEIGHT {
        left.luv_row(y, &mut rgb, &mut by_table);
        Converted(left).luv_row(y, &mut rgb, &mut converted);
        assert_eq!(by_table, converted, "row {y}");
        distinct.extend(by_table.iter().map(|p| p.to_bits()));
    }
    // The scene has colours, not one flat value.
    assert!(distinct.len() > 4, "{} colours", distinct.len());
}

/// The half-size rows from the RGB565 pixels are the default's (rounded
/// means of the expanded pixels), on the demo pair and on every value of
/// each channel.
#[test]
fn rgb565_half_rows_are_the_means() {
    // Each 5- and 6-bit value of a channel with its neighbours, so every
    // entry of the tables and rounding case is met.
    for v in 0..=u16::MAX {
        let p = [v, v.wrapping_add(0x0841), v ^ 0xffff, v.rotate_left(5)];
        let rgb = p.map(expand_rgb565);
        let mut want = [Rgb8::default()];
        mean_2x2_row(&rgb[..2], &rgb[2..], &mut want);
        assert_eq!(mean_rgb565(p), want[0], "{p:04x?}");
    }
    let (frame, layout) = demo_frame();
    let (left, right) = layout.views(&frame).unwrap();
    let mut scratch = vec![Rgb8::default(); 2 * WIDTH];
    let (mut mine, mut default) = (
        vec![Rgb8::default(); WIDTH / 2],
        vec![Rgb8::default(); WIDTH / 2],
    );
    for eye in [left, right] {
        for j in 0..HEIGHT / 2 {
            eye.half_row(j, &mut mine, &mut scratch);
            Converted(eye).half_row(j, &mut default, &mut scratch);
            assert_eq!(mine, default, "row {j}");
        }
    }
}

/// The frame's grey tables give core's `grey8` for all 65,536 RGB565
/// values, and a grey row by table is the default row.
#[test]
fn rgb565_grey_tables_are_grey8() {
    for v in 0..=u16::MAX {
        assert_eq!(
            grey8_of_rgb565(v),
            grey8(expand_rgb565(v)),
            "RGB565 {v:#06x}"
        );
    }
    assert_eq!(grey8_of_rgb565(0xffff), 255 * 256);
    let (frame, layout) = demo_frame();
    let (_, right) = layout.views(&frame).unwrap();
    let mut rgb = vec![Rgb8::default(); WIDTH];
    let (mut by_table, mut converted) = (vec![0i32; WIDTH], vec![0i32; WIDTH]);
    for y in 0..HEIGHT {
        right.grey8_row(y, &mut rgb, &mut by_table);
        Converted(right).grey8_row(y, &mut rgb, &mut converted);
        assert_eq!(by_table, converted, "row {y}");
    }
}

#[test]
fn rgb565_expands_by_bit_replication() {
    for v in 0..=u16::MAX {
        assert_eq!(pack_rgb565(expand_rgb565(v)), v);
    }
    assert_eq!(expand_rgb565(0), Rgb8::new(0, 0, 0));
    assert_eq!(expand_rgb565(0xffff), Rgb8::new(255, 255, 255));
    // Red 0b10000 -> 0b10000_100, green 0b100000 -> 0b100000_10.
    assert_eq!(
        expand_rgb565((0b10000 << 11) | (0b10_0000 << 5) | 0b10000),
        Rgb8::new(132, 130, 132)
    );
    // Expanding is monotonic in each channel.
    let reds: Vec<u8> = (0..32u16).map(|r| expand_rgb565(r << 11).r).collect();
    assert!(reds.windows(2).all(|w| w[0] < w[1]));
}

#[test]
fn bad_input_gets_typed_errors() {
    let mut product = Product::new(SimStereoCamera::new(), MockLed::default(), pipeline());
    let (mut kept, mut shared) = workspace();
    let mut out = String::new();
    // A frame buffer short of one pixel.
    let mut short = vec![0u16; FRAME_LEN - 1];
    let e = product
        .frame(
            (WIDTH, HEIGHT),
            &mut short,
            (&mut kept, &mut shared),
            &mut NoTicks,
            &mut out,
        )
        .unwrap_err();
    assert!(matches!(
        e,
        ProductError::Camera(SimStereoError::BufferTooSmall { needed, got })
            if needed == FRAME_LEN && got == FRAME_LEN - 1
    ));
    // A zero-sized frame.
    let mut frame = vec![0u16; FRAME_LEN];
    let e = product
        .frame(
            (0, HEIGHT),
            &mut frame,
            (&mut kept, &mut shared),
            &mut NoTicks,
            &mut out,
        )
        .unwrap_err();
    assert!(matches!(e, ProductError::Camera(SimStereoError::BadSize)));
    // A workspace part short of one word, named, with the bytes needed.
    let mut kept_short = vec![0u64; KEPT_WORDS - 1];
    let e = product
        .frame(
            (WIDTH, HEIGHT),
            &mut frame,
            (&mut kept_short, &mut shared),
            &mut NoTicks,
            &mut out,
        )
        .unwrap_err();
    let ProductError::Pipeline(PipelineError::RegionTooSmall {
        region: Region::Kept,
        needed,
        got,
    }) = e
    else {
        panic!("{e:?}");
    };
    assert_eq!((needed, got), (KEPT_WORDS * 8, (KEPT_WORDS - 1) * 8));
    let mut plain = String::new();
    e.write_plain(&mut plain).unwrap();
    assert!(
        plain.contains("kept maps") && plain.contains(&needed.to_string()),
        "{plain}"
    );
    // A frame the engine cannot run (smaller than its coarsest level).
    let e = product
        .frame(
            (8, 6),
            &mut frame,
            (&mut kept, &mut shared),
            &mut NoTicks,
            &mut out,
        )
        .unwrap_err();
    assert!(
        matches!(e, ProductError::Pipeline(PipelineError::Stereo(_))),
        "{e:?}"
    );
    // No object line was written by a failed frame.
    assert!(!out.contains("object "), "{out}");

    // The side-by-side adapter: a width whose double overflows, an odd
    // sensor frame, a short buffer; and eyes outside a short buffer.
    let mut camera = SideBySide::new(SimSideBySideSensor);
    let e = camera.capture_pair(&mut frame, usize::MAX, 1).unwrap_err();
    assert!(matches!(e, SideBySideError::TooWide));
    assert_eq!(e.kind(), CameraErrorKind::UnsupportedResolution);
    assert_eq!(
        SimSideBySideSensor.capture(&mut frame, 2 * WIDTH + 1, 4),
        Err(SimStereoError::BadSize)
    );
    let e = camera
        .capture_pair(&mut frame[..pair_len(WIDTH, HEIGHT) - 2], WIDTH, HEIGHT)
        .unwrap_err();
    assert_eq!(e.kind(), CameraErrorKind::BufferTooSmall);
    assert!(PairLayout::side_by_side(WIDTH, HEIGHT)
        .views(&frame[..FRAME_LEN - 1])
        .is_err());
    assert!(PairLayout::stacked(WIDTH, HEIGHT)
        .views(&frame[..FRAME_LEN - 1])
        .is_err());
}

/// A clock that advances one tick per reading.
struct Counter(u64);

impl firmware_sim::Ticks for Counter {
    fn now(&mut self) -> u64 {
        self.0 += 1;
        self.0
    }
}

#[test]
fn every_stage_and_step_is_timed() {
    let mut product = Product::new(SimStereoCamera::new(), MockLed::default(), pipeline());
    let (mut frame, (mut kept, mut shared)) = (vec![0u16; FRAME_LEN], workspace());
    let mut ticks = Counter(0);
    let s = product
        .frame(
            (WIDTH, HEIGHT),
            &mut frame,
            (&mut kept, &mut shared),
            &mut ticks,
            &mut String::new(),
        )
        .unwrap();
    assert!(s.ticks.0.iter().all(|&t| t > 0), "{:?}", s.ticks);
    assert!(s.ticks.0.iter().sum::<u64>() <= s.total);
    let steps = firmware_sim::product::STEPS;
    for (name, t) in steps.iter().zip(s.steps.0) {
        assert!(t > 0, "{name} not timed: {:?}", s.steps);
    }
    let stereo: u64 = s.steps.0[..5].iter().sum();
    assert!(
        stereo <= s.ticks.0[1],
        "stereo's steps are within the stage"
    );
}

#[test]
fn rgb565_row_parts_are_the_rows_there() {
    let (frame, layout) = demo_frame();
    let (left, _) = layout.views(&frame).unwrap();
    let mut whole = vec![Rgb8::default(); WIDTH];
    let marker = Rgb8::new(1, 2, 3);
    for (y, xs) in [
        (0, 0..WIDTH),
        (40, 32..96),
        (HEIGHT - 1, 100..WIDTH),
        (7, 5..5),
    ] {
        left.rgb_row(y, &mut whole);
        let mut part = vec![marker; WIDTH];
        left.rgb_part(y, xs.clone(), &mut part);
        for x in 0..WIDTH {
            let want = if xs.contains(&x) { whole[x] } else { marker };
            assert_eq!(part[x], want, "row {y}, x {x}");
        }
    }
}
