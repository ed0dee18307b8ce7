//! f32 reference of `protogist::conspicuity` (being written).
