//! Which disparity-energy decoder tables a run uses, shared by every
//! command: a given file, the bundled default, or trained now, checked
//! against the parameters; and the f32 reference's parameters of a core
//! stereo point.

use crate::error::{HostError, Result};
use crate::reference::stereo::table::{DemTable, DEFAULT_TABLE};
use crate::reference::stereo::{self as dem, Aggregation, Decoder, DemParams, StereoError};
use protogist::stereo::c2f::{C2fParams, LeftRight};
use std::path::Path;

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

/// The f32 reference's parameters of core's point `e`: no pooling, SGM
/// with `e`'s penalties and paths, `LeftRight::Off` as a negative
/// tolerance (no check), `Derived` as `lr_from_left`.
pub fn params_of(e: &C2fParams) -> DemParams {
    let d = &e.dem;
    DemParams {
        max_disp: d.max_disp,
        carriers: d.carriers,
        levels: d.levels,
        wavelength: d.wavelength,
        sigma_per_wavelength: d.sigma_per_wavelength,
        radius: d.radius,
        shift_step: d.shift_step,
        pool_radius: d.pool_radius,
        min_energy: d.min_energy,
        min_margin: d.min_margin,
        lr_tolerance: match e.left_right {
            LeftRight::Off => -1.0,
            LeftRight::Read | LeftRight::Derived => d.lr_tolerance,
        },
        lr_from_left: e.left_right == LeftRight::Derived,
        aggregation: Aggregation::Sgm {
            p1: e.p1,
            p2: e.p2,
            paths: e.paths,
        },
        ..DemParams::default()
    }
}
