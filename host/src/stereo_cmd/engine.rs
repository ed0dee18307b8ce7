//! `protogist stereo --engine core`: the pair through core's fixed-point
//! coarse-to-fine engine ([`protogist::stereo::c2f`]) instead of the f32
//! reference.
//!
//! The engine runs one configuration of the reference: `--levels 1 --pool 0
//! --sgm --paths 5 --c2f K` (K 1..=3; or `--paths 3`), grey, no border
//! refinement, no completion. With `--engine core` those are the defaults
//! (levels 1, pool 0, SGM with 5 paths on), so `--engine core --c2f 2`
//! alone is valid; any option that asks for something else is a
//! [`HostError::InvalidArgument`], checked before any training.
//! `--c2f-radius`, `--c2f-band`, `--c2f-finest`, `--p1`, `--p2`,
//! `--p2-ref-width`, `--min-margin`, `--lr`, `--lr-from-left` and `--paths`
//! map to [`C2fParams`] ([`c2f_params`]). The per-level tables are trained
//! as the reference path's ([`super::table_for`]), so both engines decode
//! with the same integer weights.

use super::preset::{self, Search};
use super::{table_for, StereoOptions};
use crate::error::{HostError, Result};
use crate::reference::stereo::c2f::level_params;
use crate::reference::stereo::{Aggregation, Colour, DemParams};
use crate::storage::C2fStorage;
use protogist::disparity::DisparityCell;
use protogist::image::{ImageView, Rgb8};
use protogist::stereo::c2f::{C2f, C2fParams};
use protogist::stereo::phase::PhaseParams;
use protogist::stereo::{self as qs, StereoReport};
use std::time::{Duration, Instant};

/// Which implementation `protogist stereo` runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Engine {
    /// The f32 reference (every option).
    #[default]
    Reference,
    /// Core's fixed-point coarse-to-fine engine, single thread.
    Core,
}

impl Engine {
    /// The name printed and written to the JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Reference => "reference",
            Self::Core => "core",
        }
    }
}

/// The SGM path count the engine runs.
const PATHS: u8 = protogist::stereo::c2f::PATHS as u8;

/// The settings of `--engine core`: the reference's parameters and search
/// (as the reference path would run them) and the engine's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// The reference's parameters of level 0 (what the tables are trained
    /// for, and what the summary reports).
    pub params: DemParams,
    /// The coarse-to-fine search.
    pub search: Search,
    /// The engine's parameters.
    pub engine: C2fParams,
}

fn invalid(name: &'static str, reason: &str) -> HostError {
    HostError::InvalidArgument {
        name,
        reason: format!("--engine core {reason}"),
    }
}

/// The settings of `--engine core` at working width `width`.
///
/// # Errors
/// [`HostError::InvalidArgument`] for every option the engine does not
/// run (`--preset`, `--table`, `--complete`, a colour other than grey,
/// `--chroma-weight`, `--refine` other than 0, `--levels` other than 1,
/// `--pool` other than 0, `--paths` other than 5 or 3, no `--c2f` or one
/// outside 1..=3) and for the reference's own option checks;
/// [`HostError::Engine`] for values the engine rejects (penalties).
pub fn plan(opts: &StereoOptions, width: usize) -> Result<Plan> {
    let r = &opts.readout;
    let given = |name: &'static str, bad: bool, reason: &str| {
        if bad {
            Err(invalid(name, reason))
        } else {
            Ok(())
        }
    };
    given(
        "preset",
        r.preset.is_some(),
        "runs its own settings; give the options explicitly",
    )?;
    given("table", opts.table.is_some(), "trains one table per level")?;
    given("complete", opts.complete, "does not complete the map")?;
    given(
        "colour",
        opts.colour.is_some_and(|c| c != Colour::Grey),
        "runs grey only",
    )?;
    given(
        "chroma-weight",
        opts.chroma_weight.is_some(),
        "runs grey only",
    )?;
    given(
        "refine",
        opts.refine.is_some_and(|v| v != 0),
        "has no border refinement (--refine 0)",
    )?;
    given(
        "levels",
        opts.levels.is_some_and(|v| v != 1),
        "runs one pyramid level per c2f level (--levels 1)",
    )?;
    given(
        "pool",
        opts.pool.is_some_and(|v| v != 0),
        "does not pool the scores (--pool 0)",
    )?;
    given(
        "paths",
        r.paths.is_some_and(|v| v != PATHS && v != 3),
        "runs the 5 SGM paths of one top-to-bottom pass (--paths 5) or 3 (--paths 3)",
    )?;
    let levels = r.c2f.unwrap_or(0);
    given(
        "c2f",
        !(1..=protogist::stereo::c2f::MAX_COARSE).contains(&usize::from(levels)),
        "needs --c2f 1..=3 (coarse levels)",
    )?;
    // The engine's fixed settings as explicit options: from here the
    // reference path's own mapping gives the parameters.
    let mut fixed = opts.clone();
    fixed.levels = Some(1);
    fixed.pool = Some(0);
    fixed.refine = Some(0);
    fixed.colour = Some(Colour::Grey);
    fixed.readout.sgm = true;
    fixed.readout.paths = Some(r.paths.unwrap_or(PATHS));
    let params = preset::params_for(&fixed, width)?;
    params.check()?;
    let search = preset::search(&fixed)?.ok_or_else(|| invalid("c2f", "needs --c2f"))?;
    let engine = c2f_params(&params, search)?;
    // Rejects what the engine cannot run (penalties out of range) before
    // any training.
    C2f::new(&engine)?;
    Ok(Plan {
        params,
        search,
        engine,
    })
}

