//! Command-line interface: argument parsing and the commands.
//!
//! ```text
//! protogist                                   # same as `protogist demo`
//! protogist demo [--out DIR] [--width W --height H]
//! protogist conspicuity --image FILE --out DIR [--width W]
//! protogist stereo --left L --right R [--gt GT --gt-scale S] [--width W]
//!                  [--max-disp D] [--pool R] [--levels L] [--table FILE] [--json] --out DIR
//! protogist train-dem --out FILE [--max-disp D --levels L --radius R]
//! protogist gen-shapes --out DIR [--classes N --per-class M --seed S --size PX]
//! protogist gen-rgbd --out DIR [--categories N --instances M --frames F --seed S]
//! protogist experiment --dataset DIR --out DIR [--hidden H --epochs E]
//!                      [--conditions LIST] [--json]
//! protogist train-speed [--inputs D --hidden H --classes N --rows R]
//! protogist train --dataset DIR --out model.json [--hidden H --epochs E]
//!                 [--through-pipeline --views N --with-clean]
//!                 [--mirror-images] [--test-fraction F --seed S --gamma G]
//! protogist eval --model model.json --dataset DIR --out DIR [--json]
//! protogist gen-scenes --out DIR [--scenes N --seed S --split test|train]
//!                      [--width W --height H --objects LO..HI --classes N]
//! protogist gist-eval --scenes DIR --model M [--objects K]
//!                     [--mode reference|gt-disparity] [--json] --out DIR
//! ```

use crate::demo::{run_demo, DemoOptions};
use crate::error::{HostError, Result};
use crate::io;
use crate::output::finish;
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
    /// Memory a run may plan to use, MiB (default 4096): a run that would
    /// need more is refused before it starts (docs/CLI.md, `limits`).
    #[arg(long, global = true, value_name = "MIB")]
    pub max_memory: Option<u64>,
    /// Decode a truncated or corrupt JPEG anyway, with a warning (the
    /// missing part comes out grey); by default it is an error.
    #[arg(long, global = true)]
    pub accept_damaged: bool,
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
        /// Gabor kernel radius, px (7: the design's ⌈3σ⌉; 2: the
        /// pipeline's `half-narrow` point).
        #[arg(long, default_value_t = 7)]
        radius: u8,
    },
    /// Generate seeded binary silhouettes of parametric shapes (PNG, object
    /// white on black), one subfolder per class.
    GenShapes(crate::classify::shapes::GenShapesOptions),
    /// Generate seeded stereo scenes of 1 to 4 `gen-shapes` objects on
    /// textured backgrounds, with ground truth (views, disparity PFM,
    /// masks, truth.json, index.json).
    GenScenes(crate::scenes::GenScenesOptions),
    /// The end-to-end benchmark on a `gen-scenes` set: detection recall and
    /// precision, mask IoU, top-1/top-5 category and gist accuracy, time.
    GistEval(crate::gist::GistEvalOptions),
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
    Train(crate::classify::model_cmd::TrainCommand),
    /// Evaluate a trained model on its test split, float and int8 side by
    /// side: ROR, CMC, EER, HTER_min, AUC, verification rates; CMC, DET and
    /// ROC plots.
    Eval(crate::classify::model_cmd::EvalOptions),
    /// Quantise a float model to the int8 blob, or emit a blob as a Rust
    /// `static` for firmware (`--emit-rust`).
    Quantize(crate::classify::quant_cmd::QuantizeOptions),
    /// Add per-class symmetry (the mirrors a class looks the same under,
    /// for the mirror check) to an existing model blob, derived as `train`
    /// derives it from the clean held-out silhouettes.
    ModelSymmetry(crate::classify::symmetry_cmd::ModelSymmetryOptions),
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

/// Parses a command line (`args` with the program name first), then checks
/// every float flag of every command in one place: a NaN or infinite value
/// (`nan`, `inf`, or `1e39` for an `f32`) is a usage error, as a malformed
/// number is. Each flag's range (such as `--gamma` in `(0, 1]`) is then its
/// command's to check.
///
/// # Errors
/// clap's error for bad arguments, `--help` and `--version`.
pub fn parse_args<I, T>(args: I) -> std::result::Result<Cli, clap::Error>
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    use clap::{CommandFactory, FromArgMatches};
    let mut cmd = Cli::command();
    let matches = cmd.try_get_matches_from_mut(args)?;
    check_float_flags(&mut cmd, &matches)?;
    Cli::from_arg_matches(&matches)
}

