//! `protogist train-speed`: GFLOP/s of one training step's products (the
//! forward and backward GEMMs of [`Mlp::gradient_blocked`]) on random data,
//! and the projected time of the paper's training (34,921 images, 1000
//! Rprop epochs) at that rate. The products run on `ndarray`'s
//! `matrixmultiply` GEMM, threaded (`matrixmultiply-threading`), in f64.

use crate::classify::mlp::{unit, Mlp, SplitMix, BLOCK_ROWS, GAMMA};
use crate::error::{HostError, Result};
use crate::summary::Summary;
use ndarray::Array2;
use std::time::Instant;

/// The paper's training images.
pub const PAPER_TRAIN: usize = 34_921;

/// Options of `protogist train-speed`.
#[derive(Clone, Debug, PartialEq, Eq, clap::Args)]
pub struct TrainSpeedOptions {
    /// Inputs (11,520: shape + range + conspicuity + luminance).
    #[arg(long, default_value_t = 11_520)]
    pub inputs: usize,
    /// Hidden units.
    #[arg(long, default_value_t = 2000)]
    pub hidden: usize,
    /// Classes.
    #[arg(long, default_value_t = 51)]
    pub classes: usize,
    /// Rows timed (one block of the blocked gradient by default).
    #[arg(long, default_value_t = BLOCK_ROWS)]
    pub rows: usize,
    /// Repetitions (the best is kept).
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
}

/// `(GFLOP/s, seconds per gradient)` of the blocked gradient on random
/// data of the given size.
pub fn measure(
    inputs: usize,
    hidden: usize,
    classes: usize,
    rows: usize,
    repeat: usize,
) -> (f64, f64) {
    let net = Mlp::new(inputs, hidden, classes, 1);
    let mut rng = SplitMix::new(2);
    let x = Array2::from_shape_simple_fn((rows, inputs), || unit(&mut rng) - 0.5);
    let t = Array2::from_shape_fn((rows, classes), |(r, c)| {
        f64::from(u8::from(r % classes == c))
    });
    let mut best = f64::INFINITY;
    for _ in 0..repeat.max(1) {
        let start = Instant::now();
        std::hint::black_box(net.gradient_blocked(x.view(), t.view(), GAMMA, BLOCK_ROWS));
        best = best.min(start.elapsed().as_secs_f64());
    }
    (net.gradient_flops(rows) / best / 1e9, best)
}

/// `protogist train-speed`.
///
/// # Errors
/// [`HostError::ZeroDimension`] for a zero size.
pub fn run_train_speed(o: &TrainSpeedOptions) -> Result<Summary> {
    for (name, v) in [
        ("inputs", o.inputs),
        ("hidden", o.hidden),
        ("classes", o.classes),
        ("rows", o.rows),
    ] {
        if v == 0 {
            return Err(HostError::ZeroDimension { name });
        }
    }
    let (gflops, secs) = measure(o.inputs, o.hidden, o.classes, o.rows, o.repeat);
    let epoch_flops = (4.0 * o.inputs as f64 * o.hidden as f64
        + 6.0 * o.hidden as f64 * o.classes as f64)
        * PAPER_TRAIN as f64;
    let epoch_s = epoch_flops / (gflops * 1e9);
    let mut s = Summary::new(format!(
        "protogist train-speed: {}-{}-{} network, {} rows, f64, {} threads",
        o.inputs,
        o.hidden,
        o.classes,
        o.rows,
        rayon::current_num_threads()
    ));
    s.push(
        "gradient",
        format!("{:.3} s ({:.2} GFLOP)", secs, gflops * secs),
    );
    s.push("throughput", format!("{gflops:.1} GFLOP/s"));
    s.push(
        "paper epoch",
        format!(
            "{:.2} TFLOP over {PAPER_TRAIN} images: {epoch_s:.0} s",
            epoch_flops / 1e12
        ),
    );
    s.push(
        "paper training",
        format!("1000 epochs: {:.1} h", 1000.0 * epoch_s / 3600.0),
    );
    Ok(s)
}
