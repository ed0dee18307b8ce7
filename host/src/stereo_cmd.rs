//! `protogist stereo` and `protogist train-dem`: the DEM reference on a
//! stereo pair, with optional ground truth, and the decoder table.

use crate::demo::finish;
use crate::error::{HostError, Result};
use crate::ground_truth::{gt_at, load_gt, metrics, GtMap, Metrics};
use crate::io;
use crate::panels::{rgb_from, Panel};
use crate::reference::stereo::table::{DemTable, DEFAULT_TABLE};
use crate::reference::stereo::{self as dem, Decoder, DemParams, StereoError};
use crate::summary::Summary;
use image::{Rgb, RgbImage};
use protogist::disparity::DisparityCell;
use protogist::image::ImageView;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub mod engine;
pub mod preset;
pub use engine::Engine;
pub use preset::Preset;

/// Options of `protogist stereo`.
#[derive(Clone, Debug, PartialEq, clap::Args)]
pub struct StereoOptions {
    /// Left image (PNG or JPEG).
    #[arg(long)]
    pub left: PathBuf,
    /// Right image, the same size as the left.
    #[arg(long)]
    pub right: PathBuf,
    /// Ground-truth disparity of the left view at the input size: a
    /// grey PNG (0 = unknown) or a Middlebury PFM (inf = unknown).
    #[arg(long)]
    pub gt: Option<PathBuf>,
    /// PNG ground-truth values per pixel of disparity.
    #[arg(long, default_value_t = 1.0)]
    pub gt_scale: f32,
    /// Working width, px (area-averaged down, aspect kept).
    #[arg(long, default_value_t = 160)]
    pub width: u32,
    /// Largest disparity searched, px of the working size.
    #[arg(long, default_value_t = 15)]
    pub max_disp: u8,
    /// Score pooling radius, px (default: the model's, 2).
    #[arg(long)]
    pub pool: Option<u8>,
    /// Pyramid levels (default: the model's, 2: λ 4 and 8).
    #[arg(long)]
    pub levels: Option<u8>,
    /// Decoder table (default: built in for max-disp 15, else trained).
    #[arg(long)]
    pub table: Option<PathBuf>,
    /// Border refinement radius, px (default: the model's; 0 disables).
    #[arg(long)]
    pub refine: Option<u8>,
    /// Input channels of the DEM (experiment): grey (the default), or
    /// energies summed over R, G, B or over CIELUV L*, u*, v*
    /// (docs/STEREO.md).
    #[arg(long, value_enum)]
    pub colour: Option<dem::Colour>,
    /// With `--colour luv`: weight of u*, v* against L* (default 1; 0: L*
    /// only).
    #[arg(long)]
    pub chroma_weight: Option<f32>,
    /// Complete the map over the conspicuity regions of the left view
    /// (`protogist::complete`, the pipeline's border step); the metrics
    /// then score the completed map, and `model` the map before it.
    #[arg(long)]
    pub complete: bool,
    /// Read-out options: aggregation and OFF thresholds.
    #[command(flatten)]
    pub readout: ReadoutOptions,
    /// Print the numbers as JSON.
    #[arg(long)]
    pub json: bool,
    /// With `--engine core`: time the engine's runs until both 15 runs and
    /// this many ms have passed; the time reported is the fastest run.
    /// `cargo xtask bench` uses 1000, so that a burst of load on a shared
    /// machine cannot set the figure.
    #[arg(long, default_value_t = 0, value_name = "MS")]
    pub time_at_least: u32,
    /// Output directory (created if missing).
    #[arg(long)]
    pub out: PathBuf,
}

