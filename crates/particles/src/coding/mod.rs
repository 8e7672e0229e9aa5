//! Coding of the particle octree — §7 of Yemez & Schmitt, "Multilevel
//! representation and transmission of real objects with progressive octree
//! particles" (IEEE TVCG 2003), and the entropy mode beyond it.
//!
//! The symbol sequence, shared by the encoder and the decoder:
//! - [`levels`] — §7.1, one octree level at a time: child occupancy,
//!   phantom flags, new particles' leaf paths;
//! - [`precision_layers`] — §7.2, one bit of every particle's coordinates
//!   per layer below the octree's depth;
//! - [`links`] — the face neighbours of each node, level by level, that
//!   the entropy mode's [`contexts`] read.
//!
//! Each symbol goes through a [`bit_coder::BitCoder`]: [`raw_bits`] (the
//! baseline, one bit per symbol, eq. 5's count) or [`range_coder`] (an
//! adaptive binary range coder, one model per context).
pub mod bit_coder;
pub mod contexts;
pub mod levels;
pub mod links;
pub mod precision_layers;
pub mod range_coder;
pub mod raw_bits;
