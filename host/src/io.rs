//! Image loading, downscaling and PNG panels (being written).
