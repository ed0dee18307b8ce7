//! Command-line interface: argument parsing and the commands.
//!
//! ```text
//! protogist                                   # same as `protogist demo`
//! protogist demo [--out DIR] [--width W --height H]
//! protogist conspicuity --image FILE --out DIR [--width W]
//! protogist stereo --left L --right R [--gt GT --gt-scale S] [--width W]
//!                  [--max-disp D] [--pool R] [--levels L] [--table FILE] [--json] --out DIR
//! protogist train-dem --out FILE [--max-disp D --levels L]
//! protogist gen-shapes --out DIR [--classes N --per-class M --seed S --size PX]
//! protogist gen-rgbd --out DIR [--categories N --instances M --frames F --seed S]
//! protogist experiment --dataset DIR --out DIR [--hidden H --epochs E]
//!                      [--conditions LIST] [--json]
//! protogist train-speed [--inputs D --hidden H --classes N --rows R]
//! protogist train --dataset DIR --out model.json [--hidden H --epochs E]
//!                 [--test-fraction F --seed S --gamma G]
//! protogist eval --model model.json --dataset DIR --out DIR [--json]
//! ```

use crate::demo::{finish, run_demo, DemoOptions};
use crate::error::{HostError, Result};
use crate::io;
use crate::panels::{rgb_from, Panel};
use crate::reference::stereo::DemParams;
use crate::stages::run_conspicuity;
use crate::stereo_cmd::{run_stereo, run_train_dem, StereoOptions};
use crate::summary::Summary;
use clap::{Parser, Subcommand};
use protogist::conspicuity::{EdgeParams, LuvTables};
use std::path::PathBuf;
use std::time::Instant;

/// Proto-object detection for microcontroller camera boards: host tools.
#[derive(Debug, Parser)]
#[command(name = "protogist", version, about)]
pub struct Cli {
    /// What to run; without one, the demo runs with its defaults.
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run the built-in synthetic stereo scene through every stage and write
    /// PNG panels.
    Demo {
        /// Output directory (created if missing).
        #[arg(long, default_value = "protogist-out")]
        out: PathBuf,
        /// Frame width, px.
        #[arg(long, default_value_t = 160)]
        width: usize,
        /// Frame height, px.
        #[arg(long, default_value_t = 120)]
        height: usize,
    },
    /// Run the conspicuity stage on a PNG or JPEG and write its panels.
    Conspicuity {
        /// Input image (PNG or JPEG).
        #[arg(long)]
        image: PathBuf,
        /// Output directory (created if missing).
        #[arg(long)]
        out: PathBuf,
        /// Working width, px: wider inputs are area-averaged down to it,
        /// keeping the aspect ratio; narrower ones are kept as they are.
        #[arg(long, default_value_t = 160)]
        width: u32,
    },
    /// Run the disparity energy model (f32 reference) on a stereo pair;
    /// with ground truth, print bad-pixel rates and write an error map.
    Stereo(StereoOptions),
    /// Run the whole pipeline on a stereo pair: conspicuity, disparity,
    /// figure-ground, object masks and shape vectors; write the paper's
    /// Fig. 2 panels, shape plots and report.json.
    Run(crate::run_cmd::RunOptions),
    /// Train the DEM decoder on seeded random-dot stereograms and write its
    /// integer table (host/data/dem_default.bin is `--max-disp 15`).
    TrainDem {
        /// Output file.
        #[arg(long)]
        out: PathBuf,
        /// Largest disparity, px.
        #[arg(long, default_value_t = 15)]
        max_disp: u8,
        /// Pyramid levels of the model (1 for each level of the
        /// coarse-to-fine engine).
        #[arg(long, default_value_t = 2)]
        levels: u8,
    },
    /// Generate seeded binary silhouettes of parametric shapes (PNG, object
    /// white on black), one subfolder per class.
    GenShapes(crate::classify::shapes::GenShapesOptions),
    /// Render a synthetic stand-in for the RGB-D Object Dataset, in its
    /// cropped layout (RGB, 16-bit depth in mm, mask, location).
    GenRgbd(crate::rgbd::gen::GenRgbdOptions),
    /// The paper's experiment (sections 4.2 to 5) on an RGB-D Object Dataset
    /// folder: one network per input condition, float and int8; writes
    /// Table 1 (Markdown, JSON) and Fig. 8 (CMC, DET, ROC as PNG and SVG).
    Experiment(crate::rgbd::experiment::ExperimentOptions),
    /// Time one training epoch's products (forward and backward GEMMs) and
    /// print GFLOP/s and the projected time of the paper's training.
    TrainSpeed(crate::rgbd::speed::TrainSpeedOptions),
    /// Train the float network (section 4.4) on the shape vectors of an
    /// image-folder dataset; write the int8 model blob and its float JSON
    /// sidecar (`<out>.json`).
    Train(crate::classify::model_cmd::TrainOptions),
    /// Evaluate a trained model on its test split, float and int8 side by
    /// side: ROR, CMC, EER, HTER_min, AUC, verification rates; CMC, DET and
    /// ROC plots.
    Eval(crate::classify::model_cmd::EvalOptions),
    /// Quantise a float model to the int8 blob, or emit a blob as a Rust
    /// `static` for firmware (`--emit-rust`).
    Quantize(crate::classify::quant_cmd::QuantizeOptions),
    /// Print the core's working memory per stage and frame size, from its
    /// `const fn`s (`scratch <stage> <W>x<H> <bytes>` lines).
    Scratch,
    /// Mean mask IoU of segmentation on seeded synthetic scenes, with
    /// ground-truth disparity as input.
    SegmentEval {
        /// Number of scenes (seeds 0..N).
        #[arg(long, default_value_t = 24)]
        scenes: u64,
        /// Frame width, px.
        #[arg(long, default_value_t = 160)]
        width: usize,
        /// Frame height, px.
        #[arg(long, default_value_t = 120)]
        height: usize,
        /// Disparity input: ground truth or the disparity energy model.
        #[arg(long, value_enum, default_value = "gt")]
        disparity: crate::eval::DisparitySource,
    },
}