/// Read-out options of `protogist stereo`: the engine, a named preset,
/// semi-global aggregation and the OFF thresholds (all default to the
/// model's).
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct ReadoutOptions {
    /// Implementation: `reference` (f32, every option) or `core` (the
    /// fixed-point coarse-to-fine engine, single thread). `core` runs
    /// `--levels 1 --pool 0 --sgm --paths 5`, grey, `--refine 0`, and these
    /// are its defaults, so `--engine core --c2f 2` alone is valid; it
    /// needs `--c2f 1..=3`, and any other value, `--preset`, `--table`,
    /// `--colour` other than grey or `--complete` is an error.
    #[arg(long, value_enum, default_value_t = Engine::Reference)]
    pub engine: Engine,
    /// Named settings (f32 reference; options given explicitly override
    /// them): `held-out`, chosen on the Middlebury Motorcycle pair
    /// (docs/STEREO.md, "Settings chosen on a held-out pair").
    #[arg(long, value_enum)]
    pub preset: Option<Preset>,
    /// Semi-global aggregation of the read-out's costs after the box
    /// pooling (an experiment, docs/STEREO.md; `--pool 0` for none).
    #[arg(long)]
    pub sgm: bool,
    /// SGM penalty for a 1 px step, in units of a pixel's mean cost gap
    /// (default 0.25).
    #[arg(long)]
    pub p1: Option<f32>,
    /// SGM penalty for a larger step, in the same units (default 16).
    #[arg(long)]
    pub p2: Option<f32>,
    /// SGM path set: 3, 4, 5 (one top-to-bottom pass, the default) or 8.
    #[arg(long)]
    pub paths: Option<u8>,
    /// Scale P2 with the working width: P2 · width / this (default: off).
    #[arg(long)]
    pub p2_ref_width: Option<u32>,
    /// Ambiguity threshold (default: the model's, 0); with `--sgm`, per
    /// path in units of a pixel's mean cost gap.
    #[arg(long)]
    pub min_margin: Option<f32>,
    /// Left-right tolerance, px (default: the model's, 1; negative: off).
    #[arg(long, allow_negative_numbers = true)]
    pub lr: Option<f32>,
    /// Left-right check against a right map derived from the left map's
    /// SGM sums, as SGBM does, instead of the right-referenced read-out
    /// (both engines; needs --sgm; the engine then skips the right eye).
    #[arg(long)]
    pub lr_from_left: bool,
    /// Coarse-to-fine (an experiment, docs/STEREO.md): halve the pair this
    /// many times, search every candidate on the coarsest level and only
    /// `2·d ± --c2f-radius` on each finer one (default 0: off).
    #[arg(long)]
    pub c2f: Option<u8>,
    /// Half width of the fine windows of `--c2f`, px of the finer level
    /// (default 2).
    #[arg(long)]
    pub c2f_radius: Option<u8>,
    /// With `--c2f`: decode a fine pixel only from the groups whose shift
    /// is within this many px of its window's centre (default: every group).
    #[arg(long)]
    pub c2f_band: Option<u8>,
    /// With `--c2f`: stop at this level (1..=--c2f; default 0, the full
    /// size) and spread its map over the frame, each pixel over its
    /// 2^k x 2^k block with its disparity times 2^k: about 4^k times fewer
    /// operations for a coarser map (docs/STEREO.md "Finest level").
    #[arg(long)]
    pub c2f_finest: Option<u8>,
    /// With `--c2f`: refine the map with the phase of the frame's own 0°
    /// Gabor responses (λ 4, σ/λ 0.4, radius 2, 3 px pooling): each pixel
    /// keeps the position shift round(d) and takes the remainder from the
    /// phase difference between the eyes; with `--c2f-finest 1`, a map of
    /// the frame's resolution (docs/STEREO.md "Phase refinement").
    #[arg(long)]
    pub c2f_phase: bool,
    /// Speckle filter (both engines, after the read-out; docs/STEREO.md
    /// "Third round"): pixels in an island of at most this many pixels go
    /// OFF (default 0: off).
    #[arg(long)]
    pub speckle: Option<u32>,
    /// With `--speckle`: 4-neighbours join an island when their
    /// disparities differ by at most this, px (default 1).
    #[arg(long, allow_negative_numbers = true)]
    pub speckle_range: Option<f32>,
}

