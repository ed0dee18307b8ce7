//! The engines of `protogist stereo`: core's fixed-point coarse-to-fine
//! engine ([`protogist::stereo::c2f`]) at a named operating point, or the
//! f32 reference of exactly what it computes
//! ([`crate::reference::stereo::c2f`]: one pyramid level per c2f level, no
//! pooling, SGM, the same windows, band, paths, left-right check, finest
//! level and phase refinement).
//!
//! Both decode with the same integer weights: the per-level tables are
//! trained (or taken from the built-in table) by [`crate::dem_tables::table_for`].

use crate::dem_tables::{decoder_for, params_of, table_for};
use crate::error::{HostError, Result};
use crate::reference::stereo::c2f::level_params;
use crate::reference::stereo::{self as dem, DemParams, DisparityMapsF};
use crate::storage::C2fStorage;
use protogist::disparity::DisparityCell;
use protogist::image::{ImageView, Rgb8};
use protogist::stereo::c2f::{C2f, C2fParams, LeftRight};
use protogist::stereo::{self as qs, StereoReport};
use std::time::{Duration, Instant};

/// Which implementation `protogist stereo` runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Engine {
    /// Core's fixed-point engine, single thread (what the board runs).
    #[default]
    Core,
    /// The f32 reference of the same point (for the agreement tests).
    Reference,
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

/// The left-right check of `--lr` ([`LeftRight`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Lr {
    /// No left-right check (the right eye is not read out).
    Off,
    /// Against the right eye read out.
    Read,
    /// Against a right map derived from the left map's path sums.
    Derived,
}

impl From<Lr> for LeftRight {
    fn from(v: Lr) -> Self {
        match v {
            Lr::Off => Self::Off,
            Lr::Read => Self::Read,
            Lr::Derived => Self::Derived,
        }
    }
}

/// The coarse-to-fine search of a point, as the reference runs it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Search {
    /// Coarse levels (at least 1).
    pub levels: usize,
    /// Half width of the fine windows.
    pub radius: usize,
    /// Band of the fine decode (`None`: every group).
    pub band: Option<usize>,
    /// The finest level run (0: the full size), at most `levels`.
    pub finest: usize,
}

/// The settings of a run: the engine's parameters and the reference's
/// mirror of them.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// The engine's parameters.
    pub engine: C2fParams,
    /// The reference's parameters of level 0 (what the tables are trained
    /// for).
    pub params: DemParams,
    /// The coarse-to-fine search.
    pub search: Search,
}

/// The plan of the named point `point` with `max_disp` and, if given, the
/// left-right check `lr` instead of the point's.
///
/// # Errors
/// [`HostError::InvalidArgument`] for an unknown point name (the names
/// listed); [`HostError::Engine`] for parameters the engine rejects.
pub fn plan(point: &str, max_disp: u8, lr: Option<Lr>) -> Result<Plan> {
    let mut engine = C2fParams::from_name(point).ok_or_else(|| HostError::InvalidArgument {
        name: "point",
        reason: format!(
            "unknown point {point:?}; the points are {}",
            C2fParams::NAMED.map(|(n, _)| n).join(", ")
        ),
    })?;
    engine.dem.max_disp = max_disp;
    if let Some(lr) = lr {
        engine.left_right = lr.into();
    }
    // Rejects what the engine cannot run before any training.
    C2f::new(&engine)?;
    let (params, search) = reference_of(&engine);
    Ok(Plan {
        engine,
        params,
        search,
    })
}

/// The reference's parameters ([`crate::dem_tables::params_of`]) and
/// search for the engine's `e`.
pub fn reference_of(e: &C2fParams) -> (DemParams, Search) {
    let search = Search {
        levels: usize::from(e.coarse),
        radius: usize::from(e.radius),
        band: e.band.map(usize::from),
        finest: usize::from(e.finest),
    };
    (params_of(e), search)
}

