//! Benchmarks next to their peers: criterion benches in `benches/`, and the
//! in-process comparisons that `lodkit bench` prints (`simplify`: lodkit's
//! HQMS against meshoptimizer).

pub mod simplify;