/// `--p1` default (docs/STEREO.md, semi-global aggregation).
pub const SGM_P1: f32 = 0.25;
/// `--p2` default.
pub const SGM_P2: f32 = 16.0;
/// `--paths` default.
pub const SGM_PATHS: u8 = 5;

/// The decoder for `params`: `table` if given (it must match), else the
/// built-in default table when it matches, else trained now. A trained
/// decoder goes through the integer table, so every path decodes with the
/// weights core will hold.
///
/// # Errors
/// [`HostError::Io`], [`HostError::Table`] for a bad table,
/// [`HostError::Stereo`] when it was trained for other parameters.
pub fn decoder_for(params: &DemParams, table: Option<&Path>) -> Result<Decoder> {
    Ok(table_for(params, table)?.to_decoder())
}

/// The integer table behind [`decoder_for`] (the same choice and checks):
/// what core's engines parse.
///
/// # Errors
/// As [`decoder_for`].
pub fn table_for(params: &DemParams, table: Option<&Path>) -> Result<DemTable> {
    let parse = |bytes: &[u8], path: &Path| {
        DemTable::parse(bytes).map_err(|source| HostError::Table {
            path: path.to_path_buf(),
            source,
        })
    };
    let t = match table {
        Some(path) => parse(
            &std::fs::read(path).map_err(|e| HostError::io(path, e))?,
            path,
        )?,
        None => match DemTable::parse(DEFAULT_TABLE) {
            Ok(t) if t.layout == dem::layout_of(params) => t,
            _ => DemTable::from_decoder(&dem::train(params)),
        },
    };
    if t.layout != dem::layout_of(params) {
        return Err(StereoError::DecoderMismatch {
            got: t.layout.max_disp,
            expected: params.max_disp,
        }
        .into());
    }
    Ok(t)
}

/// `protogist train-dem`: trains for `params` and writes the table.
///
/// # Errors
/// [`HostError::Stereo`] for bad parameters, [`HostError::Io`].
pub fn run_train_dem(params: &DemParams, out: &Path) -> Result<Summary> {
    params.check()?;
    let start = Instant::now();
    let table = DemTable::from_decoder(&dem::train(params));
    let bytes = table.to_bytes();
    crate::output::write_atomic(out, &bytes)?;
    let mut s = Summary::new(format!("protogist train-dem: {}", out.display()));
    s.push("max disparity", params.max_disp);
    s.push("groups", table.layout.groups());
    s.push(
        "weights",
        format!("Q{}.{} i16", 15 - table.weight_frac, table.weight_frac),
    );
    s.push("bytes", bytes.len());
    s.push("train seed", format!("{:#x}", params.train_seed));
    s.push(
        "total time",
        format!("{:.1} ms", start.elapsed().as_secs_f64() * 1e3),
    );
    Ok(s)
}

/// Disparity colour-mapped with turbo over `0..=max`, OFF black.
pub fn disparity_panel(d: &[Option<f32>], w: usize, h: usize, max: f32) -> RgbImage {
    RgbImage::from_fn(w as u32, h as u32, |x, y| {
        match d[y as usize * w + x as usize] {
            Some(v) => {
                let c =
                    colorous::TURBO.eval_continuous(f64::from((v / max.max(1.0)).clamp(0.0, 1.0)));
                Rgb([c.r, c.g, c.b])
            }
            None => Rgb([0, 0, 0]),
        }
    })
}

/// Error map: black no GT, blue no estimate, green ≤ 1 px, yellow ≤ 2,
/// orange ≤ 4, red above.
pub fn error_panel(est: &[Option<f32>], gt: &GtMap) -> RgbImage {
    RgbImage::from_fn(gt.width as u32, gt.height as u32, |x, y| {
        let p = y as usize * gt.width + x as usize;
        Rgb(match (est[p], gt.data[p]) {
            (_, None) => [0, 0, 0],
            (None, Some(_)) => [0, 0, 160],
            (Some(e), Some(g)) => match (e - g).abs() {
                v if v <= 1.0 => [0, 190, 0],
                v if v <= 2.0 => [230, 210, 0],
                v if v <= 4.0 => [240, 120, 0],
                _ => [220, 0, 0],
            },
        })
    })
}