/// What one run gave.
#[derive(Clone, Debug)]
pub struct Run {
    /// The map, left-referenced (`U8F8` px or OFF).
    pub cells: Vec<DisparityCell>,
    /// The counts of ON and OFF pixels (`cells` 0 for the reference).
    pub report: StereoReport,
    /// Time to train (or load) the tables, ms.
    pub train_ms: f64,
    /// Time of the run alone, ms (core: the best of the timed runs).
    pub run_ms: f64,
}

/// Runs of [`C2f::run`] timed per pair; `run_ms` is the fastest (single
/// runs move by up to 2x on a shared machine; the OpenCV baseline script
/// times SGBM the same way).
pub const TIMED_RUNS: usize = 15;

/// Trains the per-level tables of `plan` and runs core's engine on the
/// packed `w x h` pair; only [`C2f::run`] is timed in `run_ms`, the best
/// of the runs (single thread): [`TIMED_RUNS`] of them, and more until
/// `min_ms` ms have passed.
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
) -> Result<Run> {
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
    Ok(Run {
        cells,
        report,
        train_ms,
        run_ms,
    })
}

/// The f32 reference of `plan` on the packed `w x h` pair: the
/// coarse-to-fine maps, then the phase refinement when the point has one.
///
/// # Errors
/// [`HostError::Stereo`] for what the reference rejects.
pub fn run_reference(
    plan: &Plan,
    left: &[Rgb8],
    right: &[Rgb8],
    w: usize,
    h: usize,
) -> Result<(DisparityMapsF, f64, f64)> {
    let t_train = Instant::now();
    let decoders = (0..=plan.search.levels)
        .map(|k| decoder_for(&level_params(&plan.params, k), None))
        .collect::<Result<Vec<_>>>()?;
    let train_ms = t_train.elapsed().as_secs_f64() * 1e3;
    let t_run = Instant::now();
    let (lv, rv) = (
        ImageView::packed(left, w, h)?,
        ImageView::packed(right, w, h)?,
    );
    let s = plan.search;
    let mut maps = dem::c2f::stereo_c2f_from(
        &plan.params,
        &decoders,
        &lv,
        &rv,
        s.radius,
        s.band,
        s.finest,
    )?;
    if let Some(ph) = plan.engine.phase {
        dem::phase::refine(
            &ph.into(),
            plan.params.max_disp,
            &lv,
            &rv,
            &mut maps.disparity,
        )?;
        maps.disparity_f32 = super::cells_f32(&maps.disparity);
    }
    Ok((maps, train_ms, t_run.elapsed().as_secs_f64() * 1e3))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_named_point_plans_and_mirrors_the_engine() {
        for (name, point) in C2fParams::NAMED {
            let p = plan(name, 31, None).unwrap();
            assert_eq!(p.engine, point, "{name}");
            assert_eq!(p.search.levels, usize::from(point.coarse));
            assert_eq!(p.search.finest, usize::from(point.finest));
            assert_eq!(
                p.params.lr_from_left,
                point.left_right == LeftRight::Derived
            );
            assert_eq!((p.params.levels, p.params.pool_radius), (1, 0));
        }
    }

    #[test]
    fn max_disp_and_lr_override_the_point() {
        let p = plan("fast", 40, Some(Lr::Off)).unwrap();
        assert_eq!(p.engine.dem.max_disp, 40);
        assert_eq!(p.engine.left_right, LeftRight::Off);
        assert!(p.params.lr_tolerance < 0.0 && !p.params.lr_from_left);
        let p = plan("full", 31, Some(Lr::Derived)).unwrap();
        assert!(p.params.lr_from_left);
    }

    #[test]
    fn an_unknown_point_is_a_typed_error_naming_the_points() {
        match plan("r2b1l3p", 31, None) {
            Err(HostError::InvalidArgument { name, reason }) => {
                assert_eq!(name, "point");
                assert!(reason.contains("full, fast, half"), "{reason}");
            }
            other => panic!("{other:?}"),
        }
    }
}