/// Runs the parsed command line; returns the summary to print.
///
/// # Errors
/// Whatever the command fails with, as a [`HostError`].
pub fn run(cli: Cli) -> Result<Summary> {
    match cli.command {
        None => run_demo(&DemoOptions::default()),
        Some(Command::Demo { out, width, height }) => run_demo(&DemoOptions { out, width, height }),
        Some(Command::Conspicuity { image, out, width }) => {
            run_image(&ImageOptions { image, out, width })
        }
        Some(Command::Stereo(opts)) => run_stereo(&opts),
        Some(Command::Run(opts)) => crate::run_cmd::run_pipeline(&opts),
        Some(Command::TrainDem {
            out,
            max_disp,
            levels,
        }) => run_train_dem(
            &DemParams {
                max_disp,
                levels,
                ..DemParams::default()
            },
            &out,
        ),
        Some(Command::GenShapes(opts)) => crate::classify::shapes::gen_shapes(&opts),
        Some(Command::GenRgbd(opts)) => crate::rgbd::gen::gen_rgbd(&opts),
        Some(Command::Experiment(opts)) => crate::rgbd::experiment::run_experiment(&opts),
        Some(Command::TrainSpeed(opts)) => crate::rgbd::speed::run_train_speed(&opts),
        Some(Command::Train(opts)) => crate::classify::model_cmd::run_train(&opts),
        Some(Command::Eval(opts)) => crate::classify::model_cmd::run_eval(&opts),
        Some(Command::Quantize(opts)) => crate::classify::quant_cmd::run_quantize(&opts),
        Some(Command::Scratch) => Ok(scratch_summary()),
        Some(Command::SegmentEval {
            scenes,
            width,
            height,
            disparity,
        }) => segment_eval_summary(scenes, width, height, disparity),
    }
}

/// Options of `protogist conspicuity`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImageOptions {
    /// Input PNG or JPEG.
    pub image: PathBuf,
    /// Output directory.
    pub out: PathBuf,
    /// Working width (never upscaled to).
    pub width: u32,
}

/// Loads an image, brings it to the working width, runs the conspicuity
/// stage and writes `input`, its panels and `overview` into the output
/// directory.
///
/// # Errors
/// [`HostError`] for a zero width, an unreadable or
/// corrupt image, a size the core rejects, or an unwritable directory.
pub fn run_image(opts: &ImageOptions) -> Result<Summary> {
    let start = Instant::now();
    // Check the width before touching the file, so `--width 0` is reported
    // as such whatever the input.
    if opts.width == 0 {
        return Err(HostError::ZeroDimension { name: "width" });
    }
    let original = io::load_rgb(&opts.image)?;
    let (ow, oh) = original.dimensions();
    let (w, h) = io::working_size(ow, oh, opts.width)?;
    let img = if (w, h) == (ow, oh) {
        original
    } else {
        io::area_downscale(&original, w, h)
    };
    let (w, h) = (w as usize, h as usize);
    let px = io::to_core_rgb(&img);

    let mut summary = Summary::new(format!("protogist conspicuity: {}", opts.image.display()));
    summary.push("input", format!("{ow}x{oh}"));
    summary.push("working size", format!("{w}x{h}"));
    let maps = run_conspicuity(&LuvTables::new(), &EdgeParams::default(), &px, w, h)?;
    let mut out = vec![Panel::new("input", rgb_from(&px, w, h))];
    out.extend(maps.panels());
    maps.summarise(&mut summary);

    finish(&opts.out, out, &mut summary, start)?;
    Ok(summary)
}

/// Frame sizes the `scratch` command reports.
pub const SCRATCH_SIZES: [(usize, usize); 2] = [(160, 120), (320, 240)];

/// `protogist scratch`: core working memory from the stages' `const fn`s.
pub fn scratch_summary() -> Summary {
    let mut s = Summary::new("protogist scratch: core working memory, bytes");
    for (w, h) in SCRATCH_SIZES {
        s.push(
            format!("scratch conspicuity {w}x{h}"),
            protogist::conspicuity::scratch_bytes(w, h),
        );
        s.push(
            format!("scratch complete {w}x{h}"),
            protogist::complete::scratch_bytes(w, h, protogist::complete::DEFAULT_REGION_CAPACITY),
        );
        s.push(
            format!("scratch segment {w}x{h}"),
            protogist::segment::scratch_bytes(w, h),
        );
    }
    s
}

/// `protogist segment-eval`: one line per scene and the mean IoU.
///
/// # Errors
/// A stage's typed error for a bad size.
pub fn segment_eval_summary(
    scenes: u64,
    width: usize,
    height: usize,
    source: crate::eval::DisparitySource,
) -> Result<Summary> {
    if scenes == 0 {
        return Err(HostError::ZeroDimension { name: "scenes" });
    }
    let results = crate::eval::segment_eval(scenes, width, height, source)?;
    let mut s = Summary::new(format!(
        "protogist segment-eval: {scenes} seeded scenes at {width}x{height}, disparity {source:?}"
    ));
    for r in &results {
        s.push(
            format!("scene {}", r.seed),
            format!("IoU {:.3} ({} objects)", r.iou, r.objects),
        );
    }
    let mean = results.iter().map(|r| r.iou).sum::<f64>() / results.len() as f64;
    s.push("mean IoU", format!("{mean:.3}"));
    Ok(s)
}
