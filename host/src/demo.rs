//! The built-in demo (being written).
