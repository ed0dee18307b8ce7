//! protogist-host: the f32 reference of every core stage, image I/O, the CLI
//! and the demo.
//!
//! [`reference`] mirrors `protogist` stage by stage, with the same names and
//! argument order, in `f32`. It is what the fixed-point core is tested against.

pub mod cli;
pub mod demo;
pub mod io;
pub mod reference;
