//! `protogist stereo` and `protogist train-dem`: the stereo engine at a
//! named operating point on a pair, with optional ground truth, and the
//! decoder table.

use crate::error::Result;
use crate::ground_truth::{metrics, Metrics};
use crate::output::finish;
use crate::pair::load_pair;
use crate::panels::{disparity_panel, error_panel, rgb_from, Panel};
use crate::reference::stereo::table::DemTable;
use crate::reference::stereo::{self as dem, DemParams, StereoError};
use crate::summary::Summary;
use protogist::disparity::DisparityCell;
use protogist::stereo::c2f::C2fParams;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub mod engine;
pub use engine::{Engine, Lr};

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
    /// grey PNG (0 = unknown), a Middlebury PFM (inf = unknown) or a NumPy
    /// array.
    #[arg(long)]
    pub gt: Option<PathBuf>,
    /// PNG ground-truth values per pixel of disparity.
    #[arg(long, default_value_t = 1.0)]
    pub gt_scale: f32,
    /// Working width, px (area-averaged down, aspect kept).
    #[arg(long, default_value_t = 160)]
    pub width: u32,
    /// Largest disparity searched, px of the working size (candidates
    /// `0..=max-disp`).
    #[arg(long, default_value_t = 31)]
    pub max_disp: u8,
    /// Operating point of the engine (`protogist::stereo::c2f::C2fParams`):
    /// `full` (most accurate estimates), `fast` (full resolution within
    /// 1,500 M4 instructions per pixel) or `half` (half-size map spread
    /// over 2x2 blocks, cheapest); docs/STEREO.md, "Operating points".
    #[arg(long, default_value = "full", value_parser = point_names())]
    pub point: String,
    /// The left-right check instead of the point's: `off`, `read` (the
    /// right eye read out) or `derived` (from the left map's path sums).
    #[arg(long, value_enum)]
    pub lr: Option<Lr>,
    /// Implementation: `core` (fixed point, what the board runs) or
    /// `reference` (the f32 reference of the same point).
    #[arg(long, value_enum, default_value_t = Engine::Core)]
    pub engine: Engine,
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

/// The names of `--point`, from [`C2fParams::NAMED`].
fn point_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(C2fParams::NAMED.map(|(n, _)| n))
}

impl StereoOptions {
    /// The options with every default: `left`, `right`, `out` as given.
    pub fn new(left: PathBuf, right: PathBuf, out: PathBuf) -> Self {
        Self {
            left,
            right,
            gt: None,
            gt_scale: 1.0,
            width: 160,
            max_disp: C2fParams::FULL.dem.max_disp,
            point: "full".into(),
            lr: None,
            engine: Engine::Core,
            json: false,
            time_at_least: 0,
            out,
        }
    }
}

