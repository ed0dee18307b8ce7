//! protogist-host: the f32 reference of every core stage, image I/O, the CLI
//! and the demo.
//!
//! [`reference`](mod@reference) mirrors `protogist` stage by stage, with the same names and
//! argument order, in `f32`. It is what the fixed-point core is tested against.
//!
//! The CLI side: [`cli`] parses and dispatches, [`demo`] runs the synthetic
//! scene, [`stages`] runs the core stages step by step and turns their maps
//! into [`panels`], [`io`] loads and downscales images, [`output`] writes results all or nothing, [`summary`]
//! is what gets printed, and [`error`] is the one error type of them all.
//! [`product`] runs core's pipeline on a [`pair`] for `run`, the demo and
//! the evaluations; [`dem_tables`] picks the disparity decoder tables.
//! [`stereo_cmd`] runs the stereo stage alone and scores it against
//! [`ground_truth`]. [`classify`] holds the classification rules, the
//! performance measures and plots of the paper's sections 4.1 and 5.1, and
//! the development silhouettes of `protogist gen-shapes`. [`scenes`] renders
//! seeded stereo scenes with ground truth (`protogist gen-scenes`), and
//! [`gist`] measures the whole job on them (`protogist gist-eval`).

pub mod canvas;
pub mod classify;
pub mod cli;
pub mod dem_tables;
pub mod demo;
pub mod error;
pub mod eval;
pub mod gist;
pub mod ground_truth;
pub mod io;
pub mod limits;
pub mod output;
pub mod pair;
pub mod panels;
pub mod plot;
pub mod product;
pub mod reference;
pub mod reference_chain;
pub mod rgbd;
pub mod run_cmd;
pub mod scenes;
pub mod stages;
pub mod stereo_cmd;
pub mod storage;
pub mod summary;
