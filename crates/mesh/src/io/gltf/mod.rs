//! glTF 2.0 (`.gltf` JSON and `.glb` binary): read into one [`TriMesh`],
//! write an LOD chain as one GLB.
//!
//! **Reading** takes every triangle primitive of every mesh reachable from
//! the default scene (when the file names none: from every root node; when
//! it has no nodes at all: every mesh, untransformed), with each node's world
//! transform applied. Conventions:
//! - `TRIANGLES` are read as they are; `TRIANGLE_STRIP` and `TRIANGLE_FAN`
//!   are converted to triangles (the degenerate triangles strips use as
//!   joints are dropped); points and lines are skipped;
//! - positions get the world matrix, normals its inverse transpose
//!   (renormalised; under an identity transform normals are kept exactly as
//!   stored); a mirroring transform (negative determinant) has its
//!   triangles' winding swapped so faces stay CCW seen from outside;
//! - `COLOR_0` (float, or normalised u8/u16; RGB or RGBA) is *linear* in
//!   glTF and becomes sRGB RGBA8 (alpha stays linear, RGB gets alpha 255);
//! - `TEXCOORD_0` (float or normalised u8/u16) has its V flipped:
//!   `v = 1 − v_gltf` (glTF's origin is top-left, lodkit's bottom-left);
//! - indices may be u8/u16/u32 or absent (non-indexed);
//! - an attribute is kept only if *every* primitive read has it (dropped
//!   otherwise, never filled with made-up defaults);
//! - materials, textures, skins, morph targets, cameras, animations and
//!   other texture coordinate / colour sets are ignored by [`read`];
//!   [`read_scene`] keeps meshes apart, one material per primitive, the
//!   nodes and the material, texture, sampler and image tables (see
//!   `crate::scene` and `materials_read`), and [`write_scene_glb`] writes
//!   such a scene (see `materials_write`).
//!
//! Buffers come from the GLB `BIN` chunk, `data:` URIs (base64 only), or
//! files relative to `base_dir` (`None` refuses them). A file URI is
//! percent-decoded first, then must pass [`crate::io::input::resolve_inside`]:
//! relative, no `..`, no scheme (`http:`, `file:`…), so it stays inside the
//! glTF file's own folder; it is read through
//! [`crate::io::input::read_file`] (regular files only, size-capped).
//! Only the buffers that the primitives read actually use are resolved.
//!
//! **Guarantees on bad input**: the GLB container is parsed here, not by
//! `gltf::Glb::from_slice` (which, in gltf 1.4, subtracts 12 from the header
//! length unchecked and so panics in debug builds on a header length < 12).
//! Before `gltf`'s validation runs, every primitive's accessor indices are
//! range-checked (gltf-json 1.4's POSITION min/max check indexes the accessor
//! list without checking, and panics). Before any accessor is read through
//! `gltf`'s reader, its type, count (≥ 1), stride (≥ element size) and
//! extent (accessor inside view, view inside the buffer's real bytes, all in
//! checked arithmetic) are verified, since the reader would otherwise panic
//! (stride smaller than an element, count 0) or silently read short.
//! Sparse accessors are refused. Indices out of range, cycles in the node
//! graph and nodes with two parents are errors. Instances are expanded
//! (each node's copy becomes vertices of its own), within a stated limit
//! checked before allocating: the expanded vertices and indices are at most
//! [`MAX_INSTANCING_GROWTH`] times what the file stores, or
//! [`INSTANCING_FLOOR`] each, whichever is larger. All of these are
//! one-line [`ParseError`]s.
//!
//! **Reading a model** ([`read_model`], what `io::load` uses): the file
//! first goes through `extensions` — `KHR_mesh_quantization` accessors are
//! turned into floats, `EXT_meshopt_compression` / `KHR_meshopt_compression`
//! views are decoded (with the `meshopt` feature; without it, a one-line
//! error naming the extension), `KHR_draco_mesh_compression` is a one-line
//! error (no maintained Rust Draco decoder exists) — then a scene with
//! triangles is read as above, and one with only `POINTS` primitives as a
//! point cloud (POSITION, NORMAL, COLOR_0, each kept only when every
//! primitive has it).
//!
//! **Writing** ([`write_glb`], [`write_glb_with`]): one mesh + one node per level, all nodes
//! siblings in the default scene. The node and mesh are named
//! `"{name} ({triangles} triangles)"` and the node's `extras` hold
//! `{"triangles": N, "vertices": M}`. Accessors: POSITION (f32 vec3 with
//! min/max), NORMAL (f32 vec3), COLOR_0 (normalised **u16** vec4, linear:
//! sRGB → linear in u16 is lossless for RGBA8, in u8 it is not, and
//! `write → read` must give the same colours back), TEXCOORD_0 (f32 vec2, V
//! flipped), indices u16 when every index fits below 65535 (the
//! primitive-restart value is reserved) and u32 otherwise. Each accessor has
//! its own 4-byte-aligned buffer view; the JSON chunk is padded with spaces
//! and the BIN chunk with zeros. The JSON is built with `gltf-json` types and
//! serialised with `serde_json`, whose maps are ordered: the same levels
//! always give the same bytes.
//!
//! **LOD chains** ([`write_lod_glb`]): level 0 is the only root node and
//! carries `MSFT_lod` (the other levels' node ids) with
//! `extras.MSFT_screencoverage`, strictly decreasing so that every level
//! is reached ([`screen_coverages`]; [`error_coverage`] gives a level's
//! coverage from its error); the other levels' nodes are reachable
//! only through it, so a loader without `MSFT_lod` shows level 0 alone.
//! **Point clouds** ([`write_points_glb`]): one `POINTS` primitive.
//!
//! **Compression** ([`GlbOptions::compress`], `meshopt` feature): triangles
//! reordered for the vertex cache and vertices in first-use order
//! (meshoptimizer), then `KHR_mesh_quantization` — POSITION as 14-bit
//! `u16` on a grid shared by every level (the node's translation + uniform
//! scale undo it), NORMAL as normalised `i8`, TEXCOORD_0 as normalised
//! `u16` when inside `[0, 1]` — and every view through meshoptimizer's
//! vertex codec (version 0) or index codec (`TRIANGLES`) as
//! `EXT_meshopt_compression`, with the uncompressed layout in a fallback
//! buffer that has no data (both extensions are required). Lossy: 1/16383
//! of the largest extent for positions, 1/127 for normals.
//!
//! Stages, one file each: `glb` (the binary container: chunks in, chunks
//! out), `buffers` (where a buffer's bytes come from: BIN chunk, data URI,
//! relative file), `read` (document → one mesh), `write` (levels → GLB),
//! `color` (linear ↔ sRGB, shared by both directions), `extensions`
//! (compressed and quantised files → plain ones, before reading), `points`
//! (`POINTS` primitives → a point cloud; which reader a file needs).

mod buffers;
mod codec;
mod color;
mod extensions;
mod glb;
mod grid;
mod lod_links;
mod materials_read;
mod materials_write;
mod points;
mod read;
mod write;

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_engines;

pub use grid::{
    MAX_GRID_INDEX, QuantGrid, write_glb_on_grid, write_points_glb_on_grid, write_scene_glb_on_grid,
};
pub use lod_links::{COVERAGE_LINES, COVERAGE_PIXELS, error_coverage, screen_coverages};
pub use materials_write::{
    SceneLodLevel, write_scene_glb, write_scene_glb_with, write_scene_lod_glb,
};
pub use points::read_model;
pub use read::{INSTANCING_FLOOR, MAX_INSTANCING_GROWTH, read, read_scene};
pub use write::{
    GlbOptions, LodLevel, write_glb, write_glb_with, write_lod_glb, write_model_glb,
    write_points_glb,
};

#[cfg(doc)]
use crate::{error::ParseError, mesh::TriMesh};