fn push_metrics(s: &mut Summary, name: &str, m: &Metrics) {
    let f = |v: [f64; 3]| format!("{:.1} / {:.1} / {:.1}", v[0], v[1], v[2]);
    s.push(
        format!("{name} bad-1/2/4 % (estimated)"),
        f(m.bad_estimated),
    );
    s.push(format!("{name} bad-1/2/4 % (all GT)"), f(m.bad_all));
    s.push(format!("{name} MAE px"), format!("{:.2}", m.mae));
    s.push(format!("{name} density %"), format!("{:.1}", m.density));
}

fn metrics_json(m: &Metrics) -> serde_json::Value {
    serde_json::json!({
        "gt_pixels": m.gt_pixels,
        "estimated": m.estimated,
        "bad1_estimated": m.bad_estimated[0],
        "bad2_estimated": m.bad_estimated[1],
        "bad4_estimated": m.bad_estimated[2],
        "bad1_all": m.bad_all[0],
        "bad2_all": m.bad_all[1],
        "bad4_all": m.bad_all[2],
        "mae": m.mae,
        "density": m.density,
    })
}

/// A stereo pair (and its optional ground truth) at the working size.
#[derive(Clone, Debug)]
pub struct Pair {
    /// Input size `(width, height)`.
    pub input_size: (u32, u32),
    /// Working width.
    pub width: usize,
    /// Working height.
    pub height: usize,
    /// Left view, packed.
    pub left: Vec<protogist::image::Rgb8>,
    /// Right view, packed.
    pub right: Vec<protogist::image::Rgb8>,
    /// Ground-truth disparity in px of the working size, when given.
    pub gt: Option<GtMap>,
}

/// Loads a pair and optional GT, checks their sizes, and area-downscales all
/// to `max_width` (GT disparities scale with the images).
///
/// # Errors
/// [`HostError`] for unreadable files, a pair of different sizes, GT of
/// another size, or a zero width.
pub fn load_pair(
    left: &Path,
    right: &Path,
    gt: Option<&Path>,
    gt_scale: f32,
    max_width: u32,
) -> Result<Pair> {
    if max_width == 0 {
        return Err(HostError::ZeroDimension { name: "width" });
    }
    let (left, right) = (io::load_rgb(left)?, io::load_rgb(right)?);
    let (ow, oh) = left.dimensions();
    if right.dimensions() != (ow, oh) {
        let (rw, rh) = right.dimensions();
        return Err(StereoError::SizeMismatch {
            left: (ow as usize, oh as usize),
            right: (rw as usize, rh as usize),
        }
        .into());
    }
    let gt_full = match gt {
        Some(path) => {
            let g = load_gt(path, gt_scale)?;
            if (g.width, g.height) != (ow as usize, oh as usize) {
                return Err(HostError::GroundTruthSize {
                    path: path.to_path_buf(),
                    expected: (ow as usize, oh as usize),
                    got: (g.width, g.height),
                });
            }
            Some(g)
        }
        None => None,
    };
    let (w, h) = io::working_size(ow, oh, max_width)?;
    let scale = |img: image::RgbImage| {
        if (w, h) == (ow, oh) {
            img
        } else {
            io::area_downscale(&img, w, h)
        }
    };
    let (lp, rp) = (
        io::to_core_rgb(&scale(left)),
        io::to_core_rgb(&scale(right)),
    );
    let (w, h) = (w as usize, h as usize);
    Ok(Pair {
        input_size: (ow, oh),
        width: w,
        height: h,
        left: lp,
        right: rp,
        gt: match (gt_full, gt) {
            (Some(g), Some(path)) => Some(gt_at(&g, w, h, path)?),
            _ => None,
        },
    })
}

