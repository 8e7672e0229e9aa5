//! Benchmarks next to their peers: criterion benches in `benches/`, and the
//! in-process comparisons that `lodkit bench` prints (`simplify`: lodkit's
//! HQMS against meshoptimizer; `mco`: the marching cube octree's
//! extraction next to a memcpy).

pub mod mco;
pub mod simplify;
