//! The one place this crate binds to the lodkit libraries.
//!
//! Everything the browser runs goes through the functions here, and they use
//! only the crates' high-level entry points: `lodkit_particles::{decode,
//! DecodeOptions, PrefixDecoder, triangulate, TriangulateOptions}`,
//! `Decoded::surface`, and `lodkit_mco::{McoModel, McoStream, Camera}`
//! with `McoModel::from_bytes`. When those APIs move, this file is the only one to
//! re-point.
//!
//! `.pop` prefixes: a stream arriving over the network goes through
//! `PrefixDecoder`, which decodes each whole chunk once as it arrives. A
//! level whose attribute chunk has not arrived yet is left out: a level is
//! usable once its colours and normals are there too.

use glam::Vec3;
pub use lodkit_mco::Camera;
use lodkit_mco::{McoModel, McoStream, ViewCut};
use lodkit_particles::{DecodeOptions, Decoded, PrefixDecoder, TriangulateOptions};

/// A mesh ready to be copied into GPU buffers: positions (and normals,
/// colours where present) per vertex, three indices per triangle.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct MeshOut {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub colors: Option<Vec<[u8; 4]>>,
    pub indices: Vec<u32>,
}

/// What the complete chunks of a `.pop` prefix hold.
pub struct PopPrefix {
    /// The decoded chunks; its last level may lack its attribute chunk
    /// (then it is not counted in `levels`).
    pub decoded: Decoded,
    /// Levels usable: `0..levels`, each with its colours and normals where
    /// the stream has them.
    pub levels: usize,
    /// Bytes of the prefix those levels (and precision layers) take; the
    /// rest waits for more bytes.
    pub bytes_used: usize,
}

/// A `.pop` stream as it arrives: the bytes received so far and
/// `lodkit_particles::PrefixDecoder`'s state, so each chunk is decoded once.
pub struct PopStream {
    pub bytes: Vec<u8>,
    decoder: PrefixDecoder,
}

/// An empty stream (every level, every precision layer).
pub fn pop_stream_new() -> PopStream {
    PopStream {
        bytes: Vec::new(),
        decoder: PrefixDecoder::new(&DecodeOptions::default()),
    }
}

/// Decodes the chunks of `s.bytes` that arrived since the last call and
/// returns the bytes usable now: the end of the last chunk that is not a
/// level waiting for its attribute chunk (a level is usable once its
/// colours and normals are there too). Zero before the first level.
/// `Err`: a bad header or a damaged chunk.
pub fn pop_stream_read(s: &mut PopStream) -> Result<usize, String> {
    s.decoder.read(&s.bytes).map_err(|e| e.to_string())?;
    Ok(s.decoder.whole_bytes())
}

/// The usable levels decoded so far (`None` before the first); a copy of
/// the decoder's state. Call after [`pop_stream_read`].
pub fn pop_stream_decoded(s: &PopStream) -> Result<Option<PopPrefix>, String> {
    let levels = s.decoder.whole_levels();
    if levels == 0 {
        return Ok(None);
    }
    let decoded = s.decoder.decoded().map_err(|e| e.to_string())?;
    Ok(Some(PopPrefix {
        decoded,
        levels,
        bytes_used: s.decoder.whole_bytes(),
    }))
}

/// Decodes every usable chunk of a whole buffer (a stream prefix).
pub fn pop_decode_prefix(bytes: &[u8]) -> Result<Option<PopPrefix>, String> {
    let mut s = pop_stream_new();
    s.bytes = bytes.to_vec();
    pop_stream_read(&mut s)?;
    pop_stream_decoded(&s)
}

/// Triangulates (and orients) level `r` of a decoded prefix with the
/// defaults of `lodkit pop decode`. A stream without coded normals gets
/// area-weighted vertex normals, so the page does no per-vertex work.
pub fn pop_level_mesh(d: &Decoded, r: u8) -> Result<MeshOut, String> {
    let s = d.surface(r).map_err(|e| e.to_string())?;
    let t = lodkit_particles::triangulate(&s, &TriangulateOptions::DEFAULT);
    let mut m = t.mesh;
    if m.normals.is_none() {
        m.normals = Some(lodkit_mesh::normals::vertex_normals(&m));
    }
    Ok(MeshOut {
        positions: m.positions,
        normals: m.normals,
        colors: m.colors,
        indices: m.faces.into_flattened(),
    })
}

/// Octree depth `R` of a decoded stream (its finest level).
pub fn pop_depth(d: &Decoded) -> u8 {
    d.header.depth
}

