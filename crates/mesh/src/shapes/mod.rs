//! Synthetic shapes for tests and benchmarks.
