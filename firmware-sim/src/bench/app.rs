//! The bench firmware's application: capture, conspicuity, checksum,
//! report, frame after frame.

use core::fmt::{self, Write};

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{self, OutputPin};

use crate::camera::Camera;
use crate::pg::checksum::Fnv1a;
use crate::pg::conspicuity::{self, ConspicuityError, EdgeCell, EdgeParams, Luv, LuvTables};
use crate::pg::image::{ImageError, ImageView, ImageViewMut, Rgb8};
use crate::Ticks;

/// Ticks spent in each step of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepTicks {
    /// Camera capture (scene rendering for [`crate::SimCamera`]).
    pub capture: u64,
    /// The core's edge-conspicuity stage: the sum of the four steps below.
    pub conspicuity: u64,
    /// sRGB to CIELUV.
    pub luv: u64,
    /// Copy plus the smoothing passes.
    pub smooth: u64,
    /// C~ and its maximum.
    pub cmap: u64,
    /// The 10 % threshold.
    pub threshold: u64,
    /// FNV-1a checksum over the output maps.
    pub checksum: u64,
}

/// Outcome of one processed frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameResult {
    /// Frame width in pixels.
    pub width: usize,
    /// Frame height in pixels.
    pub height: usize,
    /// FNV-1a 32 over the luv, smoothed and conspicuity maps.
    pub checksum: u32,
    /// Pixels at or above the edge threshold.
    pub on_count: u32,
    /// Ticks per step.
    pub ticks: StepTicks,
}

/// Feeds a Luv map's bits to `hash`, row-major, little endian.
fn hash_luv(hash: &mut Fnv1a, map: &ImageView<'_, Luv>) {
    map.pixels().for_each(|p| {
        p.to_bits()
            .iter()
            .for_each(|b| hash.write(&b.to_le_bytes()))
    });
}

/// Caller-owned working memory, sized for the largest frame to be processed.
pub struct Buffers<'a> {
    /// RGB frame, at least width * height pixels.
    pub rgb: &'a mut [Rgb8],
    /// Luv map, at least `luv_len(width, height)`; smoothed in place, so it
    /// holds the smoothed map after [`App::process`].
    pub luv: &'a mut [Luv],
    /// Row scratch, at least `row_scratch_len(width)`.
    pub rows: &'a mut [Luv],
    /// Conspicuity map, at least `luv_len(width, height)`.
    pub conspicuity: &'a mut [EdgeCell],
}

/// Why a frame could not be processed.
#[derive(Debug)]
pub enum AppError<E> {
    /// The camera failed.
    Camera(E),
    /// A buffer in [`Buffers`] is too small for the requested frame.
    BufferTooSmall,
    /// The frame buffer does not form a valid image.
    Image(ImageError),
    /// The conspicuity stage rejected its inputs.
    Conspicuity(ConspicuityError),
    /// The status LED pin failed.
    Pin(digital::ErrorKind),
    /// The report sink failed.
    Report,
}

impl<E: crate::CameraError> fmt::Display for AppError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Camera(e) => write!(f, "camera: {} ({:?})", e.kind(), e),
            Self::BufferTooSmall => f.write_str("working buffers too small for the frame size"),
            Self::Image(e) => write!(f, "invalid frame buffer: {e:?}"),
            Self::Conspicuity(e) => write!(f, "conspicuity stage: {e:?}"),
            Self::Pin(e) => write!(f, "status LED pin: {e:?}"),
            Self::Report => f.write_str("report sink failed"),
        }
    }
}

impl<E> From<fmt::Error> for AppError<E> {
    fn from(_: fmt::Error) -> Self {
        Self::Report
    }
}

/// LED on-time per frame and pause between frames, in milliseconds.
pub const BLINK_MS: u32 = 1;

/// The firmware application, generic over camera, status LED and delay.
pub struct App<C, P, D> {
    camera: C,
    led: P,
    delay: D,
    tables: LuvTables,
    params: EdgeParams,
}

fn pin_err<E>(e: impl digital::Error) -> AppError<E> {
    AppError::Pin(e.kind())
}

fn prefix<T>(buf: &mut [T], len: usize) -> Result<&mut [T], ()> {
    buf.get_mut(..len).ok_or(())
}

impl<C: Camera, P: OutputPin, D: DelayNs> App<C, P, D> {
    /// Builds the one-time tables (LUV) with default edge parameters.
    pub fn new(camera: C, led: P, delay: D) -> Self {
        Self {
            camera,
            led,
            delay,
            tables: LuvTables::new(),
            params: EdgeParams::default(),
        }
    }