/// Bits of precision of the decoded positions.
pub fn pop_precision(d: &Decoded) -> u8 {
    d.precision
}

/// Loads a whole `.mco` file held in memory.
pub fn mco_load(bytes: &[u8]) -> Result<McoModel, String> {
    McoModel::from_bytes(bytes).map_err(|e| e.to_string())
}

/// A `.mco` read as its bytes arrive (version 2 only: its chunks are in
/// LOD-number order, so each complete chunk serves more LOD numbers).
pub fn mco_stream_new() -> McoStream {
    McoStream::new()
}

/// Feeds the next `bytes` of the file to `s`. Returns the model of every
/// chunk complete so far when these bytes completed at least one (every
/// cut up to its `max_lod` is the whole file's cut), `None` while the next
/// chunk is still short. `Err`: a bad header or chunk (the stream stays
/// failed). Cost: linear in the bytes, plus a copy of the model read so
/// far and its extraction tables per call that completes a chunk.
pub fn mco_stream_push(s: &mut McoStream, bytes: &[u8]) -> Result<Option<McoModel>, String> {
    if !s.push(bytes).map_err(|e| e.to_string())? {
        return Ok(None);
    }
    Ok(s.model())
}

/// Whether every chunk of the file has been read.
pub fn mco_stream_complete(s: &McoStream) -> bool {
    s.is_complete()
}

/// The `.mco` format version the first bytes of a file declare (`None`:
/// too short, or no `.mco` signature).
pub fn mco_file_version(bytes: &[u8]) -> Option<u32> {
    McoModel::file_version(bytes)
}

/// The model's whole vertex buffer (every cut indexes into it).
pub fn mco_vertices(m: &McoModel) -> MeshOut {
    MeshOut {
        positions: m.positions().to_vec(),
        normals: Some(m.normals().to_vec()),
        colors: m.has_colors().then(|| m.colors().to_vec()),
        indices: Vec::new(),
    }
}

/// Highest LOD number (every leaf drawn).
pub fn mco_max_lod(m: &McoModel) -> usize {
    m.max_lod()
}

/// Triangles at full resolution.
pub fn mco_full_triangles(m: &McoModel) -> usize {
    m.full_triangles()
}

/// The model's bounding cube as (min corner, max corner).
pub fn mco_bounds(m: &McoModel) -> (Vec3, Vec3) {
    m.bounds()
}

/// Index buffer at LOD number `k` (clamped to the highest).
pub fn mco_extract_lod(m: &McoModel, k: usize, out: &mut Vec<u32>) -> usize {
    let k = k.min(m.max_lod());
    m.extract_lod(k, out);
    k
}

/// Index buffer closest to `triangles` triangles; returns the LOD number.
pub fn mco_extract_triangles(m: &McoModel, triangles: usize, out: &mut Vec<u32>) -> usize {
    m.extract_triangles(triangles, out)
}

