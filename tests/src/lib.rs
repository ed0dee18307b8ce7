//! Shared strategies for integration tests.