/// The engine's parameters for the reference's `params` (one level, no
/// pooling, SGM) and `search`.
///
/// # Errors
/// [`HostError::InvalidArgument`] when `params` is not a configuration the
/// engine runs (no SGM, or a window or band above 255 px).
pub fn c2f_params(params: &DemParams, search: Search) -> Result<C2fParams> {
    let Aggregation::Sgm { p1, p2, paths } = params.aggregation else {
        return Err(invalid("sgm", "runs SGM"));
    };
    if paths != PATHS && paths != 3 {
        return Err(invalid("paths", "runs 5 or 3 paths"));
    }
    let byte = |name, v: usize| u8::try_from(v).map_err(|_| invalid(name, "takes at most 255"));
    Ok(C2fParams {
        dem: qs::DemParams {
            max_disp: params.max_disp,
            carriers: params.carriers,
            levels: params.levels,
            wavelength: params.wavelength,
            sigma_per_wavelength: params.sigma_per_wavelength,
            radius: params.radius,
            shift_step: params.shift_step,
            pool_radius: params.pool_radius,
            min_energy: params.min_energy,
            min_margin: params.min_margin,
            lr_tolerance: params.lr_tolerance,
        },
        coarse: byte("c2f", search.levels)?,
        radius: byte("c2f-radius", search.radius)?,
        band: search.band.map(|b| byte("c2f-band", b)).transpose()?,
        p1,
        p2,
        lr_from_left: params.lr_from_left,
        paths,
        finest: byte("c2f-finest", search.finest)?,
        phase: search.phase.then_some(PhaseParams::DEFAULT),
    })
}

/// What one run of the engine gave.
#[derive(Clone, Debug)]
pub struct CoreRun {
    /// The map, left-referenced (`U8F8` px or OFF).
    pub cells: Vec<DisparityCell>,
    /// The counts of ON and OFF pixels.
    pub report: StereoReport,
    /// Time to train (or load) the tables, ms.
    pub train_ms: f64,
    /// Time of [`C2f::run`] alone, ms: the best of at least [`TIMED_RUNS`]
    /// runs (more if `min_ms` asks for them).
    pub run_ms: f64,
}

/// Runs of [`C2f::run`] timed per pair; `run_ms` is the fastest (single
/// runs move by up to 2x on a shared machine; the OpenCV baseline script
/// times SGBM the same way).
pub const TIMED_RUNS: usize = 15;