/// View-dependent index buffer at `tolerance_px` pixels of projected error,
/// left in `cut`, the handle's kept state ([`ViewCut::indices`]: so a cut
/// per frame allocates and copies nothing once warm; the same cut as
/// `McoModel::extract_view`); returns the number of expanded nodes.
pub fn mco_extract_view(m: &McoModel, cut: &mut ViewCut, cam: &Camera, tolerance_px: f32) -> usize {
    cut.update(m, cam, tolerance_px);
    cut.expanded_nodes()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stream the browser's worker warms up on (a shipped `.pop`):
    /// what `PrefixDecoder` guarantees for every prefix, attributes
    /// included, is tested with it (`lodkit_particles::decode_stream`);
    /// here, that these bindings hand it on.
    const STREAM: &[u8] = include_bytes!("warm_up.pop");

    #[test]
    fn a_stream_read_as_it_arrives_shows_only_levels_with_their_attributes() {
        let full = pop_decode_prefix(STREAM).unwrap().expect("levels");
        assert_eq!(full.bytes_used, STREAM.len());
        let mut s = pop_stream_new();
        let mut levels = 0;
        for piece in STREAM.chunks(7) {
            s.bytes.extend_from_slice(piece);
            let used = pop_stream_read(&mut s).expect("a prefix is no error");
            assert!(used <= s.bytes.len());
            let Some(p) = pop_stream_decoded(&s).unwrap() else {
                continue;
            };
            assert!(p.levels >= levels, "levels never go back");
            levels = p.levels;
            if let Some(n) = &p.decoded.normals {
                assert!(n.len() >= levels, "a level comes with its normals");
            }
            assert!(pop_level_mesh(&p.decoded, (levels - 1) as u8).is_ok());
        }
        assert_eq!(levels, full.levels);
    }

    #[test]
    fn the_finest_level_matches_a_plain_decode() {
        let p = pop_decode_prefix(STREAM).unwrap().unwrap();
        let r = pop_depth(&p.decoded);
        let mesh = pop_level_mesh(&p.decoded, r).unwrap();
        let d = lodkit_particles::decode(STREAM, &DecodeOptions::default()).unwrap();
        let s = d.surface(r).unwrap();
        let t = lodkit_particles::triangulate(&s, &TriangulateOptions::DEFAULT);
        assert_eq!(mesh.indices, t.mesh.faces.into_flattened());
        assert_eq!(mesh.positions, t.mesh.positions);
    }

    #[test]
    fn a_streamed_mco_serves_more_lod_numbers_as_chunks_arrive() {
        let mesh = lodkit_mesh::shapes::icosphere(3);
        let model =
            lodkit_mco::build_from_mesh(&mesh, &lodkit_mco::Options::default()).expect("builds");
        let bytes = model.to_bytes();
        assert_eq!(mco_file_version(&bytes), Some(2));
        let whole = mco_load(&bytes).unwrap();
        let mut s = mco_stream_new();
        let mut last = None;
        let mut max_lod = 0;
        for piece in bytes.chunks(97) {
            if let Some(m) = mco_stream_push(&mut s, piece).unwrap() {
                assert!(m.max_lod() >= max_lod, "LOD numbers never go back");
                max_lod = m.max_lod();
                last = Some(m);
            }
        }
        assert!(mco_stream_complete(&s));
        let last = last.expect("a model");
        assert_eq!(last.max_lod(), whole.max_lod());
        let (mut a, mut b) = (Vec::new(), Vec::new());
        mco_extract_lod(&last, whole.max_lod(), &mut a);
        mco_extract_lod(&whole, whole.max_lod(), &mut b);
        assert_eq!(a, b);
    }

    /// A coloured point cloud's model (an open surface: its root cube
    /// holds triangles) loads whole and streamed, colours kept, and its
    /// view cut refines nodes.
    #[test]
    fn a_coloured_point_cloud_mco_loads_and_cuts() {
        let n = 40;
        let mut cloud = lodkit_mesh::PointCloud::default();
        let mut colors = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
                cloud
                    .positions
                    .push(Vec3::new(x, y, 0.1 * (6.0 * x).sin() * (4.0 * y).cos()));
                colors.push([(x * 255.0) as u8, (y * 255.0) as u8, 90, 255]);
            }
        }
        cloud.colors = Some(colors);
        let model =
            lodkit_mco::build_from_points(&cloud, &lodkit_mco::Options::default()).expect("builds");
        let bytes = model.to_bytes();
        let whole = mco_load(&bytes).unwrap();
        let v = mco_vertices(&whole);
        assert_eq!(v.colors.as_ref().map(Vec::len), Some(v.positions.len()));
        let mut s = mco_stream_new();
        let mut last = None;
        for piece in bytes.chunks(301) {
            if let Some(m) = mco_stream_push(&mut s, piece).unwrap() {
                last = Some(m);
            }
        }
        assert!(mco_stream_complete(&s));
        let (mut a, mut b) = (Vec::new(), Vec::new());
        mco_extract_lod(&last.expect("a model"), whole.max_lod(), &mut a);
        mco_extract_lod(&whole, whole.max_lod(), &mut b);
        assert_eq!(a, b);
        assert!(!a.is_empty());
        let (lo, hi) = mco_bounds(&whole);
        let c = (lo + hi) * 0.5;
        let view = Camera {
            position: c + Vec3::new(0.0, 0.0, 2.0),
            direction: Vec3::new(0.0, 0.0, -1.0),
            up: Vec3::Y,
            vfov_deg: 60.0,
            viewport_height: 1080.0,
            aspect: 1.0,
        };
        let mut cut = ViewCut::default();
        assert!(mco_extract_view(&whole, &mut cut, &view, 1.0) > 0);
    }

    #[test]
    fn a_damaged_header_is_an_error_not_a_panic() {
        let mut bytes = STREAM.to_vec();
        bytes[0] ^= 0xff;
        let mut s = pop_stream_new();
        s.bytes = bytes.clone();
        assert!(pop_stream_read(&mut s).is_err());
        assert!(mco_load(&bytes).is_err());
    }
}
