//! `panic-probe`: every core stage with opaque inputs ([`firmware_sim::probe`]).
//!
//! Built for thumbv7em, it exists to be linked: `cargo xtask firmware`
//! requires its ELF, like the firmware's, to contain no panic function, so
//! no input can make a core stage panic. On the desktop it runs the stages
//! once on the demo scene at 96x64 (with the firmware's decoder tables and
//! the shipped model) and prints which of them succeeded.
#![cfg_attr(target_os = "none", no_std, no_main)]
#![deny(unsafe_code)]

use firmware_sim::pg::{complete, conspicuity, disparity, mlp, segment, stereo};
use firmware_sim::probe::{probe, ProbeBuffers};

/// Probe frame size: any size works, the probe hides it from the optimiser.
const W: usize = 96;
/// See [`W`].
const H: usize = 64;
const N: usize = W * H;
const LUV: usize = conspicuity::luv_len(W, H);
const ROWS: usize = conspicuity::row_scratch_len(W);
const C2F: stereo::c2f::C2fParams = firmware_sim::probe::C2F;
const LABELS: usize = segment::label_capacity(W, H);
const REGIONS: usize = complete::region_table_len(W, H);
/// The shipped model's shape: 720 inputs, 256 hidden, 19 classes
/// (`tests/panic_probe.rs` fails when the model outgrows these buffers).
const HIDDEN: usize = mlp::hidden_len(256);
const OUTPUT: usize = mlp::output_len(19);
const INPUT: usize = mlp::input_len(720);
const MIRROR_OUTPUTS: usize = mlp::mirror_outputs_len(19);

mod len {
    use super::*;
    use firmware_sim::pg::stereo::c2f as c;
    pub const C_GREY: usize = c::grey_len(W, &C2F);
    pub const C_RGB: usize = c::rgb_len(W, &C2F);
    pub const C_Z: usize = c::z_len(W, &C2F);
    pub const C_SCORES: usize = c::score_len(W, &C2F);
    pub const C_COSTS: usize = c::cost_len(W, &C2F);
    pub const C_SUMS: usize = c::sum_len(W, &C2F);
    pub const C_PICKS: usize = c::pick_len(W);
    pub const C_MAPS: usize = c::map_len(W, H, &C2F);
    const PHASE: stereo::phase::PhaseParams = stereo::phase::PhaseParams::DEFAULT;
    pub const P_RGB: usize = W;
    pub const P_V: usize = stereo::phase::v_len(W, &PHASE);
    pub const P_Z: usize = stereo::phase::z_len(W, &PHASE, C2F.dem.max_disp);
    pub const P_ROW: usize = W;
    pub const SEG_MAPS: usize = segment::maps_len(W, H);
    pub const SEG_TABLE: usize = segment::table_len(W, H);
}

