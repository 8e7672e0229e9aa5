//! Benchmarks next to their peers: criterion benches in `benches/`, and the
//! in-process comparisons that `lodkit-bench` prints (`simplify`: lodkit's
//! HQMS against meshoptimizer; `mco`: the marching cube octree's
//! extraction next to a memcpy).
//!
//! Feature `peers` (default): links meshoptimizer, which compiles C++. The
//! `lodkit` CLI depends on this crate without it, so installing the CLI
//! needs no C++ compiler; `lodkit --features peers` turns it back on.

pub mod alloc;
pub mod mco;
#[cfg(feature = "peers")]
mod meshopt_peer;
pub mod simplify;

/// Whether this build links the peer libraries (feature `peers`); without
/// them [`simplify::run_case`] returns [`simplify::NO_PEERS`].
pub const PEERS: bool = cfg!(feature = "peers");
