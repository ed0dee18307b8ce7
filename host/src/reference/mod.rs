//! f32 references of the core stages, same names and argument order.

pub mod complete;
pub mod conspicuity;
pub mod holes;
pub mod refine;
pub mod relabel;
pub mod segment;
pub mod shape;
pub mod stereo;
