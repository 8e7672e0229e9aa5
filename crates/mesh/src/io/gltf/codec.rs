//! meshoptimizer's codecs for GLB buffer views (`EXT_meshopt_compression`):
//! the compression mode of a view, the reordering that makes levels
//! compress well, and the encoder (with the `meshopt` feature; without
//! it, a one-line error).

#[cfg(feature = "meshopt")]
use glam::{Vec2, Vec3};

use crate::error::ParseError;
use crate::mesh::TriMesh;
#[cfg(feature = "meshopt")]
use crate::parse_err;

/// How a buffer view is compressed (`EXT_meshopt_compression` modes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Codec {
    /// Vertex data with this stride (bytes, a multiple of 4).
    Attributes(usize),
    /// Unit vectors through the octahedral filter, 8-bit (stride 4).
    Octahedral,
    /// A triangle list's indices of this size (2 or 4 bytes).
    Triangles(usize),
}

/// Reorders a level for the codecs: triangles for the vertex cache, then
/// vertices in first-use order (meshoptimizer's `optimizeVertexCache` and
/// `optimizeVertexFetch`), as gltfpack does before encoding: the index
/// codec and the vertex deltas both depend on that order. Same triangles,
/// same winding; unreferenced vertices are dropped.
#[cfg(feature = "meshopt")]
pub(super) fn reorder_for_codec(m: &TriMesh) -> TriMesh {
    let flat: Vec<u32> = m.faces.iter().flatten().copied().collect();
    // The strip-like order: a little worse for a GPU's vertex cache than
    // `optimize_vertex_cache`, but it compresses better (what meshoptimizer
    // recommends when size is the goal).
    let mut cached = meshopt::optimize_vertex_cache_strip(&flat, m.positions.len());
    // Vertices in first-use order (what optimizeVertexFetch does).
    let mut remap = vec![u32::MAX; m.positions.len()];
    let mut next = 0u32;
    for i in &mut cached {
        let r = &mut remap[*i as usize];
        if *r == u32::MAX {
            *r = next;
            next += 1;
        }
        *i = *r;
    }
    let count = remap.iter().filter(|&&r| r != u32::MAX).count();
    let mut out = TriMesh {
        positions: vec![Vec3::ZERO; count],
        normals: m.normals.as_ref().map(|_| vec![Vec3::ZERO; count]),
        colors: m.colors.as_ref().map(|_| vec![[0u8; 4]; count]),
        uvs: m.uvs.as_ref().map(|_| vec![Vec2::ZERO; count]),
        faces: cached.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    };
    for (old, &new) in remap.iter().enumerate() {
        if new == u32::MAX {
            continue;
        }
        let new = new as usize;
        out.positions[new] = m.positions[old];
        if let (Some(d), Some(s)) = (out.normals.as_mut(), m.normals.as_ref()) {
            d[new] = s[old];
        }
        if let (Some(d), Some(s)) = (out.colors.as_mut(), m.colors.as_ref()) {
            d[new] = s[old];
        }
        if let (Some(d), Some(s)) = (out.uvs.as_mut(), m.uvs.as_ref()) {
            d[new] = s[old];
        }
    }
    out
}

#[cfg(not(feature = "meshopt"))]
pub(super) fn reorder_for_codec(m: &TriMesh) -> TriMesh {
    m.clone()
}

/// One view's bytes through meshoptimizer's encoders: the vertex codec at
/// format version 0 (the only one `EXT_meshopt_compression` allows) or the
/// index codec (version 1, the extension's `TRIANGLES` mode).
#[cfg(feature = "meshopt")]
pub(super) fn encode_view(bytes: &[u8], count: usize, codec: Codec) -> Result<Vec<u8>, ParseError> {
    fn vertices<const N: usize>(bytes: &[u8]) -> Result<Vec<u8>, ParseError> {
        let v: Vec<[u8; N]> = bytes
            .chunks_exact(N)
            .map(|c| <[u8; N]>::try_from(c).expect("chunks_exact"))
            .collect();
        meshopt::encode_vertex_buffer_level(&v, 2, Some(0))
            .map_err(|e| parse_err!("GLB: meshopt vertex encoder: {e:?}"))
    }
    match codec {
        Codec::Attributes(4) | Codec::Octahedral => vertices::<4>(bytes),
        Codec::Attributes(8) => vertices::<8>(bytes),
        Codec::Attributes(12) => vertices::<12>(bytes),
        Codec::Attributes(s) => Err(parse_err!("GLB: no vertex encoding for stride {s}")),
        Codec::Triangles(size) => {
            let idx: Vec<u32> = match size {
                2 => bytes
                    .chunks_exact(2)
                    .map(|c| u16::from_le_bytes([c[0], c[1]]) as u32)
                    .collect(),
                _ => bytes
                    .chunks_exact(4)
                    .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                    .collect(),
            };
            debug_assert_eq!(idx.len(), count);
            let vertex_count = idx.iter().max().map_or(0, |&m| m as usize + 1);
            meshopt::encode_index_buffer(&idx, vertex_count)
                .map_err(|e| parse_err!("GLB: meshopt index encoder: {e:?}"))
        }
    }
}

#[cfg(not(feature = "meshopt"))]
pub(super) fn encode_view(_: &[u8], _: usize, _: Codec) -> Result<Vec<u8>, ParseError> {
    Err(ParseError::new(
        "GLB compression needs the `meshopt` feature",
    ))
}
