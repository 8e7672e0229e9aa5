//! A tile's glTF content (GLB bytes).

use lodkit_mesh::TriMesh;
use lodkit_mesh::io::gltf::{GlbOptions, write_glb_with};

use crate::{Error, Result};

/// Encodes one tile's mesh (y-up, object units, with normals) as a GLB
/// named `name`.
///
/// Merge point: this is the single place tile bytes are made. It writes
/// each tile with the plain GLB writer (`compress`: meshoptimizer codecs
/// and quantisation on the file's own grid); it is to be switched to the
/// writer whose quantisation grid is shared by every tile of a tileset,
/// so that border vertices of neighbouring tiles stay equal when
/// quantised.
///
/// Errors: the writer's (an invalid mesh, `compress` without the
/// `meshopt` feature), naming the tile.
pub fn encode_tile(name: &str, mesh: &TriMesh, compress: bool) -> Result<Vec<u8>> {
    write_glb_with(&[(name, mesh)], &GlbOptions { compress })
        .map_err(|e| Error::Encode(format!("tile {name}: {e}")))
}