/// `protogist train-dem`: trains for `params` and writes the table.
///
/// # Errors
/// [`HostError::Stereo`](crate::error::HostError::Stereo) for bad parameters, [`HostError::InvalidArgument`](crate::error::HostError::InvalidArgument) for a radius core cannot hold, [`HostError::Io`](crate::error::HostError::Io).
pub fn run_train_dem(params: &DemParams, out: &Path) -> Result<Summary> {
    params.check()?;
    let max = protogist::stereo::filters::MAX_RADIUS;
    if usize::from(params.radius) > max {
        return Err(crate::error::HostError::InvalidArgument {
            name: "radius",
            reason: format!("{} px: core's kernels hold radii 1..={max}", params.radius),
        });
    }
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

/// A map of cells in px (`None`: OFF).
fn cells_f32(cells: &[DisparityCell]) -> Vec<Option<f32>> {
    cells
        .iter()
        .map(|c| c.get().map(|d| d.to_num::<f32>()))
        .collect()
}

/// `protogist stereo`: loads, downscales, runs the engine at the named
/// point (core's, or the f32 reference of it with `--engine reference`),
/// writes the panels and, with GT, the error map and metrics.
///
/// # Errors
/// [`HostError`](crate::error::HostError) for unreadable or mismatched inputs, bad GT, an unknown
/// point, parameters the engine rejects, or an unwritable output
/// directory.
pub fn run_stereo(opts: &StereoOptions) -> Result<Summary> {
    let start = Instant::now();
    let plan = engine::plan(&opts.point, opts.max_disp, opts.lr)?;
    let pair = load_pair(
        &opts.left,
        &opts.right,
        opts.gt.as_deref(),
        opts.gt_scale,
        opts.width,
    )?;
    let (ow, oh) = pair.input_size;
    let (w, h) = (pair.width, pair.height);
    let params = plan.params;
    // Size checks first: training for a hopeless size is wasted time.
    if usize::from(params.max_disp) >= w {
        return Err(StereoError::MaxDispTooLarge {
            max_disp: params.max_disp,
            width: w,
        }
        .into());
    }
    // The coarsest level must hold the filters.
    let min = params.min_size();
    let coarse = plan.search.levels;
    let coarsest = (w >> coarse, h >> coarse);
    if coarsest.0 < min || coarsest.1 < min {
        return Err(StereoError::TooSmall { min, got: coarsest }.into());
    }
    let (cells, off, raw, train_ms, run_ms) = match opts.engine {
        Engine::Core => {
            let r = engine::run(&plan, &pair.left, &pair.right, w, h, opts.time_at_least)?;
            let off = [
                r.report.off_texture,
                r.report.off_ambiguous,
                r.report.off_inconsistent,
            ];
            (r.cells, off, None, r.train_ms, r.run_ms)
        }
        Engine::Reference => {
            let (maps, train_ms, run_ms) =
                engine::run_reference(&plan, &pair.left, &pair.right, w, h)?;
            let off = [maps.off_texture, maps.off_ambiguous, maps.off_inconsistent];
            (maps.disparity, off, Some(maps.left_raw), train_ms, run_ms)
        }
    };
    let disparity = cells_f32(&cells);
    let (lp, gt_small) = (pair.left, pair.gt);
    let e = &plan.engine;

    let mut s = Summary::new(format!("protogist stereo: {}", opts.left.display()));
    s.push("input", format!("{ow}x{oh}"));
    s.push("working size", format!("{w}x{h}"));
    s.push("engine", opts.engine.name());
    s.push("point", &opts.point);
    s.push("max disparity", params.max_disp);
    s.push(
        "search",
        format!(
            "coarse to fine, {} coarse levels, windows ±{}, {}, finest level {}{}",
            e.coarse,
            e.radius,
            e.band
                .map_or("every group".to_string(), |b| format!("band {b} px")),
            e.finest,
            if e.phase.is_some() {
                ", phase refinement"
            } else {
                ""
            }
        ),
    );
    s.push(
        "aggregation",
        format!("SGM, P1 {}, P2 {}, {} paths", e.p1, e.p2, e.paths),
    );
    s.push("left-right check", format!("{:?}", e.left_right));
    let n = (w * h) as f64;
    s.push("decoder ms", format!("{train_ms:.1}"));
    s.push("stereo ms", format!("{run_ms:.1}"));
    let on = disparity.iter().filter(|d| d.is_some()).count();
    s.push("ON %", format!("{:.1}", 100.0 * on as f64 / n));
    s.push(
        "OFF texture/ambiguous/left-right %",
        format!(
            "{:.1} / {:.1} / {:.1}",
            100.0 * off[0] as f64 / n,
            100.0 * off[1] as f64 / n,
            100.0 * off[2] as f64 / n
        ),
    );
    let max = f32::from(params.max_disp);
    let mut panels = vec![
        Panel::new("left", rgb_from(&lp, w, h)),
        Panel::new("disparity", disparity_panel(&disparity, w, h, max)),
    ];
    if let Some(raw) = &raw {
        panels.push(Panel::new("disparity_raw", disparity_panel(raw, w, h, max)));
    }
    let mut json = serde_json::json!({
        "left": opts.left.display().to_string(),
        "width": w, "height": h,
        "max_disp": params.max_disp,
        "point": opts.point,
        "on_fraction": on as f64 / n,
        "engine": opts.engine.name(),
        "stereo_ms": run_ms,
    });
    let final_f32 = disparity;
    if let Some(gt) = gt_small {
        let m = metrics(&final_f32, &gt.data);
        let gmax = gt.data.iter().flatten().fold(0.0f32, |a, &b| a.max(b));
        s.push("GT max disparity px", format!("{gmax:.1}"));
        push_metrics(&mut s, "final", &m);
        let raw = raw.as_ref().map(|r| metrics(r, &gt.data));
        if let Some(raw) = &raw {
            push_metrics(&mut s, "raw argmin", raw);
        }
        panels.push(Panel::new("gt", disparity_panel(&gt.data, w, h, max)));
        panels.push(Panel::new("error", error_panel(&final_f32, &gt)));
        json["gt_max_disp"] = serde_json::json!(gmax);
        json["final"] = metrics_json(&m);
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