/// The buffers, wherever they live, as the probe's slices.
macro_rules! buffers {
    ($alloc:ident) => {
        ProbeBuffers {
            rgb: [
                $alloc!(
                    firmware_sim::pg::image::Rgb8,
                    N,
                    firmware_sim::pg::image::Rgb8::new(0, 0, 0)
                ),
                $alloc!(
                    firmware_sim::pg::image::Rgb8,
                    N,
                    firmware_sim::pg::image::Rgb8::new(0, 0, 0)
                ),
            ],
            luv: [
                $alloc!(conspicuity::Luv, LUV, conspicuity::Luv::default()),
                $alloc!(conspicuity::Luv, LUV, conspicuity::Luv::default()),
                $alloc!(conspicuity::Luv, ROWS, conspicuity::Luv::default()),
            ],
            edges: $alloc!(conspicuity::EdgeCell, LUV, conspicuity::EdgeCell::OFF),
            disparity: $alloc!(disparity::DisparityCell, N, disparity::DisparityCell::OFF),
            c2f: stereo::c2f::C2fBuffers {
                grey: $alloc!(u16, len::C_GREY, 0u16),
                rgb: $alloc!(
                    firmware_sim::pg::image::Rgb8,
                    len::C_RGB,
                    firmware_sim::pg::image::Rgb8::new(0, 0, 0)
                ),
                z: $alloc!([i16; 2], len::C_Z, [0i16; 2]),
                col: $alloc!([i32; 3], W, [0i32; 3]),
                scores: $alloc!(i64, len::C_SCORES, 0i64),
                costs: $alloc!(u16, len::C_COSTS, 0u16),
                sums: $alloc!(u32, len::C_SUMS, 0u32),
                picks: $alloc!(i32, len::C_PICKS, 0i32),
                maps: $alloc!(u8, len::C_MAPS, 0u8),
                phase: stereo::phase::PhaseBuffers {
                    rgb: $alloc!(
                        firmware_sim::pg::image::Rgb8,
                        len::P_RGB,
                        firmware_sim::pg::image::Rgb8::new(0, 0, 0)
                    ),
                    v: $alloc!(i32, len::P_V, 0i32),
                    z: $alloc!([i16; 2], len::P_Z, [0i16; 2]),
                    row: $alloc!(
                        disparity::DisparityCell,
                        len::P_ROW,
                        disparity::DisparityCell::OFF
                    ),
                },
            },
            seg: [
                $alloc!(u32, len::SEG_MAPS, 0u32),
                $alloc!(u32, len::SEG_TABLE, 0u32),
            ],
            masks: [$alloc!(bool, N, false), $alloc!(bool, N, false)],
            labels: [$alloc!(u16, N, 0u16), $alloc!(u16, LABELS, 0u16)],
            counts: [
                $alloc!(u32, LABELS, 0u32),
                $alloc!(u32, REGIONS, 0u32),
                $alloc!(u32, REGIONS, 0u32),
            ],
            bounds: [$alloc!(u8, REGIONS, 0u8), $alloc!(u8, REGIONS, 0u8)],
            spans: $alloc!(
                firmware_sim::pg::complete::RowSpan,
                REGIONS,
                firmware_sim::pg::complete::RowSpan { first: 0, last: 0 }
            ),
            mask: $alloc!(u8, N, 0u8),
            mlp: mlp::Scratch {
                input: $alloc!(u32, INPUT, 0u32),
                hidden: $alloc!(u8, HIDDEN, 0u8),
                output: $alloc!(u16, OUTPUT, 0u16),
            },
            ranked: $alloc!(mlp::Ranked, 5, mlp::Ranked::default()),
            mirror: mlp::MirrorScratch {
                vector: $alloc!(
                    firmware_sim::pg::shape::ShapeElem,
                    720,
                    firmware_sim::pg::shape::ShapeElem::ZERO
                ),
                outputs: $alloc!(u16, MIRROR_OUTPUTS, 0u16),
                mean: $alloc!(u16, OUTPUT, 0u16),
            },
        }
    };
}

#[cfg(not(target_os = "none"))]
fn main() {
    use firmware_sim::pg::image::ImageViewMut;
    use firmware_sim::pg::synth::{render_left, render_right, SceneSpec};
    macro_rules! boxed {
        ($t:ty, $n:expr, $init:expr) => {
            Vec::<$t>::leak(vec![$init; $n])
        };
    }
    let mut b = buffers!(boxed);
    // The demo scene, so that the stages run their whole paths.
    let scene = SceneSpec::demo(W, H);
    let [left, right] = &mut b.rgb;
    let ok = ImageViewMut::packed(left, W, H)
        .map_err(|_| "left")
        .and_then(|mut l| render_left(&scene, &mut l).map_err(|_| "render"))
        .and(ImageViewMut::packed(right, W, H).map_err(|_| "right"))
        .and_then(|mut r| render_right(&scene, &mut r).map_err(|_| "render"));
    // A square object for the shape vector.
    for (i, m) in b.mask.iter_mut().enumerate() {
        let (x, y) = (i % W, i / W);
        *m = u8::from((30..60).contains(&x) && (20..50).contains(&y));
    }
    let bits = probe(
        b,
        W,
        H,
        firmware_sim::bench::stereo_run::TABLES,
        firmware_sim::bench::mlp_run::SHIPPED,
    );
    println!("panic-probe {W}x{H}: scene {ok:?}, stages ok {bits:#014b}");
}

#[cfg(target_os = "none")]
mod mcu {
    use super::*;
    use cortex_m::singleton;
    use cortex_m_rt::entry;
    use cortex_m_semihosting::debug;

    /// Stand-in table and model bytes: the probe hides their contents.
    static BYTES: [u8; 64] = [0; 64];

    #[entry]
    fn main() -> ! {
        macro_rules! fixed {
            ($t:ty, $n:expr, $init:expr) => {
                singleton!(: [$t; $n] = [$init; $n]).map_or(&mut [][..], |b| &mut b[..])
            };
        }
        let bits = probe(buffers!(fixed), W, H, [&BYTES; 3], &BYTES);
        debug::exit(if bits == u32::MAX {
            debug::EXIT_FAILURE
        } else {
            debug::EXIT_SUCCESS
        });
        loop {
            cortex_m::asm::wfi();
        }
    }

    /// Required by `no_std`, and never linked in (`cargo xtask firmware`).
    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo) -> ! {
        debug::exit(debug::EXIT_FAILURE);
        loop {
            cortex_m::asm::wfi();
        }
    }
}
