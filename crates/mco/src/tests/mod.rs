//! End-to-end behaviour on synthetic closed shapes that reads the model's
//! internal arrays (nodes, LOD array, accumulation table, birth/death
//! tables): reconstruction error, no cracks, budget accuracy, incremental
//! building, the extraction forms against each other.

#[path = "../../tests/support/mod.rs"]
mod support;

mod extraction;
mod pipeline;
mod validation;
mod view_cut;