/// [`parse_args`]' check, over `matches` and its subcommands.
fn check_float_flags(
    cmd: &mut clap::Command,
    matches: &clap::ArgMatches,
) -> std::result::Result<(), clap::Error> {
    use std::any::TypeId;
    let mut bad = None;
    for arg in cmd.get_arguments() {
        let id = arg.get_id().as_str();
        let ty = arg.get_value_parser().type_id();
        let values: Vec<f64> = if ty == TypeId::of::<f32>() {
            matches
                .get_many::<f32>(id)
                .map(|v| v.map(|&x| f64::from(x)).collect())
                .unwrap_or_default()
        } else if ty == TypeId::of::<f64>() {
            matches
                .get_many::<f64>(id)
                .map(|v| v.copied().collect())
                .unwrap_or_default()
        } else {
            continue;
        };
        if let Some(v) = values.iter().find(|v| !v.is_finite()) {
            let name = arg.get_long().unwrap_or(id).to_string();
            bad = Some(format!(
                "invalid value '{v}' for '--{name}': not a finite number"
            ));
            break;
        }
    }
    if let Some(msg) = bad {
        return Err(cmd.error(clap::error::ErrorKind::ValueValidation, msg));
    }
    if let Some((name, sub)) = matches.subcommand() {
        if let Some(c) = cmd.find_subcommand_mut(name) {
            check_float_flags(c, sub)?;
        }
    }
    Ok(())
}

/// Runs the parsed command line; returns the summary to print.
///
/// # Errors
/// Whatever the command fails with, as a [`HostError`].
pub fn run(cli: Cli) -> Result<Summary> {
    io::set_accept_damaged(cli.accept_damaged);
    if let Some(cmd) = &cli.command {
        preflight(cmd, crate::limits::limit_bytes(cli.max_memory))?;
    }
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
            radius,
        }) => run_train_dem(
            &DemParams {
                max_disp,
                levels,
                radius,
                ..DemParams::default()
            },
            &out,
        ),
        Some(Command::GenShapes(opts)) => crate::classify::shapes::gen_shapes(&opts),
        Some(Command::GenScenes(opts)) => crate::scenes::gen_scenes(&opts),
        Some(Command::GistEval(opts)) => crate::gist::gist_eval(&opts),
        Some(Command::GenRgbd(opts)) => crate::rgbd::gen::gen_rgbd(&opts),
        Some(Command::Experiment(opts)) => crate::rgbd::experiment::run_experiment(&opts),
        Some(Command::TrainSpeed(opts)) => crate::rgbd::speed::run_train_speed(&opts),
        Some(Command::Train(opts)) => {
            crate::classify::model_cmd::run_train_with(&opts.train, &opts.pipeline)
        }
        Some(Command::Eval(opts)) => crate::classify::model_cmd::run_eval(&opts),
        Some(Command::Quantize(opts)) => crate::classify::quant_cmd::run_quantize(&opts),
        Some(Command::ModelSymmetry(opts)) => {
            crate::classify::symmetry_cmd::run_model_symmetry(&opts)
        }
        Some(Command::Scratch) => Ok(scratch_summary()),
        Some(Command::SegmentEval {
            scenes,
            width,
            height,
            disparity,
        }) => segment_eval_summary(scenes, width, height, disparity),
    }
}