/// Trains the per-level tables of `plan` and runs the engine on the packed
/// `w x h` pair; only [`C2f::run`] is timed in `run_ms`, the best of the
/// runs (single thread): [`TIMED_RUNS`] of them, and more until `min_ms`
/// ms have passed.
///
/// # Errors
/// [`HostError::Engine`] for what the engine rejects (sizes, tables).
pub fn run(
    plan: &Plan,
    left: &[Rgb8],
    right: &[Rgb8],
    w: usize,
    h: usize,
    min_ms: u32,
) -> Result<CoreRun> {
    let t_train = Instant::now();
    let bytes = (0..=plan.search.levels)
        .map(|k| Ok(table_for(&level_params(&plan.params, k), None)?.to_bytes()))
        .collect::<Result<Vec<_>>>()?;
    let train_ms = t_train.elapsed().as_secs_f64() * 1e3;
    let tables = bytes
        .iter()
        .map(|b| qs::DemTable::parse(b).map_err(qs::StereoError::Table))
        .collect::<Result<Vec<_>, _>>()?;
    let engine = C2f::new(&plan.engine)?;
    let mut storage = C2fStorage::new(w, h, &plan.engine);
    let (lv, rv) = (
        ImageView::packed(left, w, h)?,
        ImageView::packed(right, w, h)?,
    );
    let mut cells = vec![DisparityCell::OFF; w * h];
    // The engine is deterministic: every run writes the same cells.
    let mut run_ms = f64::INFINITY;
    let mut report = StereoReport::default();
    let (start, min) = (Instant::now(), Duration::from_millis(u64::from(min_ms)));
    let mut runs = 0;
    while runs < TIMED_RUNS || start.elapsed() < min {
        runs += 1;
        let t_run = Instant::now();
        report = engine.run(
            &tables,
            &lv,
            &rv,
            &mut storage.buffers(),
            &mut |x, y, c| {
                if let Some(o) = cells.get_mut(y * w + x) {
                    *o = c;
                }
            },
            &mut (),
        )?;
        run_ms = run_ms.min(t_run.elapsed().as_secs_f64() * 1e3);
    }
    Ok(CoreRun {
        cells,
        report,
        train_ms,
        run_ms,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::{Cli, Command};
    use clap::Parser;

    fn parse(extra: &str) -> StereoOptions {
        let base = "protogist stereo --left l.png --right r.png --out o --max-disp 31 \
                    --engine core";
        let args: Vec<&str> = base
            .split_whitespace()
            .chain(extra.split_whitespace())
            .collect();
        match Cli::try_parse_from(args).unwrap().command {
            Some(Command::Stereo(o)) => o,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn c2f_alone_is_the_engine_default() {
        let p = plan(&parse("--c2f 2"), 160).unwrap();
        // The firmware's setting (`C2fParams::DEFAULT`) with the reference's
        // read-out defaults (every group, P2 16; the firmware's band 2 and
        // P2 4 are given explicitly): the host's and core's model defaults
        // agree.
        assert_eq!(
            p.engine,
            C2fParams {
                band: None,
                p2: super::super::SGM_P2,
                ..C2fParams::DEFAULT
            }
        );
        // Spelled out, the same settings.
        let spelled = plan(
            &parse("--c2f 2 --levels 1 --pool 0 --sgm --paths 5 --colour grey --refine 0"),
            160,
        )
        .unwrap();
        assert_eq!(p, spelled);
    }

    #[test]
    fn every_option_maps_to_the_engine() {
        let p = plan(
            &parse(
                "--c2f 3 --c2f-radius 3 --c2f-band 1 --p1 0.5 --p2 8 --p2-ref-width 320 \
                 --min-margin 0.75 --lr -1",
            ),
            160,
        )
        .unwrap()
        .engine;
        assert_eq!((p.coarse, p.radius, p.band), (3, 3, Some(1)));
        assert_eq!((p.p1, p.p2), (0.5, 4.0));
        assert_eq!((p.dem.min_margin, p.dem.lr_tolerance), (0.75, -1.0));
        assert_eq!(
            (p.dem.max_disp, p.dem.levels, p.dem.pool_radius),
            (31, 1, 0)
        );
    }

    #[test]
    fn options_the_engine_does_not_run_are_typed_errors() {
        for (extra, name) in [
            ("", "c2f"),
            ("--c2f 0", "c2f"),
            ("--c2f 4", "c2f"),
            ("--c2f 2 --levels 2", "levels"),
            ("--c2f 2 --pool 1", "pool"),
            ("--c2f 2 --colour luv", "colour"),
            ("--c2f 2 --colour rgb", "colour"),
            ("--c2f 2 --chroma-weight 1", "chroma-weight"),
            ("--c2f 2 --paths 8", "paths"),
            ("--c2f 2 --paths 4", "paths"),
            ("--c2f 2 --refine 1", "refine"),
            ("--c2f 2 --complete", "complete"),
            ("--c2f 2 --table t.bin", "table"),
            ("--preset held-out", "preset"),
            ("--c2f 2 --p2-ref-width 0", "p2-ref-width"),
        ] {
            match plan(&parse(extra), 160) {
                Err(HostError::InvalidArgument { name: got, .. }) => {
                    assert_eq!(got, name, "{extra}");
                }
                other => panic!("{extra}: {other:?}"),
            }
        }
        // 3 paths and the derived right map are the engine's options.
        let p = plan(&parse("--c2f 2 --c2f-finest 1"), 160).unwrap();
        assert_eq!(p.engine.finest, 1);
        assert_eq!(p.engine.phase, None);
        let p = plan(&parse("--c2f 2 --c2f-finest 1 --c2f-phase"), 160).unwrap();
        assert_eq!(p.engine.phase, Some(PhaseParams::DEFAULT));
        assert!(plan(&parse("--c2f-phase"), 160).is_err());
        let p = plan(&parse("--c2f 2 --paths 3 --lr-from-left"), 160).unwrap();
        assert_eq!((p.engine.paths, p.engine.lr_from_left), (3, true));
        let p = plan(&parse("--c2f 2"), 160).unwrap();
        assert_eq!((p.engine.paths, p.engine.lr_from_left), (5, false));
        // Penalties the engine rejects: its own typed error.
        let e = plan(&parse("--c2f 2 --p1 2 --p2 1"), 160).unwrap_err();
        assert!(
            matches!(e, HostError::Engine(_) | HostError::Stereo(_)),
            "{e}"
        );
    }
}