/// One run of an engine on the pair, before the report.
struct Estimate {
    /// The engine that ran.
    engine: Engine,
    /// The map, left-referenced (what `--complete` starts from).
    cells: Vec<DisparityCell>,
    /// The same in px (`None`: OFF).
    disparity: Vec<Option<f32>>,
    /// The reference's argmax before the OFF tests (the core engine does
    /// not expose it).
    raw: Option<Vec<Option<f32>>>,
    /// Pixels OFF for lack of texture, as ambiguous, by the left-right
    /// check.
    off: [usize; 3],
    /// Time to train (or load) the decoders, ms.
    train_ms: f64,
    /// Time of the stage's run, ms.
    run_ms: f64,
}

/// A map of cells in px (`None`: OFF).
fn cells_f32(cells: &[DisparityCell]) -> Vec<Option<f32>> {
    cells
        .iter()
        .map(|c| c.get().map(|d| d.to_num::<f32>()))
        .collect()
}

/// The f32 reference on the packed `w x h` pair: `params`, coarse to fine
/// with `search`.
fn run_reference(
    opts: &StereoOptions,
    params: &DemParams,
    search: Option<preset::Search>,
    pair: &Pair,
) -> Result<Estimate> {
    let (w, h) = (pair.width, pair.height);
    let t_train = Instant::now();
    let mut decoders = vec![decoder_for(params, opts.table.as_deref())?];
    for k in 1..=search.map_or(0, |c| c.levels) {
        decoders.push(decoder_for(&dem::c2f::level_params(params, k), None)?);
    }
    let train_ms = t_train.elapsed().as_secs_f64() * 1e3;
    let t_run = Instant::now();
    let (lv, rv) = (
        ImageView::packed(&pair.left, w, h)?,
        ImageView::packed(&pair.right, w, h)?,
    );
    let maps = if let Some(c) = search.filter(|c| c.phase) {
        // Spread, then the phase refinement, then the border refinement.
        let inner = DemParams {
            refine_radius: 0,
            ..*params
        };
        let mut maps =
            dem::c2f::stereo_c2f_from(&inner, &decoders, &lv, &rv, c.radius, c.band, c.finest)?;
        dem::phase::refine(
            &protogist::stereo::phase::PhaseParams::DEFAULT.into(),
            params.max_disp,
            &lv,
            &rv,
            &mut maps.disparity,
        )?;
        maps.disparity_f32 = cells_f32(&maps.disparity);
        dem::refine::refine_borders(params, &lv, &mut maps);
        maps
    } else if let Some(c) = search {
        dem::c2f::stereo_c2f_from(params, &decoders, &lv, &rv, c.radius, c.band, c.finest)?
    } else {
        dem::stereo(params, &decoders[0], &lv, &rv)?
    };
    let run_ms = t_run.elapsed().as_secs_f64() * 1e3;
    Ok(Estimate {
        engine: Engine::Reference,
        cells: maps.disparity,
        disparity: maps.disparity_f32,
        raw: Some(maps.left_raw),
        off: [maps.off_texture, maps.off_ambiguous, maps.off_inconsistent],
        train_ms,
        run_ms,
    })
}

/// Sets OFF, in `est`'s map and cells alike, the pixels in islands of at
/// most `size` px ([`dem::speckle::speckles`]); returns how many.
fn remove_speckles(est: &mut Estimate, w: usize, h: usize, size: usize, range: f32) -> usize {
    let removed = dem::speckle::speckles(&est.disparity, w, h, size, range);
    let mut count = 0;
    for ((r, d), c) in removed.iter().zip(&mut est.disparity).zip(&mut est.cells) {
        if *r {
            *d = None;
            *c = DisparityCell::OFF;
            count += 1;
        }
    }
    count
}

