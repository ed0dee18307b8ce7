//! The product's data in flash: the stereo engine's decoder tables and
//! the shipped classifier, each at an aligned address ([`Aligned`]), for
//! the pipeline point [`PARAMS`] names.

use crate::product::PARAMS;
use crate::Aligned;

/// The coarse-to-fine engine's decoder tables at the pipeline's point
/// (`half-narrow`: kernels of radius 2), level 0 first
/// (`data/dem_c2f_narrow_l{0,1,2}.bin`, written by `protogist train-dem
/// --levels 1 --max-disp 31 | 16 | 8 --radius 2`), each at an aligned
/// address ([`Aligned`]).
#[cfg(not(feature = "accurate"))]
pub const TABLES: [&[u8]; 3] = [
    &Aligned(*include_bytes!("../data/dem_c2f_narrow_l0.bin")).0,
    &Aligned(*include_bytes!("../data/dem_c2f_narrow_l1.bin")).0,
    &Aligned(*include_bytes!("../data/dem_c2f_narrow_l2.bin")).0,
];
/// With the `accurate` feature: its point (`fast-narrow-full-search`)
/// has no level 2, so levels 0 and 1 of the same tables.
#[cfg(feature = "accurate")]
pub const TABLES: [&[u8]; 2] = [
    &Aligned(*include_bytes!("../data/dem_c2f_narrow_l0.bin")).0,
    &Aligned(*include_bytes!("../data/dem_c2f_narrow_l1.bin")).0,
];
const _: () = assert!(
    TABLES.len() == PARAMS.tables(),
    "one table per stereo level"
);
/// The shipped classifier (`host/data/shapes_model.bin`), word-aligned.
pub const MODEL: &[u8] = &Aligned(*include_bytes!("../../host/data/shapes_model.bin")).0;