    /// Captures and processes one `width` x `height` frame; the LED is on meanwhile.
    pub fn process<T: Ticks>(
        &mut self,
        width: usize,
        height: usize,
        bufs: &mut Buffers<'_>,
        ticks: &mut T,
    ) -> Result<FrameResult, AppError<C::Error>> {
        let n = conspicuity::luv_len(width, height);
        let too_small = |_| AppError::BufferTooSmall;
        let rgb = prefix(
            bufs.rgb,
            width.checked_mul(height).ok_or(AppError::BufferTooSmall)?,
        )
        .map_err(too_small)?;
        let luv = prefix(bufs.luv, n).map_err(too_small)?;
        let rows = prefix(bufs.rows, conspicuity::row_scratch_len(width)).map_err(too_small)?;
        let cmap = prefix(bufs.conspicuity, n).map_err(too_small)?;

        self.led.set_high().map_err(pin_err)?;
        let t0 = ticks.now();
        self.camera
            .capture(rgb, width, height)
            .map_err(AppError::Camera)?;
        let t1 = ticks.now();
        let view = ImageView::new(rgb, width, height, width).map_err(AppError::Image)?;
        // The stage's four steps, timed one by one (`edge_conspicuity` runs
        // the same calls; a core test checks they agree).
        let image_err = AppError::Image;
        let stage_err = AppError::Conspicuity;
        let mut luv_v = ImageViewMut::packed(luv, width, height).map_err(image_err)?;
        conspicuity::rgb_to_luv(&self.tables, &view, &mut luv_v).map_err(stage_err)?;
        let t_luv = ticks.now();
        // The checksum covers the Luv map, the smoothed map and C, in that
        // order (as `EdgeBuffers::checksum`); the Luv part is hashed now,
        // untimed, because smoothing then runs in place.
        let mut hash = Fnv1a::new();
        hash_luv(&mut hash, &luv_v.as_view());
        let t_hash = ticks.now();
        conspicuity::smooth(&self.params.smooth, &mut luv_v, rows).map_err(stage_err)?;
        let t_smooth = ticks.now();
        let mut c_v = ImageViewMut::packed(cmap, width, height).map_err(image_err)?;
        let max = conspicuity::conspicuity(&luv_v.as_view(), &mut c_v, rows).map_err(stage_err)?;
        let t_cmap = ticks.now();
        let on_count = conspicuity::threshold(&mut c_v, max, self.params.threshold_percent)
            .map_err(stage_err)?;
        let t2 = ticks.now();
        hash_luv(&mut hash, &luv_v.as_view());
        c_v.as_view()
            .pixels()
            .for_each(|c| hash.write(&c.raw().to_bits().to_le_bytes()));
        let checksum = hash.finish();
        let t3 = ticks.now();
        self.led.set_low().map_err(pin_err)?;

        let ticks = StepTicks {
            capture: t1 - t0,
            conspicuity: t2 - t1 - (t_hash - t_luv),
            luv: t_luv - t1,
            smooth: t_smooth - t_hash,
            cmap: t_cmap - t_smooth,
            threshold: t2 - t_cmap,
            checksum: t3 - t2 + (t_hash - t_luv),
        };
        Ok(FrameResult {
            width,
            height,
            checksum,
            on_count,
            ticks,
        })
    }

    /// Processes every size in `sizes`, writing the checksum lines to `out`.
    pub fn run<T: Ticks, W: Write>(
        &mut self,
        sizes: &[(usize, usize)],
        bufs: &mut Buffers<'_>,
        ticks: &mut T,
        out: &mut W,
        mut each: impl FnMut(&FrameResult, &mut W) -> fmt::Result,
    ) -> Result<(), AppError<C::Error>> {
        for &(w, h) in sizes {
            let r = self.process(w, h, bufs, ticks)?;
            write_checksum(out, &r)?;
            each(&r, out)?;
            self.delay.delay_ms(BLINK_MS);
        }
        Ok(())
    }

    /// Gives back the camera, LED pin and delay.
    pub fn release(self) -> (C, P, D) {
        (self.camera, self.led, self.delay)
    }

    /// The camera, e.g. to read its frame counter.
    pub fn camera(&self) -> &C {
        &self.camera
    }
}

/// `checksum WxH 0x........` and `edges WxH on=N`: the lines compared host vs QEMU.
pub fn write_checksum(out: &mut impl Write, r: &FrameResult) -> fmt::Result {
    writeln!(
        out,
        "checksum {}x{} 0x{:08x}",
        r.width, r.height, r.checksum
    )?;
    writeln!(out, "edges {}x{} on={}", r.width, r.height, r.on_count)
}