/// `protogist stereo`: loads, downscales, runs the DEM (the f32 reference,
/// or core's engine with `--engine core`), writes the panels and, with GT,
/// the error map and metrics.
///
/// # Errors
/// [`HostError`] for unreadable or mismatched inputs, bad GT, parameters
/// the stage (or the engine) rejects, or an unwritable output directory.
pub fn run_stereo(opts: &StereoOptions) -> Result<Summary> {
    let start = Instant::now();
    let pair = load_pair(
        &opts.left,
        &opts.right,
        opts.gt.as_deref(),
        opts.gt_scale,
        opts.width,
    )?;
    let (ow, oh) = pair.input_size;
    let (w, h) = (pair.width, pair.height);
    let plan = match opts.readout.engine {
        Engine::Reference => None,
        Engine::Core => Some(engine::plan(opts, w)?),
    };
    let (params, search, complete) = match &plan {
        Some(p) => (p.params, Some(p.search), false),
        None => (
            preset::params_for(opts, w)?,
            preset::search(opts)?,
            preset::complete(opts),
        ),
    };
    params.check()?;
    let speckle = preset::speckle(opts)?;
    // Size checks first: training for a hopeless size is wasted time.
    if usize::from(params.max_disp) >= w {
        return Err(StereoError::MaxDispTooLarge {
            max_disp: params.max_disp,
            width: w,
        }
        .into());
    }
    // The coarsest level searched (the pair itself without `--c2f`) must
    // hold the filters.
    let min = params.min_size();
    let coarse_levels = search.map_or(0, |c| c.levels);
    let coarsest = (w >> coarse_levels, h >> coarse_levels);
    if coarsest.0 < min || coarsest.1 < min {
        return Err(StereoError::TooSmall { min, got: coarsest }.into());
    }
    let mut est = match &plan {
        Some(p) => {
            let r = engine::run(p, &pair.left, &pair.right, w, h, opts.time_at_least)?;
            Estimate {
                engine: Engine::Core,
                disparity: cells_f32(&r.cells),
                cells: r.cells,
                raw: None,
                off: [
                    r.report.off_texture,
                    r.report.off_ambiguous,
                    r.report.off_inconsistent,
                ],
                train_ms: r.train_ms,
                run_ms: r.run_ms,
            }
        }
        None => run_reference(opts, &params, search, &pair)?,
    };
    let off_speckle = match speckle {
        Some((size, range)) => remove_speckles(&mut est, w, h, size, range),
        None => 0,
    };
    let (train_ms, run_ms) = (est.train_ms, est.run_ms);
    let (lp, gt_small) = (pair.left, pair.gt);

    let mut s = Summary::new(format!("protogist stereo: {}", opts.left.display()));
    s.push("input", format!("{ow}x{oh}"));
    s.push("working size", format!("{w}x{h}"));
    s.push("engine", est.engine.name());
    s.push("max disparity", params.max_disp);
    s.push("pool radius", params.pool_radius);
    s.push("levels", params.levels);
    if let dem::Aggregation::Sgm { p1, p2, paths } = params.aggregation {
        s.push(
            "aggregation",
            format!("SGM, P1 {p1}, P2 {p2}, {paths} paths"),
        );
    }
    if params.colour != dem::Colour::Grey {
        s.push(
            "colour",
            format!(
                "{:?} ({} channels, chroma weight {})",
                params.colour,
                params.colour.channels(&params),
                params.chroma_weight
            ),
        );
    }
    if let Some(c) = search {
        let band = c
            .band
            .map_or("every group".to_string(), |b| format!("band {b} px"));
        s.push(
            "search",
            format!(
                "coarse to fine, {} coarse levels, windows ±{}, {band}",
                c.levels, c.radius
            ),
        );
    }
    if let Some(p) = opts.readout.preset {
        s.push("preset", p.options());
    }
    let n = (w * h) as f64;
    s.push("decoder ms", format!("{train_ms:.1}"));
    s.push("stereo ms", format!("{run_ms:.1}"));
    let on = est.disparity.iter().filter(|d| d.is_some()).count();
    s.push("ON %", format!("{:.1}", 100.0 * on as f64 / n));
    s.push(
        "OFF texture/ambiguous/left-right %",
        format!(
            "{:.1} / {:.1} / {:.1}",
            100.0 * est.off[0] as f64 / n,
            100.0 * est.off[1] as f64 / n,
            100.0 * est.off[2] as f64 / n
        ),
    );
    if let Some((size, range)) = speckle {
        s.push(
            "speckle filter",
            format!(
                "islands of at most {size} px (joined within {range} px) OFF: {:.1} %",
                100.0 * off_speckle as f64 / n
            ),
        );
    }
    let max = f32::from(params.max_disp);
    let mut panels = vec![
        Panel::new("left", rgb_from(&lp, w, h)),
        Panel::new("disparity", disparity_panel(&est.disparity, w, h, max)),
    ];
    if let Some(raw) = &est.raw {
        panels.push(Panel::new("disparity_raw", disparity_panel(raw, w, h, max)));
    }
    let mut json = serde_json::json!({
        "left": opts.left.display().to_string(),
        "width": w, "height": h,
        "max_disp": params.max_disp,
        "pool_radius": params.pool_radius,
        "colour": format!("{:?}", params.colour).to_lowercase(),
        "chroma_weight": params.chroma_weight,
        "on_fraction": on as f64 / n,
        "engine": est.engine.name(),
        "stereo_ms": run_ms,
    });
    if let Some(p) = opts.readout.preset {
        json["preset_options"] = serde_json::json!(p.options());
    }
    if let Some((size, range)) = speckle {
        json["speckle"] = serde_json::json!({
            "size": size, "range": range, "off_fraction": off_speckle as f64 / n,
        });
    }
    if let Some(c) = search {
        json["c2f"] = serde_json::json!({
            "levels": c.levels, "radius": c.radius, "band": c.band,
        });
    }
    let model_f32 = est.disparity.clone();
    let mut final_f32 = est.disparity;
    if complete {
        let t = Instant::now();
        let edges = crate::stages::run_conspicuity(
            &protogist::conspicuity::LuvTables::new(),
            &protogist::conspicuity::EdgeParams::default(),
            &lp,
            w,
            h,
        )?;
        let (done, report) = crate::stages::run_complete(
            &protogist::complete::CompleteParams::default(),
            &edges.edges,
            &edges.smoothed,
            &est.cells,
            w,
            h,
        )?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        s.push(
            "completion",
            format!(
                "{} regions, {} replaced, {} filled, {ms:.1} ms",
                report.regions, report.replaced, report.filled
            ),
        );
        json["completion_ms"] = serde_json::json!(ms);
        final_f32 = cells_f32(&done);
        panels.push(Panel::new(
            "disparity_completed",
            disparity_panel(&final_f32, w, h, max),
        ));
    }
    if let Some(gt) = gt_small {
        let m = metrics(&final_f32, &gt.data);
        let gmax = gt.data.iter().flatten().fold(0.0f32, |a, &b| a.max(b));
        s.push("GT max disparity px", format!("{gmax:.1}"));
        push_metrics(&mut s, "final", &m);
        let raw = est.raw.as_ref().map(|r| metrics(r, &gt.data));
        if let Some(raw) = &raw {
            push_metrics(&mut s, "raw argmax", raw);
        }
        panels.push(Panel::new("gt", disparity_panel(&gt.data, w, h, max)));
        panels.push(Panel::new("error", error_panel(&final_f32, &gt)));
        json["gt_max_disp"] = serde_json::json!(gmax);
        json["final"] = metrics_json(&m);
        if complete {
            let before = metrics(&model_f32, &gt.data);
            push_metrics(&mut s, "model (before completion)", &before);
            json["model"] = metrics_json(&before);
        }
        if let Some(raw) = &raw {
            json["raw_argmax"] = metrics_json(raw);
        }
    }
    finish(&opts.out, panels, &mut s, start)?;
    if opts.json {
        s.raw = Some(format!("{json:#}"));
    }
    Ok(s)
}