/// Checks sizes, parameters and memory before a command starts
/// ([`crate::limits`]): nothing is allocated or trained for a run that
/// cannot finish.
///
/// # Errors
/// The first failed check's typed error.
pub fn preflight(cmd: &Command, limit: u64) -> Result<()> {
    use crate::limits as l;
    let frame = |w: usize, h: usize, what: &str| {
        l::check_frame(w, h)?;
        l::check_memory(what, l::core_frame_bytes(w, h), limit)
    };
    match cmd {
        Command::Demo { width, height, .. } => frame(*width, *height, "the demo"),
        Command::Conspicuity { image, width, .. } if *width > 0 => {
            let (w, h) = l::working_size_of(image, *width)?;
            frame(w, h, "conspicuity")
        }
        Command::Stereo(opts) if opts.width > 0 => {
            let (w, h) = l::working_size_of(&opts.left, opts.width)?;
            let point = protogist::stereo::c2f::C2fParams::from_name(&opts.point);
            match (&opts.engine, point) {
                (crate::stereo_cmd::Engine::Reference, Some(p)) => {
                    let mut dem = crate::dem_tables::params_of(&p);
                    dem.max_disp = opts.max_disp;
                    l::check_stereo(&dem, w, h, limit)
                }
                _ => frame(w, h, "the stereo engine"),
            }
        }
        Command::Run(opts) if opts.width > 0 => {
            let (w, h) = l::working_size_of(&opts.left, opts.width)?;
            l::check_frame(w, h)?;
            let params =
                crate::product::preset(&opts.preset)?.with_objects(opts.objects.clamp(1, 8));
            let workspace = protogist::pipeline::workspace_bytes(w, h, &params) as u64;
            l::check_memory(
                "the pipeline",
                l::core_frame_bytes(w, h).saturating_add(workspace),
                limit,
            )?;
            if opts.gt_disparity.is_some() || opts.reference {
                let params = DemParams {
                    max_disp: opts
                        .max_disp
                        .unwrap_or_else(|| crate::product::default_max_disp(w)),
                    ..DemParams::default()
                };
                l::check_stereo(&params, w, h, limit)?;
            }
            Ok(())
        }
        Command::SegmentEval { width, height, .. } => frame(*width, *height, "segment-eval"),
        Command::Train(cmd) => {
            let opts = &cmd.train;
            l::check_hidden(opts.hidden)?;
            let (classes, images) = crate::classify::dataset::count_images(&opts.dataset)?;
            // Through the pipeline: up to `views` masks per image, and the
            // clean ones.
            let images = if cmd.pipeline.through_pipeline {
                images.saturating_mul(cmd.pipeline.views.saturating_add(1))
            } else {
                images
            };
            l::check_memory(
                &format!(
                    "training a {}-{}-{classes} network on up to {images} images",
                    protogist::shape::SHAPE_LEN,
                    opts.hidden
                ),
                l::train_bytes(protogist::shape::SHAPE_LEN, opts.hidden, classes, images),
                limit,
            )
        }
        _ => Ok(()),
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
    crate::limits::check_frame(width, height)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;
    use std::any::TypeId;

    /// Every float flag of every command, found by walking the parser, with
    /// the arguments its command requires.
    fn float_flags() -> Vec<(String, String, Vec<String>)> {
        let mut out = Vec::new();
        for sub in Cli::command().get_subcommands() {
            let required: Vec<String> = sub
                .get_arguments()
                .filter(|a| a.is_required_set())
                .flat_map(|a| [format!("--{}", a.get_long().unwrap()), "x".into()])
                .collect();
            for a in sub.get_arguments() {
                let ty = a.get_value_parser().type_id();
                if ty == TypeId::of::<f32>() || ty == TypeId::of::<f64>() {
                    let name = a.get_long().unwrap().to_string();
                    out.push((sub.get_name().to_string(), name, required.clone()));
                }
            }
        }
        out
    }

    #[test]
    fn every_float_flag_of_every_command_rejects_nan_and_infinity() {
        let flags = float_flags();
        // The walk finds the flags the issue named, among the others.
        for name in ["gamma", "test-fraction", "gt-scale"] {
            assert!(flags.iter().any(|(_, n, _)| n == name), "{name}: {flags:?}");
        }
        for (sub, name, required) in &flags {
            for bad in ["nan", "NaN", "inf", "-inf", "1e39"] {
                let mut argv = vec!["protogist".to_string(), sub.clone()];
                argv.extend(required.iter().cloned());
                argv.push(format!("--{name}={bad}"));
                let err = match parse_args(&argv) {
                    // 1e39 is finite as an f64.
                    Ok(_) if bad == "1e39" => continue,
                    Ok(_) => panic!("{argv:?} accepted"),
                    Err(e) => e,
                };
                assert_eq!(
                    err.kind(),
                    clap::error::ErrorKind::ValueValidation,
                    "{argv:?}: {err}"
                );
                assert!(err.to_string().contains(&format!("--{name}")), "{err}");
            }
            let mut argv = vec!["protogist".to_string(), sub.clone()];
            argv.extend(required.iter().cloned());
            argv.extend([format!("--{name}"), "0.5".into()]);
            assert!(parse_args(&argv).is_ok(), "{argv:?}");
        }
    }
}
