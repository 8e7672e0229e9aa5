//! `.mco` files: the public load/save entry points, and the version-1
//! layout (flat arrays). Byte layouts are specified in
//! `docs/formats/mco.md`. [`save`] and [`McoModel::to_bytes`] write
//! version 2 ([`v2`], the compact, streamable layout);
//! [`decode`] and [`load`] read both versions.
//!
//! Reading is defensive: the file size must equal the size the header's
//! counts imply (checked in 64-bit arithmetic before anything is
//! allocated), the CRC-32 must match, every index the extractor will
//! follow is range-checked, and every table is checked against the others
//! ([`validate`], for both versions): the nodes form one octree, the LOD
//! array, priority numbers and balance dependencies agree, and the
//! accumulation table is the triangle count the nodes give at every LOD
//! number. So a loaded model can never make extraction panic, read out of
//! bounds, or size an allocation by a table that disagrees with the data.
//! Each array is one allocation — there is no per-node allocation. Any
//! problem is one error line naming the file.

use std::path::Path;

use crate::model::McoModel;
use crate::{Error, Result};

pub(crate) mod format;
pub(crate) mod v1;
pub(crate) mod v2;
pub(crate) mod validate;

use format::MAX_FILE_BYTES;
pub use v2::{ChunkInfo, Header, McoStream, PartialModel};
pub(crate) use v2::{snapped_position, stored_normal};

/// The `.mco` format version this crate writes ([`McoModel::to_bytes`],
/// `docs/formats/mco.md`); it reads this one and version 1.
pub const FORMAT_VERSION: u32 = v2::VERSION;

/// Parses `.mco` bytes of version 1 or 2; the error says what is wrong
/// (no path).
pub(crate) fn decode(bytes: &[u8]) -> std::result::Result<McoModel, String> {
    match v2::file_version(bytes) {
        Some(v2::VERSION) => v2::decode(bytes),
        Some(v) if v != v1::VERSION => Err(format!(
            "unsupported .mco version {v} (this lodkit reads versions 1 and 2)"
        )),
        _ => v1::decode(bytes),
    }
}

impl McoModel {
    /// The model as `.mco` bytes (`docs/formats/mco.md`, version
    /// [`FORMAT_VERSION`]: LOD-ordered, deflated chunks, so any prefix
    /// serves a coarse cut): deterministic — the same model always gives
    /// the same bytes (no time stamps, no paths). Lossless for a built model
    /// (or one read from version 2): [`McoModel::from_bytes`] gives a model whose every cut
    /// is this one's, bit for bit (positions, normals, colours; vertices
    /// renumbered). No larger than the model's binary PLY on the shipped
    /// bunny. `O(size)`.
    pub fn to_bytes(&self) -> Vec<u8> {
        v2::encode(self)
    }

    /// Reads a model from `.mco` bytes (a file's contents, or an
    /// in-memory buffer such as a download).
    ///
    /// Reads versions 1 and 2. Errors ([`Error::Format`], one line):
    /// wrong signature or version,
    /// a size that differs from what the header's counts imply, a
    /// checksum mismatch, any index out of range, or tables that disagree
    /// (the octree, the LOD array and priority numbers, the per-LOD
    /// triangle counts against the nodes' triangles). Every check runs
    /// before the model is used, so a model that loads can never make a
    /// cut panic or read out of bounds; untrusted bytes are safe. Memory
    /// is allocated only after the size check: at most a small multiple
    /// of `bytes.len()`. Cost: `O(size)`, plus building the extraction
    /// tables (`O(n log n)` in the triangles).
    pub fn from_bytes(bytes: &[u8]) -> Result<McoModel> {
        decode(bytes).map_err(Error::Format)
    }

    /// Writes the model to `path` as `.mco` bytes ([`McoModel::to_bytes`]),
    /// atomically: a failed write leaves no partial file. Errors name the
    /// file.
    pub fn save(&self, path: &Path) -> Result<()> {
        save(path, self)
    }

    /// Reads a `.mco` file ([`McoModel::from_bytes`]); files over 16 GiB
    /// are refused before reading. Errors ([`Error::File`]) name the file
    /// and say what is wrong, one line.
    pub fn load(path: &Path) -> Result<McoModel> {
        load(path)
    }

    /// The `.mco` format version `bytes` declare (1 or 2), or `None` when
    /// they are too short or lack the signature. Reads 12 bytes; checks
    /// nothing else.
    pub fn file_version(bytes: &[u8]) -> Option<u32> {
        v2::file_version(bytes)
    }

    /// The chunk table of version-2 bytes, in file order: a prefix through
    /// chunk `c` serves LOD numbers `0..=last_lod` of that chunk. Errors
    /// ([`Error::Format`], one line) as [`McoModel::from_bytes`], and for
    /// version-1 bytes (which have no chunks). Cost: `O(size)` (each chunk
    /// is inflated and checked).
    pub fn chunk_table(bytes: &[u8]) -> Result<Vec<ChunkInfo>> {
        v2::chunk_table(bytes).map_err(Error::Format)
    }

    /// Reads a prefix of version-2 bytes (a partial download) as far as its
    /// complete chunks go: the model serves every LOD number up to
    /// [`PartialModel::max_lod`] exactly as the whole file would. Errors
    /// ([`Error::Format`], one line) on a bad header or chunk, or a prefix
    /// without one complete chunk; the checks of [`McoModel::from_bytes`]
    /// run on what was read. Cost: `O(prefix)`. For bytes arriving in
    /// pieces, [`McoStream`](crate::McoStream) reads each chunk once.
    pub fn from_prefix(bytes: &[u8]) -> Result<PartialModel> {
        v2::decode_prefix(bytes).map_err(Error::Format)
    }
}

/// Writes `model` to `path` atomically, as version 2
/// ([`McoModel::to_bytes`]).
fn save(path: &Path, model: &McoModel) -> Result<()> {
    lodkit_mesh::io::write_atomic(path, &model.to_bytes())?;
    Ok(())
}

/// Reads a `.mco` file; errors name the file.
fn load(path: &Path) -> Result<McoModel> {
    let named = |message: String| Error::File {
        path: path.display().to_string(),
        message,
    };
    let meta = std::fs::metadata(path).map_err(|e| named(e.to_string()))?;
    if meta.len() > MAX_FILE_BYTES {
        return Err(named(format!(
            "{} bytes is larger than the {MAX_FILE_BYTES}-byte limit",
            meta.len()
        )));
    }
    let bytes = std::fs::read(path).map_err(|e| named(e.to_string()))?;
    decode(&bytes).map_err(named)
}

#[cfg(test)]
mod tests;
