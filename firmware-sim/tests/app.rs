//! Host tests of the bench firmware's application with mock pins and delays.

use std::convert::Infallible;

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{ErrorType, OutputPin};
use firmware_sim::bench::{App, AppError, Buffers};
use firmware_sim::pg::conspicuity::{luv_len, row_scratch_len, EdgeCell, Luv};
use firmware_sim::pg::image::Rgb8;
use firmware_sim::{write_ipp, Camera, CameraError, CameraErrorKind, NoTicks, SimCamera};

const W: usize = 64;
const H: usize = 48;

#[derive(Default)]
struct MockPin {
    high: bool,
    rising_edges: u32,
}

impl ErrorType for MockPin {
    type Error = Infallible;
}

impl OutputPin for MockPin {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.high = false;
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.rising_edges += u32::from(!self.high);
        self.high = true;
        Ok(())
    }
}

#[derive(Default)]
struct MockDelay {
    total_ns: u64,
}

impl DelayNs for MockDelay {
    fn delay_ns(&mut self, ns: u32) {
        self.total_ns += u64::from(ns);
    }
}

struct Storage {
    rgb: Vec<Rgb8>,
    luv: Vec<Luv>,
    rows: Vec<Luv>,
    conspicuity: Vec<EdgeCell>,
}

impl Storage {
    fn new(w: usize, h: usize) -> Self {
        Self {
            rgb: vec![Rgb8::default(); w * h],
            luv: vec![Luv::default(); luv_len(w, h)],
            rows: vec![Luv::default(); row_scratch_len(w)],
            conspicuity: vec![EdgeCell::default(); luv_len(w, h)],
        }
    }
    fn bufs(&mut self) -> Buffers<'_> {
        Buffers {
            rgb: &mut self.rgb,
            luv: &mut self.luv,
            rows: &mut self.rows,
            conspicuity: &mut self.conspicuity,
        }
    }
}

fn checksum_with(camera: SimCamera) -> u32 {
    let mut storage = Storage::new(W, H);
    let mut app = App::new(camera, MockPin::default(), MockDelay::default());
    app.process(W, H, &mut storage.bufs(), &mut NoTicks)
        .expect("frame processes")
        .checksum
}

#[test]
fn sim_camera_is_deterministic() {
    let mut a = vec![Rgb8::default(); W * H];
    let mut b = vec![Rgb8 { r: 1, g: 2, b: 3 }; W * H];
    SimCamera::new().capture(&mut a, W, H).unwrap();
    let mut cam = SimCamera::new();
    cam.capture(&mut b, W, H).unwrap();
    assert_eq!(a, b);
    assert_eq!(cam.frames(), 1);
    assert!(a.iter().any(|p| *p != a[0]), "scene is not flat");
}

#[test]
fn checksum_is_stable_and_follows_the_image() {
    let base = checksum_with(SimCamera::new());
    assert_eq!(base, checksum_with(SimCamera::new()));
    assert_ne!(base, checksum_with(SimCamera::with_seed(0xDEAD_BEEF)));
}

#[test]
fn run_reports_blinks_and_delays() {
    let mut storage = Storage::new(W, H);
    let mut app = App::new(SimCamera::new(), MockPin::default(), MockDelay::default());
    let mut out = String::new();
    let sizes = [(32, 24), (W, H)];
    app.run(
        &sizes,
        &mut storage.bufs(),
        &mut NoTicks,
        &mut out,
        |_, _| Ok(()),
    )
    .unwrap();
    let lines: Vec<&str> = out.lines().filter(|l| l.starts_with("checksum ")).collect();
    assert_eq!(lines.len(), 2, "{out}");
    assert!(
        lines[1].starts_with("checksum 64x48 0x")
            && lines[1].len() == "checksum 64x48 0x".len() + 8
    );
    assert_eq!(app.camera().frames(), 2);
    let (_, led, delay) = app.release();
    assert_eq!(led.rising_edges, 2);
    assert!(!led.high, "LED is off between frames");
    assert_eq!(
        delay.total_ns,
        2 * u64::from(firmware_sim::bench::app::BLINK_MS) * 1_000_000
    );
}

#[test]
fn small_buffers_are_an_error_not_a_panic() {
    let mut storage = Storage::new(16, 16);
    let mut app = App::new(SimCamera::new(), MockPin::default(), MockDelay::default());
    let err = app
        .process(W, H, &mut storage.bufs(), &mut NoTicks)
        .unwrap_err();
    assert!(matches!(err, AppError::BufferTooSmall), "{err}");

    let mut tiny = vec![Rgb8::default(); 4];
    let cam_err = SimCamera::new().capture(&mut tiny, W, H).unwrap_err();
    assert_eq!(cam_err.kind(), CameraErrorKind::BufferTooSmall);
}

#[test]
fn ipp_has_one_decimal() {
    let mut s = String::new();
    write_ipp(
        &mut s,
        "conspicuity",
        160,
        120,
        160 * 120 * 183 + 160 * 120 / 4,
    )
    .unwrap();
    assert_eq!(s, "ipp conspicuity 160x120 183.3\n");
}
