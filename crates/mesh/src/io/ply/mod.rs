//! PLY (Stanford polygon file format): reading and writing.
//!
//! # Reading ([`read`])
//! - Encodings: `ascii`, `binary_little_endian`, `binary_big_endian`
//!   (version 1.0). Header lines may end in `\n` or `\r\n`; `comment` and
//!   `obj_info` lines may appear anywhere in the header.
//! - Types: the spec's `char uchar short ushort int uint float double` and
//!   the aliases `int8 uint8 int16 uint16 int32 uint32 float32 float64`.
//! - `vertex` element, properties in any order: `x y z` (required), `nx ny
//!   nz`, `red green blue [alpha]` (or `diffuse_red …`; integer colours are
//!   taken as 0–255, `ushort` as 0–65535, floats as 0–1; all become RGBA8,
//!   alpha 255 when absent), texture coordinates as `u v`, `s t`,
//!   `texture_u texture_v` or `texture_s texture_t`.
//! - `face` element: the index list `vertex_indices` (or `vertex_index`,
//!   or the element's only list), any integer count and index type.
//!   Polygons are triangulated as a fan from their first corner (`a b c d`
//!   → `a b c`, `a c d`); a list with fewer than 3 indices, an index past
//!   the header's vertex count or a triangle repeating a corner is refused
//!   (one set of face checks for this reader and [`stream`]'s).
//! - `range_grid` element (Stanford range scans): `obj_info num_cols` and
//!   `num_rows` give the lattice, each cell lists 0 vertex indices (no
//!   sample) or 1 (extra indices are ignored); vertex colours follow their
//!   vertex into the cell.
//! - Result: [`Model::Mesh`] when a `face` element has records,
//!   [`Model::Range`] when there is a `range_grid` element, else
//!   [`Model::Points`]. Every other property and element, lists included,
//!   is skipped.
//!
//! Guarantees: no panic on any input, and no allocation sized by a header
//! count before that count, at its smallest record size (binary: the sum of
//! its scalar sizes and list-count sizes; ASCII: 2 bytes per value), has
//! been checked to fit in the bytes after the header. Every problem is a
//! one-line [`ParseError`]. Face indices are checked as they are read,
//! range-grid indices once the grid is read. A binary body must end with
//! the last element the header declares: bytes after it (a face count
//! below the data, a damaged file) are refused, in both readers.
//!
//! # Writing ([`write_mesh`], [`write_points`])
//! Binary little-endian unless ASCII is asked for; see `write.rs` for the
//! layout. Output is deterministic.
//!
//! Stages, one file each: `header` (text header → element list),
//! `read` (body → model), `write` (model → bytes), `stream` (a binary
//! mesh read in bounded memory, for inputs larger than memory).

pub(crate) mod header;
mod read;
mod sources;
pub mod stream;
mod write;

#[cfg(test)]
mod tests;

pub use read::read;
pub use write::{write_mesh, write_points};

#[cfg(doc)]
use crate::{error::ParseError, mesh::Model};
